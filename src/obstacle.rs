//! Obstacles: convex polygons that block sight lines (buildings and
//! screens) and end targets' flights (buildings).
//!
//! The model's rules (docs/obstacles.md):
//! - *sight*: a sensor at `p` sees a point `q` when the open segment
//!   `(p, q)` meets no obstacle's interior (touching an edge or a vertex
//!   does not block);
//! - *flight*: a target's straight flight ends where its ray first enters
//!   a building's interior.
//!
//! For one convex polygon `O` the points hidden from `p` form its
//! *shadow*, an open convex set: for `p` outside `O`, the intersection of
//! the inner open half-planes of the edges that face `p` (or hold it) with
//! the open cone from `p` that `O` spans; for `p` on `O`'s boundary, the
//! open tangent cone at `p` (the inner half-planes of the edges through
//! it); for `p` inside, the whole plane (the sensor sees nothing). So the
//! visible part of a line is the line less a few open intervals: interval
//! arithmetic along rays, like every other integral of the exact estimator.

use crate::geometry::{Point, Rect, Region};

/// What an obstacle does (the spec's `kind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObstacleKind {
    /// Blocks sight, stops targets, and no ground sensor may stand on or
    /// cross a cell whose centre lies in it.
    Building,
    /// Blocks sight only (trees, a hedge, smoke).
    Screen,
}

/// An open half-plane `{x : n·x < c}` with a unit normal `n`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfPlane {
    n: Point,
    c: f64,
}

impl HalfPlane {
    /// The half-plane left of the directed line `a → b` (unit normal).
    fn left_of(a: Point, b: Point) -> Self {
        let (dx, dy) = (b.x - a.x, b.y - a.y);
        let len = dx.hypot(dy);
        // Left of a→b: cross(b − a, x − a) > 0 ⇔ (dy, −dx)·(x − a) < 0.
        let n = Point::new(dy / len, -dx / len);
        HalfPlane {
            n,
            c: n.x * a.x + n.y * a.y,
        }
    }

    #[inline]
    fn slack(&self, p: Point) -> f64 {
        self.c - (self.n.x * p.x + self.n.y * p.y)
    }
}

/// The open parameter interval `(t0, t1)` of the line `o + t·d` inside an
/// intersection of open half-planes (`t0 < t1`), or `None`.
#[inline]
fn line_in(planes: &[HalfPlane], o: Point, d: Point) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for h in planes {
        // n·(o + t d) < c ⇔ (n·d)·t < c − n·o.
        let nd = h.n.x * d.x + h.n.y * d.y;
        let rhs = h.slack(o);
        if nd > 0.0 {
            t1 = t1.min(rhs / nd);
        } else if nd < 0.0 {
            t0 = t0.max(rhs / nd);
        } else if rhs <= 0.0 {
            return None;
        }
        if t0 >= t1 {
            return None;
        }
    }
    Some((t0, t1))
}

/// A validated convex polygon, counter-clockwise.
#[derive(Debug, Clone, PartialEq)]
pub struct Polygon {
    vertices: Vec<Point>,
    /// Edge `i` (from vertex `i` to `i + 1`): the polygon's interior is the
    /// intersection of these open half-planes.
    edges: Vec<HalfPlane>,
    bbox: Rect,
    /// Tolerance of closed containment, zone units.
    eps: f64,
}

/// Why a list of points is not a valid convex polygon.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PolygonError {
    /// A coordinate is NaN or infinite.
    #[error("vertex {0} is not a pair of finite numbers")]
    NotFinite(usize),
    /// Two vertices are equal.
    #[error("vertices {0} and {1} are the same point")]
    Repeated(usize, usize),
    /// Three consecutive vertices are collinear.
    #[error("vertices {0}, {1} and {2} are collinear")]
    Collinear(usize, usize, usize),
    /// The turns change direction.
    #[error("the polygon is not convex (it turns both ways at vertex {0})")]
    NotConvex(usize),
    /// Every turn is the same way, but the boundary winds more than once.
    #[error("the polygon intersects itself (its boundary winds {0} times)")]
    SelfIntersecting(usize),
}

impl Polygon {
    /// Validates `points` as a convex polygon (either orientation) with no
    /// repeated vertex and no three consecutive vertices collinear.
    ///
    /// # Errors
    /// The first defect found.
    pub fn new(points: &[Point]) -> Result<Self, PolygonError> {
        let n = points.len();
        if let Some(i) = points
            .iter()
            .position(|p| !p.x.is_finite() || !p.y.is_finite())
        {
            return Err(PolygonError::NotFinite(i));
        }
        for i in 0..n {
            for j in i + 1..n {
                if points[i] == points[j] {
                    return Err(PolygonError::Repeated(i, j));
                }
            }
        }
        let scale = points
            .iter()
            .map(|p| p.x.abs().max(p.y.abs()))
            .fold(1.0f64, f64::max);
        let mut sign = 0.0f64;
        let mut turning = 0.0f64;
        for i in 0..n {
            let (a, b, c) = (points[i], points[(i + 1) % n], points[(i + 2) % n]);
            let (ux, uy) = (b.x - a.x, b.y - a.y);
            let (vx, vy) = (c.x - b.x, c.y - b.y);
            let cross = ux * vy - uy * vx;
            // Collinear within rounding of the coordinates' magnitude.
            let tol = 1e-12 * ux.hypot(uy) * vx.hypot(vy) + 1e-15 * scale * scale;
            if cross.abs() <= tol {
                return Err(PolygonError::Collinear(i, (i + 1) % n, (i + 2) % n));
            }
            if sign != 0.0 && cross.signum() != sign {
                return Err(PolygonError::NotConvex((i + 1) % n));
            }
            sign = cross.signum();
            turning += cross.atan2(ux * vx + uy * vy);
        }
        let winds = (turning.abs() / std::f64::consts::TAU).round() as usize;
        if winds != 1 {
            return Err(PolygonError::SelfIntersecting(winds));
        }
        let mut vertices = points.to_vec();
        if sign < 0.0 {
            vertices.reverse();
        }
        // Counter-clockwise: the interior lies left of every edge.
        let edges = (0..n)
            .map(|i| HalfPlane::left_of(vertices[i], vertices[(i + 1) % n]))
            .collect();
        let bbox = vertices.iter().fold(
            Rect {
                x0: f64::INFINITY,
                y0: f64::INFINITY,
                x1: f64::NEG_INFINITY,
                y1: f64::NEG_INFINITY,
            },
            |r, p| Rect {
                x0: r.x0.min(p.x),
                y0: r.y0.min(p.y),
                x1: r.x1.max(p.x),
                y1: r.y1.max(p.y),
            },
        );
        Ok(Polygon {
            vertices,
            edges,
            bbox,
            // A cell centre on an edge is inside despite rounding: 1e-9 of
            // the coordinates' size, but at most 1e-5, so that a polygon
            // with far vertices does not take in the cells near it; the
            // rounding of an edge's line (about 1e-16 of its vertices'
            // size) is covered by the second term.
            eps: 1e-9 * scale.min(1e4) + 1e-13 * scale,
        })
    }

    /// The vertices, counter-clockwise.
    pub fn vertices(&self) -> &[Point] {
        &self.vertices
    }

    /// The bounding box.
    pub fn bbox(&self) -> Rect {
        self.bbox
    }

    /// True when `p` lies in the open interior.
    #[inline]
    pub fn contains_open(&self, p: Point) -> bool {
        self.edges.iter().all(|h| h.slack(p) > 0.0)
    }

    /// True when `p` lies in the closed polygon (within a rounding
    /// tolerance of its edges: a cell centre on an edge is inside).
    #[inline]
    pub fn contains_closed(&self, p: Point) -> bool {
        self.edges.iter().all(|h| h.slack(p) >= -self.eps)
    }

    /// The closed interval of `x` where the horizontal line at `y` lies in
    /// the closed polygon (within the tolerance of
    /// [`Polygon::contains_closed`], by the same inequalities), or `None`.
    pub fn row_span(&self, y: f64) -> Option<(f64, f64)> {
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for h in &self.edges {
            // n.x·x + n.y·y ≤ c + eps.
            let rhs = h.c + self.eps - h.n.y * y;
            if h.n.x > 0.0 {
                hi = hi.min(rhs / h.n.x);
            } else if h.n.x < 0.0 {
                lo = lo.max(rhs / h.n.x);
            } else if rhs < 0.0 {
                return None;
            }
        }
        (lo <= hi).then_some((lo, hi))
    }

    /// Area of the part of the polygon inside `rect`.
    pub fn area_within(&self, rect: &Rect) -> f64 {
        let mut poly = self.vertices.clone();
        for side in [
            &(|p: Point| p.x - rect.x0) as &dyn Fn(Point) -> f64,
            &|p: Point| rect.x1 - p.x,
            &|p: Point| p.y - rect.y0,
            &|p: Point| rect.y1 - p.y,
        ] {
            poly = crate::geometry::clip_half_plane(&poly, side);
            if poly.len() < 3 {
                return 0.0;
            }
        }
        let n = poly.len();
        0.5 * (0..n)
            .map(|i| {
                let (a, b) = (poly[i], poly[(i + 1) % n]);
                a.x * b.y - b.x * a.y
            })
            .sum::<f64>()
            .abs()
    }

    /// The open interval `(t0, t1)` of the line `o + t·d` inside the
    /// polygon's interior, or `None` when the line misses it (or only
    /// touches its boundary).
    #[inline]
    pub fn line_interior(&self, o: Point, d: Point) -> Option<(f64, f64)> {
        line_in(&self.edges, o, d)
    }

    /// The polygon's shadow seen from `p`: the points `q` whose open
    /// segment from `p` meets the interior.
    pub fn shadow(&self, p: Point) -> Shadow {
        if self.contains_open(p) {
            return Shadow::Everything;
        }
        // Edges that face p or hold it: p is not strictly inside them.
        let mut planes: Vec<HalfPlane> = self
            .edges
            .iter()
            .copied()
            .filter(|h| h.slack(p) <= 0.0)
            .collect();
        if planes.iter().any(|h| h.slack(p) < 0.0) {
            // p is strictly outside: the cone from p that the polygon spans
            // (less than π wide), bounded by the rays through its most
            // clockwise and most counter-clockwise vertices.
            let rel = |v: Point| Point::new(v.x - p.x, v.y - p.y);
            let cross = |a: Point, b: Point| a.x * b.y - a.y * b.x;
            let (mut cw, mut ccw) = (self.vertices[0], self.vertices[0]);
            for &v in &self.vertices[1..] {
                if cross(rel(cw), rel(v)) < 0.0 {
                    cw = v;
                }
                if cross(rel(ccw), rel(v)) > 0.0 {
                    ccw = v;
                }
            }
            // The polygon lies left of p → cw and right of p → ccw.
            planes.push(HalfPlane::left_of(p, cw));
            planes.push(HalfPlane::left_of(ccw, p));
        }
        Shadow::Planes(planes)
    }
}

/// Below this share of the coordinates' size a point test counts a sight
/// line as touching an obstacle, not crossing it: rounding (about 1e-16
/// of the size) puts a point on a line that grazes a vertex on either side
/// of the shadow's edge. Only point tests use it; intervals along rays
/// differ by it in measure zero.
const GRAZE: f64 = 1e-9;

/// The points hidden from a viewpoint by one obstacle.
#[derive(Debug, Clone, PartialEq)]
pub enum Shadow {
    /// The viewpoint is inside the obstacle: it sees nothing.
    Everything,
    /// An open convex set, the intersection of these open half-planes.
    Planes(Vec<HalfPlane>),
}

impl Shadow {
    /// True when `q` is hidden: strictly inside every half-plane, by more
    /// than [`GRAZE`] of its coordinates' size (a point on a line that
    /// grazes a vertex is seen, whichever side rounding puts it).
    #[inline]
    fn hides(&self, q: Point) -> bool {
        match self {
            Shadow::Everything => true,
            Shadow::Planes(planes) => {
                let tol = GRAZE * (1.0 + q.x.abs().max(q.y.abs()));
                planes.iter().all(|h| h.slack(q) > tol)
            }
        }
    }

    /// A rectangle holding the part of `rect` that this shadow hides, or
    /// `None` when it hides none of it: the bounding box of `rect` clipped
    /// by the shadow's half-planes, grown by a relative 1e-9 so that
    /// rounding never leaves a hidden sliver out.
    fn bbox_within(&self, rect: &Rect) -> Option<Rect> {
        let Shadow::Planes(planes) = self else {
            return Some(*rect);
        };
        let mut poly = vec![
            Point::new(rect.x0, rect.y0),
            Point::new(rect.x1, rect.y0),
            Point::new(rect.x1, rect.y1),
            Point::new(rect.x0, rect.y1),
        ];
        let mut next = Vec::with_capacity(poly.len() + planes.len());
        for h in planes {
            next.clear();
            for (i, &p) in poly.iter().enumerate() {
                let q = poly[(i + 1) % poly.len()];
                let (sp, sq) = (h.slack(p), h.slack(q));
                if sp >= 0.0 {
                    next.push(p);
                }
                if (sp >= 0.0) != (sq >= 0.0) {
                    let f = sp / (sp - sq);
                    next.push(Point::new(p.x + (q.x - p.x) * f, p.y + (q.y - p.y) * f));
                }
            }
            std::mem::swap(&mut poly, &mut next);
            if poly.is_empty() {
                return None;
            }
        }
        let pad = 1e-9 * (1.0 + (rect.x1 - rect.x0).abs() + (rect.y1 - rect.y0).abs());
        let bbox = poly.iter().fold(
            Rect {
                x0: f64::INFINITY,
                y0: f64::INFINITY,
                x1: f64::NEG_INFINITY,
                y1: f64::NEG_INFINITY,
            },
            |b, p| Rect {
                x0: b.x0.min(p.x - pad),
                y0: b.y0.min(p.y - pad),
                x1: b.x1.max(p.x + pad),
                y1: b.y1.max(p.y + pad),
            },
        );
        Some(bbox.intersect(rect))
    }

    /// The open interval of `o + t·d` that is hidden.
    #[inline]
    fn on_line(&self, o: Point, d: Point) -> Option<(f64, f64)> {
        match self {
            Shadow::Everything => Some((f64::NEG_INFINITY, f64::INFINITY)),
            Shadow::Planes(planes) => line_in(planes, o, d),
        }
    }
}

/// One validated obstacle.
#[derive(Debug, Clone, PartialEq)]
pub struct Obstacle {
    /// Its outline.
    pub polygon: Polygon,
    /// What it blocks.
    pub kind: ObstacleKind,
}

/// A scenario's obstacles, with the queries the model asks of them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Obstacles {
    list: Vec<Obstacle>,
}

impl Obstacles {
    /// The obstacles of a scenario (validated one by one).
    pub fn new(list: Vec<Obstacle>) -> Self {
        Obstacles { list }
    }

    /// True when there are none: sight is never blocked and flights never
    /// end early.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// The obstacles, in the spec's order.
    pub fn list(&self) -> &[Obstacle] {
        &self.list
    }

    /// True when some obstacle is a building.
    pub fn in_building_anywhere(&self) -> bool {
        self.list.iter().any(|o| o.kind == ObstacleKind::Building)
    }

    /// True when `p` lies in a building (closed): no ground sensor may
    /// stand there.
    pub fn in_building(&self, p: Point) -> bool {
        self.list
            .iter()
            .any(|o| o.kind == ObstacleKind::Building && o.polygon.contains_closed(p))
    }

    /// True when `p` lies in a building's interior: no target is there.
    pub fn inside_building(&self, p: Point) -> bool {
        self.list
            .iter()
            .any(|o| o.kind == ObstacleKind::Building && o.polygon.contains_open(p))
    }

    /// The speed of a target at `pos` moving `vel` per step, and how far
    /// it flies from there before it enters a building (0 when it stands
    /// in one, infinity when its path meets none): it still flies after
    /// `t` steps while that distance exceeds `speed·t`.
    pub fn flight(&self, pos: Point, vel: Point) -> (f64, f64) {
        let speed = vel.x.hypot(vel.y);
        if speed == 0.0 {
            let stop = if self.inside_building(pos) {
                0.0
            } else {
                f64::INFINITY
            };
            return (speed, stop);
        }
        (
            speed,
            self.stop(pos, Point::new(vel.x / speed, vel.y / speed)),
        )
    }

    /// Where a target flying from `o` along the unit direction `d` stops:
    /// the distance at which the ray first enters a building's interior
    /// (0 when it starts inside one), or infinity.
    pub fn stop(&self, o: Point, d: Point) -> f64 {
        first_entry(
            self.list
                .iter()
                .filter(|ob| ob.kind == ObstacleKind::Building),
            o,
            d,
        )
    }

    /// How far a sight line from `p` along the unit direction `d` runs
    /// before it enters an obstacle's interior (0 from inside one), or
    /// infinity.
    pub fn sight_reach(&self, p: Point, d: Point) -> f64 {
        first_entry(self.list.iter(), p, d)
    }

    /// True when the open segment `(p, q)` meets no obstacle's interior
    /// (over more than [`GRAZE`] of the coordinates' size: a segment that
    /// grazes a vertex is clear, whichever side rounding puts it).
    pub fn clear(&self, p: Point, q: Point) -> bool {
        let d = Point::new(q.x - p.x, q.y - p.y);
        let (len, size) = (
            d.x.hypot(d.y),
            p.x.abs().max(p.y.abs()).max(q.x.abs()).max(q.y.abs()),
        );
        let tol = GRAZE * (1.0 + size);
        self.list.iter().all(|ob| {
            ob.polygon
                .line_interior(p, d)
                .is_none_or(|(t0, t1)| (t1.min(1.0) - t0.max(0.0)) * len <= tol)
        })
    }

    /// What a sensor at `p` cannot see within `region` (a convex region
    /// holding `p`: only obstacles that meet it can block a sight line
    /// inside it), or `None` when nothing there is hidden.
    pub fn sight(&self, p: Point, region: &Region) -> Option<Sight> {
        let r = region.rect;
        let shadows: Vec<Shadow> = self
            .list
            .iter()
            .filter(|ob| {
                let b = ob.polygon.bbox();
                b.x0 < r.x1 && b.x1 > r.x0 && b.y0 < r.y1 && b.y1 > r.y0
            })
            .map(|ob| ob.polygon.shadow(p))
            .collect();
        (!shadows.is_empty()).then_some(Sight { from: p, shadows })
    }
}

/// The distance along the ray `o + t·d` (`t ≥ 0`) at which it first
/// enters one of `obstacles`' interiors (0 when it starts inside one), or
/// infinity.
fn first_entry<'a>(obstacles: impl Iterator<Item = &'a Obstacle>, o: Point, d: Point) -> f64 {
    obstacles
        .filter_map(|ob| ob.polygon.line_interior(o, d))
        .filter(|&(_, t1)| t1 > 0.0)
        .map(|(t0, _)| t0.max(0.0))
        .fold(f64::INFINITY, f64::min)
}

/// The shadows that hide points from one viewpoint: what a ground sensor's
/// look cannot see.
#[derive(Debug, Clone, PartialEq)]
pub struct Sight {
    from: Point,
    shadows: Vec<Shadow>,
}

impl Sight {
    /// The viewpoint.
    pub fn from(&self) -> Point {
        self.from
    }

    /// True when the viewpoint sees `q`.
    #[inline]
    pub fn sees(&self, q: Point) -> bool {
        q == self.from || !self.shadows.iter().any(|s| s.hides(q))
    }

    /// True when the viewpoint is inside an obstacle: it sees nothing but
    /// itself.
    pub fn blind(&self) -> bool {
        self.shadows.iter().any(|s| matches!(s, Shadow::Everything))
    }

    /// A rectangle holding every point of `rect` that the viewpoint does
    /// not see, or `None` when it sees all of it.
    pub fn hidden_within(&self, rect: &Rect) -> Option<Rect> {
        self.shadows
            .iter()
            .filter_map(|s| s.bbox_within(rect))
            .reduce(|a, b| a.hull(&b))
    }

    /// Pushes onto `out` the visible parts of `[lo, hi]` on the line
    /// `o + t·d`, sorted and disjoint (closed intervals of positive length;
    /// the hidden parts are open, so this is exact up to measure zero).
    pub fn visible(&self, o: Point, d: Point, lo: f64, hi: f64, out: &mut Vec<(f64, f64)>) {
        let first = out.len();
        out.push((lo, hi));
        for s in &self.shadows {
            let Some((a, b)) = s.on_line(o, d) else {
                continue;
            };
            if b <= lo || a >= hi {
                continue;
            }
            // Cut (a, b) out of every interval pushed so far.
            let mut i = first;
            while i < out.len() {
                let (p, q) = out[i];
                if b <= p || a >= q {
                    i += 1;
                    continue;
                }
                match (a > p, b < q) {
                    (true, true) => {
                        out[i] = (p, a);
                        out.insert(i + 1, (b, q));
                        i += 2;
                    }
                    (true, false) => {
                        out[i] = (p, a);
                        i += 1;
                    }
                    (false, true) => {
                        out[i] = (b, q);
                        i += 1;
                    }
                    (false, false) => {
                        out.remove(i);
                    }
                }
            }
            if out.len() == first {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests;
