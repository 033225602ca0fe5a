//! The OpenAPI document: the checked-in copy is current, the server serves
//! it, every documented operation is routed and answers a documented
//! status, and the examples and live bodies fit the documented schemas.
//!
//! To regenerate `openapi/openapi.json` after changing the API:
//! `VIGIL_UPDATE_OPENAPI=1 cargo test --test api openapi`.

use std::path::PathBuf;

use reqwest::{Method, StatusCode, header};
use serde_json::{Map, Value};
use vigil::http::openapi::spec_json;

use crate::helpers::spawn_app;

const REGENERATE: &str = "VIGIL_UPDATE_OPENAPI=1 cargo test --test api openapi";

fn checked_in_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("openapi/openapi.json")
}

fn document() -> Value {
    serde_json::from_str(&spec_json()).unwrap()
}

#[test]
fn checked_in_document_is_current() {
    let generated = spec_json();
    let path = checked_in_path();
    if std::env::var_os("VIGIL_UPDATE_OPENAPI").is_some() {
        std::fs::write(&path, &generated).unwrap();
        eprintln!("wrote {}", path.display());
        return;
    }
    let checked_in = std::fs::read_to_string(&path).unwrap_or_default();
    if checked_in != generated {
        let first_diff = checked_in
            .lines()
            .zip(generated.lines())
            .position(|(a, b)| a != b)
            .map_or_else(
                || {
                    format!(
                        "the files differ in length ({} vs {} lines)",
                        checked_in.lines().count(),
                        generated.lines().count()
                    )
                },
                |i| format!("first difference at line {}", i + 1),
            );
        panic!(
            "{} is not what the code generates ({first_diff}).\n\
             If the API change is intended, regenerate it with:\n    {REGENERATE}\n\
             and commit the result.",
            path.display()
        );
    }
}

#[test]
fn info_is_pinned() {
    let doc = document();
    assert_eq!(doc["openapi"], "3.1.0");
    assert_eq!(doc["info"]["title"], "Vigil planning API");
    assert_eq!(doc["info"]["version"], "1");
    assert!(
        doc["info"]["description"]
            .as_str()
            .is_some_and(|d| !d.is_empty())
    );
}

#[tokio::test]
async fn served_document_is_the_generated_one() {
    let app = spawn_app().await;
    let res = app.get("/openapi.json").await;
    assert_eq!(res.status(), StatusCode::OK);
    assert_eq!(res.headers()[header::CONTENT_TYPE], "application/json");
    let body = res.text().await.unwrap();
    assert_eq!(body, spec_json());
}

/// A small JSON Schema (2020-12) checker for the keywords the document
/// uses. Returns the first mismatch as `path: reason`.
struct Checker<'a> {
    doc: &'a Value,
}

impl Checker<'_> {
    fn resolve(&self, reference: &str) -> &Value {
        let pointer = reference.strip_prefix('#').unwrap();
        self.doc
            .pointer(pointer)
            .unwrap_or_else(|| panic!("dangling $ref {reference}"))
    }

    fn check(&self, schema: &Value, value: &Value, at: &str) -> Result<(), String> {
        let schema = schema.as_object().unwrap();
        if let Some(Value::String(r)) = schema.get("$ref") {
            self.check(self.resolve(r), value, at)?;
        }
        if let Some(t) = schema.get("type") {
            let types: Vec<&str> = match t {
                Value::String(t) => vec![t.as_str()],
                Value::Array(ts) => ts.iter().map(|t| t.as_str().unwrap()).collect(),
                other => panic!("bad type {other}"),
            };
            if !types.iter().any(|t| has_type(value, t)) {
                return Err(format!("{at}: {value} is not of type {t}"));
            }
        }
        if let Some(Value::Array(options)) = schema.get("enum")
            && !options.contains(value)
        {
            return Err(format!("{at}: {value} is not one of {options:?}"));
        }
        if let Some(Value::Array(options)) = schema.get("oneOf") {
            let fits = options
                .iter()
                .filter(|o| self.check(o, value, at).is_ok())
                .count();
            if fits != 1 {
                return Err(format!("{at}: {value} fits {fits} of the oneOf options"));
            }
        }
        if let Some(Value::Array(all)) = schema.get("allOf") {
            for s in all {
                self.check(s, value, at)?;
            }
        }
        if let Some(x) = value.as_f64() {
            let bound = |k: &str| schema.get(k).and_then(Value::as_f64);
            if bound("minimum").is_some_and(|m| x < m)
                || bound("maximum").is_some_and(|m| x > m)
                || bound("exclusiveMinimum").is_some_and(|m| x <= m)
            {
                return Err(format!("{at}: {x} is out of bounds"));
            }
        }
        if let Some(items) = value.as_array() {
            let len = items.len() as u64;
            let bound = |k: &str| schema.get(k).and_then(Value::as_u64);
            if bound("minItems").is_some_and(|m| len < m)
                || bound("maxItems").is_some_and(|m| len > m)
            {
                return Err(format!("{at}: {len} items is out of bounds"));
            }
            if let Some(item_schema) = schema.get("items") {
                for (i, item) in items.iter().enumerate() {
                    self.check(item_schema, item, &format!("{at}[{i}]"))?;
                }
            }
        }
        if let Some(fields) = value.as_object() {
            let empty = Map::new();
            let properties = schema
                .get("properties")
                .and_then(Value::as_object)
                .unwrap_or(&empty);
            for required in schema
                .get("required")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
            {
                let name = required.as_str().unwrap();
                if !fields.contains_key(name) {
                    return Err(format!("{at}: missing required `{name}`"));
                }
            }
            for (name, v) in fields {
                match properties.get(name) {
                    Some(p) => self.check(p, v, &format!("{at}.{name}"))?,
                    None if schema.get("additionalProperties") == Some(&Value::Bool(false)) => {
                        return Err(format!("{at}: unknown property `{name}`"));
                    }
                    None => {}
                }
            }
        }
        Ok(())
    }
}

fn has_type(v: &Value, t: &str) -> bool {
    match t {
        "null" => v.is_null(),
        "boolean" => v.is_boolean(),
        "string" => v.is_string(),
        "array" => v.is_array(),
        "object" => v.is_object(),
        "number" => v.is_number(),
        "integer" => v.is_i64() || v.is_u64() || v.as_f64().is_some_and(|x| x.fract() == 0.0),
        other => panic!("unknown type {other}"),
    }
}

/// Follows a `$ref` to a reusable component, if the value is one.
fn deref<'a>(doc: &'a Value, v: &'a Value) -> &'a Value {
    match v.get("$ref").and_then(Value::as_str) {
        Some(r) => doc.pointer(r.strip_prefix('#').unwrap()).unwrap(),
        None => v,
    }
}

/// Every (method, path, operation) of the document.
fn operations(doc: &Value) -> Vec<(Method, String, Value)> {
    let mut ops = Vec::new();
    for (path, item) in doc["paths"].as_object().unwrap() {
        for (method, op) in item.as_object().unwrap() {
            let method = Method::from_bytes(method.to_uppercase().as_bytes()).unwrap();
            ops.push((method, path.clone(), op.clone()));
        }
    }
    ops
}

/// Every example of a media type object, by name.
fn media_examples(media: &Value) -> Vec<(String, Value)> {
    let mut out = Vec::new();
    if let Some(e) = media.get("example") {
        out.push(("example".to_owned(), e.clone()));
    }
    for (name, e) in media
        .get("examples")
        .and_then(Value::as_object)
        .into_iter()
        .flatten()
    {
        out.push((name.clone(), e["value"].clone()));
    }
    out
}

#[test]
fn every_example_fits_its_schema() {
    let doc = document();
    let checker = Checker { doc: &doc };
    let mut checked = 0;
    for (name, schema) in doc["components"]["schemas"].as_object().unwrap() {
        for (i, example) in schema
            .get("examples")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .enumerate()
        {
            checker
                .check(schema, example, &format!("schemas.{name}.examples[{i}]"))
                .unwrap();
            checked += 1;
        }
    }
    for (method, path, op) in operations(&doc) {
        let mut media = Vec::new();
        if let Some(body) = op.get("requestBody") {
            for (ct, m) in body["content"].as_object().unwrap() {
                media.push((format!("{method} {path} request {ct}"), m.clone()));
            }
        }
        for (status, response) in op["responses"].as_object().unwrap() {
            let response = deref(&doc, response);
            for (ct, m) in response
                .get("content")
                .and_then(Value::as_object)
                .into_iter()
                .flatten()
            {
                media.push((format!("{method} {path} {status} {ct}"), m.clone()));
            }
        }
        for (at, m) in media {
            for (name, example) in media_examples(&m) {
                let schema = m.get("schema").unwrap_or_else(|| panic!("{at}: no schema"));
                checker
                    .check(schema, &example, &format!("{at} ({name})"))
                    .unwrap();
                if at.contains("problem+json") {
                    let status: u64 = at.split(' ').nth(2).unwrap().parse().unwrap();
                    assert_eq!(example["status"], status, "{at} ({name})");
                }
                checked += 1;
            }
        }
    }
    assert!(checked > 30, "only {checked} examples");
}

#[test]
fn every_error_response_is_a_problem() {
    let doc = document();
    for (method, path, op) in operations(&doc) {
        let responses = op["responses"].as_object().unwrap();
        assert!(
            responses.keys().any(|s| s.starts_with('2')),
            "{method} {path}"
        );
        for (status, response) in responses {
            if !status.starts_with('4') && !status.starts_with('5') {
                continue;
            }
            let content = deref(&doc, response)["content"].as_object().unwrap();
            assert_eq!(content.len(), 1, "{method} {path} {status}");
            assert_eq!(
                content["application/problem+json"]["schema"]["$ref"],
                "#/components/schemas/Problem",
                "{method} {path} {status}"
            );
        }
        if path.starts_with("/v1/") {
            for status in ["401", "503", "504"] {
                assert!(
                    responses.contains_key(status),
                    "{method} {path} lacks {status}"
                );
            }
        }
    }
}

/// Each documented operation, sent with its first request example and
/// `paper-v10` for `{id}`, reaches a handler (no route 404 or 405) and
/// answers a documented status, content type and body.
#[tokio::test]
async fn every_documented_operation_is_served_as_documented() {
    let doc = document();
    let checker = Checker { doc: &doc };
    let app = spawn_app().await;
    let ops = operations(&doc);
    assert!(ops.len() >= 9, "{} operations", ops.len());
    for (method, path, op) in ops {
        let url = app.url(&path.replace("{id}", "paper-v10"));
        let mut req = app.client.request(method.clone(), url);
        if let Some(body) = op.get("requestBody") {
            let media = &body["content"]["application/json"];
            let (_, example) = media_examples(media).into_iter().next().unwrap();
            req = req.json(&example);
        }
        let res = req.send().await.unwrap();
        let status = res.status();
        let ct = res
            .headers()
            .get(header::CONTENT_TYPE)
            .map(|v| v.to_str().unwrap().to_owned());
        let text = res.text().await.unwrap();
        let at = format!("{method} {path} → {status}");
        assert_ne!(status, StatusCode::METHOD_NOT_ALLOWED, "{at}: {text}");
        assert!(
            !text.contains("/problems/not-found\""),
            "{at}: the route is not served: {text}"
        );
        let response = op["responses"]
            .get(status.as_str())
            .unwrap_or_else(|| panic!("{at}: undocumented status: {text}"));
        let response = deref(&doc, response);
        match response.get("content").and_then(Value::as_object) {
            None => assert!(text.is_empty(), "{at}: documented without a body: {text}"),
            Some(content) => {
                let ct = ct.unwrap_or_else(|| panic!("{at}: no content type"));
                let media = content
                    .get(&ct)
                    .unwrap_or_else(|| panic!("{at}: undocumented content type {ct}"));
                let body = if ct.contains("json") {
                    serde_json::from_str(&text).unwrap()
                } else {
                    Value::String(text)
                };
                checker.check(&media["schema"], &body, &at).unwrap();
            }
        }
    }
}

/// The names of an object schema's properties, sorted.
fn property_names(schema: &Value) -> Vec<String> {
    let mut names: Vec<String> = schema["properties"]
        .as_object()
        .unwrap()
        .keys()
        .cloned()
        .collect();
    names.sort();
    names
}

/// `POST /v1/plan`'s doc-only body schema is one of two objects, each
/// `PlanRequest`'s fields and one more, required: `scenario_id` or
/// `scenario`. A body with both or neither matches neither.
#[test]
fn inline_plan_request_extends_plan_request() {
    let doc = document();
    let schemas = &doc["components"]["schemas"];
    let fields = |name: &str| property_names(&schemas[name]);
    let refs: Vec<&str> = schemas["InlinePlanRequest"]["oneOf"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["$ref"].as_str().unwrap())
        .collect();
    assert_eq!(
        refs,
        [
            "#/components/schemas/PlanRequestById",
            "#/components/schemas/PlanRequestWithScenario"
        ]
    );
    for (name, extra) in [
        ("PlanRequestById", "scenario_id"),
        ("PlanRequestWithScenario", "scenario"),
    ] {
        let mut expected = fields("PlanRequest");
        expected.push(extra.to_owned());
        expected.sort();
        assert_eq!(fields(name), expected, "{name}");
        let mut required = schemas["PlanRequest"]["required"]
            .as_array()
            .unwrap()
            .clone();
        required.insert(0, Value::from(extra));
        assert_eq!(schemas[name]["required"], Value::Array(required), "{name}");
        assert_eq!(schemas[name]["additionalProperties"], false, "{name}");
    }
    let checker = Checker { doc: &doc };
    let body = |v: Value| {
        let schema = serde_json::json!({"$ref": "#/components/schemas/InlinePlanRequest"});
        checker.check(&schema, &v, "$")
    };
    let sensors = serde_json::json!([{"id": "a", "x": 1.0, "y": 2.0}]);
    let spec = serde_json::to_value(vigil::scenario::paper_spec(10.0)).unwrap();
    assert!(body(serde_json::json!({"scenario_id": "paper-v10", "sensors": sensors})).is_ok());
    assert!(body(serde_json::json!({"scenario": spec, "sensors": sensors})).is_ok());
    assert!(body(serde_json::json!({"sensors": sensors})).is_err());
    assert!(
        body(serde_json::json!({"scenario_id": "paper-v10", "scenario": spec, "sensors": sensors}))
            .is_err()
    );
}

/// `POST /v1/sessions`' two body shapes take every field a session's
/// settings parse (`SessionSettings`) and their scenario, by id or inline:
/// a client generated from the document can ask for all of them (the
/// shapes once lacked `learn_rates`, `tolerance`, `certify` and
/// `objective`, which the server took).
#[test]
fn session_bodies_take_every_setting() {
    let doc = document();
    let schemas = &doc["components"]["schemas"];
    let fields = |name: &str| property_names(&schemas[name]);
    // Every field set: a field added to the settings fails to compile here.
    let all = vigil::session::SessionSettings {
        horizon: Some(3.into()),
        estimator: Some(vigil::planner::EstimatorKind::Exact),
        coordination: Some(vigil::coordination::Coordination::Priority),
        observed: Some(vigil::planner::Observed::Sensors),
        objective: Some(vigil::coordination::Objective::Detections),
        min_separation: Some(0.into()),
        history_steps: Some(16.into()),
        certify: Some(true),
        learn_rates: Some(true),
        tolerance: Some(Default::default()),
    };
    let mut settings: Vec<String> = serde_json::to_value(&all)
        .unwrap()
        .as_object()
        .unwrap()
        .keys()
        .cloned()
        .collect();
    settings.sort();
    assert_eq!(fields("SessionSettings"), settings);
    let checker = Checker { doc: &doc };
    for (name, extra, value) in [
        (
            "SessionRequestById",
            "scenario_id",
            Value::from("paper-v10"),
        ),
        (
            "SessionRequestWithScenario",
            "scenario",
            serde_json::to_value(vigil::scenario::paper_spec(10.0)).unwrap(),
        ),
    ] {
        let mut expected = settings.clone();
        expected.push(extra.to_owned());
        expected.sort();
        assert_eq!(fields(name), expected, "{name}");
        assert_eq!(
            schemas[name]["required"],
            serde_json::json!([extra]),
            "{name}"
        );
        assert_eq!(schemas[name]["additionalProperties"], false, "{name}");
        let mut body = serde_json::to_value(&all).unwrap();
        body[extra] = value;
        let schema = serde_json::json!({"$ref": format!("#/components/schemas/{name}")});
        assert!(checker.check(&schema, &body, "$").is_ok(), "{name}: {body}");
    }
}

/// The checker above is strict enough to be worth trusting.
#[test]
fn the_schema_checker_rejects_mismatches() {
    let doc = document();
    let checker = Checker { doc: &doc };
    let check = |schema: &str, value: Value| {
        let schema = serde_json::json!({"$ref": format!("#/components/schemas/{schema}")});
        checker.check(&schema, &value, "$")
    };
    let sensor = serde_json::json!({"id": "a", "x": 1.0, "y": 2.0});
    assert!(
        check(
            "PlanRequest",
            serde_json::json!({"sensors": [sensor], "estimator": "paper"})
        )
        .is_ok()
    );
    assert!(check("PlanRequest", serde_json::json!({"sensors": []})).is_err());
    assert!(
        check(
            "PlanRequest",
            serde_json::json!({"sensors": [sensor], "bogus": 1})
        )
        .is_err()
    );
    assert!(
        check(
            "PlanRequest",
            serde_json::json!({"sensors": [sensor], "horizon": 13})
        )
        .is_err()
    );
    assert!(
        check(
            "PlanRequest",
            serde_json::json!({"sensors": [sensor], "estimator": "x"})
        )
        .is_err()
    );
    assert!(
        check(
            "PlanRequest",
            serde_json::json!({"sensors": [{"id": true, "x": 1, "y": 1}]})
        )
        .is_err()
    );
    assert!(
        check(
            "FovSpec",
            serde_json::json!({"shape": "circle", "radius": 3})
        )
        .is_ok()
    );
    assert!(
        check(
            "FovSpec",
            serde_json::json!({"shape": "square", "radius": 3})
        )
        .is_err()
    );
    assert!(
        check(
            "FovSpec",
            serde_json::json!({"shape": "circle", "radius": 0})
        )
        .is_err()
    );
    assert!(check("PlanResponse", serde_json::json!({})).is_err());
}

/// The reverse of the test above: every path the router declares (read from
/// `src/http/mod.rs`, where `router()` lives) is in the document.
#[test]
fn every_routed_path_is_documented() {
    let source =
        std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src/http/mod.rs"))
            .unwrap();
    let routed: Vec<&str> = source
        .split(".route(")
        .skip(1)
        .filter_map(|rest| rest.trim_start().strip_prefix('"')?.split('"').next())
        .collect();
    assert!(routed.len() >= 8, "found only {routed:?}");
    let doc = document();
    for path in routed {
        assert!(
            doc["paths"].get(path).is_some(),
            "{path} is routed but not in the OpenAPI document: add a #[utoipa::path] for it \
             to src/http/openapi.rs's ApiDoc, then run {REGENERATE}"
        );
    }
}

/// The bounds written into the schemas are the code's constants.
#[test]
fn schema_bounds_are_the_code_limits() {
    use vigil::limits::{
        MAX_HISTORY_POSITIONS, MAX_HISTORY_STEPS, MAX_HORIZON, MAX_MIN_SEPARATION, MAX_SENSORS,
        MAX_SOURCES, MAX_SPEED_CLASSES, MAX_TARGETS,
    };
    let doc = document();
    let schemas = &doc["components"]["schemas"];
    for request in ["PlanRequest", "PlanRequestById", "PlanRequestWithScenario"] {
        let p = &schemas[request]["properties"];
        assert_eq!(p["sensors"]["maxItems"], MAX_SENSORS, "{request}");
        assert_eq!(p["sensors"]["minItems"], 1, "{request}");
        assert_eq!(p["targets"]["maxItems"], MAX_TARGETS, "{request}");
        assert_eq!(p["history"]["maxItems"], MAX_HISTORY_STEPS, "{request}");
        assert_eq!(
            p["history"]["items"]["maxItems"], MAX_HISTORY_POSITIONS,
            "{request}"
        );
        assert_eq!(p["horizon"]["maximum"], MAX_HORIZON, "{request}");
        assert_eq!(p["horizon"]["minimum"], 1, "{request}");
        assert_eq!(p["horizon"]["type"], serde_json::json!(["integer", "null"]));
        assert_eq!(
            p["min_separation"]["maximum"], MAX_MIN_SEPARATION,
            "{request}"
        );
        assert_eq!(p["min_separation"]["minimum"], 0, "{request}");
    }
    let spec = &schemas["ScenarioSpec"]["properties"];
    assert_eq!(spec["sources"]["maxItems"], MAX_SOURCES);
    assert_eq!(spec["sources"]["minItems"], 1);
    assert_eq!(spec["horizon"]["maximum"], MAX_HORIZON);
    assert_eq!(spec["min_separation"]["maximum"], MAX_MIN_SEPARATION);
    let source = &schemas["SourceSpec"]["properties"];
    assert_eq!(source["speeds"]["maxItems"], MAX_SPEED_CLASSES);
    assert_eq!(source["spread"]["maximum"], 180);
    // The variants of a field of view take no other fields.
    for variant in schemas["FovSpec"]["oneOf"].as_array().unwrap() {
        assert_eq!(variant["additionalProperties"], false);
    }
}
