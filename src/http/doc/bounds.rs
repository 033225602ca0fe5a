//! The bounds the OpenAPI document states, written from [`crate::limits`]:
//! utoipa's derive takes only literals, so the request types' schemas carry
//! none, and [`Bounds`] writes each from its one definition.

use utoipa::Modify;
use utoipa::openapi::schema::{ArrayItems, ObjectBuilder, Schema, Type};
use utoipa::openapi::{OpenApi, RefOr};

use crate::limits::{
    MAX_BUDGET_MS, MAX_HISTORY_POSITIONS, MAX_HISTORY_STEPS, MAX_HORIZON,
    MAX_IDEMPOTENCY_KEY_CHARS, MAX_MIN_SEPARATION, MAX_NAME_CHARS, MAX_NO_GO,
    MAX_OBSTACLE_VERTICES, MAX_OBSTACLES, MAX_RAYS_PER_PI, MAX_SENSOR_SPEED, MAX_SENSOR_TYPES,
    MAX_SENSORS, MAX_SOURCES, MAX_SPEED_CLASSES, MAX_TARGETS, MAX_TYPE_NAME_CHARS,
    MIN_OBSTACLE_VERTICES, MIN_RAYS_PER_PI,
};

/// A bound on one property.
#[derive(Debug, Clone, Copy)]
enum Bound {
    /// `maximum` of an integer.
    Maximum(usize),
    /// `minimum` and `maximum` of an integer.
    Range(usize, usize),
    /// `maxItems` of an array.
    MaxItems(usize),
    /// `maxItems` of an array of arrays, and of each of its items.
    MaxItemsEach(usize, usize),
    /// `maxLength` of a string.
    MaxLength(usize),
    /// `minItems` and `maxItems` of an array of points, each exactly two
    /// numbers.
    Points(usize, usize),
}

/// The bodies shaped like a plan request (the planner's input).
const PLAN_BODIES: &[&str] = &[
    "PlanRequest",
    "PlanRequestById",
    "PlanRequestWithScenario",
    "EvaluateBody",
    "EvaluateRequestById",
    "EvaluateRequestWithScenario",
    "StepRequest",
];

/// The bodies that set a session's defaults.
const SESSION_BODIES: &[&str] = &[
    "SessionRequestById",
    "SessionRequestWithScenario",
    "SessionSettings",
];

/// Which schemas' property states which bound; a schema without the
/// property is left alone.
const RULES: &[(&[&str], &str, Bound)] = &[
    (PLAN_BODIES, "horizon", Bound::Maximum(MAX_HORIZON)),
    (SESSION_BODIES, "horizon", Bound::Maximum(MAX_HORIZON)),
    (&["ScenarioSpec"], "horizon", Bound::Maximum(MAX_HORIZON)),
    (
        PLAN_BODIES,
        "min_separation",
        Bound::Maximum(MAX_MIN_SEPARATION),
    ),
    (
        SESSION_BODIES,
        "min_separation",
        Bound::Maximum(MAX_MIN_SEPARATION),
    ),
    (
        &["ScenarioSpec"],
        "min_separation",
        Bound::Maximum(MAX_MIN_SEPARATION),
    ),
    (
        PLAN_BODIES,
        "budget_ms",
        Bound::Maximum(MAX_BUDGET_MS as usize),
    ),
    (PLAN_BODIES, "sensors", Bound::MaxItems(MAX_SENSORS)),
    (PLAN_BODIES, "paths", Bound::MaxItems(MAX_SENSORS)),
    (PLAN_BODIES, "targets", Bound::MaxItems(MAX_TARGETS)),
    (PLAN_BODIES, "detections", Bound::MaxItems(MAX_TARGETS)),
    (
        PLAN_BODIES,
        "history",
        Bound::MaxItemsEach(MAX_HISTORY_STEPS, MAX_HISTORY_POSITIONS),
    ),
    (
        SESSION_BODIES,
        "history_steps",
        Bound::Maximum(MAX_HISTORY_STEPS),
    ),
    (&["ScenarioSpec"], "name", Bound::MaxLength(MAX_NAME_CHARS)),
    (
        &["ScenarioSpec"],
        "rays_per_pi",
        Bound::Range(MIN_RAYS_PER_PI, MAX_RAYS_PER_PI),
    ),
    (&["ScenarioSpec"], "sources", Bound::MaxItems(MAX_SOURCES)),
    (&["ScenarioSpec"], "no_go", Bound::MaxItems(MAX_NO_GO)),
    (
        &["ScenarioSpec"],
        "obstacles",
        Bound::MaxItems(MAX_OBSTACLES),
    ),
    (
        &["ObstacleSpec"],
        "polygon",
        Bound::Points(MIN_OBSTACLE_VERTICES, MAX_OBSTACLE_VERTICES),
    ),
    (
        &["ScenarioSpec"],
        "sensor_speed",
        Bound::Maximum(MAX_SENSOR_SPEED),
    ),
    (
        &["SensorTypeSpec"],
        "speed",
        Bound::Maximum(MAX_SENSOR_SPEED),
    ),
    (
        &["SourceSpec"],
        "speeds",
        Bound::MaxItems(MAX_SPEED_CLASSES),
    ),
    (&["SensorPathIn"], "path", Bound::MaxItems(MAX_HORIZON)),
    (
        &["SensorIn", "PositionIn"],
        "type",
        Bound::MaxLength(MAX_TYPE_NAME_CHARS),
    ),
];

/// Writes every bound of `RULES`, the length of a step's `Idempotency-Key`,
/// and the count and the name pattern of a scenario's sensor types (a map,
/// which the derive cannot bound).
#[derive(Debug)]
pub struct Bounds;

impl Modify for Bounds {
    fn modify(&self, doc: &mut OpenApi) {
        // The session step's Idempotency-Key header.
        let operations = doc.paths.paths.values_mut().filter_map(|p| p.post.as_mut());
        for parameter in operations.flat_map(|o| o.parameters.iter_mut().flatten()) {
            if let RefOr::T(parameter) = parameter
                && parameter.name == "Idempotency-Key"
                && let Some(RefOr::T(schema)) = parameter.schema.as_mut()
            {
                apply(schema, Bound::MaxLength(MAX_IDEMPOTENCY_KEY_CHARS));
            }
        }
        let Some(components) = doc.components.as_mut() else {
            return;
        };
        for &(schemas, property, bound) in RULES {
            for &name in schemas {
                let Some(RefOr::T(Schema::Object(object))) = components.schemas.get_mut(name)
                else {
                    continue;
                };
                if let Some(RefOr::T(schema)) = object.properties.get_mut(property) {
                    apply(schema, bound);
                }
            }
        }
        if let Some(RefOr::T(Schema::Object(spec))) = components.schemas.get_mut("ScenarioSpec")
            && let Some(RefOr::T(Schema::Object(types))) = spec.properties.get_mut("sensor_types")
        {
            types.max_properties = Some(MAX_SENSOR_TYPES);
            types.property_names = Some(Box::new(Schema::Object(
                ObjectBuilder::new()
                    .schema_type(Type::String)
                    .pattern(Some(format!("^[A-Za-z0-9_-]{{1,{MAX_TYPE_NAME_CHARS}}}$")))
                    .build(),
            )));
        }
    }
}

/// Writes `bound` into a property's schema of the kind it bounds.
fn apply(schema: &mut Schema, bound: Bound) {
    match (schema, bound) {
        (Schema::Object(o), Bound::Maximum(max)) => o.maximum = Some(max.into()),
        (Schema::Object(o), Bound::Range(min, max)) => {
            o.minimum = Some(min.into());
            o.maximum = Some(max.into());
        }
        (Schema::Object(o), Bound::MaxLength(max)) => o.max_length = Some(max),
        (Schema::Array(a), Bound::MaxItems(max)) => a.max_items = Some(max),
        (Schema::Array(a), Bound::Points(min, max)) => {
            a.min_items = Some(min);
            a.max_items = Some(max);
            if let ArrayItems::RefOrSchema(item) = &mut a.items
                && let RefOr::T(Schema::Array(item)) = item.as_mut()
            {
                item.min_items = Some(2);
                item.max_items = Some(2);
            }
        }
        (Schema::Array(a), Bound::MaxItemsEach(outer, inner)) => {
            a.max_items = Some(outer);
            if let ArrayItems::RefOrSchema(item) = &mut a.items
                && let RefOr::T(Schema::Array(item)) = item.as_mut()
            {
                item.max_items = Some(inner);
            }
        }
        _ => {}
    }
}
