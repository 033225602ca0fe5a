//! Buildings and screens against an independent Monte Carlo of the target
//! process: targets whose flight a building ends, looks that detect only
//! along clear sight lines, elevated sensors that see over everything.
//!
//! Over many stationary worlds, the mean realised detections along fixed
//! paths equal `evaluate`'s expectation within four standard errors per
//! step, for both objectives; the same paths scored by a model told no
//! obstacles are caught (|z| > 6). The statistics' stationary counts match
//! the simulation's.
#![allow(clippy::unwrap_used)]

use std::collections::{HashMap, HashSet};

use rand::{RngExt, SeedableRng, rngs::StdRng};
use rayon::prelude::*;
use serde_json::{Value, json};
use vigil::cancel::CancelToken;
use vigil::evaluate::EvaluateRequest;
use vigil::planner::Planner;
use vigil::scenario::{Cell, Look, Scenario, ScenarioSpec};
use vigil::stats::Stats;
use vigil::world::World;

fn mean_se(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

fn cell(col: i32, row: i32) -> Cell {
    Cell { col, row }
}

/// A 200 m yard of 10 m cells: a building in the middle, one across the
/// east fence, a hedge (screen) to the south-west; two gates with cones and
/// speed mixtures; ground cameras (p 0.8) and drones (p 0.6, elevated,
/// two cells a step).
fn yard_spec() -> Value {
    json!({
        "zone": {"width": 200.0, "height": 200.0},
        "cell_size": 10.0,
        "fov": {"shape": "square", "half_width": 35.0},
        "p_detect": 0.8,
        "sensor_types": {
            "drone": {"fov": {"shape": "square", "half_width": 30.0}, "speed": 2,
                      "p_detect": 0.6, "elevated": true}
        },
        "sources": [
            {"x": -1.0, "y": 100.0, "rate": 0.6, "direction": 0.0, "spread": 90.0,
             "speeds": [{"speed": 6.0, "weight": 2.0}, {"speed": 14.0, "weight": 1.0}]},
            {"x": 100.0, "y": -1.0, "rate": 0.5, "direction": 90.0, "spread": 120.0,
             "speeds": [{"speed": 8.0, "weight": 1.0}]}
        ],
        "obstacles": [
            {"polygon": [[80.0, 80.0], [125.0, 80.0], [125.0, 120.0], [80.0, 120.0]]},
            {"polygon": [[170.0, 140.0], [215.0, 150.0], [185.0, 185.0]], "kind": "building"},
            {"polygon": [[30.0, 30.0], [60.0, 40.0], [45.0, 60.0]], "kind": "screen"}
        ]
    })
}

fn scenario(spec: Value) -> Scenario {
    Scenario::new(serde_json::from_value::<ScenarioSpec>(spec).unwrap()).unwrap()
}

/// The same yard told no obstacles.
fn blind_spec() -> Value {
    let mut spec = yard_spec();
    spec.as_object_mut().unwrap().remove("obstacles");
    spec
}

/// Sensors (type, history track `s` steps ago, path at steps 1..=T): a
/// camera west of the building whose view it blocks, a camera by the
/// hedge, a drone over the building's corner.
const TYPES: [&str; 3] = ["default", "default", "drone"];

fn track(s_ago: usize) -> [Cell; 3] {
    let d = s_ago as i32;
    [cell(6 - d.min(2), 10), cell(3, 6 + d), cell(12 + d, 12)]
}

fn path(t: usize) -> [Cell; 3] {
    let t = t as i32;
    [cell(6, 10 + t), cell(3 + t, 6), cell(12 - 2 * t, 12)]
}

const HISTORY: usize = 3;
const HORIZON: usize = 3;

/// The evaluate request of one world's reports.
fn request(s: &Scenario, reported: &[(f64, f64, f64, f64)], objective: &str) -> EvaluateRequest {
    let at = |c: Cell| {
        let p = s.centre(c);
        (p.x, p.y)
    };
    let sensors: Vec<Value> = track(0)
        .iter()
        .zip(TYPES)
        .enumerate()
        .map(|(i, (&c, ty))| json!({"id": i, "x": at(c).0, "y": at(c).1, "type": ty}))
        .collect();
    let history: Vec<Vec<Value>> = (1..=HISTORY)
        .map(|s_ago| {
            track(s_ago)
                .iter()
                .zip(TYPES)
                .map(|(&c, ty)| json!({"x": at(c).0, "y": at(c).1, "type": ty}))
                .collect()
        })
        .collect();
    let paths: Vec<Value> = (0..3)
        .map(|i| {
            json!({"sensor": i, "path": (1..=HORIZON)
                .map(|t| json!({"col": path(t)[i].col, "row": path(t)[i].row}))
                .collect::<Vec<_>>()})
        })
        .collect();
    let targets: Vec<Value> = reported
        .iter()
        .map(|&(x, y, vx, vy)| json!({"x": x, "y": y, "vx": vx, "vy": vy}))
        .collect();
    serde_json::from_value(json!({
        "sensors": sensors, "targets": targets, "history": history,
        "horizon": HORIZON, "objective": objective, "paths": paths
    }))
    .unwrap()
}

/// Per objective (`detections`, `first_detections`) and step, the mean and
/// SE of (realised − expected) over `worlds` worlds drawn from the yard
/// with obstacles, the expectation by `model`'s planner (whose requests
/// name the same cells and types).
fn run(model: &Planner, worlds: usize) -> [Vec<(f64, f64)>; 2] {
    let s = &scenario(yard_spec());
    let ty = |name: &str| s.type_index(name).unwrap();
    let looks = |cells: [Cell; 3]| -> Vec<Look> {
        cells
            .iter()
            .zip(TYPES)
            .map(|(&c, n)| s.look(ty(n), c))
            .collect()
    };
    let rows: Vec<[Vec<f64>; 2]> = (0..worlds)
        .into_par_iter()
        .map(|w| {
            let mut rng = StdRng::seed_from_u64(46_000 + w as u64);
            let mut draw = StdRng::seed_from_u64(0x0b57_0000 ^ w as u64);
            let mut world = World::stationary(s, &mut rng);
            let mut detected = HashSet::new();
            for s_ago in (0..=HISTORY).rev() {
                let now = looks(track(s_ago));
                for tg in world.in_zone(s) {
                    for l in &now {
                        if s.detects(l, tg.pos) && draw.random::<f64>() < l.p_detect {
                            detected.insert(tg.id);
                        }
                    }
                }
                if s_ago > 0 {
                    world.step(s, &mut rng);
                }
            }
            let reported: Vec<(f64, f64, f64, f64)> = world
                .in_zone(s)
                .filter(|t| detected.contains(&t.id))
                .map(|t| (t.pos.x, t.pos.y, t.vel.x, t.vel.y))
                .collect();
            let expect = |objective: &str| {
                model
                    .evaluate_request(
                        &request(&model.scenario, &reported, objective),
                        &CancelToken::never(),
                    )
                    .unwrap()
                    .unwrap()
                    .expected_by_step
            };
            let (expected, expected_first) = (expect("detections"), expect("first_detections"));
            // Realised, given the world: per target and step, the chance
            // that some look of the plan detects it, and for targets never
            // detected, that it is the first time.
            let mut missed: HashMap<u64, f64> = HashMap::new();
            let (mut all, mut first) = (vec![0.0; HORIZON], vec![0.0; HORIZON]);
            for t in 1..=HORIZON {
                world.step(s, &mut rng);
                let plan = looks(path(t));
                for tg in world.in_zone(s) {
                    let miss: f64 = plan
                        .iter()
                        .filter(|l| s.detects(l, tg.pos))
                        .map(Look::miss)
                        .product();
                    all[t - 1] += 1.0 - miss;
                    if !detected.contains(&tg.id) && miss < 1.0 {
                        let before = missed.entry(tg.id).or_insert(1.0);
                        first[t - 1] += *before * (1.0 - miss);
                        *before *= miss;
                    }
                }
            }
            let diff = |r: &[f64], e: &[f64]| r.iter().zip(e).map(|(r, e)| r - e).collect();
            [diff(&all, &expected), diff(&first, &expected_first)]
        })
        .collect();
    [0, 1].map(|k| {
        (0..HORIZON)
            .map(|t| mean_se(&rows.iter().map(|r| r[k][t]).collect::<Vec<_>>()))
            .collect()
    })
}

#[test]
fn evaluate_is_unbiased_with_buildings_and_screens() {
    let planner = Planner::new(scenario(yard_spec()));
    for (objective, per_step) in ["detections", "first_detections"]
        .iter()
        .zip(run(&planner, 3_000))
    {
        for (t, &(m, se)) in per_step.iter().enumerate() {
            eprintln!(
                "{objective}: step {}: mean(realised − expected) = {m:+.4} ± {se:.4}",
                t + 1
            );
            assert!(
                m.abs() <= 4.0 * se,
                "{objective}: step {}: {m:.4} ± {se:.4}",
                t + 1
            );
            assert!(se < 0.08, "{objective}: too few worlds (se {se:.4})");
        }
    }
}

/// The check has power: the same paths scored by a model without the
/// obstacles (its sensors see through walls, its targets fly through
/// buildings) are caught.
#[test]
fn a_model_that_ignores_the_buildings_is_caught() {
    let blind = Planner::new(scenario(blind_spec()));
    let [detections, _] = run(&blind, 1_500);
    let worst = detections
        .iter()
        .map(|&(m, se)| m.abs() / se)
        .fold(0.0, f64::max);
    assert!(
        worst > 6.0,
        "largest |z| {worst:.2}: the blind model was not caught"
    );
}

/// `expected_targets_in_zone` and each view's `d_hat` (targets in a
/// field of view that its cell sees) against counts in stationary worlds.
#[test]
fn stationary_counts_match_a_simulation() {
    let s = scenario(yard_spec());
    let (ground, drone) = (Stats::for_slot(&s, 0), Stats::for_slot(&s, 1));
    assert!(!s.sees_over[0] && s.sees_over[1]);
    let probes = [cell(6, 10), cell(3, 6), cell(12, 12), cell(15, 3)];
    let looks: Vec<(Look, f64)> = probes
        .iter()
        .flat_map(|&c| {
            let i = s.index(c);
            [
                (s.look(0, c), ground.d_hat[i]),
                (s.look(1, c), drone.d_hat[i]),
            ]
        })
        .collect();
    let counts: Vec<Vec<f64>> =
        (0..4_000)
            .into_par_iter()
            .map(|w| {
                let mut rng = StdRng::seed_from_u64(7_700 + w as u64);
                let world = World::stationary(&s, &mut rng);
                let mut row = vec![world.in_zone(&s).count() as f64];
                row.extend(looks.iter().map(|(l, _)| {
                    world.in_zone(&s).filter(|t| s.detects(l, t.pos)).count() as f64
                }));
                row
            })
            .collect();
    let expected: Vec<f64> = std::iter::once(ground.expected_targets_in_zone)
        .chain(looks.iter().map(|&(_, d)| d))
        .collect();
    for (j, e) in expected.iter().enumerate() {
        let (m, se) = mean_se(&counts.iter().map(|r| r[j]).collect::<Vec<_>>());
        eprintln!("quantity {j}: Monte Carlo {m:.4} ± {se:.4}, model {e:.4}");
        assert!(
            (m - e).abs() <= 0.005 * e + 4.0 * se,
            "quantity {j}: {m:.4} ± {se:.4} vs {e:.4}"
        );
    }
    // The obstacles matter here: the blind yard holds more targets.
    let blind = Stats::compute(&scenario(blind_spec()));
    assert!(blind.expected_targets_in_zone > 1.05 * ground.expected_targets_in_zone);
}

/// The yard's precomputed parts, on rays of `rays_per_pi`, and its
/// sensors' types.
struct Yard {
    s: Scenario,
    stats: Vec<Stats>,
    rays: Vec<vigil::estimator::SourceRays>,
    types: Vec<usize>,
}

impl Yard {
    fn new(rays_per_pi: Option<f64>) -> Self {
        Self::with_spec(yard_spec(), rays_per_pi)
    }

    /// The yard's sensors and tracks on another spec of the same zone.
    fn with_spec(spec: Value, rays_per_pi: Option<f64>) -> Self {
        use vigil::estimator::SourceRays;
        let s = scenario(spec);
        let stats = (0..s.fovs.len())
            .map(|slot| Stats::for_slot(&s, slot))
            .collect();
        let rays = match rays_per_pi {
            Some(density) => SourceRays::with_density(&s, density),
            None => SourceRays::for_scenario(&s),
        };
        let types = TYPES.iter().map(|n| s.type_index(n).unwrap()).collect();
        Yard {
            s,
            stats,
            rays,
            types,
        }
    }

    /// The sensors' looks `s` steps ago, for `s` in `0..=history`.
    fn observed(&self, history: usize) -> Vec<Vec<Look>> {
        (0..=history)
            .map(|s_ago| {
                track(s_ago)
                    .iter()
                    .zip(&self.types)
                    .map(|(&c, &ty)| self.s.look(ty, c))
                    .collect()
            })
            .collect()
    }

    /// The exact estimator of the sensors at `track(0)` after `observed`.
    fn estimator<'a>(
        &'a self,
        observed: &'a [Vec<Look>],
        starts: &'a [Cell],
        horizon: usize,
    ) -> vigil::estimator::ExactEstimator<'a> {
        use vigil::estimator::{ExactEstimator, Precomputed, Situation};
        ExactEstimator::new(
            Precomputed {
                scenario: &self.s,
                stats: &self.stats,
                rays: &self.rays,
                grid: None,
                sights: None,
            },
            Situation {
                observed,
                targets: &[],
                starts,
                types: &self.types,
                horizon,
            },
        )
    }
}

/// The exact estimator's value of a look with only the looks of now
/// behind it (and at some probes an excluded look), against a brute-force
/// integral over a fine grid of points of its field of view: the density
/// of each class where the look sees the point and no building has ended
/// the flight, times the chance that every look of now missed the point's
/// target there and that the excluded look misses it now.
#[test]
fn values_match_a_brute_force_integral() {
    use vigil::estimator::Estimator;
    use vigil::geometry::Point;
    let yard = Yard::new(Some(2048.0));
    let (s, types) = (&yard.s, &yard.types);
    let observed = yard.observed(0);
    let now = &observed[0];
    let starts = track(0).to_vec();
    let est = yard.estimator(&observed, &starts, 2);
    // With an excluded look in half the probes: a camera east of the
    // building, whose view the building cuts, or the drone above it.
    let excluded = [s.look(types[0], cell(7, 8)), s.look(types[2], cell(9, 10))];
    for (sensor, k, t, x) in [
        (0, cell(6, 11), 1, None),
        (1, cell(4, 6), 2, None),
        (0, cell(6, 10), 1, Some(0)),
        (2, cell(10, 12), 1, None),
        (1, cell(5, 7), 1, Some(0)),
        (0, cell(7, 10), 2, Some(1)),
    ] {
        let excluded: Vec<Look> = x.map(|i| excluded[i]).into_iter().collect();
        let look = s.look(types[sensor], k);
        let r = look.region.rect;
        let n = 600;
        let (hx, hy) = ((r.x1 - r.x0) / n as f64, (r.y1 - r.y0) / n as f64);
        let mut brute = 0.0;
        for i in 0..n {
            for j in 0..n {
                let q = Point::new(r.x0 + (i as f64 + 0.5) * hx, r.y0 + (j as f64 + 0.5) * hy);
                if !s.detects(&look, q) {
                    continue;
                }
                for (jj, src) in s.sources.iter().enumerate() {
                    let a = src.angle_to(q);
                    if a < src.cone.0 || a > src.cone.1 {
                        continue;
                    }
                    let dist = (q.x - src.pos.x).hypot(q.y - src.pos.y);
                    let u = Point::new((q.x - src.pos.x) / dist, (q.y - src.pos.y) / dist);
                    if s.obstacles.stop(src.pos, u) <= dist {
                        continue;
                    }
                    for class in s.classes_of(jj) {
                        let back = dist - class.speed * t as f64;
                        let miss: f64 = if back < 0.0 {
                            1.0
                        } else {
                            let q0 = Point::new(src.pos.x + u.x * back, src.pos.y + u.y * back);
                            now.iter()
                                .filter(|l| s.detects(l, q0))
                                .map(Look::miss)
                                .product()
                        };
                        let miss_now: f64 = excluded
                            .iter()
                            .filter(|l| s.detects(l, q))
                            .map(Look::miss)
                            .product();
                        brute += class.rate / (src.spread * class.speed * dist)
                            * miss
                            * miss_now
                            * hx
                            * hy;
                    }
                }
            }
        }
        let value = est.value(sensor, k, t, &excluded) / look.p_detect;
        eprintln!("sensor {sensor} at {k:?}, t {t}: estimator {value:.5}, brute force {brute:.5}");
        assert!(
            (value - brute).abs() < 0.01 * brute + 1e-3,
            "{value} vs {brute}"
        );
    }
}

/// The first-detections search scores a path by its stops' gains: on the
/// yard, where buildings and the hedge cut many rays of a camera's view
/// into several visible pieces, a path's gains add up to what `by_step`
/// (the objective itself) gives its looks, alone and over the other
/// sensors' paths.
#[test]
fn path_gains_add_up_to_the_objective() {
    check_path_gains(&Yard::new(None));
}

/// [`path_gains_add_up_to_the_objective`] on the yard without obstacles,
/// where every look holds one piece per ray (the pair gains' own path).
#[test]
fn path_gains_add_up_to_the_objective_without_obstacles() {
    let mut spec = yard_spec();
    spec.as_object_mut().expect("an object").remove("obstacles");
    check_path_gains(&Yard::with_spec(spec, None));
}

fn check_path_gains(yard: &Yard) {
    use vigil::coordination::sensor_motion;
    use vigil::estimator::FirstDetections;
    let (s, types) = (&yard.s, &yard.types);
    let observed = yard.observed(HISTORY);
    let starts = track(0).to_vec();
    let est = yard.estimator(&observed, &starts, HORIZON);
    let first = FirstDetections::new(&est);
    let cells: Vec<Vec<Cell>> = (0..3)
        .map(|q| (1..=HORIZON).map(|t| path(t)[q]).collect())
        .collect();
    let paths: Vec<&[Cell]> = cells.iter().map(Vec::as_slice).collect();
    // Every sensor's stops built, as a plan's first searches build them.
    for q in 0..3 {
        let mut grid = sensor_motion(s, starts[q], types[q], HORIZON);
        first.path_cover(q, starts[q], &[], &mut grid);
    }
    let mut rng = StdRng::seed_from_u64(47);
    let mut multi = 0;
    // Paths that `apart` finds clear of the others' looks, and the others.
    let (mut apart, mut near) = (0, 0);
    for sensor in 0..3 {
        let (start, ty) = (starts[sensor], types[sensor]);
        for with_others in [false, true] {
            // The others on their fixed paths, or nobody.
            let extra: Vec<Vec<Look>> = (1..=HORIZON)
                .map(|t| {
                    (0..3)
                        .filter(|&q| with_others && q != sensor)
                        .map(|q| s.look(types[q], path(t)[q]))
                        .collect()
                })
                .collect();
            let mut grid = sensor_motion(s, start, ty, HORIZON);
            let cover = first.path_cover(sensor, start, &extra, &mut grid);
            // The same over the others' paths named, read from their stops.
            let others: Vec<usize> = (0..3).filter(|&q| with_others && q != sensor).collect();
            let mut among = sensor_motion(s, start, ty, HORIZON);
            let cover_among = first.path_cover_among(sensor, start, &paths, &others, &mut among);
            assert_eq!(grid, among);
            let background: f64 = first.by_step(&extra).iter().sum();
            for _ in 0..150 {
                let cells = random_path(&mut rng, s, start, ty);
                let offsets: Vec<(i32, i32)> = cells
                    .iter()
                    .map(|c| (c.col - start.col, c.row - start.row))
                    .collect();
                let looks: Vec<Vec<Look>> = extra
                    .iter()
                    .zip(&cells)
                    .map(|(others, &c)| {
                        let mut step = others.clone();
                        step.push(s.look(ty, c));
                        step
                    })
                    .collect();
                let objective = first.by_step(&looks).iter().sum::<f64>() - background;
                let gains = cover.value(&offsets);
                assert_eq!(gains.to_bits(), cover_among.value(&offsets).to_bits());
                assert!(
                    (gains - objective).abs() <= 1e-9 * objective.abs().max(1.0),
                    "sensor {sensor} on {cells:?}: gains {gains}, objective {objective}"
                );
                multi += usize::from(objective > 0.0);
                if with_others {
                    // Clear of the others' looks, the path detects first
                    // what it detects alone.
                    if first.apart(sensor, &cells, &paths, &others) {
                        let own: Vec<Vec<Look>> =
                            cells.iter().map(|&c| vec![s.look(ty, c)]).collect();
                        let alone: f64 = first.by_step(&own).iter().sum();
                        assert!(
                            (alone - objective).abs() <= 1e-9 * alone.abs().max(1.0),
                            "sensor {sensor} on {cells:?}: apart, yet {objective} against the others and {alone} alone"
                        );
                        apart += 1;
                    } else {
                        near += 1;
                    }
                }
            }
        }
    }
    assert!(multi > 100, "too few paths detect anything: {multi}");
    assert!(apart >= 5 && near >= 5, "{apart} paths apart, {near} near");
}

/// A random legal path of a sensor of type `ty` from `start` over
/// [`HORIZON`] steps.
fn random_path(rng: &mut StdRng, s: &Scenario, start: Cell, ty: usize) -> Vec<Cell> {
    let speed = s.types[ty].speed as i32;
    let mut at = start;
    let mut cells = Vec::new();
    while cells.len() < HORIZON {
        let next = Cell {
            col: at.col + rng.random_range(-speed..=speed),
            row: at.row + rng.random_range(-speed..=speed),
        };
        if s.on_lattice(next) && s.is_free(ty, next) {
            cells.push(next);
            at = next;
        }
    }
    cells
}

/// The first-detections marginal bound stops its searches once it passes
/// the sum of the solo bests, which is then the smaller bound: the
/// certificate is the one every search gives, to the bit, for plans of
/// the yard's three sensors (each on its track's path, its best path
/// alone or a random one), with and without obstacles.
#[test]
fn first_marginal_bound_stops_at_the_same_certificate() {
    use vigil::coordination::certificate::first_marginal_bound;
    use vigil::coordination::{Bound, Fleet};
    use vigil::estimator::FirstDetections;
    let mut without = yard_spec();
    without
        .as_object_mut()
        .expect("an object")
        .remove("obstacles");
    let mut rng = StdRng::seed_from_u64(59);
    let (mut stopped, mut whole) = (0, 0);
    for spec in [yard_spec(), without] {
        let yard = Yard::with_spec(spec, None);
        let (s, types) = (&yard.s, &yard.types);
        let observed = yard.observed(HISTORY);
        let starts = track(0).to_vec();
        let est = yard.estimator(&observed, &starts, HORIZON);
        let first = FirstDetections::new(&est);
        let cancel = CancelToken::never();
        let fleet =
            Fleet::new(s, &est, &starts, types, HORIZON, 0, &cancel).with_first_detections(&first);
        let alone: Vec<_> = (0..3)
            .map(|i| fleet.first_search(i, &[], &[], Vec::new(), None))
            .collect();
        let solo: f64 = alone.iter().map(|a| a.upper).sum();
        for _ in 0..40 {
            let cells: Vec<Vec<Cell>> = (0..3)
                .map(|q| match rng.random_range(0..3) {
                    0 => (1..=HORIZON).map(|t| path(t)[q]).collect(),
                    1 => alone[q].plan.path.clone(),
                    _ => random_path(&mut rng, s, starts[q], types[q]),
                })
                .collect();
            let paths: Vec<&[Cell]> = cells.iter().map(Vec::as_slice).collect();
            let order = [2, 0, 1];
            let value: f64 = fleet.by_step(&paths, &order).iter().sum();
            let every = first_marginal_bound(&fleet, &paths, value, &order, f64::INFINITY).unwrap();
            let early = first_marginal_bound(&fleet, &paths, value, &order, solo).unwrap();
            assert_eq!(
                Bound::new(value, [solo, early]),
                Bound::new(value, [solo, every])
            );
            if early < every {
                stopped += 1;
            } else {
                assert_eq!(early.to_bits(), every.to_bits());
                whole += 1;
            }
        }
    }
    assert!(
        stopped >= 5 && whole >= 5,
        "stopped {stopped}, whole {whole}"
    );
}

/// The vertices' own reader takes back what `Serialize` writes, in JSON
/// (the API, the catalogue) and in CBOR (sessions' specs).
#[test]
fn obstacles_round_trip_through_json_and_cbor() {
    let spec = vigil::scenario::site_campus_spec();
    assert!(spec.obstacles.as_ref().is_some_and(|o| !o.is_empty()));
    let text = serde_json::to_string(&spec).unwrap();
    assert_eq!(serde_json::from_str::<ScenarioSpec>(&text).unwrap(), spec);
    let mut cbor = Vec::new();
    ciborium::into_writer(&spec, &mut cbor).unwrap();
    let back: ScenarioSpec = ciborium::from_reader(cbor.as_slice()).unwrap();
    assert_eq!(back, spec);
}
