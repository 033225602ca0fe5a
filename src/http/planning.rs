//! What the planning handlers share: finding the planner a body names
//! (registered, cached inline, or precomputed now), running a plan on the
//! planning queue within its time limit, and cancelling work nobody waits
//! for.

use std::sync::Arc;
use std::time::Duration;

use axum::Extension;

use super::config::INLINE_PLAN_MS;
use super::error::ApiError;
use super::middleware::RequestStart;
use super::state::AppState;
use crate::cancel::{CancelToken, Progress};
use crate::catalog::{CatalogError, precompute_cancellable};
use crate::coordination::Objective;
use crate::cost;
use crate::estimator::Carry;
use crate::metric_names;
use crate::planner::{PlanInput, PlanRequest, PlanResponse, Planner};
use crate::scenario::{Scenario, ScenarioSpec};

/// Cancels a request's work (through its token) if the request is dropped
/// before the work finished: the time limit answered 504, or the client
/// went away (the server drops a request whose connection closed). Counts
/// each in `vigil_cancelled_total{kind, reason}`.
pub(super) struct CancelOnDrop {
    kind: &'static str,
    token: CancelToken,
    start: Option<RequestStart>,
    timeout: Duration,
    finished: bool,
}

impl CancelOnDrop {
    /// A guard for work of `kind` (`plan`, `precompute`) in a request that
    /// started at `start`.
    pub(super) fn new(
        kind: &'static str,
        start: Option<Extension<RequestStart>>,
        state: &AppState,
    ) -> Self {
        Self {
            kind,
            token: CancelToken::new(),
            start: start.map(|Extension(s)| s),
            timeout: state.settings.request_timeout,
            finished: false,
        }
    }

    /// The token the work checks.
    pub(super) fn token(&self) -> CancelToken {
        self.token.clone()
    }

    /// The work ended: dropping the guard now cancels nothing.
    pub(super) fn finish(mut self) {
        self.finished = true;
    }
}

impl Drop for CancelOnDrop {
    fn drop(&mut self) {
        if self.finished {
            return;
        }
        self.token.cancel();
        let timed_out = self
            .start
            .is_some_and(|RequestStart(t)| t.elapsed() >= self.timeout);
        let reason = if timed_out { "timeout" } else { "client_gone" };
        metrics::counter!(metric_names::CANCELLED_TOTAL, "kind" => self.kind, "reason" => reason)
            .increment(1);
    }
}

/// Refuses work predicted to take more than the server's `--max-plan-ms`
/// of CPU, before any of it starts (422), and counts the refusal.
///
/// # Errors
/// [`ApiError::PlanTooCostly`] past the limit.
pub(super) fn refuse_if_costly(state: &AppState, predicted_ms: f64) -> Result<(), ApiError> {
    if let Some(limit_ms) = state.settings.max_plan_ms
        && predicted_ms > limit_ms
    {
        metrics::counter!(metric_names::PLANS_REFUSED_TOTAL, "reason" => "cost").increment(1);
        return Err(ApiError::PlanTooCostly {
            predicted_ms,
            limit_ms,
        });
    }
    Ok(())
}

/// A plan request validated, its predicted cost within the server's limit
/// ([`admit`]).
pub(super) struct Admitted {
    input: PlanInput,
    /// Its predicted CPU time, ms ([`cost::plan_ms`]).
    pub(super) predicted_ms: f64,
    /// Whether a short plan may run on the async worker.
    may_inline: bool,
}

impl Admitted {
    /// The same plan, made on the pool however short, so that this async
    /// worker stays free for I/O that runs beside it.
    pub(super) fn on_pool(self) -> Self {
        Self {
            may_inline: false,
            ..self
        }
    }
}

/// Validates `req` on `planner` and refuses it if its predicted cost is
/// above the limit, before any of its work starts.
///
/// # Errors
/// The request's [`crate::scenario::ValidationError`];
/// [`ApiError::PlanTooCostly`] (see [`refuse_if_costly`]).
pub(super) fn admit(
    state: &AppState,
    planner: &Planner,
    req: &PlanRequest,
) -> Result<Admitted, ApiError> {
    let input = PlanInput::new(&planner.scenario, req)?;
    let predicted_ms = cost::plan_ms(planner, &input);
    refuse_if_costly(state, predicted_ms)?;
    Ok(Admitted {
        input,
        predicted_ms,
        may_inline: true,
    })
}

/// Validates `req`, refuses it if its predicted cost is above the limit,
/// and plans it once admitted to the planning queue: on rayon, cancelled as
/// soon as nobody waits for it, or (a short plan of detections on a
/// server that plans inline) on this async worker.
pub(super) async fn plan_admitted(
    state: &AppState,
    start: Option<Extension<RequestStart>>,
    planner: Arc<Planner>,
    req: &PlanRequest,
) -> Result<PlanResponse, ApiError> {
    let admitted = admit(state, &planner, req)?;
    let (plan, _) = plan_with(state, start, planner, admitted, None).await?;
    Ok(plan)
}

/// [`plan_admitted`] of a session's step, already [`admit`]ted, from and
/// into the session's `carry` ([`Planner::plan_carried`]), which comes
/// back with the plan (a step that fails drops it).
pub(super) async fn plan_admitted_carried(
    state: &AppState,
    start: Option<Extension<RequestStart>>,
    planner: Arc<Planner>,
    admitted: Admitted,
    carry: Carry,
) -> Result<(PlanResponse, Carry), ApiError> {
    let (plan, carry) = plan_with(state, start, planner, admitted, Some(carry)).await?;
    Ok((plan, carry.unwrap_or_default()))
}

async fn plan_with(
    state: &AppState,
    start: Option<Extension<RequestStart>>,
    planner: Arc<Planner>,
    admitted: Admitted,
    carry: Option<Carry>,
) -> Result<(PlanResponse, Option<Carry>), ApiError> {
    let Admitted {
        input,
        predicted_ms,
        may_inline,
    } = admitted;
    let guard = CancelOnDrop::new("plan", start, state);
    let token = guard.token();
    // First detections run their searches in parallel batches, each of
    // which a plan on this worker would hand to the pool and wait for: on
    // the pool, the whole plan is one hop.
    let inline = may_inline
        && state.settings.plans_inline()
        && predicted_ms <= INLINE_PLAN_MS
        && input.objective == Objective::Detections;
    let work = move || match carry {
        Some(mut carry) => planner
            .plan_carried(&input, &token, &mut carry)
            .map(|plan| (plan, Some(carry))),
        None if inline => planner.plan_here(&input, &token).map(|plan| (plan, None)),
        None => planner
            .plan_cancellable(&input, &token)
            .map(|plan| (plan, None)),
    };
    let res = if inline {
        metrics::counter!(metric_names::PLANS_TOTAL, "on" => "worker").increment(1);
        super::queue::on_this_worker(work).await
    } else {
        metrics::counter!(metric_names::PLANS_TOTAL, "on" => "pool").increment(1);
        super::queue::on_rayon(work).await
    };
    guard.finish();
    // A cancelled plan that is still awaited was cancelled by its deadline.
    res?.map_err(|_| ApiError::Timeout)
}

/// A body that names its scenario as `POST /v1/plan`'s does: the planner
/// of its `scenario_id` or inline `scenario` (see [`resolve_scenario`]),
/// and the other fields read as `T`.
pub(super) async fn with_scenario<T: serde::de::DeserializeOwned>(
    state: &AppState,
    start: Option<Extension<RequestStart>>,
    body: serde_json::Value,
) -> Result<(Arc<Planner>, T), ApiError> {
    let serde_json::Value::Object(mut fields) = body else {
        return Err(ApiError::MalformedBody(
            "the body must be a JSON object".into(),
        ));
    };
    let scenario_id = fields.remove("scenario_id");
    let inline = fields.remove("scenario");
    let req: T = crate::json_path::from_value(&serde_json::Value::Object(fields), "")
        .map_err(ApiError::MalformedBody)?;
    let planner = resolve_scenario(state, start, scenario_id, inline).await?;
    Ok((planner, req))
}

/// The planner of the scenario a body names: `scenario_id` (registered,
/// 503 while pending, or cached inline) or `scenario` (an inline spec,
/// precomputed and cached on first use; 422 above the synchronous budget).
/// Exactly one of the two is required.
pub(super) async fn resolve_scenario(
    state: &AppState,
    start: Option<Extension<RequestStart>>,
    scenario_id: Option<serde_json::Value>,
    inline: Option<serde_json::Value>,
) -> Result<Arc<Planner>, ApiError> {
    Ok(match (scenario_id, inline) {
        (Some(serde_json::Value::String(id)), None) => match registered_or_cached(state, &id)? {
            Some(planner) => planner,
            // A registered scenario not used here yet (with a database).
            None => state.registry.resolve(&id).await?,
        },
        (Some(_), None) => {
            return Err(ApiError::MalformedBody(
                "scenario_id must be a string".into(),
            ));
        }
        (None, Some(spec)) => {
            let spec: ScenarioSpec =
                crate::json_path::from_value(&spec, "scenario").map_err(ApiError::MalformedBody)?;
            let scenario = Scenario::new(spec).map_err(|mut e| {
                e.field = format!("scenario.{}", e.field);
                e
            })?;
            match registered_or_cached(state, &scenario.id)? {
                Some(p) => p,
                None => {
                    let limits = state.registry.limits();
                    if let Some(predicted_ms) = limits.too_long_inline(&scenario) {
                        return Err(ApiError::PrecomputeTooCostly {
                            predicted_ms,
                            budget_ms: limits.sync_precompute_ms,
                        });
                    }
                    let cache = state.cache.clone();
                    let guard = CancelOnDrop::new("precompute", start, state);
                    let token = guard.token();
                    let planner = tokio::task::spawn_blocking(move || {
                        precompute_cancellable(scenario, &token, &Progress::default())
                            .map(|planner| cache.insert(Arc::new(planner)))
                    })
                    .await?
                    .map_err(|_| ApiError::Timeout)?;
                    guard.finish();
                    planner
                }
            }
        }
        _ => {
            return Err(ApiError::Unprocessable(
                "exactly one of `scenario_id` and `scenario` is required".into(),
            ));
        }
    })
}

/// A registered scenario's planner held here (503 while it is pending),
/// else a cached inline one's, else `None`. Never asks the database, so
/// inline scenarios are served while it is unreachable.
fn registered_or_cached(state: &AppState, id: &str) -> Result<Option<Arc<Planner>>, ApiError> {
    match state.registry.ready(id) {
        Ok(p) => Ok(Some(p)),
        Err(CatalogError::NotFound(_)) => Ok(state.cache.get(id)),
        Err(e) => Err(e.into()),
    }
}
