//! Climbing the rate to find the knee.
//!
//! Starting at `start`, each step runs the generator at the rate times
//! `factor` of the previous one, until a step fails its SLO or the rate
//! passes `max`. A step meets the SLO when
//! - its p99 latency is at most `slo_ms`,
//! - it had no error and nothing was shed, and
//! - its achieved rate is at least `min_achieved` of its target rate (the
//!   server, and the generator, kept up).
//!
//! Optionally, `refine` more steps bisect (geometrically) between the last
//! rate that met the SLO and the first that did not. The knee is the
//! highest rate that met the SLO.

use std::time::Duration;

use anyhow::{Result, bail};
use serde::{Deserialize, Serialize};

use crate::generator::{RunConfig, RunReport, Summary, run};

/// How to climb.
#[derive(Debug, Clone, Copy)]
pub struct SweepConfig {
    /// First rate, requests per second.
    pub start: f64,
    /// Rate multiplier between steps (> 1).
    pub factor: f64,
    /// Highest rate tried.
    pub max: f64,
    /// p99 latency bound, ms.
    pub slo_ms: f64,
    /// Least achieved / target rate of a step that meets the SLO.
    pub min_achieved: f64,
    /// Bisection steps after the first failure.
    pub refine: u32,
    /// Idle time between steps, so one step's backlog does not leak into
    /// the next.
    pub pause: Duration,
}

/// The outcome of a sweep, as `--out` writes it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepReport {
    /// The SLO on p99, ms.
    pub slo_ms: f64,
    /// Least achieved / target rate of a passing step.
    pub min_achieved: f64,
    /// Highest target rate that met the SLO (null if none did).
    pub knee_rate: Option<f64>,
    /// The figures of that step.
    pub knee: Option<Summary>,
    /// Why the climb stopped.
    pub stopped: String,
    /// Every step, in the order run.
    pub steps: Vec<Summary>,
}

/// Whether `s` meets a p99 bound of `slo_ms` with no error or shed request
/// and at least `min_achieved` of its target rate achieved.
pub fn meets_slo(s: &Summary, slo_ms: f64, min_achieved: f64) -> bool {
    s.errors == 0
        && s.shed == 0
        && s.requests > 0
        && s.p99_ms <= slo_ms
        && s.achieved_rate >= min_achieved * s.target_rate
}

/// Climbs the rate from `base` (whose rate is ignored), calling `on_step`
/// after every step.
///
/// # Errors
/// If the sweep configuration is invalid, or a step cannot run at all.
pub async fn sweep(
    base: &RunConfig,
    cfg: &SweepConfig,
    mut on_step: impl FnMut(&RunReport),
) -> Result<SweepReport> {
    if !(cfg.start.is_finite() && cfg.start > 0.0) {
        bail!("--sweep-start must be positive, not {}", cfg.start);
    }
    if !(cfg.factor.is_finite() && cfg.factor > 1.0) {
        bail!("--sweep-factor must be above 1, not {}", cfg.factor);
    }
    if !(cfg.max.is_finite() && cfg.max >= cfg.start) {
        bail!("--sweep-max must be at least --sweep-start");
    }
    if !(cfg.slo_ms.is_finite() && cfg.slo_ms > 0.0) {
        bail!("--slo-ms must be positive, not {}", cfg.slo_ms);
    }
    let mut steps: Vec<Summary> = Vec::new();
    let mut pass: Option<Summary> = None;
    let mut fail: Option<f64> = None;
    let mut rate = cfg.start;
    let step = |rate: f64, steps: &[Summary]| {
        let mut c = base.clone();
        c.rate = rate;
        // A different schedule at every step.
        c.seed = base.seed.wrapping_add(steps.len() as u64);
        c
    };
    let mut stopped = format!("reached --sweep-max {} without failing the SLO", cfg.max);
    while rate <= cfg.max * (1.0 + 1e-9) {
        if !steps.is_empty() {
            tokio::time::sleep(cfg.pause).await;
        }
        let report = run(&step(rate, &steps)).await?;
        on_step(&report);
        steps.push(report.summary);
        if meets_slo(&report.summary, cfg.slo_ms, cfg.min_achieved) {
            pass = Some(report.summary);
            rate *= cfg.factor;
        } else {
            fail = Some(rate);
            stopped = format!("{rate:.1}/s failed the SLO");
            break;
        }
    }
    if let (Some(mut hi), Some(p)) = (fail, pass) {
        let mut lo = p.target_rate;
        for _ in 0..cfg.refine {
            let mid = (lo * hi).sqrt();
            tokio::time::sleep(cfg.pause).await;
            let report = run(&step(mid, &steps)).await?;
            on_step(&report);
            steps.push(report.summary);
            if meets_slo(&report.summary, cfg.slo_ms, cfg.min_achieved) {
                lo = mid;
                pass = Some(report.summary);
            } else {
                hi = mid;
            }
        }
    }
    Ok(SweepReport {
        slo_ms: cfg.slo_ms,
        min_achieved: cfg.min_achieved,
        knee_rate: pass.map(|p| p.target_rate),
        knee: pass,
        stopped,
        steps,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(p99_ms: f64, errors: u64, shed: u64, achieved: f64) -> Summary {
        Summary {
            target_rate: 100.0,
            achieved_rate: achieved,
            duration_s: 1.0,
            requests: 100,
            errors,
            shed,
            p50_ms: p99_ms / 2.0,
            p90_ms: p99_ms,
            p99_ms,
            p999_ms: p99_ms,
            max_ms: p99_ms,
        }
    }

    #[test]
    fn the_slo_needs_latency_no_errors_no_shedding_and_the_rate() {
        assert!(meets_slo(&summary(1.9, 0, 0, 99.0), 2.0, 0.9));
        assert!(!meets_slo(&summary(2.1, 0, 0, 99.0), 2.0, 0.9));
        assert!(!meets_slo(&summary(1.0, 1, 0, 99.0), 2.0, 0.9));
        assert!(!meets_slo(&summary(1.0, 0, 1, 99.0), 2.0, 0.9));
        assert!(!meets_slo(&summary(1.0, 0, 0, 80.0), 2.0, 0.9));
    }
}
