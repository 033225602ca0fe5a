//! The model: zone, lattice of cells, sources, field of view, target speed.
//!
//! [`ScenarioSpec`] is what clients send; [`Scenario`] is the validated form,
//! built once by [`Scenario::new`] (parse, don't validate), so the rest of the
//! crate never re-checks input.

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use utoipa::ToSchema;

use crate::geometry::{Disk, Point, Rect, Region};

/// Largest planning horizon accepted.
pub const MAX_HORIZON: usize = 12;
/// Largest number of cells in a lattice.
pub const MAX_CELLS: usize = 4_000_000;
/// Largest number of sources in a scenario.
pub const MAX_SOURCES: usize = 64;
/// Horizon used when a spec does not give one.
pub const DEFAULT_HORIZON: usize = 3;

/// An input value outside its bounds. `field` is a JSON path into the
/// request, `message` says the bound.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct ValidationError {
    /// JSON path of the offending field, e.g. `sources[2].rate`.
    pub field: String,
    /// The bound it breaks.
    pub message: String,
}

impl ValidationError {
    /// A validation error for `field`.
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            field: field.into(),
            message: message.into(),
        }
    }
}

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

/// Direction a source's takeoff half-plane faces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "lowercase")]
pub enum Heading {
    /// +x.
    East,
    /// −x.
    West,
    /// +y.
    North,
    /// −y.
    South,
}

impl Heading {
    /// Unit vector of the heading.
    pub fn unit(self) -> Point {
        match self {
            Heading::East => Point::new(1.0, 0.0),
            Heading::West => Point::new(-1.0, 0.0),
            Heading::North => Point::new(0.0, 1.0),
            Heading::South => Point::new(0.0, -1.0),
        }
    }
}

/// A point source of targets outside the zone.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
#[schema(examples(json!({"x": -1.0, "y": 100.0, "rate": 0.3, "heading": "east"})))]
pub struct SourceSpec {
    /// East coordinate.
    pub x: f64,
    /// North coordinate.
    pub y: f64,
    /// Poisson rate, targets per step.
    #[schema(minimum = 0)]
    pub rate: f64,
    /// Takeoff half-plane; inferred when the source is beside exactly one edge.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heading: Option<Heading>,
}

/// A scenario as clients send it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
#[schema(examples(json!(paper_spec(10.0))))]
pub struct ScenarioSpec {
    /// Free-form label.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(max_length = 200)]
    pub name: Option<String>,
    /// The zone.
    pub zone: ZoneSpec,
    /// Side of a lattice cell; must divide width and height.
    #[schema(exclusive_minimum = 0)]
    pub cell_size: f64,
    /// Sensors' field of view.
    pub fov: FovSpec,
    /// Distance a target flies per step.
    #[schema(exclusive_minimum = 0)]
    pub target_speed: f64,
    /// Target sources.
    #[schema(max_items = 64)]
    pub sources: Vec<SourceSpec>,
    /// Default planning horizon T (1..=12, default 3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(minimum = 1, maximum = 12)]
    pub horizon: Option<usize>,
}

/// A lattice cell, `col` east and `row` north.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Cell {
    /// Column, from the west edge.
    pub col: i32,
    /// Row, from the south edge.
    pub row: i32,
}

/// A validated source: position, rate and takeoff frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Source {
    /// Position.
    pub pos: Point,
    /// Targets per step.
    pub rate: f64,
    /// Takeoff half-plane.
    pub heading: Heading,
}

impl Source {
    /// Unit direction of takeoff angle `alpha ∈ [−π/2, π/2]` measured from the
    /// heading, counter-clockwise.
    #[inline]
    pub fn direction(&self, alpha: f64) -> Point {
        let h = self.heading.unit();
        let (s, c) = alpha.sin_cos();
        Point::new(c * h.x - s * h.y, c * h.y + s * h.x)
    }

    /// Takeoff angle of the direction towards `p` (see [`Source::direction`]).
    #[inline]
    pub fn angle_to(&self, p: Point) -> f64 {
        let h = self.heading.unit();
        let (dx, dy) = (p.x - self.pos.x, p.y - self.pos.y);
        (h.x * dy - h.y * dx).atan2(h.x * dx + h.y * dy)
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
    /// Field of view.
    pub fov: FovSpec,
    /// Target speed per step.
    pub speed: f64,
    /// Sources.
    pub sources: Vec<Source>,
    /// Default horizon.
    pub horizon: usize,
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

/// Checks a horizon against `1..=MAX_HORIZON`.
pub fn check_horizon(field: &str, h: usize) -> Result<usize, ValidationError> {
    if (1..=MAX_HORIZON).contains(&h) {
        Ok(h)
    } else {
        Err(ValidationError::new(
            field,
            format!("must be in 1..={MAX_HORIZON}, got {h}"),
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
            && name.chars().count() > 200
        {
            return Err(ValidationError::new(
                "name",
                "must be at most 200 characters",
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
        match spec.fov {
            FovSpec::Square { half_width } => {
                finite_positive("fov.half_width", half_width)?;
            }
            FovSpec::Circle { radius } => {
                finite_positive("fov.radius", radius)?;
            }
        }
        let speed = finite_positive("target_speed", spec.target_speed)?;
        if spec.sources.len() > MAX_SOURCES {
            return Err(ValidationError::new(
                "sources",
                format!("at most {MAX_SOURCES} sources, got {}", spec.sources.len()),
            ));
        }
        let mut sources = Vec::with_capacity(spec.sources.len());
        let mut canonical_sources = Vec::with_capacity(spec.sources.len());
        for (i, s) in spec.sources.iter().enumerate() {
            let f = |name: &str| format!("sources[{i}].{name}");
            if !s.x.is_finite() {
                return Err(ValidationError::new(f("x"), "must be finite"));
            }
            if !s.y.is_finite() {
                return Err(ValidationError::new(f("y"), "must be finite"));
            }
            if !(s.rate.is_finite() && s.rate >= 0.0) {
                return Err(ValidationError::new(
                    f("rate"),
                    format!("must be finite and ≥ 0, got {}", s.rate),
                ));
            }
            if (0.0..=width).contains(&s.x) && (0.0..=height).contains(&s.y) {
                return Err(ValidationError::new(
                    format!("sources[{i}]"),
                    format!(
                        "({}, {}) is inside the zone [0,{width}]×[0,{height}]; sources must be strictly outside",
                        s.x, s.y
                    ),
                ));
            }
            let heading = match s.heading {
                Some(h) => h,
                None => infer_heading(s.x, s.y, width, height).ok_or_else(|| {
                    ValidationError::new(
                        f("heading"),
                        "required: the source is not beside exactly one edge of the zone",
                    )
                })?,
            };
            // The takeoff half-plane must face the zone, so every target can
            // reach any part of it and the zone lies in front of the source.
            let faces = match heading {
                Heading::East => s.x <= 0.0,
                Heading::West => s.x >= width,
                Heading::North => s.y <= 0.0,
                Heading::South => s.y >= height,
            };
            if !faces {
                return Err(ValidationError::new(
                    f("heading"),
                    format!(
                        "{} does not face the zone from ({}, {}): the whole zone must lie in the takeoff half-plane",
                        serde_json::to_string(&heading).unwrap_or_default(),
                        s.x,
                        s.y
                    ),
                ));
            }
            sources.push(Source {
                pos: Point::new(s.x, s.y),
                rate: s.rate,
                heading,
            });
            canonical_sources.push(SourceSpec {
                heading: Some(heading),
                ..*s
            });
        }
        let horizon = check_horizon("horizon", spec.horizon.unwrap_or(DEFAULT_HORIZON))?;
        let canonical = ScenarioSpec {
            sources: canonical_sources,
            horizon: Some(horizon),
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
            speed,
            sources,
            horizon,
        })
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

    /// Field of view of a sensor at point `p`, clipped to the zone.
    pub fn fov_at(&self, p: Point) -> Region {
        let (half, disk) = match self.fov {
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

/// The heading of a source beside exactly one edge, if any.
pub fn infer_heading(x: f64, y: f64, w: f64, h: f64) -> Option<Heading> {
    let beside_x = (0.0..=h).contains(&y);
    let beside_y = (0.0..=w).contains(&x);
    let mut found = None;
    let mut count = 0;
    for (cond, heading) in [
        (x < 0.0 && beside_x, Heading::East),
        (x > w && beside_x, Heading::West),
        (y < 0.0 && beside_y, Heading::North),
        (y > h && beside_y, Heading::South),
    ] {
        if cond {
            count += 1;
            found = Some(heading);
        }
    }
    (count == 1).then_some(found).flatten()
}

/// Id of a canonical spec: `s-` and the first 16 hex digits of the SHA-256 of
/// its JSON (fields in declaration order, so the same spec gives the same id).
pub fn derive_id(canonical: &ScenarioSpec) -> String {
    let json = serde_json::to_vec(canonical).unwrap_or_default();
    let digest = Sha256::digest(&json);
    let hex: String = digest.iter().take(8).map(|b| format!("{b:02x}")).collect();
    format!("s-{hex}")
}

/// Names of the built-in scenarios.
pub const BUILTIN_IDS: [&str; 2] = ["paper-v10", "paper-v15"];

/// The paper's setting: a 300×300 zone, 10-unit cells, square FOV of half
/// width 30, eight sources of rate 0.3 at a third and two thirds of each edge.
pub fn paper_spec(target_speed: f64) -> ScenarioSpec {
    let src = |x: f64, y: f64| SourceSpec {
        x,
        y,
        rate: 0.3,
        heading: None,
    };
    ScenarioSpec {
        name: Some(format!("paper, target speed {target_speed}")),
        zone: ZoneSpec {
            width: 300.0,
            height: 300.0,
        },
        cell_size: 10.0,
        fov: FovSpec::Square { half_width: 30.0 },
        target_speed,
        sources: vec![
            src(-1.0, 100.0),
            src(-1.0, 200.0),
            src(301.0, 100.0),
            src(301.0, 200.0),
            src(100.0, -1.0),
            src(200.0, -1.0),
            src(100.0, 301.0),
            src(200.0, 301.0),
        ],
        horizon: Some(3),
    }
}

/// The built-in scenarios, `paper-v10` and `paper-v15`.
pub fn builtins() -> Vec<Scenario> {
    BUILTIN_IDS
        .iter()
        .zip([10.0, 15.0])
        .map(|(id, v)| Scenario::build(paper_spec(v), Some(id)).expect("built-in specs are valid"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headings_are_inferred_beside_one_edge_only() {
        assert_eq!(
            infer_heading(-1.0, 100.0, 300.0, 300.0),
            Some(Heading::East)
        );
        assert_eq!(infer_heading(301.0, 0.0, 300.0, 300.0), Some(Heading::West));
        assert_eq!(
            infer_heading(100.0, -1.0, 300.0, 300.0),
            Some(Heading::North)
        );
        assert_eq!(
            infer_heading(100.0, 301.0, 300.0, 300.0),
            Some(Heading::South)
        );
        assert_eq!(infer_heading(-1.0, -1.0, 300.0, 300.0), None);
    }

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
        s.sources[0] = SourceSpec {
            x: -1.0,
            y: -1.0,
            rate: 1.0,
            heading: None,
        };
        assert_eq!(Scenario::new(s).unwrap_err().field, "sources[0].heading");
        let mut s = paper_spec(10.0);
        s.sources[0].heading = Some(Heading::West);
        assert_eq!(Scenario::new(s).unwrap_err().field, "sources[0].heading");
        let mut s = paper_spec(10.0);
        s.horizon = Some(13);
        assert_eq!(Scenario::new(s).unwrap_err().field, "horizon");
        let mut s = paper_spec(10.0);
        s.target_speed = f64::NAN;
        assert_eq!(Scenario::new(s).unwrap_err().field, "target_speed");
        let mut s = paper_spec(10.0);
        s.cell_size = 0.01;
        assert_eq!(Scenario::new(s).unwrap_err().field, "cell_size");
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
