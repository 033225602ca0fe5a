//! Plane geometry the model needs: fields of view clipped to the zone, the
//! interval a ray from a source spends inside one, areas and overlaps, and
//! the closed-form integral of `1/r` over a rectangle.
//!
//! Every field of view clipped to the (convex) zone is convex, so a ray
//! crosses it in at most one interval. That is what makes the model's
//! integrals 1-D interval arithmetic along rays.

use std::sync::LazyLock;

/// A point or vector in zone units.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Point {
    /// East coordinate.
    pub x: f64,
    /// North coordinate.
    pub y: f64,
}

impl Point {
    /// A point from its coordinates.
    pub const fn new(x: f64, y: f64) -> Self {
        Self { x, y }
    }
}

/// An axis-aligned closed rectangle `[x0,x1] × [y0,y1]`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Rect {
    /// West edge.
    pub x0: f64,
    /// South edge.
    pub y0: f64,
    /// East edge.
    pub x1: f64,
    /// North edge.
    pub y1: f64,
}

impl Rect {
    /// Area, zero for an empty rectangle.
    pub fn area(&self) -> f64 {
        (self.x1 - self.x0).max(0.0) * (self.y1 - self.y0).max(0.0)
    }

    /// Intersection; may be empty (x0 > x1 or y0 > y1).
    pub fn intersect(&self, o: &Rect) -> Rect {
        Rect {
            x0: self.x0.max(o.x0),
            y0: self.y0.max(o.y0),
            x1: self.x1.min(o.x1),
            y1: self.y1.min(o.y1),
        }
    }

    /// The smallest rectangle holding both.
    pub fn hull(&self, o: &Rect) -> Rect {
        Rect {
            x0: self.x0.min(o.x0),
            y0: self.y0.min(o.y0),
            x1: self.x1.max(o.x1),
            y1: self.y1.max(o.y1),
        }
    }

    /// True when the closed rectangle has at least one point.
    pub fn is_empty(&self) -> bool {
        self.x0 > self.x1 || self.y0 > self.y1
    }

    /// Closed containment.
    pub fn contains(&self, p: Point) -> bool {
        p.x >= self.x0 && p.x <= self.x1 && p.y >= self.y0 && p.y <= self.y1
    }

    /// Parameter interval `[t0, t1]` (t ≥ 0) of the ray `o + t·d` inside the
    /// rectangle, given `inv = (1/d.x, 1/d.y)` (infinite where d has a zero
    /// component).
    #[inline]
    pub fn ray(&self, o: Point, d: Point, inv: Point) -> Option<(f64, f64)> {
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for (oc, dc, ic, lo, hi) in [
            (o.x, d.x, inv.x, self.x0, self.x1),
            (o.y, d.y, inv.y, self.y0, self.y1),
        ] {
            if dc == 0.0 {
                if oc < lo || oc > hi {
                    return None;
                }
            } else {
                let (a, b) = ((lo - oc) * ic, (hi - oc) * ic);
                let (a, b) = if a <= b { (a, b) } else { (b, a) };
                t0 = t0.max(a);
                t1 = t1.min(b);
            }
        }
        (t0 <= t1).then_some((t0, t1))
    }
}

/// A closed disk.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Disk {
    /// Centre.
    pub c: Point,
    /// Radius.
    pub r: f64,
}

/// A field of view clipped to the zone: `rect ∩ disk`, where the rectangle is
/// the square FOV (or the circle's bounding square) already clipped to the
/// zone. Always convex.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Region {
    /// The clipped square.
    pub rect: Rect,
    /// The circle, for circular fields of view.
    pub disk: Option<Disk>,
}

impl Region {
    /// Closed containment.
    pub fn contains(&self, p: Point) -> bool {
        self.rect.contains(p)
            && self
                .disk
                .is_none_or(|d| (p.x - d.c.x).powi(2) + (p.y - d.c.y).powi(2) <= d.r * d.r)
    }

    /// Interval of ray parameters inside the region (see [`Rect::ray`]); for a
    /// unit `d` these are distances from `o`.
    #[inline]
    pub fn ray(&self, o: Point, d: Point, inv: Point) -> Option<(f64, f64)> {
        let (a, b) = self.rect.ray(o, d, inv)?;
        match self.disk {
            None => Some((a, b)),
            Some(disk) => {
                // |o + t d − c|² = r² with |d| = 1.
                let (fx, fy) = (o.x - disk.c.x, o.y - disk.c.y);
                let bq = fx * d.x + fy * d.y;
                let cq = fx * fx + fy * fy - disk.r * disk.r;
                let disc = bq * bq - cq;
                if disc < 0.0 {
                    return None;
                }
                let s = disc.sqrt();
                let (lo, hi) = ((-bq - s).max(a), (-bq + s).min(b));
                (lo <= hi).then_some((lo, hi))
            }
        }
    }

    /// Distance range `[min, max]` from `o` to points of the region's
    /// rectangle: a cheap bound used to skip regions a ray interval cannot meet.
    pub fn radial_bounds(&self, o: Point) -> (f64, f64) {
        let r = &self.rect;
        let dx = (r.x0 - o.x).max(0.0).max(o.x - r.x1);
        let dy = (r.y0 - o.y).max(0.0).max(o.y - r.y1);
        let fx = (r.x0 - o.x).abs().max((r.x1 - o.x).abs());
        let fy = (r.y0 - o.y).abs().max((r.y1 - o.y).abs());
        (dx.hypot(dy), fx.hypot(fy))
    }

    /// Points of the region's boundary whose directions from `o` include both
    /// extreme directions and every direction at which the ray interval
    /// changes form: rectangle corners inside the disk, circle–edge
    /// crossings, and the tangent points from `o`.
    pub fn breakpoints(&self, o: Point, out: &mut Vec<Point>) {
        let r = &self.rect;
        let corners = [
            Point::new(r.x0, r.y0),
            Point::new(r.x1, r.y0),
            Point::new(r.x1, r.y1),
            Point::new(r.x0, r.y1),
        ];
        let Some(disk) = self.disk else {
            out.extend(corners);
            return;
        };
        let eps = 1e-9 * (1.0 + disk.r);
        let inside = |p: Point| self.contains_eps(p, eps);
        out.extend(corners.into_iter().filter(|&p| inside(p)));
        // Circle crossings with the four edge lines.
        for (x, vertical) in [(r.x0, true), (r.x1, true), (r.y0, false), (r.y1, false)] {
            let (c_along, c_across) = if vertical {
                (disk.c.y, disk.c.x)
            } else {
                (disk.c.x, disk.c.y)
            };
            let h2 = disk.r * disk.r - (x - c_across).powi(2);
            if h2 < 0.0 {
                continue;
            }
            let h = h2.sqrt();
            for s in [c_along - h, c_along + h] {
                let p = if vertical {
                    Point::new(x, s)
                } else {
                    Point::new(s, x)
                };
                if inside(p) {
                    out.push(p);
                }
            }
        }
        // Tangent points from o.
        let (dx, dy) = (disk.c.x - o.x, disk.c.y - o.y);
        let d2 = dx * dx + dy * dy;
        if d2 > disk.r * disk.r {
            let d = d2.sqrt();
            let base = dy.atan2(dx);
            let half = (disk.r / d).asin();
            let len = (d2 - disk.r * disk.r).sqrt();
            for a in [base - half, base + half] {
                let p = Point::new(o.x + len * a.cos(), o.y + len * a.sin());
                if inside(p) {
                    out.push(p);
                }
            }
        }
    }

    fn contains_eps(&self, p: Point, eps: f64) -> bool {
        let r = &self.rect;
        p.x >= r.x0 - eps
            && p.x <= r.x1 + eps
            && p.y >= r.y0 - eps
            && p.y <= r.y1 + eps
            && self
                .disk
                .is_none_or(|d| (p.x - d.c.x).hypot(p.y - d.c.y) <= d.r + eps)
    }

    /// True when the two regions' bounding rectangles meet (a cheap, exact
    /// test for squares and a conservative one for circles).
    pub fn may_overlap(&self, o: &Region) -> bool {
        !self.rect.intersect(&o.rect).is_empty()
    }

    /// Area of the region.
    pub fn area(&self) -> f64 {
        if self.disk.is_none() {
            return self.rect.area();
        }
        self.covered_area(std::slice::from_ref(self))
    }

    /// Area of the part of this region covered by the union of `others`.
    ///
    /// Integrates the length of the union of vertical chords over x: exact
    /// for rectangles (piecewise-constant chords), Gauss–Legendre between the
    /// breakpoints for disks.
    pub fn covered_area(&self, others: &[Region]) -> f64 {
        let others: Vec<(&Region, f64)> = others
            .iter()
            .filter(|o| self.may_overlap(o))
            .map(|o| (o, 1.0))
            .collect();
        self.cover(&others)
    }

    /// The expected area of this region in which a target is detected, when
    /// each of `others` is a region `(r, p)` that detects a target inside it
    /// with probability `p`, independently: `∫ 1 − Π_{r ∋ q} (1 − p) dq`.
    /// With every `p = 1` it is [`Region::covered_area`], computed the same
    /// way.
    pub fn detected_area(&self, others: &[(Region, f64)]) -> f64 {
        let others: Vec<(&Region, f64)> = others
            .iter()
            .filter(|(o, _)| self.may_overlap(o))
            .map(|(o, p)| (o, *p))
            .collect();
        self.cover(&others)
    }

    fn cover(&self, others: &[(&Region, f64)]) -> f64 {
        let certain = others.iter().all(|&(_, p)| p == 1.0);
        if others.is_empty() {
            return 0.0;
        }
        let (xa, xb) = (self.rect.x0, self.rect.x1);
        let mut xs = vec![xa, xb];
        for reg in others.iter().map(|o| o.0).chain(std::iter::once(self)) {
            xs.extend([reg.rect.x0, reg.rect.x1]);
            if let Some(d) = reg.disk {
                xs.extend([d.c.x - d.r, d.c.x, d.c.x + d.r]);
                for y in [reg.rect.y0, reg.rect.y1] {
                    let h2 = d.r * d.r - (y - d.c.y).powi(2);
                    if h2 > 0.0 {
                        xs.extend([d.c.x - h2.sqrt(), d.c.x + h2.sqrt()]);
                    }
                }
            }
        }
        xs.retain(|&x| x >= xa && x <= xb);
        xs.sort_by(f64::total_cmp);
        xs.dedup();
        let curved = self.disk.is_some() || others.iter().any(|o| o.0.disk.is_some());
        let (nodes, weights) = gauss_legendre(if curved { CURVED_SLAB_NODES } else { 1 });
        let mut chords: Vec<(f64, f64)> = Vec::with_capacity(others.len());
        let mut weighted: Vec<(f64, f64, f64)> = Vec::new();
        let mut events = Vec::new();
        let mut total = 0.0;
        for w in xs.windows(2) {
            let (a, b) = (w[0], w[1]);
            if b <= a {
                continue;
            }
            let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
            for (&n, &wt) in nodes.iter().zip(weights) {
                // For circles, x = mid + half·sin(πn/2): chords of a disk
                // behave like √(distance to the slab's end), and the
                // substitution makes the integrand smooth there.
                let (x, w) = if curved {
                    let q = std::f64::consts::FRAC_PI_2 * n;
                    (
                        mid + half * q.sin(),
                        wt * half * std::f64::consts::FRAC_PI_2 * q.cos(),
                    )
                } else {
                    (mid + half * n, wt * half)
                };
                let Some((ya, yb)) = self.vertical_chord(x) else {
                    continue;
                };
                if certain {
                    chords.clear();
                    chords.extend(others.iter().filter_map(|o| o.0.vertical_chord(x)));
                    total += w * union_within(&mut chords, ya, yb);
                } else {
                    weighted.clear();
                    weighted.extend(
                        others
                            .iter()
                            .filter_map(|&(o, p)| o.vertical_chord(x).map(|(a, b)| (a, b, p))),
                    );
                    total += w * detection_within(&weighted, ya, yb, &mut events);
                }
            }
        }
        total
    }

    fn vertical_chord(&self, x: f64) -> Option<(f64, f64)> {
        if x < self.rect.x0 || x > self.rect.x1 {
            return None;
        }
        let (mut a, mut b) = (self.rect.y0, self.rect.y1);
        if let Some(d) = self.disk {
            let h2 = d.r * d.r - (x - d.c.x).powi(2);
            if h2 < 0.0 {
                return None;
            }
            let h = h2.sqrt();
            a = a.max(d.c.y - h);
            b = b.min(d.c.y + h);
        }
        (a <= b).then_some((a, b))
    }
}

/// Length of `[lo, hi] ∩ ⋃ intervals`. Sorts `intervals` in place.
#[inline]
pub fn union_within(intervals: &mut [(f64, f64)], lo: f64, hi: f64) -> f64 {
    if intervals.len() > 1 {
        intervals.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    }
    let mut covered = 0.0;
    let mut reach = lo;
    for &(a, b) in intervals.iter() {
        let a = a.max(reach);
        let b = b.min(hi);
        if b > a {
            covered += b - a;
            reach = b;
        }
    }
    covered
}

/// `∫_lo^hi 1 − Π (1 − p) dx` over the intervals `(a, b, p)` that hold `x`:
/// the expected length of `[lo, hi]` in which a target is detected when
/// each interval detects independently with probability `p ∈ (0, 1]`. With
/// every `p = 1` it is the length of the union. `events` is scratch space.
///
/// ```
/// use vigil::geometry::detection_within;
/// let mut ev = Vec::new();
/// // [0,2] at ½ and [1,3] at ½: 1·½ + 1·¾ + 1·½ over [0,3].
/// let v = detection_within(&[(0.0, 2.0, 0.5), (1.0, 3.0, 0.5)], 0.0, 3.0, &mut ev);
/// assert!((v - 1.75).abs() < 1e-12);
/// // Certain intervals: the union's length, clipped to [lo, hi].
/// let v = detection_within(&[(0.0, 2.0, 1.0), (1.0, 3.0, 1.0)], 0.5, 2.5, &mut ev);
/// assert!((v - 2.0).abs() < 1e-12);
/// ```
pub fn detection_within(
    intervals: &[(f64, f64, f64)],
    lo: f64,
    hi: f64,
    events: &mut Vec<(f64, f64, bool)>,
) -> f64 {
    let mut detected = 0.0;
    detection_pieces(intervals, lo, hi, events, |a, b, p| detected += (b - a) * p);
    detected
}

/// Cuts `[lo, hi] ∩ ⋃ intervals` into pieces with one detection probability
/// each, `1 − Π (1 − p)` over the intervals `(a, b, p)` that hold it, and
/// calls `piece(a, b, detected)` for each in order. `events` is scratch
/// space.
pub fn detection_pieces(
    intervals: &[(f64, f64, f64)],
    lo: f64,
    hi: f64,
    events: &mut Vec<(f64, f64, bool)>,
    mut piece: impl FnMut(f64, f64, f64),
) {
    // Events (x, 1 − p, opens), swept in x order.
    events.clear();
    for &(a, b, p) in intervals {
        let (a, b) = (a.max(lo), b.min(hi));
        if b > a {
            events.push((a, 1.0 - p, true));
            events.push((b, 1.0 - p, false));
        }
    }
    events.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
    let mut held = OpenIntervals::default();
    let mut prev = lo;
    for &(x, q, opens) in events.iter() {
        if held.any() && x > prev {
            piece(prev, x, held.detected());
        }
        prev = x;
        held.toggle(opens, q);
    }
}

/// The intervals open at a point of a sweep over weighted intervals (see
/// [`detection_pieces`]): their miss probability, kept as a count of
/// certain ones (`p = 1`) and the product of `1 − p` over the others,
/// divided out again on closing and reset when nothing is open, so that
/// rounding cannot accumulate.
#[derive(Debug, Clone, Copy)]
pub struct OpenIntervals {
    open: usize,
    certain: usize,
    miss: f64,
}

impl Default for OpenIntervals {
    fn default() -> Self {
        Self {
            open: 0,
            certain: 0,
            miss: 1.0,
        }
    }
}

impl OpenIntervals {
    /// True when some interval is open.
    #[inline]
    pub fn any(&self) -> bool {
        self.open > 0
    }

    /// `1 − Π (1 − p)` over the open intervals.
    #[inline]
    pub fn detected(&self) -> f64 {
        if self.certain > 0 {
            1.0
        } else {
            1.0 - self.miss
        }
    }

    /// An interval of miss probability `q = 1 − p` opens (`opens`) or
    /// closes; a close must match an open.
    #[inline]
    pub fn toggle(&mut self, opens: bool, q: f64) {
        match (opens, q <= 0.0) {
            (true, true) => self.certain += 1,
            (false, true) => self.certain -= 1,
            (true, false) => self.miss *= q,
            (false, false) => self.miss /= q,
        }
        if opens {
            self.open += 1;
        } else {
            self.open -= 1;
            if self.open == 0 {
                self.miss = 1.0;
            }
        }
    }
}

/// ∫∫ over the rectangle `[x0,x1]×[y0,y1]` (coordinates relative to the
/// pole) of `1/√(x²+y²)`, in closed form.
///
/// The antiderivative `G(x,y) = x·ln(y+r) + y·ln(x+r)` holds in the closed
/// first quadrant, so the rectangle is split at the axes and each piece
/// reflected into it.
pub fn inv_r_integral(x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    fn g(x: f64, y: f64) -> f64 {
        let r = x.hypot(y);
        let a = if x > 0.0 { x * (y + r).ln() } else { 0.0 };
        let b = if y > 0.0 { y * (x + r).ln() } else { 0.0 };
        a + b
    }
    fn split(lo: f64, hi: f64) -> [(f64, f64); 2] {
        // Non-negative pieces after reflection: [lo,hi]∩(−∞,0] and ∩[0,∞).
        [((-hi).max(0.0), (-lo).max(0.0)), (lo.max(0.0), hi.max(0.0))]
    }
    let mut total = 0.0;
    for (a, b) in split(x0, x1) {
        if b <= a {
            continue;
        }
        for (c, d) in split(y0, y1) {
            if d <= c {
                continue;
            }
            total += g(b, d) - g(a, d) - g(b, c) + g(a, c);
        }
    }
    total
}

/// `∫∫ 1/|p − o| dp` over the part of `rect` inside the wedge of
/// directions from `o` between `lo` and `hi` (angles counter-clockwise from
/// the unit vector `frame`, `0 ≤ hi − lo ≤ π`), in closed form.
///
/// The rectangle is clipped by the wedge's two half-planes (a convex
/// polygon), and the polygon is the signed fan of triangles `(o, V_i,
/// V_i+1)`. Over such a triangle the integral in polar coordinates around
/// `o` is `∫ ρ(θ) dθ` with `ρ = h/cos(θ − θ_n)` the distance to the edge's
/// line, i.e. `h·(asinh(u_{i+1}/h) − asinh(u_i/h))` with `h` the distance of
/// `o` from the line and `u` the positions of the ends along it.
///
/// ```
/// use vigil::geometry::{Point, Rect, inv_r_integral, wedge_inv_r_integral};
/// let r = Rect { x0: 1.0, y0: -2.0, x1: 4.0, y1: 3.0 };
/// let o = Point::new(0.0, 0.0);
/// let east = Point::new(1.0, 0.0);
/// let half = std::f64::consts::FRAC_PI_2;
/// // The whole half-plane holds the rectangle: the plain integral.
/// let whole = wedge_inv_r_integral(o, &r, east, -half, half);
/// assert!((whole - inv_r_integral(1.0, 4.0, -2.0, 3.0)).abs() < 1e-12);
/// // Split at the x axis: the two halves add up.
/// let below = wedge_inv_r_integral(o, &r, east, -half, 0.0);
/// let above = wedge_inv_r_integral(o, &r, east, 0.0, half);
/// assert!((below + above - whole).abs() < 1e-12);
/// ```
pub fn wedge_inv_r_integral(o: Point, rect: &Rect, frame: Point, lo: f64, hi: f64) -> f64 {
    if rect.is_empty() || hi <= lo {
        return 0.0;
    }
    let turn = |a: f64| {
        let (s, c) = a.sin_cos();
        Point::new(c * frame.x - s * frame.y, c * frame.y + s * frame.x)
    };
    let (d_lo, d_hi) = (turn(lo), turn(hi));
    // Vertices relative to o, counter-clockwise.
    let mut poly = vec![
        Point::new(rect.x0 - o.x, rect.y0 - o.y),
        Point::new(rect.x1 - o.x, rect.y0 - o.y),
        Point::new(rect.x1 - o.x, rect.y1 - o.y),
        Point::new(rect.x0 - o.x, rect.y1 - o.y),
    ];
    let cross = |a: Point, b: Point| a.x * b.y - a.y * b.x;
    // Left of d_lo, then right of d_hi.
    poly = clip_half_plane(&poly, |v| cross(d_lo, v));
    poly = clip_half_plane(&poly, |v| cross(v, d_hi));
    let n = poly.len();
    let mut total = 0.0;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let (ex, ey) = (b.x - a.x, b.y - a.y);
        let len = ex.hypot(ey);
        if len == 0.0 {
            continue;
        }
        let (ex, ey) = (ex / len, ey / len);
        // Signed distance of o from the edge's line (positive: o on the
        // edge's left, a counter-clockwise triangle o, a, b).
        let h = a.x * ey - a.y * ex;
        if h.abs() < 1e-300 {
            continue;
        }
        let (ua, ub) = (a.x * ex + a.y * ey, b.x * ex + b.y * ey);
        let ha = h.abs();
        total += h.signum() * ha * ((ub / ha).asinh() - (ua / ha).asinh());
    }
    total.max(0.0)
}

/// The part of a convex polygon where `side(v) ≥ 0` (Sutherland–Hodgman
/// against one half-plane).
pub(crate) fn clip_half_plane(poly: &[Point], side: impl Fn(Point) -> f64) -> Vec<Point> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (sa, sb) = (side(a), side(b));
        if sa >= 0.0 {
            out.push(a);
        }
        if (sa >= 0.0) != (sb >= 0.0) {
            let t = sa / (sa - sb);
            out.push(Point::new(a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)));
        }
    }
    out
}

/// Gauss–Legendre nodes per slab between breakpoints of a cover with a
/// disk (see [`Region::covered_area`]); straight edges need one. The cost
/// model counts a curved cover's work by it.
pub const CURVED_SLAB_NODES: usize = 12;

static GL: LazyLock<Vec<(Vec<f64>, Vec<f64>)>> =
    LazyLock::new(|| (0..=32).map(compute_gauss_legendre).collect());

/// Gauss–Legendre nodes and weights on `[-1, 1]` for `1 ≤ n ≤ 32` points.
///
/// # Panics
/// When `n` is outside `1..=32` (a programming error, never input-driven).
pub fn gauss_legendre(n: usize) -> (&'static [f64], &'static [f64]) {
    assert!(
        (1..=32).contains(&n),
        "gauss_legendre supports 1..=32 nodes"
    );
    let (x, w) = &GL[n];
    (x, w)
}

fn compute_gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut xs = vec![0.0; n];
    let mut ws = vec![0.0; n];
    if n == 0 {
        return (xs, ws);
    }
    for i in 0..n {
        // Newton iteration on P_n from the Chebyshev-like initial guess.
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            if n == 1 {
                p1 = x;
                p0 = 1.0;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        xs[i] = x;
        ws[i] = 2.0 / ((1.0 - x * x) * dp * dp);
    }
    (xs, ws)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        for n in 1..=16 {
            let (x, w) = gauss_legendre(n);
            for deg in 0..(2 * n) {
                let q: f64 = x.iter().zip(w).map(|(x, w)| w * x.powi(deg as i32)).sum();
                let exact = if deg % 2 == 1 {
                    0.0
                } else {
                    2.0 / (deg as f64 + 1.0)
                };
                assert!((q - exact).abs() < 1e-12, "n={n} deg={deg} q={q}");
            }
        }
    }

    #[test]
    fn inv_r_integral_matches_quadrature() {
        for &(x0, x1, y0, y1) in &[
            (1.0, 3.0, -2.0, 5.0),
            (-4.0, -1.0, -3.0, -0.5),
            (0.5, 60.0, 0.0, 60.0),
            (2.0, 2.5, 100.0, 160.0),
        ] {
            let n = 2000;
            let (hx, hy) = ((x1 - x0) / n as f64, (y1 - y0) / n as f64);
            let mut q = 0.0;
            for i in 0..n {
                for j in 0..n {
                    let x = x0 + (i as f64 + 0.5) * hx;
                    let y = y0 + (j as f64 + 0.5) * hy;
                    q += hx * hy / x.hypot(y);
                }
            }
            let exact = inv_r_integral(x0, x1, y0, y1);
            assert!((q - exact).abs() < 1e-5 * exact, "{q} vs {exact}");
        }
    }

    #[test]
    fn covered_area_of_squares_is_exact() {
        let a = Region {
            rect: Rect {
                x0: 0.0,
                y0: 0.0,
                x1: 10.0,
                y1: 10.0,
            },
            disk: None,
        };
        let b = Region {
            rect: Rect {
                x0: 5.0,
                y0: 5.0,
                x1: 15.0,
                y1: 15.0,
            },
            disk: None,
        };
        let c = Region {
            rect: Rect {
                x0: 0.0,
                y0: 8.0,
                x1: 6.0,
                y1: 20.0,
            },
            disk: None,
        };
        // 25 from b, 12 from c, minus their 1×2 overlap [5,6]×[8,10].
        assert!((a.covered_area(&[b, c]) - 35.0).abs() < 1e-12);
    }

    #[test]
    fn disk_area_and_rays() {
        let d = Region {
            rect: Rect {
                x0: -1.0,
                y0: -1.0,
                x1: 1.0,
                y1: 1.0,
            },
            disk: Some(Disk {
                c: Point::new(0.0, 0.0),
                r: 1.0,
            }),
        };
        assert!(
            (d.area() - std::f64::consts::PI).abs() < 1e-6,
            "{}",
            d.area()
        );
        let o = Point::new(-5.0, 0.5);
        let dir = Point::new(1.0, 0.0);
        let inv = Point::new(1.0, f64::INFINITY);
        let (a, b) = d.ray(o, dir, inv).expect("the ray crosses the disk");
        let half = (1.0f64 - 0.25).sqrt();
        assert!((a - (5.0 - half)).abs() < 1e-12 && (b - (5.0 + half)).abs() < 1e-12);
    }
}
