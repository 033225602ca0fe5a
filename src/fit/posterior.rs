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

use statrs::function::gamma::{gamma_lr, ln_gamma};

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

    /// The `p` quantile.
    pub fn quantile(&self, p: f64) -> f64 {
        standard_gamma_quantile(self.shape, p) / self.rate
    }
}

/// The `p` quantile (`0 < p < 1`) of the Gamma distribution of shape `k`
/// and rate 1: the root of `P(k, y) = p`, `P` the regularised lower
/// incomplete gamma function, by Newton's method from the Wilson–Hilferty
/// approximation, kept inside a bracket of the root and bisecting it when
/// a step leaves it. (statrs's `inverse_cdf` bisects only a few times:
/// its quantiles were off by up to half their tail, an audit found.)
fn standard_gamma_quantile(k: f64, p: f64) -> f64 {
    let z = std::f64::consts::SQRT_2 * erf_inv(2.0 * p - 1.0);
    let c = 1.0 / (9.0 * k);
    let wilson_hilferty = k * (1.0 - c + z * c.sqrt()).powi(3);
    let mut y = if wilson_hilferty > 0.0 && wilson_hilferty.is_finite() {
        wilson_hilferty
    } else {
        // Small shapes' lower tail: P(k, y) ≈ y^k / Γ(k + 1).
        ((p.ln() + ln_gamma(k + 1.0)) / k)
            .exp()
            .max(f64::MIN_POSITIVE)
    };
    let (mut lo, mut hi) = (0.0, f64::INFINITY);
    for _ in 0..200 {
        let f = gamma_lr(k, y) - p;
        if f == 0.0 {
            break;
        }
        if f < 0.0 {
            lo = y;
        } else {
            hi = y;
        }
        let density = ((k - 1.0) * y.ln() - y - ln_gamma(k)).exp();
        let newton = y - f / density;
        let next = if newton > lo && newton < hi {
            newton
        } else if hi.is_finite() {
            0.5 * (lo + hi)
        } else {
            2.0 * y
        };
        let done = (next - y).abs() <= 4.0 * f64::EPSILON * y;
        y = next;
        if done {
            break;
        }
    }
    y
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

#[cfg(test)]
mod tests {
    use super::*;

    /// `P(k, y)` for a whole `k` from the Poisson sum
    /// `1 − Σ_{i<k} e^{−y} y^i / i!`, an independent computation (its
    /// terms summed in logarithms, as `e^{−y}` underflows).
    fn poisson_cdf(k: u32, y: f64) -> f64 {
        let mut ln_terms = Vec::new();
        let mut ln_fact = 0.0;
        for i in 0..k {
            if i > 0 {
                ln_fact += f64::from(i).ln();
            }
            ln_terms.push(-y + f64::from(i) * y.ln() - ln_fact);
        }
        let top = ln_terms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let sum: f64 = ln_terms.iter().map(|t| (t - top).exp()).sum();
        1.0 - (top + sum.ln()).exp()
    }

    #[test]
    fn quantiles_invert_the_poisson_sum() {
        // The audit's cases (0 or 1 detection over exposures 77 and 513,
        // ~150 over 37) and more, with the flat prior's shape 1 + N.
        for (k, rate) in [
            (1u32, 76.65),
            (1, 1.0),
            (2, 513.0),
            (3, 2.0),
            (11, 0.5),
            (140, 37.0),
            (160, 37.0),
            (700, 3.0),
        ] {
            let post = Posterior {
                shape: f64::from(k),
                rate,
            };
            for p in [0.025, 0.5, 0.975] {
                let q = post.quantile(p);
                let cdf = poisson_cdf(k, q * rate);
                assert!(
                    (cdf - p).abs() < 1e-11,
                    "shape {k}, rate {rate}: the {p} quantile {q} has CDF {cdf}"
                );
            }
        }
    }

    #[test]
    fn no_detection_has_the_closed_form_lower_end() {
        for exposure in [0.01, 3.09, 76.65, 1e4] {
            let [lo, hi] = Posterior {
                shape: 1.0,
                rate: exposure,
            }
            .interval()
            .unwrap();
            let (want_lo, want_hi) = (-(0.975f64).ln() / exposure, -(0.025f64).ln() / exposure);
            assert!(
                (lo / want_lo - 1.0).abs() < 1e-12,
                "{exposure}: {lo} vs {want_lo}"
            );
            assert!(
                (hi / want_hi - 1.0).abs() < 1e-12,
                "{exposure}: {hi} vs {want_hi}"
            );
        }
    }

    #[test]
    fn large_shapes_match_the_normal_limit() {
        // Past 1e6 the Gamma is normal to a few parts in 1e4 of its width.
        let k: f64 = 4e6;
        let post = Posterior {
            shape: k,
            rate: 2.0,
        };
        let q = post.quantile(0.975);
        let normal = (k + 1.959_963_984_540_054 * k.sqrt()) / 2.0;
        assert!(
            ((q - normal) / (k.sqrt() / 2.0)).abs() < 2e-3,
            "{q} vs {normal}"
        );
    }
}
