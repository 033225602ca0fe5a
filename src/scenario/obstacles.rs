//! The spec's `obstacles`, validated into [`Obstacles`].

use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use super::ValidationError;
use crate::geometry::{Point, Rect};
use crate::limits::{
    MAX_OBSTACLE_COORDINATE, MAX_OBSTACLE_VERTICES, MAX_OBSTACLES, MIN_OBSTACLE_VERTICES,
};
use crate::obstacle::{Obstacle, ObstacleKind, Obstacles, Polygon};

/// An obstacle as clients send it: a convex polygon and what it blocks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
#[schema(examples(
    json!({"polygon": [[100.0, 40.0], [140.0, 40.0], [140.0, 90.0], [100.0, 90.0]], "kind": "building"})
))]
pub struct ObstacleSpec {
    /// The outline: 3 to 32 vertices `[x, y]` of a convex polygon, in zone
    /// coordinates, in either order around it, no vertex repeated and no
    /// three consecutive ones collinear, each coordinate within ±1e9. It
    /// may cross the zone's edge but not lie wholly outside it.
    #[schema(value_type = Vec<Vec<f64>>)]
    #[serde(deserialize_with = "vertices")]
    pub polygon: Vec<[f64; 2]>,
    /// `building` (the default) blocks sight, ends the flight of a target
    /// that enters it and blocks ground sensors' cells; `screen` (trees, a
    /// hedge, smoke) blocks sight only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<ObstacleKindName>)]
    pub kind: Option<String>,
}

/// Reads a polygon's vertices, each `[x, y]`. A vertex of another length
/// is refused as such ("invalid length 3, expected a vertex [x, y]"):
/// serde_json says of a fixed-size array that goes on that the JSON fails
/// to parse ("trailing characters").
fn vertices<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<[f64; 2]>, D::Error> {
    struct Vertex([f64; 2]);
    impl<'de> Deserialize<'de> for Vertex {
        fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            struct Visitor;
            impl<'de> serde::de::Visitor<'de> for Visitor {
                type Value = Vertex;
                fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                    f.write_str("a vertex [x, y]")
                }
                fn visit_seq<A: serde::de::SeqAccess<'de>>(
                    self,
                    mut seq: A,
                ) -> Result<Vertex, A::Error> {
                    let mut xy = [0.0; 2];
                    let mut len = 0;
                    while let Some(v) = seq.next_element::<f64>()? {
                        if let Some(slot) = xy.get_mut(len) {
                            *slot = v;
                        }
                        len += 1;
                    }
                    if len != 2 {
                        return Err(serde::de::Error::invalid_length(len, &self));
                    }
                    Ok(Vertex(xy))
                }
            }
            d.deserialize_seq(Visitor)
        }
    }
    let list: Vec<Vertex> = Vec::deserialize(d)?;
    Ok(list.into_iter().map(|v| v.0).collect())
}

/// The names of the obstacle kinds (for the OpenAPI document; the spec
/// keeps the name as sent so that an unknown one gets a 422 naming it).
#[derive(ToSchema)]
#[schema(rename_all = "lowercase")]
#[allow(dead_code)]
pub enum ObstacleKindName {
    /// Blocks sight, stops targets and ground sensors.
    Building,
    /// Blocks sight only.
    Screen,
}

/// Validates the obstacles against the zone `zone`. Canonical form: no
/// `kind` for a building (the default).
pub(super) fn validate(
    specs: &[ObstacleSpec],
    zone: &Rect,
) -> Result<(Obstacles, Vec<ObstacleSpec>), ValidationError> {
    if specs.len() > MAX_OBSTACLES {
        return Err(ValidationError::new(
            "obstacles",
            format!("at most {MAX_OBSTACLES} obstacles, got {}", specs.len()),
        ));
    }
    let mut list = Vec::with_capacity(specs.len());
    let mut canonical = Vec::with_capacity(specs.len());
    for (i, spec) in specs.iter().enumerate() {
        let kind = match spec.kind.as_deref() {
            None | Some("building") => ObstacleKind::Building,
            Some("screen") => ObstacleKind::Screen,
            Some(other) => {
                return Err(ValidationError::new(
                    format!("obstacles[{i}].kind"),
                    format!("unknown kind {other:?}: `building` or `screen`"),
                ));
            }
        };
        let field = format!("obstacles[{i}].polygon");
        let n = spec.polygon.len();
        if !(MIN_OBSTACLE_VERTICES..=MAX_OBSTACLE_VERTICES).contains(&n) {
            return Err(ValidationError::new(
                field,
                format!("{MIN_OBSTACLE_VERTICES} to {MAX_OBSTACLE_VERTICES} vertices, got {n}"),
            ));
        }
        // (Not finite: Polygon::new names it.)
        if let Some(j) = spec.polygon.iter().position(|v| {
            v.iter()
                .any(|c| c.is_finite() && c.abs() > MAX_OBSTACLE_COORDINATE)
        }) {
            return Err(ValidationError::new(
                field,
                format!(
                    "vertex {j} has a coordinate beyond ±{MAX_OBSTACLE_COORDINATE:e}, the most any may have"
                ),
            ));
        }
        let points: Vec<Point> = spec
            .polygon
            .iter()
            .map(|&[x, y]| Point::new(x, y))
            .collect();
        let polygon = Polygon::new(&points)
            .map_err(|e| ValidationError::new(field.clone(), e.to_string()))?;
        if polygon.area_within(zone) <= 0.0 {
            return Err(ValidationError::new(field, "lies wholly outside the zone"));
        }
        list.push(Obstacle { polygon, kind });
        canonical.push(ObstacleSpec {
            polygon: spec.polygon.clone(),
            kind: (kind == ObstacleKind::Screen).then(|| "screen".to_owned()),
        });
    }
    Ok((Obstacles::new(list), canonical))
}
