//! Where targets come from: sources, their takeoff cones, and target
//! classes (a source × one speed of its speed distribution).
//!
//! A source at `s_j` emits a Poisson stream of `rate` targets per step. Each
//! target draws its takeoff angle uniformly over the source's cone and its
//! speed from the source's distribution, once, and flies straight. A class
//! `c` of source `j` with weight `w_c` and speed `v_c` therefore has the
//! stationary density `ρ_c(q) = λ_j·w_c / (spread_j·v_c·|q − s_j|)` inside the
//! cone (spread in radians) and 0 outside; the paper's sources are the case
//! of one speed and a half-plane (spread π).

use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use super::input::ValidationError;
use crate::geometry::{Point, Rect};
use crate::limits::{MAX_SOURCE_COORDINATE, MAX_SPEED_CLASSES};

/// Direction a source's takeoff half-plane faces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, ToSchema)]
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

crate::by_name::by_name!(Heading {
    "east" => Heading::East,
    "west" => Heading::West,
    "north" => Heading::North,
    "south" => Heading::South,
});

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

    /// True when the zone `[0,w]×[0,h]` lies in the half-plane the heading
    /// faces from `(x, y)`.
    pub fn faces_zone(self, x: f64, y: f64, w: f64, h: f64) -> bool {
        match self {
            Heading::East => x <= 0.0,
            Heading::West => x >= w,
            Heading::North => y <= 0.0,
            Heading::South => y >= h,
        }
    }
}

/// One speed of a source's speed distribution.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
#[schema(examples(json!({"speed": 1.5, "weight": 3.0})))]
pub struct SpeedSpec {
    /// Distance a target of this class flies per step.
    #[schema(exclusive_minimum = 0)]
    pub speed: f64,
    /// Relative weight; a source's weights are normalised by their sum.
    #[schema(exclusive_minimum = 0)]
    pub weight: f64,
}

/// A point source of targets outside the zone.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
#[schema(examples(
    json!({"x": -1.0, "y": 100.0, "rate": 0.3, "heading": "east"}),
    json!({"x": 200.0, "y": -5.0, "rate": 0.4, "direction": 80.0, "spread": 40.0,
           "speeds": [{"speed": 1.5, "weight": 3.0}, {"speed": 12.0, "weight": 1.0}]})
))]
pub struct SourceSpec {
    /// East coordinate, within ±1e12 (`MAX_SOURCE_COORDINATE`).
    #[schema(minimum = -1e12, maximum = 1e12)]
    pub x: f64,
    /// North coordinate, within ±1e12.
    #[schema(minimum = -1e12, maximum = 1e12)]
    pub y: f64,
    /// Poisson rate, targets per step.
    #[schema(minimum = 0)]
    pub rate: f64,
    /// Takeoff half-plane; inferred when the source is beside exactly one
    /// edge. Not used when `direction` is given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heading: Option<Heading>,
    /// Centre of the takeoff cone, degrees counter-clockwise from east
    /// (east 0, north 90, west 180, south 270); the heading's by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<f64>,
    /// Width of the takeoff cone, degrees, in (0, 180]; 180 by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(exclusive_minimum = 0, maximum = 180)]
    pub spread: Option<f64>,
    /// Speed distribution, 1 to 8 classes; the scenario's `target_speed`
    /// by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(min_items = 1)]
    pub speeds: Option<Vec<SpeedSpec>>,
}

impl SourceSpec {
    /// A source of the paper's kind: a half-plane (heading inferred), the
    /// scenario's target speed.
    pub fn at(x: f64, y: f64, rate: f64) -> Self {
        Self {
            x,
            y,
            rate,
            ..Self::default()
        }
    }
}

/// A validated source: position, rate and takeoff cone.
///
/// Takeoff angles are measured counter-clockwise from `frame`, a unit
/// vector chosen so that every point of the zone is seen from the source at
/// an angle in (−π, π) (no wrap-around): the heading for a half-plane
/// source, otherwise the bisector of the part of the cone that meets the
/// zone.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Source {
    /// Position.
    pub pos: Point,
    /// Targets per step, over all classes.
    pub rate: f64,
    /// Direction takeoff angles are measured from.
    pub frame: Point,
    /// The takeoff angles `[lo, hi]`, relative to `frame`.
    pub cone: (f64, f64),
    /// Width of the cone, radians (exactly π for a half-plane).
    pub spread: f64,
    /// The whole zone lies inside the cone (so integrals over any part of it
    /// need no cut at the cone's edges): always so for the paper's sources.
    pub covers_zone: bool,
    /// An axis-aligned heading whose half-plane holds the zone.
    pub half_plane: Heading,
}

impl Source {
    /// Unit direction of takeoff angle `alpha` (relative to `frame`,
    /// counter-clockwise).
    #[inline]
    pub fn direction(&self, alpha: f64) -> Point {
        let h = self.frame;
        let (s, c) = alpha.sin_cos();
        Point::new(c * h.x - s * h.y, c * h.y + s * h.x)
    }

    /// Takeoff angle of the direction towards `p` (see [`Source::direction`]),
    /// in (−π, π].
    #[inline]
    pub fn angle_to(&self, p: Point) -> f64 {
        let h = self.frame;
        let (dx, dy) = (p.x - self.pos.x, p.y - self.pos.y);
        (h.x * dy - h.y * dx).atan2(h.x * dx + h.y * dy)
    }

    /// `[lo, hi]` clipped to the cone, if anything of positive width is left.
    #[inline]
    pub fn clip(&self, lo: f64, hi: f64) -> Option<(f64, f64)> {
        let (lo, hi) = (lo.max(self.cone.0), hi.min(self.cone.1));
        (hi > lo).then_some((lo, hi))
    }
}

/// A target class: the targets of one source that fly at one speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetClass {
    /// Index of its source in [`super::Scenario::sources`].
    pub source: usize,
    /// Distance flown per step.
    pub speed: f64,
    /// Targets of the class emitted per step: the source's rate times the
    /// class's normalised weight.
    pub rate: f64,
    /// The class's normalised weight: its share of its source's targets
    /// (kept apart from `rate`, which is 0 for a silent source).
    pub share: f64,
}

impl TargetClass {
    /// The class's stationary density times the distance from its source,
    /// `λ_c/(spread·v)`: targets per unit of ray length per radian.
    #[inline]
    pub fn density(&self, source: &Source) -> f64 {
        self.rate / (source.spread * self.speed)
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

/// `a` wrapped into (−π, π].
fn wrap(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let r = a.rem_euclid(TAU);
    if r > PI { r - TAU } else { r }
}

/// Angles below this are no cone at all (a tangent or a corner).
const MIN_OVERLAP: f64 = 1e-9;

/// A source validated against the zone, with its canonical spec and its
/// speed classes `(speed, normalised weight)`.
pub(super) struct Validated {
    pub source: Source,
    pub canonical: SourceSpec,
    pub speeds: Vec<(f64, f64)>,
}

/// Validates source `i` of a spec against the zone `[0,w]×[0,h]`;
/// `target_speed` is the scenario's (needed when the source has no speeds).
pub(super) fn validate(
    i: usize,
    s: &SourceSpec,
    w: f64,
    h: f64,
    target_speed: Option<f64>,
) -> Result<Validated, ValidationError> {
    let f = |name: &str| format!("sources[{i}].{name}");
    for (axis, v) in [("x", s.x), ("y", s.y)] {
        if !v.is_finite() {
            return Err(ValidationError::new(f(axis), "must be finite"));
        }
        if v.abs() > MAX_SOURCE_COORDINATE {
            return Err(ValidationError::new(
                f(axis),
                format!("must lie within ±{MAX_SOURCE_COORDINATE:e}"),
            ));
        }
    }
    if !(s.rate.is_finite() && s.rate >= 0.0) {
        return Err(ValidationError::new(
            f("rate"),
            format!("must be finite and ≥ 0, got {}", s.rate),
        ));
    }
    if (0.0..=w).contains(&s.x) && (0.0..=h).contains(&s.y) {
        return Err(ValidationError::new(
            format!("sources[{i}]"),
            format!(
                "({}, {}) is inside the zone [0,{w}]×[0,{h}]; sources must be strictly outside",
                s.x, s.y
            ),
        ));
    }
    let speeds = speed_classes(i, s, target_speed)?;
    let spread_deg = match s.spread {
        None => 180.0,
        Some(v) if v.is_finite() && v > 0.0 && v <= 180.0 => v,
        Some(v) => {
            return Err(ValidationError::new(
                f("spread"),
                format!("must be in (0, 180] degrees, got {v}"),
            ));
        }
    };
    // π exactly for a half-plane, so the paper's sources keep their values.
    let spread = if spread_deg == 180.0 {
        std::f64::consts::PI
    } else {
        spread_deg.to_radians()
    };
    let pos = Point::new(s.x, s.y);
    let zone = Rect {
        x0: 0.0,
        y0: 0.0,
        x1: w,
        y1: h,
    };
    let mut half_plane = [Heading::East, Heading::West, Heading::North, Heading::South]
        .into_iter()
        .find(|hd| hd.faces_zone(s.x, s.y, w, h))
        .unwrap_or(Heading::East);
    let mut canonical = s.clone();
    canonical.spread = s.spread.filter(|&v| v != 180.0);
    let (frame, cone) = match s.direction {
        Some(dir) => {
            if !dir.is_finite() {
                return Err(ValidationError::new(f("direction"), "must be finite"));
            }
            canonical.heading = None;
            canonical.direction = Some(dir.rem_euclid(360.0));
            directed_cone(pos, dir.to_radians(), spread, &zone).ok_or_else(|| {
                ValidationError::new(
                    format!("sources[{i}]"),
                    format!(
                        "no takeoff direction of the cone {dir}° ± {}° from ({}, {}) enters the zone [0,{w}]×[0,{h}]",
                        spread_deg / 2.0,
                        s.x,
                        s.y
                    ),
                )
            })?
        }
        None => {
            let heading = match s.heading {
                Some(hd) => hd,
                None => infer_heading(s.x, s.y, w, h).ok_or_else(|| {
                    ValidationError::new(
                        f("heading"),
                        "required (or a direction): the source is not beside exactly one edge of the zone",
                    )
                })?,
            };
            // The takeoff half-plane must face the zone, so the zone lies in
            // front of the source.
            if !heading.faces_zone(s.x, s.y, w, h) {
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
            canonical.heading = Some(heading);
            half_plane = heading;
            let half = spread / 2.0;
            let frame = heading.unit();
            if spread < std::f64::consts::PI {
                let span = zone_span(pos, frame, &zone);
                if span.1.min(half) - span.0.max(-half) <= MIN_OVERLAP {
                    return Err(ValidationError::new(
                        format!("sources[{i}]"),
                        format!(
                            "no takeoff direction of the cone {}° wide around {} from ({}, {}) enters the zone [0,{w}]×[0,{h}]",
                            spread_deg,
                            serde_json::to_string(&heading).unwrap_or_default(),
                            s.x,
                            s.y
                        ),
                    ));
                }
            }
            (frame, (-half, half))
        }
    };
    let span = zone_span(pos, frame, &zone);
    let covers_zone = (s.direction.is_none() && spread == std::f64::consts::PI)
        || (span.0 >= cone.0 && span.1 <= cone.1);
    Ok(Validated {
        source: Source {
            pos,
            rate: s.rate,
            frame,
            cone,
            spread,
            covers_zone,
            half_plane,
        },
        canonical,
        speeds,
    })
}

/// The speed classes of a source, `(speed, weight / Σ weights)`.
fn speed_classes(
    i: usize,
    s: &SourceSpec,
    target_speed: Option<f64>,
) -> Result<Vec<(f64, f64)>, ValidationError> {
    let Some(speeds) = &s.speeds else {
        let v = target_speed.ok_or_else(|| {
            ValidationError::new(
                "target_speed",
                format!("required: sources[{i}] gives no speeds"),
            )
        })?;
        return Ok(vec![(v, 1.0)]);
    };
    if speeds.is_empty() || speeds.len() > MAX_SPEED_CLASSES {
        return Err(ValidationError::new(
            format!("sources[{i}].speeds"),
            format!(
                "must have 1 to {MAX_SPEED_CLASSES} classes, got {}",
                speeds.len()
            ),
        ));
    }
    for (k, c) in speeds.iter().enumerate() {
        for (name, v) in [("speed", c.speed), ("weight", c.weight)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(ValidationError::new(
                    format!("sources[{i}].speeds[{k}].{name}"),
                    format!("must be finite and > 0, got {v}"),
                ));
            }
        }
    }
    let total: f64 = speeds.iter().map(|c| c.weight).sum();
    if !total.is_finite() {
        return Err(ValidationError::new(
            format!("sources[{i}].speeds"),
            "the weights' sum must be finite",
        ));
    }
    Ok(speeds.iter().map(|c| (c.speed, c.weight / total)).collect())
}

/// The angles `[lo, hi]` relative to `frame` under which `zone` is seen from
/// `pos` (outside it); `frame` must see the zone without wrap-around.
fn zone_span(pos: Point, frame: Point, zone: &Rect) -> (f64, f64) {
    let corners = [
        (zone.x0, zone.y0),
        (zone.x1, zone.y0),
        (zone.x1, zone.y1),
        (zone.x0, zone.y1),
    ];
    corners
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(x, y)| {
            let (dx, dy) = (x - pos.x, y - pos.y);
            let a = (frame.x * dy - frame.y * dx).atan2(frame.x * dx + frame.y * dy);
            (lo.min(a), hi.max(a))
        })
}

/// The frame and cone of a source with an explicit direction `phi` and
/// `spread` (radians): the frame is the bisector of the part of the cone
/// that meets the zone. `None` when no direction of positive measure does.
fn directed_cone(pos: Point, phi: f64, spread: f64, zone: &Rect) -> Option<(Point, (f64, f64))> {
    // The zone is seen under less than π from outside, so angles relative
    // to the direction of its centre do not wrap.
    let c = Point::new(0.5 * (zone.x0 + zone.x1), 0.5 * (zone.y0 + zone.y1));
    let psi0 = (c.y - pos.y).atan2(c.x - pos.x);
    let towards = Point::new(psi0.cos(), psi0.sin());
    let (zlo, zhi) = zone_span(pos, towards, zone);
    let centre = wrap(phi - psi0);
    let half = spread / 2.0;
    // At most one copy of the cone (mod 2π) meets the zone's span.
    let (lo, hi, mid_cone) = [-std::f64::consts::TAU, 0.0, std::f64::consts::TAU]
        .into_iter()
        .map(|k| {
            let m = centre + k;
            ((m - half).max(zlo), (m + half).min(zhi), m)
        })
        .max_by(|a, b| (a.1 - a.0).total_cmp(&(b.1 - b.0)))?;
    if hi - lo <= MIN_OVERLAP {
        return None;
    }
    let m = 0.5 * (lo + hi);
    let angle = psi0 + m;
    let frame = Point::new(angle.cos(), angle.sin());
    Some((frame, (mid_cone - m - half, mid_cone - m + half)))
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

    fn directed(x: f64, y: f64, direction: f64, spread: f64) -> Result<Source, ValidationError> {
        let spec = SourceSpec {
            direction: Some(direction),
            spread: Some(spread),
            ..SourceSpec::at(x, y, 1.0)
        };
        validate(0, &spec, 300.0, 200.0, Some(5.0)).map(|v| v.source)
    }

    #[test]
    fn a_directed_cone_is_the_one_asked_for() {
        // From the south-west corner, north-east ± 15°.
        for (x, y, dir, spread) in [
            (-10.0, -10.0, 45.0, 30.0),
            (150.0, -5.0, 100.0, 60.0),
            (310.0, 100.0, 170.0, 20.0),
            (150.0, 205.0, -90.0, 180.0),
            // The cone straddles the ±180° cut of absolute angles.
            (320.0, 100.0, 180.0, 90.0),
        ] {
            let s = directed(x, y, dir, spread).expect("valid");
            for k in 0..=10 {
                let alpha = s.cone.0 + (s.cone.1 - s.cone.0) * k as f64 / 10.0;
                let d = s.direction(alpha);
                let want = (dir + spread * (k as f64 / 10.0 - 0.5)).to_radians();
                let diff = wrap(d.y.atan2(d.x) - want);
                assert!(diff.abs() < 1e-9, "({x},{y}) {dir}±{spread}: {k}: {diff}");
            }
            assert!((s.spread - spread.to_radians()).abs() < 1e-12);
        }
    }

    #[test]
    fn a_cone_that_misses_the_zone_is_refused() {
        // Pointing away from the zone, or past its corner.
        let e = directed(-10.0, 100.0, 180.0, 90.0).unwrap_err();
        assert_eq!(e.field, "sources[0]");
        assert!(directed(-10.0, -10.0, 200.0, 20.0).is_err());
        assert!(directed(-10.0, 100.0, 90.0, 10.0).is_err());
        assert!(directed(-10.0, 100.0, 90.0, 180.0).is_ok());
        // A narrow cone around a heading that misses.
        let spec = SourceSpec {
            spread: Some(10.0),
            heading: Some(Heading::North),
            ..SourceSpec::at(-50.0, -1.0, 1.0)
        };
        assert!(validate(0, &spec, 300.0, 200.0, Some(5.0)).is_err());
    }

    #[test]
    fn coverage_is_known() {
        assert!(
            directed(150.0, -300.0, 90.0, 90.0)
                .expect("valid")
                .covers_zone
        );
        assert!(
            !directed(150.0, -5.0, 90.0, 90.0)
                .expect("valid")
                .covers_zone
        );
        let paper = validate(
            0,
            &SourceSpec::at(-1.0, 100.0, 0.3),
            300.0,
            300.0,
            Some(10.0),
        )
        .expect("valid");
        assert!(paper.source.covers_zone);
        assert_eq!(
            paper.source.cone,
            (-std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2)
        );
        assert_eq!(paper.speeds, vec![(10.0, 1.0)]);
    }
}
