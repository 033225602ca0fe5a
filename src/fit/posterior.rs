//! The rates' posterior: a Gamma per source, from the thinned process's
//! likelihood.
//!
//! The distinct targets that a window detects from source `j` are a Poisson
//! process thinned by the looks: their number `N_j` is Poisson with mean
//! `λ_j·E_j` (`E_j` the exposure), independently across sources. With a
//! Gamma(`a_j`, `b_j`) prior the posterior is Gamma(`a_j + N_j`,
//! `b_j + E_j`). A detection that more than one source explains adds to
//! each `N_j` its share `λ_j·f_j/Σ λ_i·f_i` (see `traceback`): the shares
//! and the rates are solved together by expectation–maximisation, with the
//! posterior means as the rates.

use statrs::distribution::{ContinuousCDF, Gamma};

use crate::limits::RATE_PRIOR_SHAPE;
use crate::scenario::Scenario;

/// The prior on each source's rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Prior {
    /// Gamma with shape [`RATE_PRIOR_SHAPE`] and mean the spec's rate (flat
    /// for a source whose spec rate is 0).
    #[default]
    Scenario,
    /// Uniform on the rate (an improper Gamma(1, 0)).
    Flat,
}

/// A Gamma(`shape`, `rate`) distribution of a source's rate; improper
/// when `rate` is 0 (a flat prior that no look has exposed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Posterior {
    /// Shape.
    pub shape: f64,
    /// Rate (inverse scale).
    pub rate: f64,
}

impl Posterior {
    /// The prior of source `j`.
    pub fn prior(s: &Scenario, j: usize, prior: Prior) -> Self {
        let spec = s.sources[j].rate;
        match prior {
            Prior::Scenario if spec > 0.0 => Posterior {
                shape: RATE_PRIOR_SHAPE,
                rate: RATE_PRIOR_SHAPE / spec,
            },
            _ => Posterior {
                shape: 1.0,
                rate: 0.0,
            },
        }
    }

    /// The posterior after `detected` targets over `exposure`.
    pub fn update(&self, detected: f64, exposure: f64) -> Self {
        Posterior {
            shape: self.shape + detected,
            rate: self.rate + exposure,
        }
    }

    /// The mean, if proper.
    pub fn mean(&self) -> Option<f64> {
        (self.rate > 0.0).then(|| self.shape / self.rate)
    }

    /// The equal-tailed 95% credible interval (the 2.5% and 97.5%
    /// quantiles), if proper. It never holds 0: for a source with no
    /// detection its lower end is `−ln(0.975)/rate ≈ 0.0253/rate`.
    pub fn interval(&self) -> Option<[f64; 2]> {
        if self.rate <= 0.0 {
            return None;
        }
        Some([self.quantile(0.025), self.quantile(0.975)])
    }

    fn quantile(&self, p: f64) -> f64 {
        // statrs's inversion fails (NaN) at very large shapes; there the
        // Wilson–Hilferty transform is exact to many digits.
        let exact = Gamma::new(self.shape, self.rate)
            .ok()
            .map(|g| g.inverse_cdf(p))
            .filter(|q| q.is_finite());
        match exact {
            Some(q) if self.shape < 1e5 => q,
            _ => {
                let z = std::f64::consts::SQRT_2 * erf_inv(2.0 * p - 1.0);
                let k = self.shape;
                let c = 1.0 / (9.0 * k);
                k * (1.0 - c + z * c.sqrt()).powi(3) / self.rate
            }
        }
    }
}

fn erf_inv(x: f64) -> f64 {
    statrs::function::erf::erf_inv(x)
}

/// The sources' posteriors and their expected detections `N_j`, from the
/// exposures, the detections each explained by one source (`own[j]`), and
/// those explained by several (`shared`: per detection, its sources with
/// their densities). A shared detection's sources with no exposure are
/// left out (no look can have seen their targets).
pub fn solve(
    priors: &[Posterior],
    exposure: &[f64],
    own: &[f64],
    shared: &[&[(usize, f64)]],
    fallback: &[f64],
) -> (Vec<Posterior>, Vec<f64>) {
    let n = priors.len();
    let rate_of = |j: usize, detected: f64| {
        priors[j]
            .update(detected, exposure[j])
            .mean()
            .unwrap_or(fallback[j])
    };
    let mut detected = own.to_vec();
    let mut rates: Vec<f64> = (0..n).map(|j| rate_of(j, own[j])).collect();
    if !shared.is_empty() {
        // Expectation–maximisation: a fixed point of the shares and the
        // posterior means. Each round cannot lower the posterior density.
        for _ in 0..1000 {
            detected.copy_from_slice(own);
            for explained in shared {
                let total: f64 = explained
                    .iter()
                    .filter(|&&(j, _)| exposure[j] > 0.0)
                    .map(|&(j, f)| rates[j] * f)
                    .sum();
                let live = explained.iter().filter(|&&(j, _)| exposure[j] > 0.0);
                if total > 0.0 {
                    for &(j, f) in live {
                        detected[j] += rates[j] * f / total;
                    }
                } else {
                    let count = live.clone().count();
                    for &(j, _) in live {
                        detected[j] += 1.0 / count as f64;
                    }
                }
            }
            let next: Vec<f64> = (0..n).map(|j| rate_of(j, detected[j])).collect();
            let moved = next
                .iter()
                .zip(&rates)
                .map(|(a, b)| (a - b).abs() / a.abs().max(1e-300))
                .fold(0.0, f64::max);
            rates = next;
            if moved < 1e-12 {
                break;
            }
        }
    }
    let posteriors = (0..n)
        .map(|j| priors[j].update(detected[j], exposure[j]))
        .collect();
    (posteriors, detected)
}
