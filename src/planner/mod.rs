//! The planner of one scenario and the planning API's types:
//! - [`wire`]: the request and response types ([`PlanRequest`],
//!   [`PlanResponse`]), which the HTTP layer and in-process callers share;
//! - [`input`]: a request validated against its scenario ([`PlanInput`]);
//! - [`planning`]: the [`Planner`]: a scenario's statistics, computed once,
//!   and the plan of a validated request.

pub mod input;
pub mod planning;
pub mod wire;

pub use input::PlanInput;
pub(crate) use input::{check_certify, check_estimator, check_objective, place, step_looks};
pub(crate) use planning::Chosen;
pub use planning::{PRECOMPUTED_FORMAT, Planner};
pub use wire::*;
