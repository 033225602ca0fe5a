//! Certified plan quality: the gap each coordination leaves against the
//! bound on the best joint plan, and its plan time, over the same requests.
//!
//! Every request is planned with each coordination asked for, one after the
//! other, on one thread; a plan's gap is its certificate's
//! `(upper − value) / upper` (see `docs/certified-plans.md`). The figures per
//! coordination are the median and the 95th percentile of the gaps, and of
//! the plan times.

use std::time::Instant;

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use vigil::coordination::Coordination;
use vigil::planner::{PlanRequest, Planner};

/// The figures of one coordination.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CoordinationGaps {
    /// The coordination.
    pub coordination: Coordination,
    /// Plans made.
    pub plans: usize,
    /// Median certified gap (a fraction).
    pub median_gap: f64,
    /// 95th percentile of the gap.
    pub p95_gap: f64,
    /// Largest gap.
    pub max_gap: f64,
    /// Mean expected detections of the plans.
    pub mean_value: f64,
    /// Median plan time, ms.
    pub median_ms: f64,
    /// 95th percentile of the plan time, ms.
    pub p95_ms: f64,
}

/// Plans every request with each of `coordinations` (after one untimed
/// pass) and gathers their gaps and times.
///
/// # Errors
/// If there is no request, the planner refuses one, or a plan has no
/// certificate (a request asking for the paper estimator).
pub fn measure(
    planner: &Planner,
    reqs: &[PlanRequest],
    coordinations: &[Coordination],
) -> Result<Vec<CoordinationGaps>> {
    if reqs.is_empty() {
        bail!("no request to plan");
    }
    coordinations
        .iter()
        .map(|&mode| {
            let reqs: Vec<PlanRequest> = reqs
                .iter()
                .map(|r| PlanRequest {
                    coordination: Some(mode),
                    ..r.clone()
                })
                .collect();
            for (i, r) in reqs.iter().enumerate() {
                planner
                    .plan_request(r)
                    .with_context(|| format!("request {i} is invalid"))?;
            }
            let mut gaps = Vec::with_capacity(reqs.len());
            let mut times = Vec::with_capacity(reqs.len());
            let mut value = 0.0;
            for (i, r) in reqs.iter().enumerate() {
                let t = Instant::now();
                let plan = planner.plan_request(r)?;
                times.push(t.elapsed().as_secs_f64() * 1e3);
                let bound = plan.bound.with_context(|| {
                    format!("request {i}'s plan has no bound (paper estimator?)")
                })?;
                gaps.push(bound.gap);
                value += plan.expected_detections;
            }
            Ok(CoordinationGaps {
                coordination: mode,
                plans: reqs.len(),
                median_gap: quantile(&mut gaps, 0.5),
                p95_gap: quantile(&mut gaps, 0.95),
                max_gap: quantile(&mut gaps, 1.0),
                mean_value: value / reqs.len() as f64,
                median_ms: quantile(&mut times, 0.5),
                p95_ms: quantile(&mut times, 0.95),
            })
        })
        .collect()
}

/// The `q` quantile of `xs` (nearest rank; not empty).
fn quantile(xs: &mut [f64], q: f64) -> f64 {
    xs.sort_by(f64::total_cmp);
    let k = ((q * xs.len() as f64).ceil() as usize).clamp(1, xs.len()) - 1;
    xs[k]
}

#[cfg(test)]
mod tests {
    use super::quantile;

    #[test]
    fn nearest_rank_quantiles() {
        let mut xs = [5.0, 1.0, 4.0, 2.0, 3.0];
        assert_eq!(quantile(&mut xs, 0.5), 3.0);
        assert_eq!(quantile(&mut xs, 0.95), 5.0);
        assert_eq!(quantile(&mut xs, 0.2), 1.0);
    }
}
