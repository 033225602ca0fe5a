//! Learning a site's source rates from what its sensors saw.
//!
//! A window of steps gives each step's looks and the targets they
//! detected, each with a track id. The distinct targets that the window
//! detects from source `j` are its Poisson process thinned by the looks
//! ([`exposure`]); the sources that can have emitted each detected target
//! are found by tracing its track back ([`traceback`]); the rates'
//! posterior follows ([`posterior`]). See `docs/learning.md`.

pub mod exposure;
pub mod learner;
pub mod posterior;
pub mod traceback;
pub mod window;
pub mod wire;

pub use exposure::WindowLooks;
pub use learner::{LearnerSnapshot, LearntStep, RateLearner};
pub use posterior::{Posterior, Prior};
pub use traceback::Tolerance;
pub use window::{FirstDetection, FitWindow, Observed, Tolerances, TrackBook};
pub use wire::*;

use crate::scenario::Scenario;

/// How each first detection is explained: by one source, by several (with
/// their densities), or by none.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Attribution {
    /// Per source: detections that only it explains.
    pub own: Vec<f64>,
    /// Detections that several sources explain.
    pub shared: Vec<Vec<(usize, f64)>>,
    /// Detections that no source explains.
    pub unexplained: Vec<Unexplained>,
}

impl Attribution {
    /// Nothing attributed yet, for the sources of `s`.
    pub fn new(s: &Scenario) -> Self {
        Attribution {
            own: vec![0.0; s.sources.len()],
            ..Default::default()
        }
    }

    /// Attributes `firsts`.
    pub fn add(&mut self, s: &Scenario, firsts: &[FirstDetection], tol: &Tolerance) {
        for d in firsts {
            let explained = traceback::explaining(s, d.pos, d.vel, tol);
            match explained.as_slice() {
                [] => {
                    let entry = traceback::entry(s, d.pos, d.vel);
                    self.unexplained.push(Unexplained {
                        id: d.id.clone(),
                        entry: PointOut {
                            x: entry.x,
                            y: entry.y,
                        },
                    });
                }
                [(j, _)] => self.own[*j] += 1.0,
                _ => self.shared.push(explained),
            }
        }
    }

    /// Each source's fitted rate, given its exposure and prior.
    pub fn rates(&self, s: &Scenario, exposure: &[f64], prior: Prior) -> Vec<SourceRate> {
        let shared: Vec<&[(usize, f64)]> = self.shared.iter().map(Vec::as_slice).collect();
        rates_of(s, &self.own, &shared, exposure, prior)
    }

    /// The rates after `added` too (a step not yet recorded), without
    /// copying this attribution.
    pub fn rates_with(
        &self,
        added: &Attribution,
        s: &Scenario,
        exposure: &[f64],
        prior: Prior,
    ) -> Vec<SourceRate> {
        let own: Vec<f64> = self
            .own
            .iter()
            .zip(&added.own)
            .map(|(a, b)| a + b)
            .collect();
        let shared: Vec<&[(usize, f64)]> = self
            .shared
            .iter()
            .chain(&added.shared)
            .map(Vec::as_slice)
            .collect();
        rates_of(s, &own, &shared, exposure, prior)
    }

    /// Records `added`.
    pub fn extend(&mut self, added: Attribution) {
        for (a, b) in self.own.iter_mut().zip(&added.own) {
            *a += b;
        }
        self.shared.extend(added.shared);
        self.unexplained.extend(added.unexplained);
    }
}

/// Each source's fitted rate from its detections (`own`, and `shared`
/// with other sources), its exposure and prior.
fn rates_of(
    s: &Scenario,
    own: &[f64],
    shared: &[&[(usize, f64)]],
    exposure: &[f64],
    prior: Prior,
) -> Vec<SourceRate> {
    let priors: Vec<Posterior> = (0..s.sources.len())
        .map(|j| Posterior::prior(s, j, prior))
        .collect();
    let fallback: Vec<f64> = s.sources.iter().map(|src| src.rate).collect();
    let (posteriors, detected) = posterior::solve(&priors, exposure, own, shared, &fallback);
    posteriors
        .iter()
        .enumerate()
        .map(|(j, p)| SourceRate {
            index: j,
            rate: p.mean().unwrap_or(fallback[j]),
            interval: p.interval(),
            detected: detected[j],
            exposure: exposure[j],
        })
        .collect()
}

/// The rates that a window's observations support.
pub fn fit(s: &Scenario, window: &FitWindow) -> FitResponse {
    let exposure = WindowLooks::new(s, &window.looks).exposure(0);
    let mut attribution = Attribution::new(s);
    attribution.add(s, &window.firsts, &window.tolerances.traceback);
    FitResponse {
        scenario: s.id.clone(),
        steps: window.looks.len(),
        sources: attribution.rates(s, &exposure, window.prior),
        unexplained: attribution.unexplained,
        id: None,
    }
}
