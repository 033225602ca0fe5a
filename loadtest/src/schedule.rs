//! Intended send times of an open-loop run.
//!
//! The schedule is fixed before the run starts and does not depend on how
//! fast the server answers: that is what makes the generator open loop. Each
//! time is measured in seconds from the start of the run (warm-up included).

use anyhow::{Result, bail};
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, Exp};
use serde::{Deserialize, Serialize};

/// How requests arrive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Arrivals {
    /// Evenly spaced: request `i` at `i / rate`.
    Constant,
    /// A Poisson process: independent exponential gaps of mean `1 / rate`,
    /// as from many independent clients.
    #[default]
    Poisson,
}

impl std::fmt::Display for Arrivals {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Arrivals::Constant => "constant",
            Arrivals::Poisson => "poisson",
        })
    }
}

/// The intended send times in `[0, end)`, in seconds, in increasing order.
#[derive(Debug)]
pub struct Schedule {
    arrivals: Arrivals,
    rate: f64,
    end: f64,
    index: u64,
    t: f64,
    rng: StdRng,
    gap: Exp<f64>,
}

impl Schedule {
    /// The schedule of `arrivals` at `rate` per second over `[0, end)`
    /// seconds; `seed` seeds the gaps of Poisson arrivals.
    ///
    /// Constant arrivals start at 0; Poisson arrivals at the first gap.
    ///
    /// # Errors
    /// If `rate` is not a positive finite number, or `end` is negative or not
    /// finite.
    pub fn new(arrivals: Arrivals, rate: f64, end: f64, seed: u64) -> Result<Self> {
        if !(rate.is_finite() && rate > 0.0) {
            bail!("the rate must be a positive number of requests per second, not {rate}");
        }
        if !(end.is_finite() && end >= 0.0) {
            bail!("the schedule's length must be a non-negative number of seconds, not {end}");
        }
        let gap = Exp::new(rate).map_err(|e| anyhow::anyhow!("rate {rate}: {e}"))?;
        Ok(Schedule {
            arrivals,
            rate,
            end,
            index: 0,
            t: 0.0,
            rng: StdRng::seed_from_u64(seed),
            gap,
        })
    }
}

impl Iterator for Schedule {
    type Item = f64;

    fn next(&mut self) -> Option<f64> {
        let t = match self.arrivals {
            // i / rate, not a running sum: no accumulated rounding error.
            Arrivals::Constant => self.index as f64 / self.rate,
            Arrivals::Poisson => self.t + self.gap.sample(&mut self.rng),
        };
        if t >= self.end {
            return None;
        }
        self.index += 1;
        self.t = t;
        Some(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_spacing_is_exact() {
        let times: Vec<f64> = Schedule::new(Arrivals::Constant, 250.0, 2.0, 7)
            .unwrap()
            .collect();
        assert_eq!(times.len(), 500);
        for (i, t) in times.iter().enumerate() {
            assert_eq!(*t, i as f64 / 250.0);
        }
        // The seed plays no part.
        let again: Vec<f64> = Schedule::new(Arrivals::Constant, 250.0, 2.0, 8)
            .unwrap()
            .collect();
        assert_eq!(times, again);
    }

    #[test]
    fn poisson_gaps_are_exponential_with_mean_one_over_rate() {
        let rate = 1000.0;
        let times: Vec<f64> = Schedule::new(Arrivals::Poisson, rate, 100.0, 42)
            .unwrap()
            .collect();
        let n = times.len() as f64;
        // The count of a Poisson process over 100 s: mean 1e5, sd ~316.
        assert!((n - 1e5).abs() < 5.0 * 1e5_f64.sqrt(), "count {n}");
        let gaps: Vec<f64> = std::iter::once(times[0])
            .chain(times.windows(2).map(|w| w[1] - w[0]))
            .collect();
        assert!(gaps.iter().all(|g| *g >= 0.0));
        let mean = gaps.iter().sum::<f64>() / n;
        // Exponential: sd = mean = 1/rate, so the standard error is 1/(rate √n).
        let se = 1.0 / rate / n.sqrt();
        assert!(
            (mean - 1.0 / rate).abs() < 5.0 * se,
            "mean gap {mean}, want {} ± {}",
            1.0 / rate,
            5.0 * se
        );
        // Coefficient of variation 1 (a constant schedule would give 0).
        let var = gaps.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let cv = var.sqrt() / mean;
        assert!((cv - 1.0).abs() < 0.02, "cv {cv}");
    }

    #[test]
    fn poisson_schedule_is_reproducible_from_its_seed() {
        let a: Vec<f64> = Schedule::new(Arrivals::Poisson, 100.0, 5.0, 3)
            .unwrap()
            .collect();
        let b: Vec<f64> = Schedule::new(Arrivals::Poisson, 100.0, 5.0, 3)
            .unwrap()
            .collect();
        let c: Vec<f64> = Schedule::new(Arrivals::Poisson, 100.0, 5.0, 4)
            .unwrap()
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
        assert!(a.windows(2).all(|w| w[0] <= w[1]));
    }

    #[test]
    fn bad_rates_are_refused() {
        for rate in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(Schedule::new(Arrivals::Poisson, rate, 1.0, 0).is_err());
        }
        assert!(Schedule::new(Arrivals::Constant, 1.0, -1.0, 0).is_err());
    }
}
