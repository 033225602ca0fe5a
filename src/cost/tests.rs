//! The cost models' predictions: finite and positive, growing with each
//! term they count, and large enough to refuse (or run as a job) the
//! issues' large work while the reference workload passes.

use super::*;
use crate::coordination::Coordination::{Iterated, Priority};
use crate::planner::PlanRequest;
use crate::scenario::{Cell, SourceSpec, builtins, paper_spec};
use serde_json::json;

/// `n` sensors on a near-square grid (each on the first free cell of
/// its row), `history` steps in which they stood 0–2 cells west, and
/// `targets` on a spiral through the zone.
fn request(s: &Scenario, n: usize, t: usize, targets: usize, history: usize) -> PlanRequest {
    let cols = (n as f64).sqrt().ceil() as usize;
    let rows = n.div_ceil(cols);
    let at = |i: usize, back: usize| {
        let x = ((i % cols) as f64 + 0.5) * s.width / cols as f64;
        let y = ((i / cols) as f64 + 0.5) * s.height / rows as f64;
        let c = s.snap(Point::new(x - (back % 3) as f64 * s.cell_size, y));
        let free = (0..s.cols)
            .map(|k| Cell {
                col: (c.col + k) % s.cols,
                row: c.row,
            })
            .find(|&c| s.is_free(0, c))
            .unwrap_or(c);
        s.centre(free)
    };
    let sensors: Vec<_> = (0..n)
        .map(|i| json!({"id": i, "x": at(i, 0).x, "y": at(i, 0).y}))
        .collect();
    let targets: Vec<_> = (0..targets)
        .map(|k| {
            let (a, f) = (k as f64 * 2.4, ((k % 997) as f64 + 0.5) / 997.0);
            let (x, y) = (s.width * f.sqrt() * a.cos(), s.height * f.sqrt() * a.sin());
            json!({"x": s.width / 2.0 + 0.49 * x, "y": s.height / 2.0 + 0.49 * y,
                   "vx": 10.0 * a.sin(), "vy": -10.0 * a.cos()})
        })
        .collect();
    let history: Vec<Vec<_>> = (1..=history)
        .map(|h| {
            (0..n)
                .map(|i| json!({"x": at(i, h).x, "y": at(i, h).y}))
                .collect()
        })
        .collect();
    let body = json!({"sensors": sensors, "targets": targets, "history": history, "horizon": t});
    serde_json::from_value(body).expect("a plan request")
}

fn plan_cost(p: &Planner, mut req: PlanRequest, c: Coordination) -> f64 {
    req.coordination = Some(c);
    plan_ms(p, &PlanInput::new(&p.scenario, &req).expect("valid"))
}

/// A scenario like `paper-v10` on `side × side` cells, `k` sources.
fn lattice(side: usize, k: usize, cell: f64, fov: FovSpec) -> Scenario {
    let w = side as f64 * cell;
    let src = |j: usize| SourceSpec::at(w * (j as f64 + 0.5) / k as f64, -1.0, 0.3);
    let mut spec = paper_spec(10.0);
    (spec.zone.width, spec.zone.height, spec.cell_size, spec.fov) = (w, w, cell, fov);
    spec.sources = (0..k).map(src).collect();
    Scenario::new(spec).expect("a valid scenario")
}

/// First detections cost what their searches do: far above the
/// detections objective's plan of the same request, growing with the
/// horizon, and above the time a server would plan on its async
/// worker (`INLINE_PLAN_MS`, 5 ms), so they never block it.
#[test]
fn first_detections_are_predicted_by_their_searches() {
    let p = Planner::new(builtins().remove(0));
    let first = |t: usize| {
        let mut req = request(&p.scenario, 10, t, 30, 16);
        req.objective = Some(Objective::FirstDetections);
        plan_cost(&p, req, Iterated)
    };
    let j = plan_cost(&p, request(&p.scenario, 10, 3, 30, 16), Iterated);
    assert!(first(3) > 20.0 * j && first(3) > 5.0, "{} vs {j}", first(3));
    increasing("first detections by horizon", [3, 5, 8].map(first));
}

/// `ESTIMATOR_TERMS` names the constant and the seen-set and window terms
/// of `PLAN_MODEL`, the estimator a first-detections plan builds too.
#[test]
fn the_estimator_terms_are_the_seen_sets_and_windows() {
    let (estimator, rest) = PLAN_MODEL.split_at(ESTIMATOR_TERMS);
    assert_eq!(estimator[0].0, "1");
    assert!(
        estimator[1..]
            .iter()
            .all(|(name, _)| name.starts_with("seen:") || name.starts_with("windows:")),
        "{estimator:?}"
    );
    assert!(
        rest.iter()
            .all(|(name, _)| !name.starts_with("seen:") && !name.starts_with("windows:")),
        "{rest:?}"
    );
}

/// A first-detections plan is predicted by its searches: fewer searches
/// (no certificate, no coordination) cost less and best-response rounds
/// more; more sensors cost more; and ground sensors near buildings pay
/// for the parts of their looks that the walls hide.
#[test]
fn first_detections_follow_their_searches() {
    let p = Planner::new(builtins().remove(0));
    let first = |c: Coordination, certify: bool, n: usize| {
        let mut req = request(&p.scenario, n, 3, 30, 16);
        req.objective = Some(Objective::FirstDetections);
        req.certify = Some(certify);
        plan_cost(&p, req, c)
    };
    increasing(
        "first detections by searches",
        [
            first(Coordination::None, false, 10),
            first(Priority, false, 10),
            first(Priority, true, 10),
            first(Iterated, true, 10),
        ],
    );
    increasing(
        "first detections by sensors",
        [4, 10, 40].map(|n| first(Priority, true, n)),
    );
    let campus = Planner::new(builtins().remove(4));
    let input = |req: &PlanRequest| PlanInput::new(&campus.scenario, req).expect("valid");
    let mut req = request(&campus.scenario, 6, 3, 0, 4);
    req.objective = Some(Objective::FirstDetections);
    let robots = first_terms(&campus, &input(&req), 0.0);
    assert!(robots.sighted > 0.0, "{robots:?}");
    let drones = input(&req);
    let drones = PlanInput {
        types: vec![campus.scenario.type_index("drone").expect("a drone type"); 6],
        ..drones
    };
    assert_eq!(first_terms(&campus, &drones, 0.0).sighted, 0.0);
}

/// A first-detections search walks fewer pieces behind a longer history
/// of certain looks (its stops leave out what that history detected), and
/// as many behind uncertain looks as behind none.
#[test]
fn first_detections_searches_shrink_behind_a_certain_history() {
    let terms = |p: &Planner, history: usize| {
        let mut req = request(&p.scenario, 10, 3, 30, history);
        req.objective = Some(Objective::FirstDetections);
        let input = PlanInput::new(&p.scenario, &req).expect("valid");
        first_terms(p, &input, 0.0)
    };
    let paper = Planner::new(builtins().remove(0));
    let pairs = [16, 4, 1, 0].map(|h| terms(&paper, h).pairs);
    increasing("pair gains by shorter certain histories", pairs);
    assert!(pairs[0] < 0.7 * pairs[3], "{pairs:?}");
    // `site-campus` looks detect with probability 0.9.
    let campus = Planner::new(builtins().remove(4));
    assert_eq!(terms(&campus, 16), terms(&campus, 0));
}

fn increasing(what: &str, costs: impl IntoIterator<Item = f64>) {
    let costs: Vec<f64> = costs.into_iter().collect();
    assert!(costs.windows(2).all(|w| w[1] > w[0]), "{what}: {costs:?}");
}

const MODES: [Coordination; 3] = [Coordination::None, Priority, Iterated];

#[test]
fn predictions_are_finite_and_positive() {
    for s in builtins() {
        let pre = precompute_ms(&s);
        assert!(pre.is_finite() && pre > 0.0, "{}: {pre}", s.id);
        let p = Planner::new(s);
        // The paper estimator refuses scenarios with obstacles.
        let paper = (!p.scenario.has_obstacles()).then_some(EstimatorKind::Paper);
        for (estimator, c) in std::iter::once(EstimatorKind::Exact)
            .chain(paper)
            .flat_map(|e| MODES.map(|c| (e, c)))
        {
            for (n, targets, history) in [(1, 0, 0), (10, 50, 16), (40, 500, 4)] {
                let mut req = request(&p.scenario, n, 3, targets, history);
                req.estimator = Some(estimator);
                let input = PlanInput::new(&p.scenario, &req).expect("valid");
                let terms = plan_terms(&p, &input).to_array();
                assert!(terms.iter().all(|t| t.is_finite() && *t >= 0.0));
                let ms = plan_cost(&p, req.clone(), c);
                assert!(ms.is_finite() && ms > 0.0, "{}: {ms}", p.scenario.id);
                if estimator == EstimatorKind::Exact {
                    let mut req = req;
                    req.objective = Some(Objective::FirstDetections);
                    let input = PlanInput::new(&p.scenario, &req).expect("valid");
                    let terms = first_terms(&p, &input, 0.0).to_array();
                    assert!(terms.iter().all(|t| t.is_finite() && *t >= 0.0));
                    let ms = plan_cost(&p, req, c);
                    assert!(ms.is_finite() && ms > 0.0, "{}: first {ms}", p.scenario.id);
                }
            }
        }
    }
}

#[test]
fn plan_cost_grows_with_each_driver() {
    let p = Planner::new(builtins().remove(0));
    let s = &p.scenario;
    let cost = |n, t, targets, h, c| plan_cost(&p, request(s, n, t, targets, h), c);
    increasing(
        "sensors",
        [1, 4, 16, 64, 256].map(|n| cost(n, 3, 50, 16, Priority)),
    );
    increasing("horizon", (1..=12).map(|t| cost(10, t, 50, 16, Priority)));
    increasing(
        "targets",
        [0, 100, 1000, 20_000].map(|k| cost(10, 3, k, 16, Priority)),
    );
    increasing(
        "history",
        [0, 4, 16, 32].map(|h| cost(10, 3, 50, h, Priority)),
    );
    increasing("coordination", MODES.map(|c| cost(10, 3, 50, 16, c)));
}

/// Obstacles add the statistics' rays: more with more obstacles, more
/// vertices and more cells, none without.
#[test]
fn precompute_cost_grows_with_obstacles() {
    let campus = crate::scenario::site_campus_spec();
    let cost =
        |spec: crate::scenario::ScenarioSpec| precompute_ms(&Scenario::new(spec).expect("valid"));
    // The same obstacles drawn with more vertices each.
    let rounded = |k: usize| {
        let mut spec = campus.clone();
        for ob in spec.obstacles.iter_mut().flatten() {
            let n = ob.polygon.len() as f64;
            let (cx, cy) = ob
                .polygon
                .iter()
                .fold((0.0, 0.0), |(x, y), p| (x + p[0] / n, y + p[1] / n));
            ob.polygon = (0..k)
                .map(|j| {
                    let a = std::f64::consts::TAU * j as f64 / k as f64;
                    [cx + 4.0 * a.cos(), cy + 4.0 * a.sin()]
                })
                .collect();
        }
        cost(spec)
    };
    increasing("vertices", [rounded(4), rounded(16), rounded(32)]);
    let without = cost(crate::scenario::ScenarioSpec {
        obstacles: None,
        ..campus.clone()
    });
    let mut four = campus.clone();
    four.obstacles.as_mut().expect("obstacles").truncate(4);
    let finer = crate::scenario::ScenarioSpec {
        cell_size: 5.0,
        ..campus.clone()
    };
    increasing(
        "obstacles, then cells",
        [without, cost(four), cost(campus), cost(finer)],
    );
}

#[test]
fn precompute_cost_grows_with_cells_sources_and_circles() {
    let square = FovSpec::Square { half_width: 30.0 };
    let cells = [30, 100, 300, 1000, 2000].map(|side| lattice(side, 8, 10.0, square));
    increasing("cells", cells.iter().map(precompute_ms));
    let sources = [1, 4, 16, 64].map(|k| lattice(100, k, 10.0, square));
    increasing("sources", sources.iter().map(precompute_ms));
    let circle = lattice(30, 8, 10.0, FovSpec::Circle { radius: 30.0 });
    assert!(precompute_ms(&circle) > 5.0 * precompute_ms(&builtins()[0]));
}

#[test]
fn the_issues_large_work_is_refused_or_a_job_and_the_reference_is_not() {
    let p = Planner::new(builtins().remove(0));
    let s = &p.scenario;
    let large = plan_cost(&p, request(s, 256, 12, 20_000, 32), Iterated);
    assert!(large > 2000.0, "{large} ms");
    let reference = plan_cost(&p, request(s, 10, 3, 50, 16), Priority);
    assert!(reference < 10.0, "{reference} ms");
    // 2000 × 2000 cells of 1, circles of radius 40, 64 sources: built,
    // not precomputed.
    let big = lattice(2000, 64, 1.0, FovSpec::Circle { radius: 40.0 });
    assert!(precompute_ms(&big) > 1000.0);
    assert!(precompute_ms(&builtins()[0]) < 100.0);
}

/// The separation's repair is counted where it can run: sensors that may
/// come within the separation of each other in the horizon pay for its
/// searches (`MAX_REPAIR_SEARCHES_PER_SENSOR` passes and one more), a
/// fleet spread wider than the separation and its reach does not.
#[test]
fn the_separation_repair_is_counted_where_pairs_can_meet() {
    let p = Planner::new(builtins().remove(0));
    let cost = |n: usize, d: usize| {
        let mut req = request(&p.scenario, n, 3, 30, 16);
        req.min_separation = Some(d.into());
        plan_cost(&p, req, Priority)
    };
    // 100 sensors on a 300-wide zone of 10-wide cells: 3 cells apart.
    assert!(
        cost(100, 2) > 1.5 * cost(100, 0),
        "{} vs {}",
        cost(100, 2),
        cost(100, 0)
    );
    // 4 sensors: 15 cells apart, more than 2 + 2·3 steps of reach.
    assert_eq!(cost(4, 2), cost(4, 0));
}

/// `req` with every sensor (now and in the history) moved into a square
/// of `half` cells either side of the zone's centre, keeping their order.
fn crowded(s: &Scenario, mut req: PlanRequest, half: f64) -> PlanRequest {
    let (cx, cy) = (s.width / 2.0, s.height / 2.0);
    let f = half * s.cell_size / cx;
    let squeeze = |x: &mut f64, y: &mut f64| {
        *x = cx + (*x - cx) * f;
        *y = cy + (*y - cy) * f;
    };
    for p in &mut req.sensors {
        squeeze(&mut p.x, &mut p.y);
    }
    for p in req.history.iter_mut().flatten().flatten() {
        squeeze(&mut p.x, &mut p.y);
    }
    req
}

/// A fleet crowded within a few cells costs more than the same fleet
/// spread over the zone where each value tests the looks that overlap
/// its view (the paper estimator's cover, the exact estimator's rays
/// through circles), and uncertain looks through circles more than
/// certain ones; the windows' block sums of squares, which a crowd does
/// not slow as much, are not what this measures.
#[test]
fn crowded_fleets_and_uncertain_circles_cost_more() {
    let p = Planner::new(builtins().remove(0));
    let paper = |req: PlanRequest| {
        let mut req = req;
        req.estimator = Some(EstimatorKind::Paper);
        plan_cost(&p, req, Iterated)
    };
    let spread = request(&p.scenario, 32, 3, 0, 8);
    let crowd = crowded(&p.scenario, spread.clone(), 3.0);
    assert!(
        paper(crowd.clone()) > 5.0 * paper(spread.clone()),
        "paper: {} vs {}",
        paper(crowd),
        paper(spread)
    );
    let circles = |p_detect: f64| {
        let mut spec = paper_spec(10.0);
        spec.fov = FovSpec::Circle { radius: 30.0 };
        spec.p_detect = Some(p_detect);
        Planner::new(Scenario::new(spec).expect("valid"))
    };
    let certain = circles(1.0);
    let spread = request(&certain.scenario, 32, 3, 0, 8);
    let crowd = crowded(&certain.scenario, spread.clone(), 3.0);
    let (a, b) = (
        plan_cost(&certain, crowd, Priority),
        plan_cost(&certain, spread.clone(), Priority),
    );
    assert!(a > 3.0 * b, "circles: {a} vs {b}");
    let uncertain = circles(0.7);
    let (c, d) = (
        plan_cost(&uncertain, spread.clone(), Priority),
        plan_cost(&certain, spread, Priority),
    );
    assert!(c > 1.5 * d, "uncertain circles: {c} vs {d}");
}

/// An evaluate with the paper estimator costs the covers of its
/// marginals on top of a plan without coordination: far more for a fleet
/// whose views overlap (and for circles than squares); with the exact
/// estimator it is that plan's cost.
#[test]
fn evaluate_counts_the_paper_estimators_marginals() {
    let p = Planner::new(builtins().remove(0));
    let cost = |req: &PlanRequest, estimator: EstimatorKind| {
        let mut req = req.clone();
        req.estimator = Some(estimator);
        let input = PlanInput::new(&p.scenario, &req).expect("valid");
        // Every sensor stays where it stands.
        let paths: Vec<Vec<Cell>> = (input.starts.iter())
            .map(|&c| vec![c; input.horizon])
            .collect();
        let mut none = input.clone();
        none.coordination = Coordination::None;
        (evaluate_ms(&p, &input, &paths), plan_ms(&p, &none))
    };
    let spread = request(&p.scenario, 64, 6, 0, 8);
    let crowd = crowded(&p.scenario, spread.clone(), 3.0);
    let (exact, plan) = cost(&crowd, EstimatorKind::Exact);
    assert_eq!(exact, plan);
    let (crowded_paper, plan) = cost(&crowd, EstimatorKind::Paper);
    let (spread_paper, _) = cost(&spread, EstimatorKind::Paper);
    assert!(crowded_paper > 10.0 * plan, "{crowded_paper} vs {plan}");
    assert!(
        crowded_paper > 5.0 * spread_paper,
        "{crowded_paper} vs {spread_paper}"
    );
}
