//! The fleet: sensor types (a field of view, a speed in cells per step, a
//! detection probability), the looks they take, and the ground they may not
//! stand on.
//!
//! A *look* is one sensor's field of view at one step with its detection
//! probability: a target inside it is detected with probability `p_detect`,
//! independently of every other look. The paper's sensors are the type
//! `default`: the scenario's `fov`, one cell per step, `p_detect` 1.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use super::input::{Integer, ValidationError};
use crate::geometry::{Point, Region};
use crate::limits::{MAX_NO_GO, MAX_SENSOR_SPEED, MAX_SENSOR_TYPES, MAX_TYPE_NAME_CHARS};

/// Name of the type made of the scenario's top-level `fov`.
pub const DEFAULT_TYPE: &str = "default";

/// Field of view of every sensor, tagged by `shape`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(tag = "shape", rename_all = "lowercase", deny_unknown_fields)]
#[schema(examples(
    json!({"shape": "square", "half_width": 30.0}),
    json!({"shape": "circle", "radius": 30.0})
))]
pub enum FovSpec {
    /// The paper's inscribed square, `|dx|, |dy| ≤ half_width`.
    Square {
        /// Half the side of the square.
        #[schema(exclusive_minimum = 0)]
        half_width: f64,
    },
    /// A disk of the given radius (the paper's future work).
    Circle {
        /// Radius of the disk.
        #[schema(exclusive_minimum = 0)]
        radius: f64,
    },
}

/// A sensor type as clients send it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
#[schema(examples(
    json!({"fov": {"shape": "square", "half_width": 50.0}, "speed": 3, "p_detect": 0.8})
))]
pub struct SensorTypeSpec {
    /// The type's field of view.
    pub fov: FovSpec,
    /// Cells (king moves) per step, 1..=3; 1 by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>, minimum = 1)]
    pub speed: Option<Integer>,
    /// Probability of detecting a target inside the field of view at a
    /// step, in (0, 1]; 1 by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(exclusive_minimum = 0, maximum = 1)]
    pub p_detect: Option<f64>,
    /// True for a type that sees over every obstacle and may fly over
    /// buildings (a drone); false by default (a ground sensor, whose sight
    /// lines obstacles block and which never stands on a building's cell).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub elevated: Option<bool>,
}

/// A validated sensor type.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorType {
    /// Its name (`default` for the top-level field of view).
    pub name: String,
    /// Field of view.
    pub fov: FovSpec,
    /// Cells per step, 1..=[`MAX_SENSOR_SPEED`].
    pub speed: usize,
    /// Detection probability, in (0, 1].
    pub p_detect: f64,
    /// Sees over obstacles and flies over buildings.
    pub elevated: bool,
    /// Index of its view among the scenario's distinct ones
    /// ([`super::Scenario::fovs`] and [`super::Scenario::sees_over`]):
    /// types that share a field of view, and with obstacles whether they
    /// see over them, share its statistics.
    pub fov_slot: usize,
}

/// A rectangle of ground no sensor may stand on, in zone coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
#[schema(examples(json!({"x0": 150.0, "y0": 100.0, "x1": 210.0, "y1": 160.0})))]
pub struct NoGoSpec {
    /// West edge.
    pub x0: f64,
    /// South edge.
    pub y0: f64,
    /// East edge (> x0).
    pub x1: f64,
    /// North edge (> y0).
    pub y1: f64,
}

/// One look: a field of view at a step and the probability that it detects
/// a target inside it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Look {
    /// The field of view, clipped to the zone.
    pub region: Region,
    /// Detection probability, in (0, 1].
    pub p_detect: f64,
    /// The viewpoint whose sight lines the scenario's obstacles block (a
    /// ground sensor's cell centre), or `None` when nothing blocks them
    /// (an elevated sensor, or no obstacles): the look detects only the
    /// part of `region` it sees.
    pub from: Option<Point>,
}

impl Look {
    /// A look that detects everything inside `region`.
    pub fn certain(region: Region) -> Self {
        Look {
            region,
            p_detect: 1.0,
            from: None,
        }
    }

    /// Probability that a target at a point inside the look is missed.
    #[inline]
    pub fn miss(&self) -> f64 {
        1.0 - self.p_detect
    }
}

/// True when every look detects with certainty (the paper's sensors):
/// seen sets are then plain unions.
pub fn all_certain(looks: &[Look]) -> bool {
    looks.iter().all(|l| l.p_detect == 1.0)
}

fn check_fov(field: &str, fov: &FovSpec) -> Result<(), ValidationError> {
    let (name, v) = match *fov {
        FovSpec::Square { half_width } => ("half_width", half_width),
        FovSpec::Circle { radius } => ("radius", radius),
    };
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(ValidationError::new(
            format!("{field}.{name}"),
            format!("must be finite and > 0, got {v}"),
        ))
    }
}

fn check_p_detect(field: &str, p: Option<f64>) -> Result<f64, ValidationError> {
    match p {
        None => Ok(1.0),
        Some(p) if p.is_finite() && p > 0.0 && p <= 1.0 => Ok(p),
        Some(p) => Err(ValidationError::new(
            field,
            format!("must be in (0, 1], got {p}"),
        )),
    }
}

fn check_speed(field: &str, v: Option<&Integer>) -> Result<usize, ValidationError> {
    v.map_or(Ok(1), |v| v.check(field, 1..=MAX_SENSOR_SPEED))
}

fn valid_name(name: &str) -> bool {
    (1..=MAX_TYPE_NAME_CHARS).contains(&name.len())
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-')
}

/// The validated fleet of a spec: the types (`default` first), the distinct
/// fields of view, and the canonical forms of the fields that define them.
pub(super) struct Fleet {
    pub types: Vec<SensorType>,
    pub fovs: Vec<FovSpec>,
    pub sees_over: Vec<bool>,
    pub sensor_speed: Option<Integer>,
    pub p_detect: Option<f64>,
    pub sensor_types: Option<BTreeMap<String, SensorTypeSpec>>,
}

/// Validates the top-level field of view, `sensor_speed`, `p_detect` and
/// `sensor_types`. Canonical forms drop defaults, so a spec that uses none
/// of the fleet's fields keeps the id it had before they existed. With
/// `obstacles`, types that see over them get views of their own.
pub(super) fn validate_fleet(
    fov: &FovSpec,
    sensor_speed: Option<&Integer>,
    p_detect: Option<f64>,
    sensor_types: Option<&BTreeMap<String, SensorTypeSpec>>,
    obstacles: bool,
) -> Result<Fleet, ValidationError> {
    check_fov("fov", fov)?;
    let speed = check_speed("sensor_speed", sensor_speed)?;
    let p = check_p_detect("p_detect", p_detect)?;
    let mut fovs = vec![*fov];
    let mut sees_over = vec![!obstacles];
    let mut types = vec![SensorType {
        name: DEFAULT_TYPE.into(),
        fov: *fov,
        speed,
        p_detect: p,
        elevated: false,
        fov_slot: 0,
    }];
    let named = sensor_types.map_or(0, BTreeMap::len);
    if named > MAX_SENSOR_TYPES {
        return Err(ValidationError::new(
            "sensor_types",
            format!("at most {MAX_SENSOR_TYPES} sensor types, got {named}"),
        ));
    }
    let mut canonical = BTreeMap::new();
    for (name, spec) in sensor_types.into_iter().flatten() {
        let field = format!("sensor_types.{name}");
        if !valid_name(name) {
            return Err(ValidationError::new(
                "sensor_types",
                format!(
                    "type name {name:?} must be 1–{MAX_TYPE_NAME_CHARS} characters of [A-Za-z0-9_-]"
                ),
            ));
        }
        if name == DEFAULT_TYPE {
            return Err(ValidationError::new(
                field,
                "`default` is the top-level fov (with sensor_speed and p_detect); name this type otherwise",
            ));
        }
        check_fov(&format!("{field}.fov"), &spec.fov)?;
        let speed = check_speed(&format!("{field}.speed"), spec.speed.as_ref())?;
        let p = check_p_detect(&format!("{field}.p_detect"), spec.p_detect)?;
        let elevated = spec.elevated.unwrap_or(false);
        let over = elevated || !obstacles;
        let fov_slot =
            match (fovs.iter().zip(&sees_over)).position(|(f, &o)| *f == spec.fov && o == over) {
                Some(i) => i,
                None => {
                    fovs.push(spec.fov);
                    sees_over.push(over);
                    fovs.len() - 1
                }
            };
        types.push(SensorType {
            name: name.clone(),
            fov: spec.fov,
            speed,
            p_detect: p,
            elevated,
            fov_slot,
        });
        canonical.insert(
            name.clone(),
            SensorTypeSpec {
                fov: spec.fov,
                speed: (speed != 1).then(|| speed.into()),
                p_detect: (p != 1.0).then_some(p),
                elevated: elevated.then_some(true),
            },
        );
    }
    Ok(Fleet {
        sensor_speed: (types[0].speed != 1).then(|| types[0].speed.into()),
        p_detect: (types[0].p_detect != 1.0).then_some(types[0].p_detect),
        sensor_types: (!canonical.is_empty()).then_some(canonical),
        types,
        fovs,
        sees_over,
    })
}

/// Validates the no-go rectangles and marks the blocked cells (those whose
/// centre lies in a rectangle, edges included), row-major. Empty when
/// nothing is blocked.
pub(super) fn blocked_cells(
    no_go: &[NoGoSpec],
    cols: i32,
    rows: i32,
    cell_size: f64,
) -> Result<Vec<bool>, ValidationError> {
    if no_go.len() > MAX_NO_GO {
        return Err(ValidationError::new(
            "no_go",
            format!("at most {MAX_NO_GO} rectangles, got {}", no_go.len()),
        ));
    }
    let mut blocked = Vec::new();
    for (i, r) in no_go.iter().enumerate() {
        for (name, v) in [("x0", r.x0), ("y0", r.y0), ("x1", r.x1), ("y1", r.y1)] {
            if !v.is_finite() {
                return Err(ValidationError::new(
                    format!("no_go[{i}].{name}"),
                    format!("must be a finite number, got {v}"),
                ));
            }
        }
        if r.x0 >= r.x1 {
            return Err(ValidationError::new(
                format!("no_go[{i}]"),
                format!("x0 must be < x1, got {} and {}", r.x0, r.x1),
            ));
        }
        if r.y0 >= r.y1 {
            return Err(ValidationError::new(
                format!("no_go[{i}]"),
                format!("y0 must be < y1, got {} and {}", r.y0, r.y1),
            ));
        }
        if blocked.is_empty() {
            blocked = vec![false; cols as usize * rows as usize];
        }
        // Columns whose centre (c + ½)·size lies in [x0, x1].
        let span = |a: f64, b: f64, n: i32| {
            let lo = ((a / cell_size - 0.5).ceil().max(0.0)) as i64;
            let hi = ((b / cell_size - 0.5).floor().min(n as f64 - 1.0)) as i64;
            (lo, hi)
        };
        let (c0, c1) = span(r.x0, r.x1, cols);
        let (r0, r1) = span(r.y0, r.y1, rows);
        for row in r0..=r1 {
            for col in c0..=c1 {
                blocked[row as usize * cols as usize + col as usize] = true;
            }
        }
    }
    Ok(blocked)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocked_cells_are_those_whose_centre_is_inside() {
        let r = |x0, y0, x1, y1| NoGoSpec { x0, y0, x1, y1 };
        // Cells of 10: centres at 5, 15, 25, …
        let b = blocked_cells(&[r(5.0, 0.0, 14.9, 10.0)], 4, 3, 10.0).expect("valid");
        let on: Vec<usize> = (0..12).filter(|&i| b[i]).collect();
        assert_eq!(on, vec![0]);
        let b = blocked_cells(&[r(5.0, 5.0, 15.0, 15.0)], 4, 3, 10.0).expect("valid");
        let on: Vec<usize> = (0..12).filter(|&i| b[i]).collect();
        assert_eq!(on, vec![0, 1, 4, 5]);
        // Outside the zone: nothing, and no panic.
        let b = blocked_cells(&[r(-50.0, -50.0, -10.0, 1e300)], 4, 3, 10.0).expect("valid");
        assert!(b.iter().all(|&x| !x));
        assert!(blocked_cells(&[], 4, 3, 10.0).expect("valid").is_empty());
        let e = blocked_cells(&[r(1.0, 0.0, 1.0, 5.0)], 4, 3, 10.0).unwrap_err();
        assert_eq!(e.field, "no_go[0]");
        let e = blocked_cells(&[r(1.0, 0.0, f64::NAN, 5.0)], 4, 3, 10.0).unwrap_err();
        assert_eq!(e.field, "no_go[0].x1");
    }

    #[test]
    fn type_names_and_bounds() {
        let fov = FovSpec::Square { half_width: 30.0 };
        let spec = |speed: usize, p: f64| SensorTypeSpec {
            fov,
            speed: Some(speed.into()),
            p_detect: Some(p),
            elevated: None,
        };
        let one = |name: &str, s: SensorTypeSpec| BTreeMap::from([(name.to_owned(), s)]);
        let err = |m: BTreeMap<String, SensorTypeSpec>| {
            validate_fleet(&fov, None, None, Some(&m), false)
                .err()
                .map(|e| e.field)
        };
        assert_eq!(err(one("drone", spec(3, 0.5))), None);
        assert_eq!(
            err(one("drone", spec(4, 0.5))).as_deref(),
            Some("sensor_types.drone.speed")
        );
        assert_eq!(
            err(one("drone", spec(1, 0.0))).as_deref(),
            Some("sensor_types.drone.p_detect")
        );
        assert_eq!(
            err(one("no spaces", spec(1, 1.0))).as_deref(),
            Some("sensor_types")
        );
        assert_eq!(
            err(one("default", spec(1, 1.0))).as_deref(),
            Some("sensor_types.default")
        );
        // Defaults are dropped from the canonical form; a shared fov is
        // one slot.
        let f = validate_fleet(
            &fov,
            Some(&1.into()),
            Some(1.0),
            Some(&one("a", spec(1, 1.0))),
            false,
        )
        .expect("valid");
        assert_eq!(f.sensor_speed, None);
        assert_eq!(f.p_detect, None);
        assert_eq!(f.fovs.len(), 1);
        assert_eq!(f.types[1].fov_slot, 0);
        let a = f.sensor_types.expect("one type");
        assert_eq!(a["a"].speed, None);
        assert_eq!(a["a"].p_detect, None);
    }
}
