//! Session mode: the steps of a session, timed in process.
//!
//! A session replays a [`SessionWorkload`]: a fresh session
//! ([`Session::new`]) takes the run's warm-up steps untimed, so that its
//! history and tracks are full, then the timed steps. Timed step `k` leads
//! to the state of the stateless request `k` of the same run (the
//! reference workload's requests), so the session's figures compare with
//! the stateless ones like for like.
//!
//! A step's server-side work is [`session_step`]: the one function to
//! change if the session API gains a faster single call.

use std::hint::black_box;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use vigil::cancel::CancelToken;
use vigil::estimator::Carry;
use vigil::planner::{PlanInput, PlanRequest, PlanResponse, Planner};
use vigil::session::{Session, StepRequest};

use crate::inproc::{InprocReport, from_nanos};
use crate::workload::SessionWorkload;

/// One step of `session`, as the server does it for
/// `POST /v1/sessions/{id}/step`: a learning session's fold of the step
/// ([`vigil::fit::RateLearner::fold`]), the stateless request of the
/// session's state with this step ([`Session::prepare`]), its plan (at the
/// learnt rates, from and into the session's `carry`), and the step
/// recorded ([`Session::commit`]). A step whose plan fails changes nothing
/// but the carry.
///
/// # Errors
/// If the learner or the planner refuses the step.
pub fn session_step(
    session: &mut Session,
    carry: &mut Carry,
    step: &StepRequest,
) -> Result<PlanResponse> {
    let learnt = session
        .learner()
        .map(|l| l.fold(&step.sensors, &step.detections))
        .transpose()
        .context("the learning session refused the step")?;
    let prepared = session.prepare(step);
    let planner = session.planner_for(learnt.as_ref());
    let input = PlanInput::new(&planner.scenario, &prepared.request)
        .context("the session's step was refused")?;
    let plan = planner
        .plan_carried(&input, &CancelToken::never(), carry)
        .context("a plan that is never cancelled was cancelled")?;
    session.commit(prepared);
    if let Some(learnt) = learnt {
        session.commit_learnt(learnt);
    }
    Ok(plan)
}

/// A fresh session of `workload` on `planner`, its warm-up steps replayed,
/// and the carry they left.
///
/// # Errors
/// If a warm-up step is refused (the error names it).
pub fn warmed(planner: &Arc<Planner>, workload: &SessionWorkload) -> Result<(Session, Carry)> {
    let mut session = Session::new(Arc::clone(planner), workload.settings.clone());
    let mut carry = Carry::new();
    for (i, step) in workload.warmup.iter().enumerate() {
        session_step(&mut session, &mut carry, step)
            .with_context(|| format!("warm-up step {i}"))?;
    }
    Ok((session, carry))
}

/// In-process session step times, as `inproc --session --out` writes them:
/// the fields of `inproc --out` for the session steps (`requests` is the
/// distinct timed steps of one session, `iterations` the steps timed,
/// `plans_per_s_per_core` the same as `steps_per_s_per_core`), and the
/// stateless plans of the same states, timed alternately with them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SessionInprocReport {
    /// The session steps' times.
    #[serde(flatten)]
    pub steps: InprocReport,
    /// `1 / median`: session steps per second of one core with no HTTP.
    pub steps_per_s_per_core: f64,
    /// Untimed warm-up steps replayed into each fresh session.
    pub warmup_steps: usize,
    /// Fresh sessions replayed (one per pass over the timed steps).
    pub sessions: usize,
    /// `Planner::plan_request` of the stateless request of the same state,
    /// timed right after each session step.
    pub stateless: Option<InprocReport>,
}

/// Times `iterations` session steps on one thread: fresh sessions of
/// `workload`, each warmed untimed and then stepped through the timed steps
/// in order, as many sessions as needed. With `stateless` (the requests of
/// the same run, `stateless[k]` the state of step `k`), each timed step's
/// stateless plan is timed beside it: after it for even steps, before it
/// for odd ones, so that neither side always runs on the other's warm
/// cache.
///
/// # Errors
/// If there is no timed step, `iterations` is 0, `stateless` does not match
/// the steps, or the planner refuses a step.
pub fn measure(
    planner: &Arc<Planner>,
    workload: &SessionWorkload,
    stateless: Option<&[PlanRequest]>,
    iterations: usize,
) -> Result<SessionInprocReport> {
    let n = workload.steps.len();
    if n == 0 {
        bail!("no session step to time");
    }
    if iterations == 0 {
        bail!("--iterations must be at least 1");
    }
    if let Some(reqs) = stateless
        && reqs.len() != n
    {
        bail!(
            "{} stateless requests for {n} session steps: they must come from the same run",
            reqs.len()
        );
    }
    let nanos = |t: Instant| u64::try_from(t.elapsed().as_nanos()).unwrap_or(u64::MAX);
    let mut steps: Vec<u64> = Vec::with_capacity(iterations);
    let mut plans: Vec<u64> = Vec::with_capacity(if stateless.is_some() { iterations } else { 0 });
    let mut sessions = 0;
    while steps.len() < iterations {
        let (mut session, mut carry) = warmed(planner, workload)?;
        sessions += 1;
        for (k, step) in workload.steps.iter().enumerate() {
            if steps.len() == iterations {
                break;
            }
            // The second of two plans of one state finds the first's data
            // in cache: every other state, the stateless plan goes first.
            let plan_first = steps.len() % 2 == 1;
            let plan = |plans: &mut Vec<u64>| -> Result<()> {
                if let Some(reqs) = stateless {
                    let t = Instant::now();
                    let res = planner.plan_request(black_box(&reqs[k]));
                    plans.push(nanos(t));
                    black_box(res.with_context(|| format!("stateless request {k}"))?);
                }
                Ok(())
            };
            if plan_first {
                plan(&mut plans)?;
            }
            let t = Instant::now();
            let res = session_step(&mut session, &mut carry, black_box(step));
            steps.push(nanos(t));
            black_box(res.with_context(|| format!("step {k}"))?);
            if !plan_first {
                plan(&mut plans)?;
            }
        }
    }
    let steps = from_nanos(steps, n);
    Ok(SessionInprocReport {
        steps_per_s_per_core: steps.plans_per_s_per_core,
        steps,
        warmup_steps: workload.warmup.len(),
        sessions,
        stateless: stateless.map(|_| from_nanos(plans, n)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::workload::Workload;

    fn small() -> Workload {
        Workload {
            sensors: 4,
            history: 4,
            horizon: 3,
            seed: 5,
        }
    }

    #[test]
    fn measures_steps_over_fresh_sessions() {
        let planner = Arc::new(crate::requests::planner_for("paper-v10").expect("built-in"));
        let (reqs, wl) = small().requests_and_session(&planner, 5);
        assert_eq!(wl.steps.len(), 5);
        assert!(!wl.warmup.is_empty());
        let r = measure(&planner, &wl, Some(&reqs), 12).expect("measured");
        assert_eq!(r.steps.iterations, 12);
        assert_eq!(r.steps.requests, 5);
        // 5 steps per fresh session: 3 sessions for 12 steps.
        assert_eq!(r.sessions, 3);
        assert_eq!(r.warmup_steps, wl.warmup.len());
        assert_eq!(r.steps_per_s_per_core, r.steps.plans_per_s_per_core);
        let s = r.stateless.expect("timed");
        assert_eq!(s.iterations, 12);
        assert!(r.steps.min_ms <= r.steps.median_ms && r.steps.median_ms <= r.steps.p99_ms);
        assert!(measure(&planner, &wl, Some(&reqs[1..]), 1).is_err());
        assert!(measure(&planner, &wl, None, 0).is_err());
        // Its JSON reads as an `inproc --out` report too.
        let json = serde_json::to_string(&r).expect("serialised");
        let plain: InprocReport = serde_json::from_str(&json).expect("an inproc report");
        // Compared with the steps' own report read back the same way:
        // serde_json's default float parsing may miss the last bit.
        let steps = serde_json::to_string(&r.steps).expect("serialised");
        let steps: InprocReport = serde_json::from_str(&steps).expect("read back");
        assert_eq!(plain, steps);
        let back: SessionInprocReport = serde_json::from_str(&json).expect("round trip");
        assert_eq!((back.sessions, back.warmup_steps), (3, r.warmup_steps));
        assert_eq!(back.stateless.map(|s| s.iterations), Some(12));
    }
}
