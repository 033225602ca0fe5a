//! The visibility geometry against brute force: points sampled along open
//! segments, on random convex obstacles, and sight lines that graze
//! vertices and run along edges.

use proptest::prelude::*;

use super::*;

/// A convex polygon: `n` points on an ellipse at sorted random angles.
fn polygon_from(cx: f64, cy: f64, rx: f64, ry: f64, angles: &[f64]) -> Option<Polygon> {
    let mut a = angles.to_vec();
    a.sort_by(f64::total_cmp);
    a.dedup_by(|x, y| (*x - *y).abs() < 0.05);
    let pts: Vec<Point> = a
        .iter()
        .map(|t| Point::new(cx + rx * t.cos(), cy + ry * t.sin()))
        .collect();
    Polygon::new(&pts).ok()
}

fn polygons() -> impl Strategy<Value = Polygon> {
    (
        20.0..80.0f64,
        20.0..80.0f64,
        3.0..25.0f64,
        3.0..25.0f64,
        prop::collection::vec(0.0..std::f64::consts::TAU, 3..9),
    )
        .prop_filter_map("a convex polygon", |(cx, cy, rx, ry, a)| {
            polygon_from(cx, cy, rx, ry, &a)
        })
}

/// Brute force: does the open segment `(p, q)` meet the interior? Samples
/// 4,000 points strictly between the ends.
fn blocked_by_sampling(poly: &Polygon, p: Point, q: Point) -> bool {
    (1..4000).any(|i| {
        let t = f64::from(i) / 4000.0;
        poly.contains_open(Point::new(p.x + t * (q.x - p.x), p.y + t * (q.y - p.y)))
    })
}

fn point() -> impl Strategy<Value = Point> {
    (0.0..100.0f64, 0.0..100.0f64).prop_map(|(x, y)| Point::new(x, y))
}

fn one(poly: Polygon, kind: ObstacleKind) -> Obstacles {
    Obstacles::new(vec![Obstacle {
        polygon: poly,
        kind,
    }])
}

fn whole() -> Region {
    Region {
        rect: Rect {
            x0: 0.0,
            y0: 0.0,
            x1: 100.0,
            y1: 100.0,
        },
        disk: None,
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// `sees`, `clear` and sampling agree: a segment that sampling finds
    /// blocked is hidden; one the geometry hides but sampling misses
    /// crosses the interior over less than a sample's length.
    #[test]
    fn sight_matches_sampled_segments(poly in polygons(), p in point(), q in point()) {
        let obs = one(poly.clone(), ObstacleKind::Screen);
        let sampled = blocked_by_sampling(&poly, p, q);
        let hidden = obs.sight(p, &whole()).is_some_and(|s| !s.sees(q));
        prop_assert_eq!(hidden, !obs.clear(p, q));
        if sampled {
            prop_assert!(hidden, "sampling finds {:?}→{:?} blocked", p, q);
        } else if hidden {
            let d = Point::new(q.x - p.x, q.y - p.y);
            let (t0, t1) = poly.line_interior(p, d).expect("a hidden segment meets the interior");
            prop_assert!(t1.min(1.0) - t0.max(0.0) < 2.0 / 4000.0);
        }
    }

    /// The visible intervals of a line are exactly the sampled points that
    /// `sees` admits, away from the intervals' ends.
    #[test]
    fn visible_intervals_match_points(
        polys in prop::collection::vec(polygons(), 1..4),
        p in point(),
        o in point(),
        angle in 0.0..std::f64::consts::TAU,
    ) {
        let obs = Obstacles::new(polys.into_iter().map(|polygon| Obstacle {
            polygon,
            kind: ObstacleKind::Building,
        }).collect());
        let Some(sight) = obs.sight(p, &whole()) else { return Ok(()); };
        let d = Point::new(angle.cos(), angle.sin());
        let mut out = Vec::new();
        sight.visible(o, d, 0.0, 120.0, &mut out);
        for w in out.windows(2) {
            prop_assert!(w[0].1 <= w[1].0, "sorted and disjoint: {:?}", out);
        }
        for i in 0..=1200 {
            let t = f64::from(i) * 0.1;
            if out.iter().any(|&(a, b)| (t - a).abs() < 1e-7 || (t - b).abs() < 1e-7) {
                continue;
            }
            let q = Point::new(o.x + t * d.x, o.y + t * d.y);
            let inside = out.iter().any(|&(a, b)| a < t && t < b);
            prop_assert_eq!(inside, sight.sees(q), "t = {}", t);
            if !sight.from().eq(&q) {
                prop_assert_eq!(inside, obs.clear(p, q));
            }
        }
    }

    /// Every point of a rectangle that a viewpoint does not see lies in
    /// `hidden_within`'s rectangle (sampled on a 60 × 60 grid), which is
    /// `None` only when every sample is seen.
    #[test]
    fn hidden_points_lie_in_the_hidden_box(
        poly in polygons(),
        p in point(),
        (x0, y0, w, h) in (0.0..80.0f64, 0.0..80.0f64, 5.0..60.0f64, 5.0..60.0f64),
    ) {
        let rect = Rect { x0, y0, x1: x0 + w, y1: y0 + h };
        let region = Region { rect, disk: None };
        let Some(sight) = one(poly, ObstacleKind::Building).sight(p, &region) else {
            return Ok(());
        };
        let hidden = sight.hidden_within(&rect);
        for i in 0..60 {
            for j in 0..60 {
                let q = Point::new(
                    x0 + w * (f64::from(i) + 0.5) / 60.0,
                    y0 + h * (f64::from(j) + 0.5) / 60.0,
                );
                if !sight.sees(q) {
                    prop_assert!(hidden.is_some_and(|b| b.contains(q)), "{:?} {:?}", q, hidden);
                }
            }
        }
    }

    /// A flight stops where sampling first finds the building's interior.
    #[test]
    fn stop_is_the_first_interior_point(poly in polygons(), o in point(), angle in 0.0..std::f64::consts::TAU) {
        prop_assume!(!poly.contains_closed(o));
        let obs = one(poly.clone(), ObstacleKind::Building);
        let d = Point::new(angle.cos(), angle.sin());
        let stop = obs.stop(o, d);
        let first = (0..20000)
            .map(|i| f64::from(i) * 0.01)
            .find(|&t| poly.contains_open(Point::new(o.x + t * d.x, o.y + t * d.y)));
        match first {
            Some(t) => prop_assert!(stop <= t && t - stop < 0.011, "stop {} sampled {}", stop, t),
            None => prop_assert!(stop.is_infinite() || poly.line_interior(o, d).is_some_and(|(a, b)| b - a < 0.02)),
        }
        // Screens never stop a flight.
        prop_assert!(one(poly, ObstacleKind::Screen).stop(o, d).is_infinite());
    }
}

fn square(x0: f64, y0: f64, x1: f64, y1: f64) -> Polygon {
    Polygon::new(&[
        Point::new(x0, y0),
        Point::new(x1, y0),
        Point::new(x1, y1),
        Point::new(x0, y1),
    ])
    .expect("a square")
}

#[test]
fn grazing_a_vertex_or_running_along_an_edge_does_not_block() {
    let obs = one(square(40.0, 40.0, 60.0, 60.0), ObstacleKind::Building);
    let p = Point::new(20.0, 20.0);
    let sight = obs.sight(p, &whole()).expect("the square is in view");
    // The diagonal through the corners (40, 40) and (60, 60) crosses the
    // interior.
    assert!(!sight.sees(Point::new(80.0, 80.0)));
    assert!(blocked_by_sampling(
        &obs.list()[0].polygon,
        p,
        Point::new(80.0, 80.0)
    ));
    // Of two lines by the vertex (40, 60), one crosses the interior and
    // one only touches the vertex.
    let (p2, q2) = (Point::new(20.0, 80.0), Point::new(60.0, 40.0));
    assert!(!obs.clear(p2, q2), "this one passes through the interior");
    let (p3, q3) = (Point::new(20.0, 40.0), Point::new(60.0, 80.0));
    assert!(obs.clear(p3, q3), "through (40, 60) only");
    assert!(obs.sight(p3, &whole()).expect("in view").sees(q3));
    assert!(!blocked_by_sampling(&obs.list()[0].polygon, p3, q3));
    // Along the south edge y = 40, from the west to the east.
    let (w, e) = (Point::new(10.0, 40.0), Point::new(90.0, 40.0));
    assert!(obs.clear(w, e));
    assert!(obs.sight(w, &whole()).expect("in view").sees(e));
    // Just inside the edge: blocked.
    assert!(!obs.clear(Point::new(10.0, 40.001), Point::new(90.0, 40.001)));
    // A flight along the edge is not stopped; one just inside is.
    assert!(obs.stop(w, Point::new(1.0, 0.0)).is_infinite());
    assert!((obs.stop(Point::new(10.0, 41.0), Point::new(1.0, 0.0)) - 30.0).abs() < 1e-12);
}

#[test]
fn a_viewpoint_on_the_boundary_or_inside() {
    let poly = square(40.0, 40.0, 60.0, 60.0);
    let obs = one(poly.clone(), ObstacleKind::Screen);
    // On the west edge: the interior side is hidden, the outside is not.
    let p = Point::new(40.0, 50.0);
    let sight = obs.sight(p, &whole()).expect("in view");
    assert!(!sight.sees(Point::new(45.0, 50.0)));
    assert!(!sight.sees(Point::new(90.0, 55.0)));
    assert!(sight.sees(Point::new(10.0, 50.0)));
    assert!(sight.sees(Point::new(40.0, 90.0)), "along the edge");
    // Inside a screen: nothing is visible but the viewpoint.
    let inside = obs
        .sight(Point::new(50.0, 50.0), &whole())
        .expect("in view");
    assert!(!inside.sees(Point::new(10.0, 10.0)));
    let mut out = Vec::new();
    inside.visible(
        Point::new(0.0, 0.0),
        Point::new(1.0, 0.0),
        0.0,
        100.0,
        &mut out,
    );
    assert!(out.is_empty());
}

#[test]
fn polygons_are_validated() {
    let p = |v: &[(f64, f64)]| {
        Polygon::new(&v.iter().map(|&(x, y)| Point::new(x, y)).collect::<Vec<_>>())
    };
    assert!(p(&[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]).is_ok());
    // Clockwise is accepted and stored counter-clockwise.
    let cw = p(&[(0.0, 0.0), (0.0, 1.0), (1.0, 0.0)]).expect("clockwise");
    assert!(cw.contains_open(Point::new(0.2, 0.2)));
    assert_eq!(
        p(&[(0.0, 0.0), (1.0, 0.0), (0.0, 0.0)]),
        Err(PolygonError::Repeated(0, 2))
    );
    assert!(matches!(
        p(&[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (1.0, 1.0)]),
        Err(PolygonError::Collinear(..))
    ));
    assert!(matches!(
        p(&[(0.0, 0.0), (2.0, 0.0), (1.0, 0.5), (2.0, 2.0), (0.0, 2.0)]),
        Err(PolygonError::NotConvex(_))
    ));
    // A pentagram turns one way at every vertex but winds twice.
    let star: Vec<(f64, f64)> = (0..5)
        .map(|i| {
            let a = f64::from(i * 2) * std::f64::consts::TAU / 5.0;
            (a.cos(), a.sin())
        })
        .collect();
    assert_eq!(p(&star), Err(PolygonError::SelfIntersecting(2)));
    assert!(matches!(
        p(&[(0.0, 0.0), (f64::NAN, 0.0), (0.0, 1.0)]),
        Err(PolygonError::NotFinite(1))
    ));
}

#[test]
fn area_within_clips_to_the_rectangle() {
    let poly = square(-10.0, -10.0, 10.0, 10.0);
    let r = Rect {
        x0: 0.0,
        y0: 0.0,
        x1: 100.0,
        y1: 100.0,
    };
    assert!((poly.area_within(&r) - 100.0).abs() < 1e-9);
    assert_eq!(square(-20.0, -20.0, -10.0, -10.0).area_within(&r), 0.0);
}

proptest! {
    /// A row's span holds exactly the points of the row in the closed
    /// polygon, away from its ends.
    #[test]
    fn row_spans_match_closed_containment(poly in polygons(), y in 0.0..100.0f64) {
        let span = poly.row_span(y);
        for i in 0..=400 {
            let x = f64::from(i) * 0.25;
            if span.is_some_and(|(a, b)| (x - a).abs() < 1e-6 || (x - b).abs() < 1e-6) {
                continue;
            }
            let inside = span.is_some_and(|(a, b)| a <= x && x <= b);
            prop_assert_eq!(inside, poly.contains_closed(Point::new(x, y)), "x = {}", x);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// A sight line through the vertex that bounds a polygon's shadow on
    /// either side only touches the polygon: every point past the vertex
    /// on it is seen and its segment clear, though rounding puts those
    /// points on either side of the shadow's edge.
    #[test]
    fn lines_that_graze_a_vertex_are_clear(poly in polygons(), p in point()) {
        prop_assume!(!poly.contains_closed(p));
        let obs = one(poly.clone(), ObstacleKind::Screen);
        let sight = obs.sight(p, &whole()).expect("in view");
        let rel = |v: Point| Point::new(v.x - p.x, v.y - p.y);
        let cross = |a: Point, b: Point| a.x * b.y - a.y * b.x;
        let vs = poly.vertices();
        for &v in vs {
            // v bounds the shadow when every other vertex lies on one side
            // of the line from p through it.
            let sides: Vec<f64> = vs.iter().filter(|&&w| w != v).map(|&w| cross(rel(v), rel(w))).collect();
            if !(sides.iter().all(|&c| c > 0.0) || sides.iter().all(|&c| c < 0.0)) {
                continue;
            }
            for s in [1.25, 1.5, 2.0, 3.0] {
                let q = Point::new(p.x + s * (v.x - p.x), p.y + s * (v.y - p.y));
                prop_assert!(sight.sees(q), "{:?} → {:?} by {:?}", p, q, v);
                prop_assert!(obs.clear(p, q), "{:?} → {:?} by {:?}", p, q, v);
            }
        }
    }
}
