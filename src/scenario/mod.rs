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
    OBSTACLE_STATS_RAYS_PER_PI,
};
use crate::obstacle::{ObstacleKind, Obstacles, Sight};

mod builtins;
mod input;
mod obstacles;
mod sensor;
mod source;

pub use builtins::{
    BUILTIN_IDS, SITE_CYCLIST, SITE_VEHICLE, SITE_WALKER, builtins, paper_spec, site_campus_spec,
    site_drone, site_fleet_spec, site_gates_spec, site_robot,
};

pub use input::{Integer, ValidationError, check_horizon, check_min_separation};
pub use obstacles::{ObstacleKindName, ObstacleSpec};
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
    /// Buildings and screens (at most 64 convex polygons): sight lines
    /// that meet an obstacle's interior are blocked (elevated sensor types
    /// see over them), a target's flight ends where it enters a building,
    /// and no ground sensor stands on or crosses a cell whose centre lies
    /// in a building (see `docs/obstacles.md`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub obstacles: Option<Vec<ObstacleSpec>>,
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

impl Cell {
    /// The cell `dc` columns east and `dr` rows north of this one, on the
    /// lattice or not.
    #[inline]
    pub fn offset(self, dc: i32, dr: i32) -> Cell {
        Cell {
            col: self.col + dc,
            row: self.row + dr,
        }
    }
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
    /// The distinct views of the types (`fovs[0]` is `fov`): a field of
    /// view, and whether its looks see over the obstacles
    /// (`sees_over[slot]`; always true without obstacles).
    pub fovs: Vec<FovSpec>,
    /// Aligned with `fovs`: true when that view's looks see over every
    /// obstacle (an elevated type's, or any without obstacles).
    pub sees_over: Vec<bool>,
    /// Row-major: true for a cell no sensor may stand on. Empty when no
    /// cell is blocked.
    blocked: Vec<bool>,
    /// Row-major: true for a cell whose centre lies in a building, where
    /// no ground sensor may stand. Empty without buildings.
    in_building: Vec<bool>,
    /// Buildings and screens.
    pub obstacles: Obstacles,
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
        let zone = Rect {
            x0: 0.0,
            y0: 0.0,
            x1: width,
            y1: height,
        };
        let (obstacles, canonical_obstacles) =
            obstacles::validate(spec.obstacles.as_deref().unwrap_or(&[]), &zone)?;
        let fleet = sensor::validate_fleet(
            &spec.fov,
            spec.sensor_speed.as_ref(),
            spec.p_detect,
            spec.sensor_types.as_ref(),
            !obstacles.is_empty(),
        )?;
        let blocked =
            sensor::blocked_cells(spec.no_go.as_deref().unwrap_or(&[]), cols, rows, cell_size)?;
        let in_building = building_cells(&obstacles, cols, rows, cell_size);
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
                share: weight,
            }));
            class_offsets.push(classes.len());
            if !obstacles.is_empty() {
                reaches_zone(i, &v.source, &obstacles, &zone)?;
            }
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
            obstacles: (!canonical_obstacles.is_empty()).then_some(canonical_obstacles),
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
            sees_over: fleet.sees_over,
            blocked,
            in_building,
            obstacles,
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

    /// Why no sensor of type `ty` may stand on `c` (a cell on the
    /// lattice), or `None` when it may: the cell is in a no-go zone, or
    /// (for a ground type) its centre lies in a building.
    #[inline]
    pub fn blocked_for(&self, ty: usize, c: Cell) -> Option<&'static str> {
        if !self.blocked.is_empty() && self.blocked[self.index(c)] {
            return Some("is in a no-go zone: no sensor may stand on it");
        }
        if !self.in_building.is_empty()
            && !self.types[ty].elevated
            && self.in_building[self.index(c)]
        {
            return Some("is in a building: no ground sensor may stand on it");
        }
        None
    }

    /// True when some cell is blocked for some type.
    pub fn has_no_go(&self) -> bool {
        !self.blocked.is_empty() || !self.in_building.is_empty()
    }

    /// True when a sensor of type `ty` may stand on `c`: on the lattice
    /// and not blocked for it.
    #[inline]
    pub fn is_free(&self, ty: usize, c: Cell) -> bool {
        self.on_lattice(c) && self.blocked_for(ty, c).is_none()
    }

    /// What a look cannot see, when obstacles hide part of it.
    pub fn sight(&self, look: &Look) -> Option<Sight> {
        self.obstacles.sight(look.from?, &look.region)
    }

    /// True when `look` can detect a target at `p`: inside its field of
    /// view, and on a sight line that no obstacle blocks (for a ground
    /// sensor).
    pub fn detects(&self, look: &Look, p: Point) -> bool {
        look.region.contains(p) && look.from.is_none_or(|from| self.obstacles.clear(from, p))
    }

    /// The outline of what `look` sees, for pictures: the point where each
    /// of `rays` rays from its viewpoint, evenly spaced in angle, leaves
    /// its field of view or first enters an obstacle's interior (for a
    /// ground look; an elevated look's outline is its field of view's).
    /// A polygon, counter-clockwise from east; exact for a ray's angle,
    /// and between rays as fine as `rays` makes it.
    pub fn view_outline(&self, look: &Look, rays: usize) -> Vec<Point> {
        let r = &look.region;
        // Any point of the (convex) field of view sees all of it when
        // nothing blocks sight.
        let p = look.from.or(r.disk.map(|d| d.c)).unwrap_or(Point::new(
            0.5 * (r.rect.x0 + r.rect.x1),
            0.5 * (r.rect.y0 + r.rect.y1),
        ));
        (0..rays)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / rays as f64;
                let d = Point::new(a.cos(), a.sin());
                let inv = Point::new(1.0 / d.x, 1.0 / d.y);
                let mut reach = r.ray(p, d, inv).map_or(0.0, |(_, b)| b);
                if look.from.is_some() {
                    reach = reach.min(self.obstacles.sight_reach(p, d));
                }
                Point::new(p.x + reach * d.x, p.y + reach * d.y)
            })
            .collect()
    }

    /// True when the scenario has obstacles.
    pub fn has_obstacles(&self) -> bool {
        !self.obstacles.is_empty()
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
        let centre = self.centre(c);
        Look {
            region: self.fov_with(t.fov, centre),
            p_detect: t.p_detect,
            from: (!self.sees_over[t.fov_slot]).then_some(centre),
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

    /// The lowest and highest corners of the block of lattice cells at most
    /// `r` cells from `start` along each axis (where a sensor of speed `v`
    /// can be after `r / v` steps), clipped to the lattice.
    #[inline]
    pub fn reach_corners(&self, start: Cell, r: i32) -> (Cell, Cell) {
        let lo = Cell {
            col: (start.col - r).max(0),
            row: (start.row - r).max(0),
        };
        let hi = Cell {
            col: (start.col + r).min(self.cols - 1),
            row: (start.row + r).min(self.rows - 1),
        };
        (lo, hi)
    }

    /// The cell `(dc, dr)` away from `start`, if it lies on the lattice.
    #[inline]
    pub fn lattice_cell(&self, start: Cell, dc: i32, dr: i32) -> Option<Cell> {
        let k = start.offset(dc, dr);
        self.on_lattice(k).then_some(k)
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

/// Row-major: true for a cell whose centre lies in a building (closed);
/// empty without buildings. Row by row, each building marks the columns
/// of its span at the row's centre line, so the work is the rows and the
/// cells the buildings cover, not every cell times every building.
fn building_cells(obstacles: &Obstacles, cols: i32, rows: i32, cell_size: f64) -> Vec<bool> {
    if !obstacles.in_building_anywhere() {
        return Vec::new();
    }
    let mut marked = vec![false; cols as usize * rows as usize];
    for ob in obstacles.list() {
        if ob.kind != ObstacleKind::Building {
            continue;
        }
        let b = ob.polygon.bbox();
        let first = ((b.y0 / cell_size - 0.5).floor().max(0.0) as i64).min(i64::from(rows));
        let last = ((b.y1 / cell_size - 0.5).ceil().max(-1.0) as i64).min(i64::from(rows) - 1);
        for row in first..=last {
            let y = (row as f64 + 0.5) * cell_size;
            let Some((x0, x1)) = ob.polygon.row_span(y) else {
                continue;
            };
            // Columns whose centre (c + ½)·size lies in [x0, x1]: those
            // within a column of either end are checked against the
            // polygon itself (the divisions round), the rest are inside.
            let a = (x0 / cell_size - 0.5).ceil();
            let b = (x1 / cell_size - 0.5).floor();
            let c0 = (a - 1.0).max(0.0) as i64;
            let c1 = (b + 1.0).min(f64::from(cols) - 1.0) as i64;
            for col in c0..=c1 {
                let near_end = col as f64 <= a || col as f64 >= b;
                if !near_end
                    || ob
                        .polygon
                        .contains_closed(Point::new((col as f64 + 0.5) * cell_size, y))
                {
                    marked[row as usize * cols as usize + col as usize] = true;
                }
            }
        }
    }
    marked
}

/// Refuses source `i` when no direction of its cone reaches the zone's
/// interior before a building ends its flight (a source inside a
/// building among them).
///
/// Exact: whether a direction reaches the zone first changes only at the
/// angles of the buildings' vertices, the zone's corners and the points
/// where a building's edge crosses the zone's edge (where the edges a ray
/// meets, or which of them comes first, change), so one direction
/// between each two of those angles decides for all of them. The grid of
/// [`OBSTACLE_STATS_RAYS_PER_PI`] rays per π this check once was is
/// tried too, so that no spec it took is refused now.
fn reaches_zone(
    i: usize,
    source: &Source,
    obstacles: &Obstacles,
    zone: &Rect,
) -> Result<(), ValidationError> {
    if obstacles.inside_building(source.pos) {
        return Err(ValidationError::new(
            format!("sources[{i}]"),
            "lies inside a building: every target it emits is stopped at once",
        ));
    }
    let (lo, hi) = source.cone;
    let reaches_at = |alpha: f64| {
        let d = source.direction(alpha);
        let inv = Point::new(1.0 / d.x, 1.0 / d.y);
        zone.ray(source.pos, d, inv)
            .is_some_and(|(a, b)| b > a && obstacles.stop(source.pos, d) > a)
    };
    let n = ((hi - lo) / std::f64::consts::PI * OBSTACLE_STATS_RAYS_PER_PI as f64).ceil() as usize;
    let on_grid =
        (0..n.max(1)).any(|m| reaches_at(lo + (hi - lo) * (m as f64 + 0.5) / n.max(1) as f64));
    let reaches = on_grid || {
        let mut angles: Vec<f64> = critical_points(obstacles, zone)
            .into_iter()
            .map(|p| source.angle_to(p))
            .filter(|a| *a > lo && *a < hi)
            .chain([lo, hi])
            .collect();
        angles.sort_by(f64::total_cmp);
        angles
            .windows(2)
            .any(|w| w[1] > w[0] && reaches_at(0.5 * (w[0] + w[1])))
    };
    if reaches {
        Ok(())
    } else {
        Err(ValidationError::new(
            format!("sources[{i}]"),
            "every direction of its cone meets a building before the zone: no target it emits can enter",
        ))
    }
}

/// The buildings' vertices, the zone's corners, and the points where a
/// building's edge crosses the zone's edge: the points at whose angles
/// from a source [`reaches_zone`]'s answer may change.
fn critical_points(obstacles: &Obstacles, zone: &Rect) -> Vec<Point> {
    let corners = [
        Point::new(zone.x0, zone.y0),
        Point::new(zone.x1, zone.y0),
        Point::new(zone.x1, zone.y1),
        Point::new(zone.x0, zone.y1),
    ];
    let mut points = corners.to_vec();
    for ob in obstacles
        .list()
        .iter()
        .filter(|ob| ob.kind == ObstacleKind::Building)
    {
        let v = ob.polygon.vertices();
        points.extend_from_slice(v);
        for k in 0..v.len() {
            let (p, q) = (v[k], v[(k + 1) % v.len()]);
            for c in 0..4 {
                if let Some(x) = segments_cross(p, q, corners[c], corners[(c + 1) % 4]) {
                    points.push(x);
                }
            }
        }
    }
    points
}

/// The point where segments `[p, q]` and `[a, b]` cross, if they do at one
/// point.
fn segments_cross(p: Point, q: Point, a: Point, b: Point) -> Option<Point> {
    let (rx, ry) = (q.x - p.x, q.y - p.y);
    let (sx, sy) = (b.x - a.x, b.y - a.y);
    let den = rx * sy - ry * sx;
    if den == 0.0 {
        return None;
    }
    let (wx, wy) = (a.x - p.x, a.y - p.y);
    let t = (wx * sy - wy * sx) / den;
    let u = (wx * ry - wy * rx) / den;
    ((0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u))
        .then(|| Point::new(p.x + t * rx, p.y + t * ry))
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
