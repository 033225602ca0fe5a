//! The name of every metric the server exports (`GET /metrics`), in one
//! place: the code that records one names it from here, and
//! `docs/operating.md` lists them with their labels.

/// Counter of requests answered, by `method`, `route` and `status`.
pub const HTTP_REQUESTS_TOTAL: &str = "vigil_http_requests_total";
/// Gauge of requests under way.
pub const HTTP_REQUESTS_IN_FLIGHT: &str = "vigil_http_requests_in_flight";
/// Counter of requests answered 503 by load shedding (the in-flight limit
/// or a full planning queue).
pub const HTTP_SHED_TOTAL: &str = "vigil_http_shed_total";
/// Histogram of the plan endpoints' durations, seconds, by `route`.
pub const PLAN_DURATION_SECONDS: &str = "vigil_plan_duration_seconds";
/// Counter of plans run, by `on` (`pool`: rayon's workers; `worker`: the
/// async worker that received it).
pub const PLANS_TOTAL: &str = "vigil_plans_total";
/// Counter of plans refused before any work, by `reason` (`cost`).
pub const PLANS_REFUSED_TOTAL: &str = "vigil_plans_refused_total";
/// Counter of work cancelled, by `kind` (`plan`, `precompute`) and
/// `reason` (`timeout`, `client_gone`, `deleted`).
pub const CANCELLED_TOTAL: &str = "vigil_cancelled_total";
/// Histogram of the time to build a scenario's statistics, seconds.
pub const PRECOMPUTE_SECONDS: &str = "vigil_precompute_seconds";
/// Gauge of precomputation jobs, by `state` (`queued`, `running`).
pub const PRECOMPUTE_JOBS: &str = "vigil_precompute_jobs";
/// Gauge of registered scenarios held by this replica (built-ins
/// included).
pub const SCENARIOS_LOADED: &str = "vigil_scenarios_loaded";
/// Gauge: 1 if the database answered its last check, 0 if not.
pub const DATABASE_UP: &str = "vigil_database_up";
/// Gauge of connections open.
pub const CONNECTIONS_OPEN: &str = "vigil_connections_open";
/// Counter of connections closed at once past `--max-connections`.
pub const CONNECTIONS_REFUSED_TOTAL: &str = "vigil_connections_refused_total";
/// Counter of connections closed by the server, by `reason`
/// (`header_timeout`, `idle_timeout`).
pub const CONNECTIONS_CLOSED_TOTAL: &str = "vigil_connections_closed_total";
/// Gauge of sessions held.
pub const SESSIONS_LIVE: &str = "vigil_sessions_live";
/// Counter of sessions dropped, by `reason` (`idle`, `capacity`).
pub const SESSIONS_EVICTED_TOTAL: &str = "vigil_sessions_evicted_total";
/// Gauge of bytes of sessions' carries held (`--session-carry-mb`).
pub const SESSION_CARRY_BYTES: &str = "vigil_session_carry_bytes";
/// Counter of sessions' steps, by `carry`: `used` (the step continued its
/// session's carry), `rebuilt` (it had none or another state's, and
/// started over) or `none` (the carry does not apply: uncertain looks,
/// buildings, the paper's estimator).
pub const SESSION_STEPS_TOTAL: &str = "vigil_session_steps_total";
/// Counter of sessions' steps written to the database, by `when`:
/// `during_plan` (begun while the plan was made, committed after it) or
/// `after_plan`.
pub const SESSION_WRITES_TOTAL: &str = "vigil_session_writes_total";

/// Counter of registered scenarios' precomputations, by `outcome`
/// (`loaded`: read from the database; `computed`: precomputed here under a
/// claim; `stored`: written for the other replicas; `rejected`: a stored
/// one this server could not use, computed again).
pub const PRECOMPUTED_TOTAL: &str = "vigil_precomputed_total";

/// Every metric above.
pub const ALL: [&str; 20] = [
    HTTP_REQUESTS_TOTAL,
    HTTP_REQUESTS_IN_FLIGHT,
    HTTP_SHED_TOTAL,
    PLAN_DURATION_SECONDS,
    PLANS_TOTAL,
    PLANS_REFUSED_TOTAL,
    CANCELLED_TOTAL,
    PRECOMPUTE_SECONDS,
    PRECOMPUTE_JOBS,
    SCENARIOS_LOADED,
    DATABASE_UP,
    CONNECTIONS_OPEN,
    CONNECTIONS_REFUSED_TOTAL,
    CONNECTIONS_CLOSED_TOTAL,
    SESSIONS_LIVE,
    SESSIONS_EVICTED_TOTAL,
    SESSION_CARRY_BYTES,
    SESSION_STEPS_TOTAL,
    SESSION_WRITES_TOTAL,
    PRECOMPUTED_TOTAL,
];

#[cfg(test)]
mod tests {
    /// The operator's page documents every metric, and no other.
    #[test]
    fn the_operating_page_lists_every_metric() {
        let page = include_str!("../docs/operating.md");
        for name in super::ALL {
            assert!(
                page.contains(&format!("`{name}`")),
                "{name} is not in docs/operating.md"
            );
        }
        let listed = page.matches("| `vigil_").count();
        assert_eq!(
            listed,
            super::ALL.len(),
            "docs/operating.md lists {listed} metrics"
        );
    }
}
