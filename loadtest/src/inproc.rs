//! The in-process cost of the same requests: a single-threaded loop calling
//! [`Planner::plan_request`], no HTTP. Its median is the denominator of the
//! HTTP efficiency (see the crate's README).

use std::hint::black_box;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use vigil::planner::{PlanRequest, Planner};

/// In-process plan times, as `inproc --out` writes them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct InprocReport {
    /// Distinct requests, cycled in order.
    pub requests: usize,
    /// Timed plans (after one untimed pass over every request).
    pub iterations: usize,
    /// Median plan time, ms.
    pub median_ms: f64,
    /// 90th percentile, ms.
    pub p90_ms: f64,
    /// 99th percentile, ms.
    pub p99_ms: f64,
    /// Mean, ms.
    pub mean_ms: f64,
    /// Fastest, ms.
    pub min_ms: f64,
    /// Slowest, ms.
    pub max_ms: f64,
    /// `1 / median`: plans per second of one core with no HTTP.
    pub plans_per_s_per_core: f64,
}

/// Times `iterations` plans of `reqs` (cycled in order) on one thread,
/// after one untimed pass over all of them, back to back.
///
/// # Errors
/// If there is no request, `iterations` is 0, or the planner refuses a
/// request (the error names it).
pub fn measure(planner: &Planner, reqs: &[PlanRequest], iterations: usize) -> Result<InprocReport> {
    measure_paced(planner, reqs, iterations, Duration::ZERO)
}

/// [`measure`] with the thread asleep for `pause` before each timed plan,
/// as a server's planner is between requests at a low rate: the plans then
/// start with the caches (and the core's clock) of an idle thread.
///
/// # Errors
/// As [`measure`].
pub fn measure_paced(
    planner: &Planner,
    reqs: &[PlanRequest],
    iterations: usize,
    pause: Duration,
) -> Result<InprocReport> {
    if reqs.is_empty() {
        bail!("no request to time");
    }
    if iterations == 0 {
        bail!("--iterations must be at least 1");
    }
    for (i, r) in reqs.iter().enumerate() {
        black_box(
            planner
                .plan_request(r)
                .with_context(|| format!("request {i} is invalid for {}", planner.scenario.id))?,
        );
    }
    let mut nanos: Vec<u64> = Vec::with_capacity(iterations);
    for i in 0..iterations {
        let r = &reqs[i % reqs.len()];
        if !pause.is_zero() {
            std::thread::sleep(pause);
        }
        let t = Instant::now();
        let res = planner.plan_request(black_box(r));
        let dt = t.elapsed();
        black_box(res.with_context(|| format!("request {} failed", i % reqs.len()))?);
        nanos.push(u64::try_from(dt.as_nanos()).unwrap_or(u64::MAX));
    }
    Ok(from_nanos(nanos, reqs.len()))
}

/// The figures of `nanos` (at least one time, ns) over `requests`
/// distinct requests.
pub(crate) fn from_nanos(mut nanos: Vec<u64>, requests: usize) -> InprocReport {
    nanos.sort_unstable();
    let n = nanos.len().max(1);
    if nanos.is_empty() {
        nanos.push(0);
    }
    let at = |q: f64| {
        let k = ((q * n as f64).ceil() as usize).clamp(1, n) - 1;
        nanos[k] as f64 / 1e6
    };
    let median_ms = if n % 2 == 1 {
        nanos[n / 2] as f64 / 1e6
    } else {
        (nanos[n / 2 - 1] as f64 + nanos[n / 2] as f64) / 2e6
    };
    let mean_ms = nanos.iter().map(|&x| x as f64).sum::<f64>() / n as f64 / 1e6;
    InprocReport {
        requests,
        iterations: n,
        median_ms,
        p90_ms: at(0.9),
        p99_ms: at(0.99),
        mean_ms,
        min_ms: nanos[0] as f64 / 1e6,
        max_ms: nanos[n - 1] as f64 / 1e6,
        plans_per_s_per_core: if median_ms > 0.0 {
            1e3 / median_ms
        } else {
            f64::INFINITY
        },
    }
}

/// HTTP efficiency: plan throughput per server core divided by what one
/// core does in process (`1 / median`). 1.0 would mean HTTP costs nothing.
pub fn http_efficiency(achieved_rate: f64, server_cores: f64, inproc_median_ms: f64) -> f64 {
    (achieved_rate / server_cores) * (inproc_median_ms / 1e3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn efficiency_is_throughput_per_core_times_the_median() {
        // 1 ms in process = 1000 plans/s/core; 800/s on one core is 80%.
        assert!((http_efficiency(800.0, 1.0, 1.0) - 0.8).abs() < 1e-12);
        assert!((http_efficiency(800.0, 2.0, 1.0) - 0.4).abs() < 1e-12);
    }

    #[test]
    fn measures_a_few_plans() {
        let p = crate::requests::planner_for("paper-v10").unwrap();
        let reqs: Vec<PlanRequest> = crate::requests::parse(
            r#"[{"sensors":[{"id":"a","x":15,"y":15}]},{"sensors":[{"id":1,"x":25,"y":5}],"horizon":2}]"#,
        )
        .unwrap();
        let r = measure(&p, &reqs, 20).unwrap();
        assert_eq!(r.iterations, 20);
        assert!(r.min_ms <= r.median_ms && r.median_ms <= r.p90_ms);
        assert!(r.p90_ms <= r.p99_ms && r.p99_ms <= r.max_ms);
        let bad = crate::requests::parse(r#"[{"sensors":[{"id":"a","x":999,"y":15}]}]"#).unwrap();
        assert!(measure(&p, &bad, 1).is_err());
    }

    #[test]
    fn paced_plans_sleep_between_and_time_only_the_plan() {
        let p = crate::requests::planner_for("paper-v10").unwrap();
        let reqs: Vec<PlanRequest> =
            crate::requests::parse(r#"[{"sensors":[{"id":"a","x":15,"y":15}]}]"#).unwrap();
        let pause = Duration::from_millis(40);
        let t = Instant::now();
        let r = measure_paced(&p, &reqs, 3, pause).unwrap();
        assert!(t.elapsed() >= 3 * pause);
        assert_eq!(r.iterations, 3);
        // A one-sensor plan takes well under a millisecond: the pause is
        // not in its time.
        assert!(r.min_ms < 40.0, "{}", r.min_ms);
    }
}
