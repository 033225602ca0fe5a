//! Property tests over the socket: random bytes, random JSON of random
//! shape, plausible plan requests with extreme numbers, random scenario
//! specs and random session runs, sent to every endpoint. The server must
//! never answer 5xx, every error must be problem+json, and it must still be
//! healthy afterwards.
//!
//! One server serves every case; proptest runs synchronously, so each case
//! `block_on`s its request on a shared runtime.

use std::cell::Cell;
use std::sync::LazyLock;

use proptest::prelude::*;
use proptest::test_runner::{Config, TestCaseError, TestRunner};
use reqwest::{Method, StatusCode, header};
use serde_json::{Map, Value, json};
use tokio::runtime::Runtime;

use crate::helpers::{TestApp, spawn_app};

/// The shared runtime and server.
static SERVER: LazyLock<(Runtime, TestApp)> = LazyLock::new(|| {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    let app = rt.block_on(spawn_app());
    (rt, app)
});

/// Every route, with `{id}` filled in, and its methods.
const ENDPOINTS: [(&str, &str); 13] = [
    ("GET", "/healthz"),
    ("GET", "/v1/scenarios"),
    ("POST", "/v1/scenarios"),
    ("GET", "/v1/scenarios/paper-v10"),
    ("DELETE", "/v1/scenarios/paper-v10"),
    ("GET", "/v1/scenarios/paper-v10/stats"),
    ("POST", "/v1/scenarios/paper-v10/plan"),
    ("POST", "/v1/plan"),
    ("POST", "/v1/scenarios/nope/plan"),
    ("POST", "/v1/sessions"),
    ("GET", "/v1/sessions/nope"),
    ("DELETE", "/v1/sessions/nope"),
    ("POST", "/v1/sessions/nope/step"),
];

/// The POST endpoints that read a JSON body.
const BODY_ENDPOINTS: [&str; 5] = [
    "/v1/scenarios",
    "/v1/scenarios/paper-v10/plan",
    "/v1/plan",
    "/v1/sessions",
    "/v1/sessions/nope/step",
];

fn runner(cases: u32) -> TestRunner {
    TestRunner::new(Config {
        cases,
        // Shrinking a server-side failure is slow and the case is printed
        // anyway; no regression files in the source tree.
        max_shrink_iters: 16,
        failure_persistence: None,
        ..Config::default()
    })
}

/// Sends one request and checks the answer: no 5xx; an error is
/// problem+json with a matching `status`; a success with a body is JSON.
fn send(
    method: &str,
    path: &str,
    content_type: Option<&str>,
    body: Vec<u8>,
) -> Result<StatusCode, TestCaseError> {
    exchange(method, path, content_type, body).map(|(status, _)| status)
}

/// [`send`], also giving the body.
fn exchange(
    method: &str,
    path: &str,
    content_type: Option<&str>,
    body: Vec<u8>,
) -> Result<(StatusCode, String), TestCaseError> {
    let (rt, app) = &*SERVER;
    let method = Method::from_bytes(method.as_bytes()).unwrap();
    let (status, ct, text) = rt.block_on(async {
        let mut req = app.client.request(method.clone(), app.url(path)).body(body);
        if let Some(ct) = content_type {
            req = req.header(header::CONTENT_TYPE, ct);
        }
        let res = req.send().await.unwrap();
        let status = res.status();
        let ct = res
            .headers()
            .get(header::CONTENT_TYPE)
            .and_then(|v| v.to_str().ok())
            .unwrap_or_default()
            .to_owned();
        (status, ct, res.text().await.unwrap_or_default())
    });
    let at = format!("{method} {path} → {status}");
    prop_assert!(!status.is_server_error(), "{}: {}", at, text);
    if status.is_client_error() {
        prop_assert_eq!(ct.as_str(), "application/problem+json", "{}: {}", at, text);
        let problem: Value = serde_json::from_str(&text)
            .map_err(|e| TestCaseError::fail(format!("{at}: not JSON ({e}): {text}")))?;
        prop_assert_eq!(&problem["status"], &json!(status.as_u16()), "{}", at);
        for member in ["type", "title", "detail"] {
            prop_assert!(
                problem[member].is_string(),
                "{}: no `{}`: {}",
                at,
                member,
                text
            );
        }
    } else if !text.is_empty() && ct == "application/json" {
        prop_assert!(
            serde_json::from_str::<Value>(&text).is_ok(),
            "{}: {}",
            at,
            text
        );
    }
    Ok((status, text))
}

fn send_json(path: &str, body: &Value) -> Result<StatusCode, TestCaseError> {
    send(
        "POST",
        path,
        Some("application/json"),
        serde_json::to_vec(body).unwrap(),
    )
}

fn assert_healthy() {
    let (rt, app) = &*SERVER;
    let status = rt.block_on(async { app.get("/healthz").await.status() });
    assert_eq!(status, StatusCode::OK);
}

// ---- strategies -----------------------------------------------------------

/// Any finite number, with the extremes over-represented.
fn number() -> impl Strategy<Value = Value> {
    prop_oneof![
        3 => (-1e3..1e3f64).prop_map(Value::from),
        1 => any::<f64>().prop_filter_map("finite", |x| x.is_finite().then(|| json!(x))),
        1 => any::<i64>().prop_map(Value::from),
        1 => prop::sample::select(vec![
            json!(0), json!(-0.0), json!(-1), json!(1e308), json!(-1e308), json!(5e-324),
            json!(u64::MAX), json!(i64::MIN), json!(1e-300),
        ]),
    ]
}

/// A coordinate, mostly inside `[0, extent]`, sometimes anywhere.
fn coordinate(extent: f64) -> impl Strategy<Value = Value> {
    prop_oneof![
        6 => (0.0..=extent).prop_map(Value::from),
        1 => prop::sample::select(vec![json!(extent), json!(0.0), json!(-1e-9), json!(extent + 1e-9)]),
        2 => number(),
        1 => prop::sample::select(vec![json!(null), json!("1"), json!([1]), json!(true)]),
    ]
}

/// A number, mostly inside `[0, extent]`.
fn finite_coordinate(extent: f64) -> impl Strategy<Value = Value> {
    prop_oneof![
        6 => (0.0..=extent).prop_map(Value::from),
        3 => number(),
    ]
}

/// Object keys: the API's field names and random ones.
fn key() -> impl Strategy<Value = String> {
    prop_oneof![
        3 => prop::sample::select(vec![
            "sensors", "targets", "history", "horizon", "estimator", "coordination", "observed",
            "explain", "id", "x", "y", "vx", "vy", "scenario", "scenario_id", "zone", "width",
            "height", "cell_size", "fov", "shape", "half_width", "radius", "target_speed",
            "sources", "rate", "heading", "name", "detections", "history_steps",
            "min_separation", "type", "sensor_types", "speeds", "p_detect",
        ])
        .prop_map(str::to_owned),
        1 => "[a-z_]{1,8}",
    ]
}

/// A JSON value of random shape, at most three levels deep.
fn any_json() -> impl Strategy<Value = Value> {
    let leaf = prop_oneof![
        Just(Value::Null),
        any::<bool>().prop_map(Value::from),
        number(),
        "[a-z0-9 ]{0,8}".prop_map(Value::from),
        prop::sample::select(vec![
            "paper-v10",
            "square",
            "circle",
            "exact",
            "paper",
            "iterated"
        ])
        .prop_map(Value::from),
    ];
    leaf.prop_recursive(3, 48, 6, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 0..6).prop_map(Value::Array),
            prop::collection::btree_map(key(), inner, 0..6)
                .prop_map(|m| Value::Object(m.into_iter().collect())),
        ]
    })
}

fn id() -> impl Strategy<Value = Value> {
    prop_oneof![
        4 => (0..6u8).prop_map(|i| json!(format!("s{i}"))),
        2 => (0..6i64).prop_map(Value::from),
        1 => prop::sample::select(vec![json!(1.5), json!(null), json!(true), json!({"a": 1}), json!([])]),
    ]
}

fn sensor(extent: f64) -> impl Strategy<Value = Value> {
    (id(), coordinate(extent), coordinate(extent))
        .prop_map(|(id, x, y)| json!({"id": id, "x": x, "y": y}))
}

fn target(extent: f64) -> impl Strategy<Value = Value> {
    (
        prop::option::of(prop_oneof![9 => (0..1000u32).prop_map(Value::from), 1 => id()]),
        finite_coordinate(extent),
        finite_coordinate(extent),
        prop_oneof![4 => (-20.0..20.0f64).prop_map(Value::from), 1 => number()],
        prop_oneof![4 => (-20.0..20.0f64).prop_map(Value::from), 1 => number()],
    )
        .prop_map(|(id, x, y, vx, vy)| {
            let mut t = json!({"x": x, "y": y, "vx": vx, "vy": vy});
            if let Some(id) = id {
                t["id"] = id;
            }
            t
        })
}

fn position(extent: f64) -> impl Strategy<Value = Value> {
    (coordinate(extent), coordinate(extent)).prop_map(|(x, y)| json!({"x": x, "y": y}))
}

/// An optional enum field: absent, one of `valid`, or now and then a
/// value it does not know.
fn option(valid: &[&'static str]) -> impl Strategy<Value = Option<&'static str>> {
    prop::option::of(prop_oneof![
        9 => prop::sample::select(valid.to_vec()),
        1 => Just("bogus"),
    ])
}

/// A small inline scenario (100×100, circular fields of view).
fn small_inline_spec() -> Value {
    json!({
        "zone": {"width": 100.0, "height": 100.0},
        "cell_size": 10.0,
        "fov": {"shape": "circle", "radius": 15.0},
        "target_speed": 10.0,
        "sources": [{"x": -1.0, "y": 50.0, "rate": 0.5}]
    })
}

/// Sets `key` in `obj` when `value` is `Some`.
fn put(obj: &mut Value, key: &str, value: Option<Value>) {
    if let Some(v) = value {
        obj[key] = v;
    }
}

/// A plan request for a zone of side `extent`: mostly well-formed, with
/// random numbers (huge, negative, zero), random options and occasionally
/// too many sensors.
fn plan_request(extent: f64) -> impl Strategy<Value = Value> {
    // Valid sensors (distinct ids, inside the zone) half the time, so that
    // the extreme target numbers reach the planner.
    let valid_sensors = prop::collection::vec((0.0..=extent, 0.0..=extent), 1..6).prop_map(|xy| {
        xy.iter()
            .enumerate()
            .map(|(i, (x, y))| json!({"id": i, "x": x, "y": y}))
            .collect::<Vec<_>>()
    });
    let sensors = prop_oneof![
        8 => valid_sensors,
        6 => prop::collection::vec(sensor(extent), 0..8),
        1 => prop::collection::vec(sensor(extent), 8..40),
        1 => Just(vec![json!({"id": "x", "x": 1.0, "y": 1.0}); 257]),
    ];
    let targets = prop_oneof![
        6 => prop::collection::vec(target(extent), 0..10),
        1 => prop::collection::vec(target(extent), 100..400),
    ];
    let valid_history = prop::collection::vec(
        prop::collection::vec(
            (0.0..=extent, 0.0..=extent).prop_map(|(x, y)| json!({"x": x, "y": y})),
            0..5,
        ),
        0..5,
    );
    let history = prop::option::of(prop_oneof![
        2 => valid_history,
        1 => prop::collection::vec(prop::collection::vec(position(extent), 0..5), 0..5),
    ]);
    let options = (
        prop::option::of(prop_oneof![6 => (1..=12i64).prop_map(Value::from), 1 => number()]),
        option(&["exact", "paper"]),
        option(&["none", "priority", "iterated"]),
        option(&["sensors", "zone"]),
        prop::option::of(any::<bool>()),
    );
    (sensors, targets, history, options).prop_map(
        |(sensors, targets, history, (horizon, estimator, coordination, observed, explain))| {
            let mut req = json!({"sensors": sensors, "targets": targets});
            put(&mut req, "history", history.map(|h| json!(h)));
            // Long horizons with many sensors are slow to plan; keep the
            // long ones for small requests.
            let small = req["sensors"].as_array().is_some_and(|s| s.len() <= 4);
            put(
                &mut req,
                "horizon",
                horizon.filter(|h| small || h.as_i64().is_none_or(|h| h <= 6)),
            );
            put(&mut req, "estimator", estimator.map(Value::from));
            put(&mut req, "coordination", coordination.map(Value::from));
            put(&mut req, "observed", observed.map(Value::from));
            put(&mut req, "explain", explain.map(Value::from));
            req
        },
    )
}

fn fov() -> impl Strategy<Value = Value> {
    prop_oneof![
        4 => (0.5..40.0f64).prop_map(|h| json!({"shape": "square", "half_width": h})),
        4 => (0.5..40.0f64).prop_map(|r| json!({"shape": "circle", "radius": r})),
        1 => number().prop_map(|h| json!({"shape": "square", "half_width": h})),
        1 => prop::sample::select(vec![
            json!({"shape": "hexagon", "side": 3}),
            json!({"shape": "circle"}),
            json!({"half_width": 10}),
            json!({"shape": "square", "half_width": 10, "radius": 3}),
            json!("square"),
        ]),
    ]
}

/// A source beside the zone `[0,w]×[0,h]`, or anywhere.
fn source(w: f64, h: f64) -> impl Strategy<Value = Value> {
    let beside = (0..4u8, 0.0..=1.0f64, 0.1..5.0f64).prop_map(move |(edge, f, d)| match edge {
        0 => (-d, f * h),
        1 => (w + d, f * h),
        2 => (f * w, -d),
        _ => (f * w, h + d),
    });
    let position = prop_oneof![
        6 => beside.prop_map(|(x, y)| (json!(x), json!(y))),
        1 => (coordinate(w), coordinate(h)),
    ];
    let rate = prop_oneof![5 => (0.0..2.0f64).prop_map(Value::from), 1 => number()];
    // Mostly inferred; a given heading is often one that does not face the
    // zone.
    let heading = prop::option::weighted(
        0.25,
        prop::sample::select(vec!["east", "west", "north", "south", "up"]),
    );
    (position, rate, heading).prop_map(|((x, y), rate, heading)| {
        let mut s = json!({"x": x, "y": y, "rate": rate});
        put(&mut s, "heading", heading.map(Value::from));
        s
    })
}

/// A scenario spec: mostly a lattice of at most 100×100 cells, sometimes out
/// of bounds (too many cells, cells that do not tile the zone, too many
/// sources, a bad horizon) — never a large valid lattice, which would be
/// slow to precompute.
fn scenario_spec() -> impl Strategy<Value = Value> {
    let lattice = (
        1..=100u32,
        1..=100u32,
        prop::sample::select(vec![1.0, 2.5, 10.0]),
    );
    let valid = lattice.prop_flat_map(|(cols, rows, cell)| {
        let (w, h) = (f64::from(cols) * cell, f64::from(rows) * cell);
        (
            Just((json!(w), json!(h), json!(cell))),
            prop::collection::vec(source(w, h), 0..4),
        )
    });
    let out_of_bounds = prop::sample::select(vec![
        (json!(1e6), json!(1e6), json!(1.0)),
        (json!(5000.0), json!(1000.0), json!(1.0)),
        (json!(100.0), json!(100.0), json!(7.0)),
        (json!(100.0), json!(100.0), json!(1e-9)),
        (json!(100.0), json!(100.0), json!(1000.0)),
        (json!(100.0), json!(100.0), json!(0.0)),
        (json!(-100.0), json!(100.0), json!(10.0)),
        (json!(1e308), json!(1e308), json!(1e-308)),
        (json!(100.0), json!(100.0), json!("10")),
    ])
    .prop_map(|dims| (dims, vec![json!({"x": -1.0, "y": 50.0, "rate": 0.5})]));
    let too_many_sources = Just((
        (json!(100.0), json!(100.0), json!(10.0)),
        vec![json!({"x": -1.0, "y": 50.0, "rate": 0.5}); 65],
    ));
    let shape = prop_oneof![8 => valid, 2 => out_of_bounds, 1 => too_many_sources];
    let speed = prop_oneof![5 => (0.5..30.0f64).prop_map(Value::from), 1 => number()];
    let horizon =
        prop::option::of(prop_oneof![4 => (1..=12i64).prop_map(Value::from), 1 => number()]);
    let name = prop::option::of(prop_oneof![
        "[a-z ]{0,12}".prop_map(Value::from),
        Just(json!("x".repeat(201))),
    ]);
    (shape, fov(), speed, horizon, name).prop_map(
        |(((w, h, cell), sources), fov, speed, horizon, name)| {
            let mut spec = json!({
                "zone": {"width": w, "height": h},
                "cell_size": cell,
                "fov": fov,
                "target_speed": speed,
                "sources": sources,
            });
            put(&mut spec, "horizon", horizon);
            put(&mut spec, "name", name);
            spec
        },
    )
}

// ---- properties -------------------------------------------------------------

#[test]
fn random_bytes_to_every_endpoint() {
    let endpoint = prop::sample::select(ENDPOINTS.to_vec());
    let content_type = prop::option::of(prop::sample::select(vec![
        "application/json",
        "application/problem+json",
        "text/plain",
        "application/json; charset=utf-8",
    ]));
    let body = prop_oneof![
        prop::collection::vec(any::<u8>(), 0..256),
        "[\\[\\]{}\",:0-9a-z. \\\\-]{0,64}".prop_map(String::into_bytes),
    ];
    runner(50)
        .run(
            &(endpoint, content_type, body),
            |((method, path), ct, body)| send(method, path, ct, body).map(|_| ()),
        )
        .unwrap();
    assert_healthy();
}

#[test]
fn random_json_to_every_body_endpoint() {
    let endpoint = prop::sample::select(BODY_ENDPOINTS.to_vec());
    runner(50)
        .run(&(endpoint, any_json()), |(path, body)| {
            send_json(path, &body).map(|_| ())
        })
        .unwrap();
    assert_healthy();
}

#[test]
fn plausible_plan_requests() {
    // paper-v10 is 300×300; by path, by id, and with a small inline scenario.
    let inline = small_inline_spec();
    let route = prop::sample::select(vec![0u8, 1, 2]);
    let ok = Cell::new(0);
    runner(60)
        .run(&(route, plan_request(300.0)), |(route, mut req)| {
            let path = match route {
                0 => "/v1/scenarios/paper-v10/plan",
                1 => {
                    req["scenario_id"] = json!("paper-v10");
                    "/v1/plan"
                }
                _ => {
                    req["scenario"] = inline.clone();
                    "/v1/plan"
                }
            };
            if send_json(path, &req)? == StatusCode::OK {
                ok.set(ok.get() + 1);
            }
            Ok(())
        })
        .unwrap();
    // The strategy is meant to produce some valid requests too.
    assert!(ok.get() > 0, "no plan request succeeded");
    assert_healthy();
}

#[test]
fn random_scenario_specs() {
    let inline = prop::bool::weighted(0.3);
    let created = Cell::new(0);
    runner(40)
        .run(&(scenario_spec(), inline), |(spec, inline)| {
            let status = if inline {
                let mut req = Map::new();
                req.insert("scenario".to_owned(), spec);
                req.insert("sensors".to_owned(), json!([{"id": 1, "x": 0.0, "y": 0.0}]));
                send_json("/v1/plan", &Value::Object(req))?
            } else {
                send_json("/v1/scenarios", &spec)?
            };
            if status.is_success() {
                created.set(created.get() + 1);
            }
            Ok(())
        })
        .unwrap();
    assert!(created.get() > 0, "no scenario spec was accepted");
    assert_healthy();
}

#[test]
fn random_scenario_ids_in_paths() {
    let id = prop_oneof![
        // `.` and `..` are dot segments, which the client resolves away.
        "[a-zA-Z0-9_.~-]{1,24}".prop_filter("a dot segment", |s| s != "." && s != ".."),
        prop::collection::vec(any::<u8>(), 1..12).prop_map(|bytes| {
            bytes
                .iter()
                .map(|b| format!("%{b:02X}"))
                .collect::<String>()
        }),
    ];
    let route = prop::sample::select(vec![
        ("GET", ""),
        ("DELETE", ""),
        ("GET", "/stats"),
        ("POST", "/plan"),
    ]);
    runner(20)
        .run(&(id, route), |(id, (method, suffix))| {
            let status = send(
                method,
                &format!("/v1/scenarios/{id}{suffix}"),
                Some("application/json"),
                br#"{"sensors":[{"id":1,"x":1,"y":1}]}"#.to_vec(),
            )?;
            prop_assert!(
                [
                    StatusCode::BAD_REQUEST,
                    StatusCode::NOT_FOUND,
                    StatusCode::OK,
                    StatusCode::NO_CONTENT,
                    StatusCode::CONFLICT
                ]
                .contains(&status),
                "{} /v1/scenarios/{}{} → {}",
                method,
                id,
                suffix,
                status
            );
            Ok(())
        })
        .unwrap();
    assert_healthy();
}

/// A session's settings beside its scenario: mostly valid, sometimes out of
/// bounds or misspelt.
fn session_body() -> impl Strategy<Value = Value> {
    let scenario = prop::sample::select(vec![
        json!({"scenario_id": "paper-v10"}),
        json!({"scenario_id": "paper-v10"}),
        json!({"scenario_id": "site-fleet"}),
        json!({"scenario_id": "site-fleet"}),
        json!({"scenario_id": "nope"}),
        json!({"scenario": small_inline_spec()}),
        json!({}),
        json!({"scenario_id": "paper-v10", "scenario": {}}),
    ]);
    let small = prop_oneof![6 => (0..=4i64).prop_map(Value::from), 1 => number()];
    let settings = (
        prop::option::of(prop_oneof![6 => (1..=4i64).prop_map(Value::from), 1 => number()]),
        prop::option::of(prop_oneof![6 => (0..=32i64).prop_map(Value::from), 1 => number()]),
        prop::option::of(small),
        option(&["exact", "paper"]),
        option(&["none", "priority", "iterated"]),
        option(&["sensors", "zone"]),
        prop::bool::weighted(0.05),
    );
    (scenario, settings).prop_map(
        |(mut body, (horizon, history, separation, estimator, coordination, observed, extra))| {
            put(&mut body, "horizon", horizon);
            put(&mut body, "history_steps", history);
            put(&mut body, "min_separation", separation);
            put(&mut body, "estimator", estimator.map(Value::from));
            put(&mut body, "coordination", coordination.map(Value::from));
            put(&mut body, "observed", observed.map(Value::from));
            if extra {
                body["colour"] = json!("red");
            }
            body
        },
    )
}

/// A session's step on a zone of side `extent`: sensors of the built-in
/// types (and unknown ones), detections with extreme numbers, sometimes a
/// per-step override out of bounds.
fn step_body(extent: f64) -> impl Strategy<Value = Value> {
    let typed = (
        0.0..=extent,
        0.0..=extent,
        prop_oneof![
            12 => Just(None),
            2 => prop::sample::select(vec![Some("robot"), Some("drone"), Some("default")]),
            1 => Just(Some("bogus")),
        ],
    );
    let valid_sensors = prop::collection::vec(typed, 1..5).prop_map(|sensors| {
        sensors
            .iter()
            .enumerate()
            .map(|(i, &(x, y, ty))| {
                let mut s = json!({"id": i, "x": x, "y": y});
                put(&mut s, "type", ty.map(Value::from));
                s
            })
            .collect::<Vec<_>>()
    });
    let sensors = prop_oneof![
        12 => valid_sensors,
        2 => prop::collection::vec(sensor(extent), 0..6),
    ];
    let detections = prop_oneof![
        8 => prop::collection::vec(target(extent), 0..8),
        1 => prop::collection::vec(target(extent), 100..300),
    ];
    let overrides = (
        prop::option::of(prop_oneof![6 => (1..=4i64).prop_map(Value::from), 1 => number()]),
        prop::option::of(prop_oneof![6 => (0..=4i64).prop_map(Value::from), 1 => number()]),
        prop::option::of(any::<bool>()),
    );
    (sensors, detections, overrides).prop_map(
        |(sensors, detections, (horizon, separation, explain))| {
            let mut req = json!({"sensors": sensors, "detections": detections});
            put(&mut req, "horizon", horizon);
            put(&mut req, "min_separation", separation);
            put(&mut req, "explain", explain.map(Value::from));
            req
        },
    )
}

/// The session's step count, from `GET /v1/sessions/{id}`.
fn session_step(id: &str) -> Result<Value, TestCaseError> {
    let (status, text) = exchange("GET", &format!("/v1/sessions/{id}"), None, Vec::new())?;
    prop_assert_eq!(status, StatusCode::OK, "GET /v1/sessions/{}: {}", id, text);
    let info: Value = serde_json::from_str(&text)
        .map_err(|e| TestCaseError::fail(format!("session info not JSON ({e}): {text}")))?;
    Ok(info["step"].clone())
}

#[test]
fn random_session_runs() {
    // A run: open a session, send it steps (some of them bad), read it back
    // after each; a step that fails records nothing, one that succeeds
    // records one step. Then delete it, and it is gone.
    let steps = prop::collection::vec(step_body(300.0), 1..6);
    let opened = Cell::new(0);
    let planned = Cell::new(0);
    runner(60)
        .run(&(session_body(), steps), |(body, steps)| {
            let (status, text) = exchange(
                "POST",
                "/v1/sessions",
                Some("application/json"),
                serde_json::to_vec(&body).unwrap(),
            )?;
            if status != StatusCode::CREATED {
                return Ok(());
            }
            opened.set(opened.get() + 1);
            let info: Value = serde_json::from_str(&text).unwrap();
            let id = info["id"].as_str().expect("an id").to_owned();
            let mut done = 0u64;
            for step in &steps {
                let status = send_json(&format!("/v1/sessions/{id}/step"), step)?;
                if status == StatusCode::OK {
                    done += 1;
                    planned.set(planned.get() + 1);
                }
                prop_assert_eq!(session_step(&id)?, json!(done), "after {}", step);
            }
            prop_assert_eq!(
                send("DELETE", &format!("/v1/sessions/{id}"), None, Vec::new())?,
                StatusCode::NO_CONTENT
            );
            prop_assert_eq!(
                send_json(&format!("/v1/sessions/{id}/step"), &steps[0])?,
                StatusCode::NOT_FOUND
            );
            Ok(())
        })
        .unwrap();
    // The strategies are meant to reach the planner too.
    assert!(opened.get() > 0, "no session was opened");
    assert!(planned.get() > 0, "no step was planned");
    assert_healthy();
}
