//! Example bodies used in the document. Ids and canonical specs come from
//! the code; computed numbers are from a real run, rounded.

use serde_json::{Value, json};

use crate::scenario::{Scenario, ScenarioSpec, builtins};

/// A small scenario: a 100×100 zone of 10-unit cells, two sources.
pub fn small_spec() -> Value {
    json!({
        "name": "small",
        "zone": {"width": 100.0, "height": 100.0},
        "cell_size": 10.0,
        "fov": {"shape": "square", "half_width": 15.0},
        "target_speed": 10.0,
        "sources": [
            {"x": -1.0, "y": 50.0, "rate": 0.5},
            {"x": 50.0, "y": 101.0, "rate": 0.25}
        ]
    })
}

/// Id and canonical spec of a spec, as the server derives them.
fn registered(spec: Value) -> (String, Value) {
    serde_json::from_value::<ScenarioSpec>(spec)
        .ok()
        .and_then(|spec| Scenario::new(spec).ok())
        .map_or_else(
            || ("s-0000000000000000".to_owned(), Value::Null),
            |s| (s.id, json!(s.spec)),
        )
}

/// The summary of [`small_spec`] once registered.
pub fn small_summary() -> Value {
    let (id, spec) = registered(small_spec());
    json!({
        "id": id,
        "spec": spec,
        "grid": {"cols": 10, "rows": 10},
        "status": "ready",
        "progress": 1.0,
        "predicted_precompute_ms": 0.04,
        "summary": {"expected_targets_in_zone": 5.4993, "precompute_ms": 0.13}
    })
}

/// A large scenario: a 2000×2000 zone of unit cells, a circular field
/// of view of radius 40, four sources.
pub fn large_spec() -> Value {
    json!({
        "name": "large",
        "zone": {"width": 2000.0, "height": 2000.0},
        "cell_size": 1.0,
        "fov": {"shape": "circle", "radius": 40.0},
        "target_speed": 10.0,
        "sources": [
            {"x": -1.0, "y": 1000.0, "rate": 0.5},
            {"x": 2001.0, "y": 1000.0, "rate": 0.5},
            {"x": 1000.0, "y": -1.0, "rate": 0.5},
            {"x": 1000.0, "y": 2001.0, "rate": 0.5}
        ]
    })
}

/// The summary of [`large_spec`] while its job precomputes it.
pub fn large_precomputing() -> Value {
    let (id, spec) = registered(large_spec());
    json!({
        "id": id,
        "spec": spec,
        "grid": {"cols": 2000, "rows": 2000},
        "status": "precomputing",
        "progress": 0.38,
        "eta_s": 13.3,
        "predicted_precompute_ms": 20736.0
    })
}

/// The summary of [`large_spec`] while its job waits behind another.
pub fn large_queued() -> Value {
    let (id, spec) = registered(large_spec());
    json!({
        "id": id,
        "spec": spec,
        "grid": {"cols": 2000, "rows": 2000},
        "status": "queued",
        "progress": 0.0,
        "eta_s": 34.0,
        "queue_position": 1,
        "predicted_precompute_ms": 20736.0
    })
}

/// The summary of `paper-v10`.
pub fn paper_v10_summary() -> Value {
    let spec = builtins()
        .into_iter()
        .find(|s| s.id == "paper-v10")
        .map_or(Value::Null, |s| json!(s.spec));
    json!({
        "id": "paper-v10",
        "spec": spec,
        "grid": {"cols": 30, "rows": 30},
        "status": "ready",
        "progress": 1.0,
        "predicted_precompute_ms": 0.94,
        "summary": {"expected_targets_in_zone": 53.0358, "precompute_ms": 1.62}
    })
}

/// A list with `paper-v10` and a registered scenario.
pub fn scenario_list() -> Value {
    json!({"scenarios": [paper_v10_summary(), small_summary(), large_precomputing()]})
}

/// Statistics of a 3×2 lattice (a 30×20 zone of 10-unit cells, circular
/// field of view of radius 10, one source west of it).
pub fn stats() -> Value {
    json!({
        "type": "default",
        "cols": 3,
        "rows": 2,
        "cell_size": 10.0,
        "lambda_hat": [0.4417, 0.2028, 0.1147, 0.4417, 0.2028, 0.1147],
        "escape_time": [1.9364, 2.6036, 2.3088, 1.9364, 2.6036, 2.3088],
        "d_hat": [0.8553, 0.5279, 0.2647, 0.8553, 0.5279, 0.2647]
    })
}

/// A plan request on `paper-v10`: three sensors, three targets.
pub fn plan_request() -> Value {
    json!({
        "sensors": [
            {"id": "a", "x": 55.0, "y": 55.0},
            {"id": 7, "x": 150.0, "y": 150.0},
            {"id": "c", "x": 245.0, "y": 60.0}
        ],
        "targets": [
            {"id": "t1", "x": 60.0, "y": 40.0, "vx": 10.0, "vy": 0.0},
            {"x": 140.0, "y": 160.0, "vx": -3.0, "vy": 9.0},
            {"id": 3, "x": 250.0, "y": 70.0, "vx": 0.0, "vy": -10.0}
        ]
    })
}

/// Two sensors on one cell and a third, kept 3 cells apart at every
/// step.
pub fn plan_request_apart() -> Value {
    json!({
        "sensors": [
            {"id": "a", "x": 150.0, "y": 150.0},
            {"id": "b", "x": 155.0, "y": 155.0},
            {"id": "c", "x": 175.0, "y": 150.0}
        ],
        "min_separation": 3
    })
}

/// [`plan_request`] for `POST /v1/plan`, naming the scenario.
pub fn plan_request_by_id() -> Value {
    let mut req = plan_request();
    req["scenario_id"] = json!("paper-v10");
    req
}

/// A `POST /v1/plan` request with its scenario inline.
pub fn plan_request_inline() -> Value {
    json!({
        "scenario": small_spec(),
        "sensors": [{"id": "a", "x": 50.0, "y": 50.0}],
        "targets": [{"x": 20.0, "y": 45.0, "vx": 10.0, "vy": 0.0}],
        "horizon": 2
    })
}

fn cell(col: i32, row: i32) -> Value {
    json!({
        "col": col,
        "row": row,
        "x": (f64::from(col) + 0.5) * 10.0,
        "y": (f64::from(row) + 0.5) * 10.0
    })
}

/// The response to [`plan_request`].
pub fn plan_response() -> Value {
    json!({
        "scenario": "paper-v10",
        "horizon": 3,
        "estimator": "exact",
        "coordination": "priority",
        "objective": "detections",
        "min_separation": 0,
        "separation_violations": 0,
        "plans": [
            {
                "sensor": "a",
                "priority": 1,
                "start": cell(5, 5),
                "path": [cell(6, 4), cell(7, 3), cell(8, 2)],
                "expected_detections": 6.9032,
                "separation_violations": 0
            },
            {
                "sensor": 7,
                "priority": 3,
                "start": cell(15, 15),
                "path": [cell(14, 16), cell(13, 17), cell(12, 18)],
                "expected_detections": 5.8559,
                "separation_violations": 0
            },
            {
                "sensor": "c",
                "priority": 2,
                "start": cell(24, 6),
                "path": [cell(23, 5), cell(22, 4), cell(22, 3)],
                "expected_detections": 6.3405,
                "separation_violations": 0
            }
        ],
        "expected_detections": 19.0996,
        "expected_by_step": [4.808, 6.538, 7.7535],
        "bound": {"upper": 19.4305, "gap": 0.017},
        "compute_micros": 335
    })
}

/// [`plan_request`]'s sensors and targets with the paths of
/// [`plan_response`], to score.
pub fn evaluate_request() -> Value {
    let mut req = plan_request();
    req["paths"] = json!([
        {"sensor": "a", "path": [{"col": 6, "row": 4}, {"col": 7, "row": 3}, {"col": 8, "row": 2}]},
        {"sensor": 7, "path": [{"col": 14, "row": 16}, {"col": 13, "row": 17}, {"col": 12, "row": 18}]},
        {"sensor": "c", "path": [{"col": 23, "row": 5}, {"col": 22, "row": 4}, {"col": 22, "row": 3}]}
    ]);
    req
}

/// [`evaluate_request`] naming its scenario.
pub fn evaluate_request_by_id() -> Value {
    let mut req = evaluate_request();
    req["scenario_id"] = json!("paper-v10");
    req
}

/// The scores of [`evaluate_request`]'s paths.
pub fn evaluate_response() -> Value {
    json!({
        "scenario": "paper-v10",
        "horizon": 3,
        "estimator": "exact",
        "objective": "detections",
        "min_separation": 0,
        "expected_detections": 19.0996,
        "expected_by_step": [4.808, 6.538, 7.7535],
        "separation_violations": 0,
        "sensors": [
            {"sensor": "a", "marginal": 6.9032, "separation_violations": 0},
            {"sensor": 7, "marginal": 5.8559, "separation_violations": 0},
            {"sensor": "c", "marginal": 6.3405, "separation_violations": 0}
        ]
    })
}

/// A session on `paper-v10` keeping 16 steps of history.
pub fn session_request() -> Value {
    json!({"scenario_id": "paper-v10", "horizon": 3, "history_steps": 16})
}

/// The session of [`session_request`] after the steps of
/// [`step_request`] and a second with the sensors moved on.
pub fn session_info() -> Value {
    json!({
        "id": "ss-36c3f1f5ddc745349553d4bb0bc86f98",
        "scenario": "paper-v10",
        "step": 2,
        "history_steps": 16,
        "history_held": 2,
        "settings": {"horizon": 3, "history_steps": 16},
        "tracks": [
            {"id": 17, "x": 70.0, "y": 40.0, "vx": 10.0, "vy": 0.0, "last_detected": 0}
        ],
        "memory_bytes": 456
    })
}

/// A step: two sensors, one target detected.
pub fn step_request() -> Value {
    json!({
        "sensors": [{"id": "a", "x": 55.0, "y": 55.0}, {"id": "b", "x": 245.0, "y": 60.0}],
        "detections": [{"id": 17, "x": 60.0, "y": 40.0, "vx": 10.0, "vy": 0.0}]
    })
}

/// The plan of [`step_request`] as the first step of a session.
pub fn step_response() -> Value {
    json!({
        "step": 0,
        "scenario": "paper-v10",
        "horizon": 3,
        "estimator": "exact",
        "coordination": "priority",
        "objective": "detections",
        "min_separation": 0,
        "separation_violations": 0,
        "plans": [
            {
                "sensor": "a",
                "priority": 1,
                "start": cell(5, 5),
                "path": [cell(6, 4), cell(7, 3), cell(8, 2)],
                "expected_detections": 6.9058,
                "separation_violations": 0
            },
            {
                "sensor": "b",
                "priority": 2,
                "start": cell(24, 6),
                "path": [cell(25, 7), cell(26, 8), cell(27, 9)],
                "expected_detections": 4.1472,
                "separation_violations": 0
            }
        ],
        "expected_detections": 11.053,
        "expected_by_step": [2.3726, 3.833, 4.8474],
        "compute_micros": 1560
    })
}

/// A fit window of two steps on `paper-v10`: two sensors, one target
/// detected at both steps.
pub fn fit_request() -> Value {
    json!({
        "steps": [
            {"sensors": [{"id": "a", "x": 55.0, "y": 95.0}, {"id": "b", "x": 155.0, "y": 105.0}],
             "detections": [{"id": 17, "x": 60.0, "y": 100.0, "vx": 10.0, "vy": 0.0}]},
            {"sensors": [{"id": "a", "x": 65.0, "y": 95.0}, {"id": "b", "x": 155.0, "y": 95.0}],
             "detections": [{"id": 17, "x": 70.0, "y": 100.0, "vx": 10.0, "vy": 0.0}]}
        ],
        "prior": "scenario"
    })
}

/// What [`fit_request`] gets back (abridged to two sources).
pub fn fit_response() -> Value {
    json!({
        "scenario": "paper-v10",
        "steps": 2,
        "sources": [
            {"index": 0, "rate": 0.311, "interval": [0.0376, 0.866], "detected": 1.0, "exposure": 3.10},
            {"index": 1, "rate": 0.191, "interval": [0.00483, 0.703], "detected": 0.0, "exposure": 1.91}
        ],
        "unexplained": []
    })
}
