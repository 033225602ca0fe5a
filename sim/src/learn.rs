//! What a policy that learns the sources' rates (`exact-learn`) learnt: the
//! rates a learning session reports at each step, judged against the
//! world's true rates.

use serde::Serialize;
use vigil::fit::SourceRate;

use crate::metrics::mean_ci;

/// How close a learnt rate must come to the world's: within this share of
/// the source's true rate (of the sources' mean true rate for a silent
/// source).
pub const TOLERANCE: f64 = 0.2;

/// Each source's allowed error: [`TOLERANCE`] × its true rate, or ×
/// the mean true rate over the sources when its own is 0 (a silent source,
/// whose learnt rate can only approach 0).
pub fn allowed_errors(truth: &[f64]) -> Vec<f64> {
    let mean = truth.iter().sum::<f64>() / truth.len().max(1) as f64;
    truth
        .iter()
        .map(|&r| TOLERANCE * if r > 0.0 { r } else { mean })
        .collect()
}

/// Follows one learning run's rates step by step.
#[derive(Debug, Clone)]
pub struct Tracker {
    truth: Vec<f64>,
    allowed: Vec<f64>,
    steps: usize,
    within_since: Option<usize>,
    last: Vec<SourceRate>,
}

impl Tracker {
    /// A run in a world whose sources emit at `truth` (targets per step,
    /// one per source in the scenario's order).
    pub fn new(truth: Vec<f64>) -> Self {
        Tracker {
            allowed: allowed_errors(&truth),
            truth,
            steps: 0,
            within_since: None,
            last: Vec::new(),
        }
    }

    /// Adds a step's `rates`, checked against the server's contract: one
    /// per source, in order (`index` j at position j), each a finite rate
    /// ≥ 0.
    pub fn add(&mut self, rates: &[SourceRate]) -> Result<(), String> {
        if rates.len() != self.truth.len() {
            return Err(format!(
                "{} learnt rates for {} sources",
                rates.len(),
                self.truth.len()
            ));
        }
        for (j, r) in rates.iter().enumerate() {
            if r.index != j {
                return Err(format!("learnt rate {j} has index {}", r.index));
            }
            if !r.rate.is_finite() || r.rate < 0.0 {
                return Err(format!("learnt rate {j} is {}", r.rate));
            }
        }
        self.steps += 1;
        let within = rates
            .iter()
            .zip(self.truth.iter().zip(&self.allowed))
            .all(|(r, (&t, &a))| (r.rate - t).abs() <= a);
        if within {
            self.within_since.get_or_insert(self.steps);
        } else {
            self.within_since = None;
        }
        self.last = rates.to_vec();
        Ok(())
    }

    /// The run's record: its last rates and the step from which on they
    /// stayed within [`TOLERANCE`].
    pub fn finish(self, seed: u64) -> Learnt {
        Learnt {
            seed,
            steps_to_20pct: self.within_since,
            steps: self.steps,
            rates: self.last,
        }
    }
}

/// What one learning run learnt.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Learnt {
    /// The run's seed.
    pub seed: u64,
    /// The first step from which on, to the end of the run, every source's
    /// learnt rate was within 20% of the world's ([`allowed_errors`]);
    /// steps are counted from the run's first step, warm-up included (1:
    /// the first warm-up step's rates). `None` (JSON `null`) if they were
    /// not within at the last step.
    pub steps_to_20pct: Option<usize>,
    /// The steps whose rates were followed: warm-up and measured.
    pub steps: usize,
    /// The last step's rates, as the server gave them.
    pub rates: Vec<SourceRate>,
}

/// A configuration's learning over its seeds, in the JSON report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Learning {
    /// Each source's rate in the world (the scenario's times
    /// `--world-rates`): what the learnt rates are judged against.
    pub true_rates: Vec<f64>,
    /// Each source's rate the session started from (its prior's mean: the
    /// rates the planner was told).
    pub prior_rates: Vec<f64>,
    /// Each source's last learnt rate: the mean over seeds.
    pub rates: Vec<f64>,
    /// Their 95% confidence half-widths over seeds.
    pub rates_ci95: Vec<f64>,
    /// Steps per run: warm-up and measured.
    pub steps: usize,
    /// Warm-up steps, counted in `steps_to_20pct`.
    pub warmup: usize,
    /// Mean of `steps_to_20pct` over the seeds that reached it; `None`
    /// when none did.
    pub steps_to_20pct: Option<f64>,
    /// Its 95% confidence half-width.
    pub steps_to_20pct_ci95: Option<f64>,
    /// Seeds whose rates were within 20% from some step to the end.
    pub reached_20pct: usize,
    /// Seeds run.
    pub seeds: usize,
    /// Each seed's run.
    pub runs: Vec<Learnt>,
}

/// The summary over seeds of `runs`, in a world at `true_rates`, with the
/// session's prior at `prior_rates`.
pub fn summarize(
    runs: Vec<Learnt>,
    true_rates: Vec<f64>,
    prior_rates: Vec<f64>,
    warmup: usize,
) -> Learning {
    let sources = true_rates.len();
    let (rates, rates_ci95) = (0..sources)
        .map(|j| {
            mean_ci(
                &runs
                    .iter()
                    .filter_map(|r| r.rates.get(j).map(|r| r.rate))
                    .collect::<Vec<_>>(),
            )
        })
        .unzip();
    let reached: Vec<f64> = runs
        .iter()
        .filter_map(|r| r.steps_to_20pct.map(|s| s as f64))
        .collect();
    let (steps_to_20pct, steps_to_20pct_ci95) = if reached.is_empty() {
        (None, None)
    } else {
        let (m, c) = mean_ci(&reached);
        (Some(m), Some(c))
    };
    Learning {
        true_rates,
        prior_rates,
        rates,
        rates_ci95,
        steps: runs.iter().map(|r| r.steps).max().unwrap_or(0),
        warmup,
        steps_to_20pct,
        steps_to_20pct_ci95,
        reached_20pct: reached.len(),
        seeds: runs.len(),
        runs,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rates(xs: &[f64]) -> Vec<SourceRate> {
        xs.iter()
            .enumerate()
            .map(|(index, &rate)| SourceRate {
                index,
                rate,
                interval: None,
                detected: 0.0,
                exposure: 0.0,
            })
            .collect()
    }

    #[test]
    fn a_silent_source_is_judged_against_the_mean_rate() {
        // Mean 1.0: the silent source may be up to 0.2.
        assert_eq!(
            allowed_errors(&[3.0, 0.0, 1.0, 0.0]),
            vec![0.6000000000000001, 0.2, 0.2, 0.2]
        );
    }

    /// The step counted is the first of the last unbroken stretch within
    /// the tolerance; a run that leaves it at the end never reached it.
    #[test]
    fn steps_to_20pct_is_the_start_of_the_last_stretch_within() {
        let truth = vec![1.0, 0.0];
        let mut t = Tracker::new(truth.clone());
        for xs in [
            [0.3, 0.3],  // 1: out
            [0.9, 0.1],  // 2: in
            [0.7, 0.1],  // 3: out (0.3 off 1.0)
            [0.85, 0.2], // 4: out (the silent one: 0.2 > 0.2 × mean 0.5)
            [1.1, 0.05], // 5: in
            [0.95, 0.0], // 6: in
        ] {
            t.add(&rates(&xs)).expect("valid");
        }
        let done = t.clone().finish(7);
        assert_eq!((done.steps_to_20pct, done.steps), (Some(5), 6));
        assert_eq!(done.rates, rates(&[0.95, 0.0]));
        t.add(&rates(&[1.3, 0.0])).expect("valid");
        assert_eq!(t.finish(7).steps_to_20pct, None);
        let mut t = Tracker::new(truth);
        assert!(t.add(&rates(&[1.0])).is_err());
        let mut swapped = rates(&[1.0, 0.0]);
        swapped.swap(0, 1);
        assert!(t.add(&swapped).is_err());
        assert!(t.add(&rates(&[f64::NAN, 0.0])).is_err());
    }

    #[test]
    fn summary_averages_the_seeds_that_reached() {
        let run = |seed, s, last: &[f64]| Learnt {
            seed,
            steps_to_20pct: s,
            steps: 50,
            rates: rates(last),
        };
        let l = summarize(
            vec![
                run(1, Some(10), &[1.0, 2.0]),
                run(2, None, &[3.0, 2.0]),
                run(3, Some(20), &[2.0, 2.0]),
            ],
            vec![2.0, 2.0],
            vec![1.0, 1.0],
            5,
        );
        assert_eq!(l.steps_to_20pct, Some(15.0));
        assert_eq!(l.steps_to_20pct_ci95, Some(mean_ci(&[10.0, 20.0]).1));
        assert_eq!((l.reached_20pct, l.seeds, l.steps), (2, 3, 50));
        assert_eq!(l.rates, vec![2.0, 2.0]);
        assert_eq!(l.rates_ci95[1], 0.0);
    }
}
