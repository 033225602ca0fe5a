//! The model: zone, lattice of cells, sources and target classes, field of
//! view.
//!
//! [`ScenarioSpec`] is what clients send; [`Scenario`] is the validated form,
//! built once by [`Scenario::new`] (parse, don't validate), so the rest of the
//! crate never re-checks input.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use utoipa::ToSchema;

use crate::geometry::{Disk, Point, Rect, Region};
use crate::limits::{
    DEFAULT_HORIZON, DEFAULT_RAYS_PER_PI_CIRCLE, DEFAULT_RAYS_PER_PI_SQUARE, MAX_CELL_STATS,
    MAX_CELLS, MAX_NAME_CHARS, MAX_POPULATION, MAX_RAYS_PER_PI, MAX_SOURCES, MIN_RAYS_PER_PI,
};

mod builtins;
mod input;
mod sensor;
mod source;

pub use builtins::{
    BUILTIN_IDS, SITE_CYCLIST, SITE_VEHICLE, SITE_WALKER, builtins, paper_spec, site_drone,
    site_fleet_spec, site_gates_spec, site_robot,
};

pub use input::{Integer, ValidationError, check_horizon, check_min_separation};
pub use sensor::{DEFAULT_TYPE, FovSpec, Look, NoGoSpec, SensorType, SensorTypeSpec, all_certain};
pub use source::{Heading, Source, SourceSpec, SpeedSpec, TargetClass, infer_heading};

/// The surveillance zone `[0,width] × [0,height]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
#[schema(examples(json!({"width": 300.0, "height": 300.0})))]
pub struct ZoneSpec {
    /// Extent east, zone units.
    #[schema(exclusive_minimum = 0)]
    pub width: f64,
    /// Extent north, zone units.
    #[schema(exclusive_minimum = 0)]
    pub height: f64,
}

/// A scenario as clients send it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
#[schema(examples(json!(paper_spec(10.0)), json!(site_gates_spec()), json!(site_fleet_spec())))]
pub struct ScenarioSpec {
    /// Free-form label.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The zone.
    pub zone: ZoneSpec,
    /// Side of a lattice cell; must divide width and height.
    #[schema(exclusive_minimum = 0)]
    pub cell_size: f64,
    /// Field of view of the sensor type `default`.
    pub fov: FovSpec,
    /// Speed of the type `default`, cells (king moves) per step (1..=3,
    /// default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>, minimum = 1)]
    pub sensor_speed: Option<Integer>,
    /// Detection probability of the type `default`, in (0, 1] (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(exclusive_minimum = 0, maximum = 1)]
    pub p_detect: Option<f64>,
    /// More sensor types, by name (at most 8; names of 1–32 characters of
    /// `[A-Za-z0-9_-]`, not `default`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensor_types: Option<BTreeMap<String, SensorTypeSpec>>,
    /// Ground no sensor may stand on: a cell whose centre lies in one of
    /// these rectangles (edges included) is blocked. Targets fly over it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub no_go: Option<Vec<NoGoSpec>>,
    /// Distance a target flies per step, for the sources that give no
    /// `speeds` (required unless every source gives them).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(exclusive_minimum = 0)]
    pub target_speed: Option<f64>,
    /// Target sources (at least one).
    #[schema(min_items = 1)]
    pub sources: Vec<SourceSpec>,
    /// Default planning horizon T (1..=12, default 3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>, minimum = 1)]
    pub horizon: Option<Integer>,
    /// Minimum separation between sensors, cells (0..=16, default 0: no
    /// rule): at every step of a plan any two sensors stand at Chebyshev
    /// distance ≥ this many cells wherever that can be kept (1: never on
    /// one cell). A plan request may override it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>, minimum = 0)]
    pub min_separation: Option<Integer>,
    /// Rays per π radians in each source's angular grid, over which the
    /// exact estimator integrates (32..=1024; default 128 when every field
    /// of view is a square, 384 otherwise). A plan's cost is about linear
    /// in it, and the error against the model falls about as its square:
    /// the measured figures are in `docs/performance.md` (*Accuracy*).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>)]
    pub rays_per_pi: Option<Integer>,
}

/// A lattice cell, `col` east and `row` north.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Cell {
    /// Column, from the west edge.
    pub col: i32,
    /// Row, from the south edge.
    pub row: i32,
}

/// A validated scenario.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// Deterministic id (a built-in's name, or derived from the canonical spec).
    pub id: String,
    /// Canonical spec: headings and horizon filled in.
    pub spec: ScenarioSpec,
    /// Zone width.
    pub width: f64,
    /// Zone height.
    pub height: f64,
    /// Cell side.
    pub cell_size: f64,
    /// Columns of the lattice.
    pub cols: i32,
    /// Rows of the lattice.
    pub rows: i32,
    /// Field of view of the type `default` (`types[0].fov`).
    pub fov: FovSpec,
    /// Sensor types; `types[0]` is `default`, the others follow by name.
    pub types: Vec<SensorType>,
    /// The distinct fields of view of the types (`fovs[0]` is `fov`).
    pub fovs: Vec<FovSpec>,
    /// Row-major: true for a cell no sensor may stand on. Empty when no
    /// cell is blocked.
    blocked: Vec<bool>,
    /// Sources.
    pub sources: Vec<Source>,
    /// Target classes (source × speed), grouped by source in source order.
    pub classes: Vec<TargetClass>,
    /// Source `j`'s classes are `classes[class_offsets[j]..class_offsets[j+1]]`.
    class_offsets: Vec<usize>,
    /// Default horizon.
    pub horizon: usize,
    /// Default minimum separation between sensors, cells (0: none).
    pub min_separation: usize,
    /// Rays per π the spec asks for (`None`: the default for its fields of
    /// view, [`Scenario::rays_per_pi`]).
    rays_per_pi: Option<usize>,
}

fn finite_positive(field: &str, v: f64) -> Result<f64, ValidationError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(ValidationError::new(
            field,
            format!("must be finite and > 0, got {v}"),
        ))
    }
}

impl Scenario {
    /// Validates a spec. Its id is derived from the canonical spec unless
    /// `id` is given (built-ins).
    pub fn new(spec: ScenarioSpec) -> Result<Self, ValidationError> {
        Self::build(spec, None)
    }

    fn build(spec: ScenarioSpec, id: Option<&str>) -> Result<Self, ValidationError> {
        if let Some(name) = &spec.name
            && name.chars().count() > MAX_NAME_CHARS
        {
            return Err(ValidationError::new(
                "name",
                format!("must be at most {MAX_NAME_CHARS} characters"),
            ));
        }
        let width = finite_positive("zone.width", spec.zone.width)?;
        let height = finite_positive("zone.height", spec.zone.height)?;
        let cell_size = finite_positive("cell_size", spec.cell_size)?;
        let whole = |field: &str, extent: f64| -> Result<i32, ValidationError> {
            let n = (extent / cell_size).round();
            if n < 1.0 || (n * cell_size - extent).abs() > 1e-9 * extent.max(1.0) {
                return Err(ValidationError::new(
                    field,
                    format!("{extent} is not a whole multiple of cell_size {cell_size}"),
                ));
            }
            if n > MAX_CELLS as f64 {
                return Err(ValidationError::new(
                    field,
                    format!("the lattice may have at most {MAX_CELLS} cells"),
                ));
            }
            Ok(n as i32)
        };
        let cols = whole("zone.width", width)?;
        let rows = whole("zone.height", height)?;
        if cols as u64 * rows as u64 > MAX_CELLS as u64 {
            return Err(ValidationError::new(
                "cell_size",
                format!(
                    "the lattice would have {cols}×{rows} = {} cells; at most {MAX_CELLS}",
                    cols as u64 * rows as u64
                ),
            ));
        }
        let fleet = sensor::validate_fleet(
            &spec.fov,
            spec.sensor_speed.as_ref(),
            spec.p_detect,
            spec.sensor_types.as_ref(),
        )?;
        let blocked =
            sensor::blocked_cells(spec.no_go.as_deref().unwrap_or(&[]), cols, rows, cell_size)?;
        if fleet.fovs.len() > 1
            && cols as u64 * rows as u64 * fleet.fovs.len() as u64 > MAX_CELL_STATS as u64
        {
            return Err(ValidationError::new(
                "sensor_types",
                format!(
                    "{} distinct fields of view on {} cells: at most {MAX_CELL_STATS} cell statistics (cells × fields of view)",
                    fleet.fovs.len(),
                    cols as u64 * rows as u64
                ),
            ));
        }
        let target_speed = spec
            .target_speed
            .map(|v| finite_positive("target_speed", v))
            .transpose()?;
        if spec.sources.is_empty() {
            return Err(ValidationError::new(
                "sources",
                "at least one source: a zone without sources has no targets",
            ));
        }
        if spec.sources.len() > MAX_SOURCES {
            return Err(ValidationError::new(
                "sources",
                format!("at most {MAX_SOURCES} sources, got {}", spec.sources.len()),
            ));
        }
        let mut sources = Vec::with_capacity(spec.sources.len());
        let mut classes = Vec::with_capacity(spec.sources.len());
        let mut canonical_sources = Vec::with_capacity(spec.sources.len());
        let mut class_offsets = vec![0];
        for (i, s) in spec.sources.iter().enumerate() {
            let v = source::validate(i, s, width, height, target_speed)?;
            classes.extend(v.speeds.iter().map(|&(speed, weight)| TargetClass {
                source: i,
                speed,
                rate: v.source.rate * weight,
            }));
            class_offsets.push(classes.len());
            sources.push(v.source);
            canonical_sources.push(v.canonical);
        }
        let diagonal = width.hypot(height);
        let population: f64 = classes.iter().map(|c| c.rate * diagonal / c.speed).sum();
        if population.is_nan() || population > MAX_POPULATION {
            return Err(ValidationError::new(
                "sources",
                format!(
                    "too many targets: Σ rate·diagonal/speed over the speed classes is {population:e}, at most {MAX_POPULATION:e}"
                ),
            ));
        }
        let horizon = check_horizon("horizon", spec.horizon.as_ref(), DEFAULT_HORIZON)?;
        let rays_per_pi = spec
            .rays_per_pi
            .as_ref()
            .map(|r| r.check("rays_per_pi", MIN_RAYS_PER_PI..=MAX_RAYS_PER_PI))
            .transpose()?;
        let min_separation =
            check_min_separation("min_separation", spec.min_separation.as_ref())?.unwrap_or(0);
        let canonical = ScenarioSpec {
            // 0 is the default: dropped, so specs keep the ids they had.
            min_separation: (min_separation > 0).then(|| min_separation.into()),
            sources: canonical_sources,
            horizon: Some(horizon.into()),
            sensor_speed: fleet.sensor_speed,
            p_detect: fleet.p_detect,
            sensor_types: fleet.sensor_types,
            no_go: spec.no_go.filter(|v| !v.is_empty()),
            ..spec
        };
        let id = match id {
            Some(id) => id.to_owned(),
            None => derive_id(&canonical),
        };
        Ok(Scenario {
            id,
            spec: canonical,
            width,
            height,
            cell_size,
            cols,
            rows,
            fov: spec.fov,
            types: fleet.types,
            fovs: fleet.fovs,
            blocked,
            sources,
            classes,
            class_offsets,
            horizon,
            min_separation,
            rays_per_pi,
        })
    }

    /// The index of the sensor type named `name`.
    pub fn type_index(&self, name: &str) -> Option<usize> {
        self.types.iter().position(|t| t.name == name)
    }

    /// True when no sensor may stand on `c` (a cell on the lattice).
    #[inline]
    pub fn is_blocked(&self, c: Cell) -> bool {
        !self.blocked.is_empty() && self.blocked[self.index(c)]
    }

    /// True when some cell is blocked.
    pub fn has_no_go(&self) -> bool {
        !self.blocked.is_empty()
    }

    /// True when a sensor may stand on `c`: on the lattice and not blocked.
    #[inline]
    pub fn is_free(&self, c: Cell) -> bool {
        self.on_lattice(c) && !self.is_blocked(c)
    }

    /// The fastest sensor type's speed, cells per step.
    pub fn max_sensor_speed(&self) -> usize {
        self.types.iter().map(|t| t.speed).max().unwrap_or(1)
    }

    /// Rays per π in each source's angular grid of the exact estimator:
    /// the spec's, else [`DEFAULT_RAYS_PER_PI_SQUARE`] when every field of
    /// view is a square, [`DEFAULT_RAYS_PER_PI_CIRCLE`] otherwise.
    pub fn rays_per_pi(&self) -> usize {
        self.rays_per_pi.unwrap_or(if self.all_square() {
            DEFAULT_RAYS_PER_PI_SQUARE
        } else {
            DEFAULT_RAYS_PER_PI_CIRCLE
        })
    }

    /// True when every sensor type's field of view is a square.
    pub fn all_square(&self) -> bool {
        self.fovs
            .iter()
            .all(|f| matches!(f, FovSpec::Square { .. }))
    }

    /// The look of a sensor of type `ty` at cell `c`.
    #[inline]
    pub fn look(&self, ty: usize, c: Cell) -> Look {
        let t = &self.types[ty];
        Look {
            region: self.fov_with(t.fov, self.centre(c)),
            p_detect: t.p_detect,
        }
    }

    /// Field of view of a sensor of type `ty` at cell `c`, clipped to the
    /// zone.
    #[inline]
    pub fn fov_region_of(&self, ty: usize, c: Cell) -> Region {
        self.fov_with(self.types[ty].fov, self.centre(c))
    }

    /// The classes of source `j`.
    #[inline]
    pub fn classes_of(&self, j: usize) -> &[TargetClass] {
        &self.classes[self.class_offsets[j]..self.class_offsets[j + 1]]
    }

    /// The target speed, when every class flies at the same one.
    pub fn single_speed(&self) -> Option<f64> {
        let v = self.classes.first()?.speed;
        self.classes.iter().all(|c| c.speed == v).then_some(v)
    }

    /// The slowest target speed of any class.
    pub fn min_speed(&self) -> f64 {
        self.classes
            .iter()
            .map(|c| c.speed)
            .fold(f64::INFINITY, f64::min)
    }

    /// The fastest target speed of any class.
    pub fn max_speed(&self) -> f64 {
        self.classes.iter().map(|c| c.speed).fold(0.0, f64::max)
    }

    /// Number of cells.
    pub fn cell_count(&self) -> usize {
        self.cols as usize * self.rows as usize
    }

    /// Row-major index of a cell.
    #[inline]
    pub fn index(&self, c: Cell) -> usize {
        c.row as usize * self.cols as usize + c.col as usize
    }

    /// The cell at a row-major index.
    pub fn cell_at(&self, index: usize) -> Cell {
        Cell {
            col: (index % self.cols as usize) as i32,
            row: (index / self.cols as usize) as i32,
        }
    }

    /// True when the cell lies on the lattice.
    #[inline]
    pub fn on_lattice(&self, c: Cell) -> bool {
        c.col >= 0 && c.row >= 0 && c.col < self.cols && c.row < self.rows
    }

    /// Centre of a cell.
    #[inline]
    pub fn centre(&self, c: Cell) -> Point {
        Point::new(
            (c.col as f64 + 0.5) * self.cell_size,
            (c.row as f64 + 0.5) * self.cell_size,
        )
    }

    /// The zone rectangle.
    pub fn zone(&self) -> Rect {
        Rect {
            x0: 0.0,
            y0: 0.0,
            x1: self.width,
            y1: self.height,
        }
    }

    /// True when `p` is in the closed zone.
    pub fn in_zone(&self, p: Point) -> bool {
        self.zone().contains(p)
    }

    /// The cell containing a point of the zone (points on an inner cell
    /// boundary go to the cell east/north of it; the far edges to the last).
    pub fn snap(&self, p: Point) -> Cell {
        let c = ((p.x / self.cell_size).floor() as i32).clamp(0, self.cols - 1);
        let r = ((p.y / self.cell_size).floor() as i32).clamp(0, self.rows - 1);
        Cell { col: c, row: r }
    }

    /// Field of view of a sensor at cell `c`, clipped to the zone: the
    /// paper's `F_c`.
    #[inline]
    pub fn fov_region(&self, c: Cell) -> Region {
        self.fov_at(self.centre(c))
    }

    /// Field of view of a `default` sensor at point `p`, clipped to the
    /// zone.
    pub fn fov_at(&self, p: Point) -> Region {
        self.fov_with(self.fov, p)
    }

    /// The field of view `fov` at point `p`, clipped to the zone.
    pub fn fov_with(&self, fov: FovSpec, p: Point) -> Region {
        let (half, disk) = match fov {
            FovSpec::Square { half_width } => (half_width, None),
            FovSpec::Circle { radius } => (radius, Some(Disk { c: p, r: radius })),
        };
        let rect = Rect {
            x0: p.x - half,
            y0: p.y - half,
            x1: p.x + half,
            y1: p.y + half,
        }
        .intersect(&self.zone());
        Region { rect, disk }
    }

    /// The zone as a region.
    pub fn zone_region(&self) -> Region {
        Region {
            rect: self.zone(),
            disk: None,
        }
    }
}

/// Id of a canonical spec: `s-` and the first 16 hex digits of the SHA-256 of
/// its JSON (fields in declaration order, so the same spec gives the same id).
pub fn derive_id(canonical: &ScenarioSpec) -> String {
    let json = serde_json::to_vec(canonical).unwrap_or_default();
    let digest = Sha256::digest(&json);
    let hex: String = digest.iter().take(8).map(|b| format!("{b:02x}")).collect();
    format!("s-{hex}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_deterministic_and_canonical() {
        let a = Scenario::new(paper_spec(10.0)).expect("valid");
        let mut spec = paper_spec(10.0);
        spec.sources[0].heading = Some(Heading::East);
        spec.horizon = None;
        let b = Scenario::new(spec).expect("valid");
        assert_eq!(a.id, b.id);
        assert_ne!(a.id, Scenario::new(paper_spec(15.0)).expect("valid").id);
    }

    #[test]
    fn rejects_bad_specs_with_field_names() {
        let mut s = paper_spec(10.0);
        s.cell_size = 7.0;
        assert_eq!(Scenario::new(s).unwrap_err().field, "zone.width");
        let mut s = paper_spec(10.0);
        s.sources[3].x = 150.0;
        s.sources[3].y = 150.0;
        assert_eq!(Scenario::new(s).unwrap_err().field, "sources[3]");
        let mut s = paper_spec(10.0);
        s.sources[0] = SourceSpec::at(-1.0, -1.0, 1.0);
        assert_eq!(Scenario::new(s).unwrap_err().field, "sources[0].heading");
        let mut s = paper_spec(10.0);
        s.sources[0].heading = Some(Heading::West);
        assert_eq!(Scenario::new(s).unwrap_err().field, "sources[0].heading");
        let mut s = paper_spec(10.0);
        s.horizon = Some(13.into());
        assert_eq!(Scenario::new(s).unwrap_err().field, "horizon");
        let mut s = paper_spec(10.0);
        s.target_speed = Some(f64::NAN);
        assert_eq!(Scenario::new(s).unwrap_err().field, "target_speed");
        let mut s = paper_spec(10.0);
        s.cell_size = 0.01;
        assert_eq!(Scenario::new(s).unwrap_err().field, "cell_size");
        for bad in [MIN_RAYS_PER_PI - 1, MAX_RAYS_PER_PI + 1] {
            let mut s = paper_spec(10.0);
            s.rays_per_pi = Some(bad.into());
            assert_eq!(Scenario::new(s).unwrap_err().field, "rays_per_pi");
        }
    }

    /// A spec's rays per π replace the default, and only a spec that gives
    /// them gets another id (the built-ins' ids and every stored spec's
    /// stay as they were).
    #[test]
    fn rays_per_pi_default_by_field_of_view_and_override() {
        let paper = Scenario::new(paper_spec(10.0)).unwrap();
        assert_eq!(paper.rays_per_pi(), DEFAULT_RAYS_PER_PI_SQUARE);
        let mut spec = paper_spec(10.0);
        spec.fov = FovSpec::Circle { radius: 30.0 };
        assert_eq!(
            Scenario::new(spec).unwrap().rays_per_pi(),
            DEFAULT_RAYS_PER_PI_CIRCLE
        );
        let mut spec = paper_spec(10.0);
        spec.rays_per_pi = Some(64.into());
        let coarse = Scenario::new(spec).unwrap();
        assert_eq!(coarse.rays_per_pi(), 64);
        assert_ne!(coarse.id, paper.id);
        assert_eq!(coarse.spec.rays_per_pi, Some(64.into()));
    }

    #[test]
    fn snapping_and_fov() {
        let s = &builtins()[0];
        assert_eq!(s.snap(Point::new(0.0, 0.0)), Cell { col: 0, row: 0 });
        assert_eq!(s.snap(Point::new(300.0, 300.0)), Cell { col: 29, row: 29 });
        assert_eq!(s.snap(Point::new(15.0, 29.99)), Cell { col: 1, row: 2 });
        let f = s.fov_region(Cell { col: 0, row: 0 });
        assert_eq!(
            f.rect,
            Rect {
                x0: 0.0,
                y0: 0.0,
                x1: 35.0,
                y1: 35.0
            }
        );
    }
}
