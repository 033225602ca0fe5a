//! Predicted costs of the work a request asks for, so the service can
//! decide before starting it: a scenario's precomputation (run as a job
//! past the synchronous budget) and a plan (refused past `--max-plan-ms`).
//!
//! PROVISIONAL: the coefficients below are placeholders until fitted.

use crate::planner::{PlanInput, Planner};
use crate::scenario::Scenario;

/// Predicted CPU time of [`Planner::new`] on `s`, milliseconds on one core.
pub fn precompute_ms(s: &Scenario) -> f64 {
    let pairs = (s.cell_count() * s.sources.len() * s.fovs.len()) as f64;
    0.5 + pairs * 2e-4
}

/// Predicted CPU time of planning `input` on `planner`, milliseconds on one
/// core.
pub fn plan_ms(planner: &Planner, input: &PlanInput) -> f64 {
    let _ = (planner, input);
    1.0
}
