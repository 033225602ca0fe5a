//! Traceback: which sources can have emitted a detected target.
//!
//! A target flies straight from its source, so a detection at `q` with
//! velocity `w` came from source `j` only if the line through `q` along `w`,
//! traced back, passes through the source's position, at a takeoff angle
//! inside its cone, at the speed of one of its classes, and without
//! crossing a building on the way. Real trackers report noisy positions
//! and velocities, so each test has a tolerance ([`Tolerance`]).
//!
//! Among the sources that explain a detection, the chance that it came
//! from `j` is proportional to `λ_j·f_j(q)`, where `f_j(q)` is the
//! stationary density at `q` of the source's targets per unit rate, summed
//! over its classes whose speed matches: `share_c/(spread_j·v_c·r_j)`, `r_j`
//! the distance from the source (the targets of a class spread evenly over
//! the cone's angles and along each ray at `1/v_c` per step of emission).
//! Tracks through `q` from every explaining source have nearly the same
//! line, so the same looks, and the chance of detecting them cancels.

use crate::geometry::Point;
use crate::scenario::Scenario;

/// How far a detection may stray from a source's targets and still be
/// explained by it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance {
    /// Largest distance between a source's position and the detection's
    /// line traced back, zone units; also how far outside its takeoff cone
    /// (at the detection's distance) and how far past a building's edge
    /// the line may run.
    pub distance: f64,
    /// Largest difference between the detection's speed and a class's
    /// speed, relative to the class's speed.
    pub speed: f64,
}

/// The sources that explain a detection at `q` moving `w` per step, each
/// with its density `f_j(q)` per unit rate (see the module docs); empty
/// when none does.
pub fn explaining(s: &Scenario, q: Point, w: Point, tol: &Tolerance) -> Vec<(usize, f64)> {
    let speed = w.x.hypot(w.y);
    if speed <= 0.0 {
        return Vec::new();
    }
    let u = Point::new(w.x / speed, w.y / speed);
    let mut found = Vec::new();
    for (j, src) in s.sources.iter().enumerate() {
        let e = Point::new(q.x - src.pos.x, q.y - src.pos.y);
        let r = e.x.hypot(e.y);
        // The source lies behind the detection, on its line.
        if e.x * u.x + e.y * u.y <= 0.0 || (e.x * u.y - e.y * u.x).abs() > tol.distance {
            continue;
        }
        // The takeoff angle is the track's heading.
        let slack = tol.distance / r;
        let angle = src.angle_to(Point::new(src.pos.x + u.x, src.pos.y + u.y));
        if angle < src.cone.0 - slack || angle > src.cone.1 + slack {
            continue;
        }
        if !s.obstacles.is_empty()
            && s.obstacles.stop(src.pos, Point::new(e.x / r, e.y / r)) < r - tol.distance
        {
            continue;
        }
        let density: f64 = s
            .classes_of(j)
            .iter()
            .filter(|c| (speed - c.speed).abs() <= tol.speed * c.speed)
            .map(|c| c.share / (src.spread * c.speed * r))
            .sum();
        if density > 0.0 {
            found.push((j, density));
        }
    }
    found
}

/// Where the track of a detection at `q` moving `w` per step entered the
/// zone: its line traced back to the zone's edge (`q` itself for a target
/// that does not move, or for a `q` outside the zone whose line, traced
/// back, never crosses it).
pub fn entry(s: &Scenario, q: Point, w: Point) -> Point {
    let speed = w.x.hypot(w.y);
    if speed <= 0.0 {
        return q;
    }
    let back = Point::new(-w.x / speed, -w.y / speed);
    let inv = Point::new(1.0 / back.x, 1.0 / back.y);
    match s.zone().ray(q, back, inv) {
        Some((_, t1)) => Point::new(q.x + back.x * t1, q.y + back.y * t1),
        None => q,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::builtins;

    /// A track inside the zone enters on the edge its line meets behind
    /// it; one outside that, traced back, crosses the zone enters on the
    /// far side; one outside that never crosses it, and a target at rest,
    /// keep the detection's position.
    #[test]
    fn entry_is_where_the_line_behind_the_detection_meets_the_edge() {
        let s = &builtins()[0];
        let z = s.zone();
        let (mx, my) = ((z.x0 + z.x1) / 2.0, (z.y0 + z.y1) / 2.0);
        let close = |a: Point, b: Point| (a.x - b.x).abs() < 1e-9 && (a.y - b.y).abs() < 1e-9;
        // Inside, flying east: entered on the west edge, at its height.
        let e = entry(s, Point::new(mx, my), Point::new(1.0, 0.0));
        assert!(close(e, Point::new(z.x0, my)), "{e:?}");
        // East of the zone, flying east: it crossed the zone from the west.
        let e = entry(s, Point::new(z.x1 + 5.0, my), Point::new(2.0, 0.0));
        assert!(close(e, Point::new(z.x0, my)), "{e:?}");
        // East of the zone, flying west: it never crossed the zone.
        let q = Point::new(z.x1 + 5.0, my);
        assert!(close(entry(s, q, Point::new(-1.0, 0.0)), q));
        // Above the zone, flying east along it: never in it.
        let q = Point::new(mx, z.y1 + 1.0);
        assert!(close(entry(s, q, Point::new(1.0, 0.0)), q));
        // At rest.
        let q = Point::new(mx, my);
        assert!(close(entry(s, q, Point::new(0.0, 0.0)), q));
    }
}
