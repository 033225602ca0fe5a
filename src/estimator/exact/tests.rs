//! The seen sets along rays, checked against the estimator's values.

use super::first::Profile;
use super::rays::{SourceRays, look_key};
use super::seen::{RayHits, Sweep};
use super::{ExactEstimator, Precomputed, Situation};
use crate::estimator::Estimator;
use crate::estimator::elementary::ElementaryGrid;
use crate::scenario::{Cell, FovSpec, Look, Scenario, builtins, site_fleet_spec};
use crate::stats::Stats;

/// Leaving out the seen intervals that start past a ray's exit from the
/// zone (and skipping the looks whose every interval does) changes no
/// value, to the bit: every built-in (`site-fleet`'s
/// uncertain looks too), a long history that pushes many intervals out,
/// by the windows and by the rays, with and without excluded looks.
#[test]
fn intervals_past_the_exit_change_no_value() {
    let (mut dropped, mut skipped) = (0, 0);
    // Scenarios with obstacles have no grid (see `sighted`).
    for s in builtins().into_iter().filter(|s| !s.has_obstacles()) {
        let stats: Vec<Stats> = (0..s.fovs.len())
            .map(|slot| Stats::for_slot(&s, slot))
            .collect();
        let grid = ElementaryGrid::new(&s).expect("squares");
        let mut rays = SourceRays::for_scenario(&s);
        SourceRays::index_crossings(&mut rays, &s, &grid);
        SourceRays::index_looks(&mut rays, &s);
        let mut kept = rays.clone();
        kept.iter_mut().for_each(SourceRays::keep_past_the_exit);
        let (cols, rows) = (s.cols, s.rows);
        let starts: Vec<Cell> = (0..6)
            .map(|i: i32| Cell {
                col: (i * 7 + 2).rem_euclid(cols),
                row: (i * 11 + 3).rem_euclid(rows),
            })
            .filter(|&c| (0..s.types.len()).all(|ty| s.is_free(ty, c)))
            .collect();
        let types: Vec<usize> = (0..starts.len()).map(|i| i % s.types.len()).collect();
        let observed: Vec<Vec<Look>> = (0..24)
            .map(|step: i32| {
                starts
                    .iter()
                    .zip(&types)
                    .map(|(c, &ty)| {
                        let c = Cell {
                            col: (c.col + step % 5 - 2).clamp(0, cols - 1),
                            row: (c.row + step % 3 - 1).clamp(0, rows - 1),
                        };
                        s.look(ty, c)
                    })
                    .collect()
            })
            .collect();
        let horizon = 3;
        let build = |rays| {
            let est = ExactEstimator::new(
                Precomputed {
                    scenario: &s,
                    stats: &stats,
                    rays,
                    grid: Some(&grid),
                    sights: None,
                },
                Situation {
                    observed: &observed,
                    targets: &[],
                    starts: &starts,
                    types: &types,
                    horizon,
                },
            );
            est.prepare();
            est
        };
        let (est, all) = (build(&rays), build(&kept));
        for (a, b) in est.seen.iter().zip(&all.seen) {
            dropped += b.hits.len() - a.hits.len();
        }
        // Whole looks are skipped too, without reading their rays.
        for (sr, table) in rays.iter().filter_map(|sr| Some((sr, sr.looks.as_ref()?))) {
            for class in s.classes_of(sr.source_index) {
                for (step, looks) in observed.iter().enumerate() {
                    let shift = class.speed * step as f64;
                    skipped += looks
                        .iter()
                        .filter_map(|l| look_key(&s, &l.region))
                        .filter(|&key| table.past_exit(key, shift))
                        .count();
                }
            }
        }
        for i in 0..starts.len() {
            let other = (i + 1) % starts.len();
            let excluded = [s.look(types[other], starts[other])];
            for t in 1..=horizon {
                for k in (0..s.cell_count()).step_by(7).map(|k| s.cell_at(k)) {
                    for x in [&[][..], &excluded[..]] {
                        let pair = [
                            (est.value(i, k, t, x), all.value(i, k, t, x)),
                            (est.value_by_rays(i, k, t, x), all.value_by_rays(i, k, t, x)),
                        ];
                        for (a, b) in pair {
                            assert_eq!(a.to_bits(), b.to_bits(), "{} {k:?} t={t}", s.id);
                        }
                    }
                }
            }
        }
    }
    assert!(dropped > 100, "{dropped}");
    assert!(skipped > 100, "{skipped}");
}

/// The seen sets built from indexed looks are the computed ones, to the
/// bit: looks of every field of view (two sizes in `site-fleet`) at
/// cells all over the lattice, its corners included, a whole-zone look
/// (never indexed), every class's speed; certain looks (unions) and
/// uncertain ones (pieces weighed by their detection probability).
#[test]
fn indexed_looks_give_the_computed_seen_sets() {
    // site-fleet's types detect with 0.9 and 0.6; made certain, it is
    // checked with unions too.
    let mut certain_fleet = site_fleet_spec();
    for ty in certain_fleet
        .sensor_types
        .iter_mut()
        .flat_map(|t| t.values_mut())
    {
        ty.p_detect = Some(1.0);
    }
    certain_fleet.p_detect = Some(1.0);
    // Scenarios with obstacles index no looks: their looks see parts of
    // their squares.
    let mut scenarios: Vec<Scenario> = builtins()
        .into_iter()
        .filter(|s| !s.has_obstacles())
        .collect();
    scenarios.push(Scenario::new(certain_fleet).expect("valid"));
    let mut compared = 0;
    for s in scenarios {
        let mut rays = SourceRays::for_scenario(&s);
        SourceRays::index_looks(&mut rays, &s);
        assert!(rays.iter().all(|r| r.looks.is_some()), "{}", s.id);
        // Every square field of view at every cell has its key.
        for (slot, fov) in s.fovs.iter().enumerate() {
            assert!(matches!(fov, FovSpec::Square { .. }));
            for k in 0..s.cell_count() {
                let region = s.fov_with(*fov, s.centre(s.cell_at(k)));
                let key = look_key(&s, &region).expect("a key");
                // A smaller field of view may equal a larger one
                // clipped: then either key holds the same region.
                let (ks, kk) = (key as usize / s.cell_count(), key as usize % s.cell_count());
                assert_eq!(s.fov_with(s.fovs[ks], s.centre(s.cell_at(kk))), region);
                assert!(ks <= slot);
            }
        }
        assert_eq!(look_key(&s, &s.zone_region()), None);
        let (cols, rows) = (s.cols, s.rows);
        for p_detect in [1.0, 0.9] {
            let look = |region| Look {
                region,
                p_detect,
                from: None,
            };
            let observed: Vec<Vec<Look>> = (0..7)
                .map(|step: i32| {
                    let mut looks: Vec<Look> = (0..9)
                        .map(|i: i32| {
                            let c = Cell {
                                col: (i * 7 + step * 3).rem_euclid(cols),
                                row: (i * 5 + step * 2).rem_euclid(rows),
                            };
                            let fov = s.fovs[i as usize % s.fovs.len()];
                            look(s.fov_with(fov, s.centre(c)))
                        })
                        .collect();
                    looks.push(look(
                        s.fov_with(s.fovs[0], s.centre(Cell { col: 0, row: 0 })),
                    ));
                    let far = Cell {
                        col: cols - 1,
                        row: rows - 1,
                    };
                    looks.push(look(
                        s.fov_with(*s.fovs.last().expect("a fov"), s.centre(far)),
                    ));
                    if step == 3 {
                        looks.push(look(s.zone_region()));
                    }
                    looks
                })
                .collect();
            let keys: Vec<Vec<_>> = observed
                .iter()
                .map(|step| step.iter().map(|l| look_key(&s, &l.region)).collect())
                .collect();
            assert!(keys.iter().flatten().filter(|k| k.is_some()).count() >= 7 * 11);
            for sr in &rays {
                for class in s.classes_of(sr.source_index) {
                    let read = RayHits::new(sr, &observed, &keys, &[], class.speed);
                    let computed = RayHits::new(sr, &observed, &[], &[], class.speed);
                    assert_eq!(read.offsets, computed.offsets);
                    let bits = |h: &RayHits| -> Vec<(u64, u64)> {
                        h.hits
                            .iter()
                            .map(|&(p, q)| (p.to_bits(), q.to_bits()))
                            .collect()
                    };
                    assert_eq!(bits(&read), bits(&computed), "{}", s.id);
                    for m in 0..sr.dirs.len() {
                        let detected = |h: &RayHits| {
                            h.detected(m)
                                .iter()
                                .map(|d| d.to_bits())
                                .collect::<Vec<_>>()
                        };
                        assert_eq!(detected(&read), detected(&computed), "{} ray {m}", s.id);
                    }
                    assert_eq!(read.certain(), p_detect == 1.0);
                    compared += read.hits.len();
                }
            }
        }
    }
    assert!(compared > 4_000, "{compared}");
}

/// A source's classes make their seen sets together (the looks' intervals
/// found once, each class pushing them by its own distances) exactly as
/// each class alone would: every built-in with speed mixtures, indexed
/// looks (`site-gates`) and looks that obstacles cut (`site-campus`), a
/// history long enough to push intervals past the rays' exits.
#[test]
fn a_sources_classes_see_together_what_each_sees_alone() {
    let mut compared = 0;
    for s in builtins() {
        let mut rays = SourceRays::for_scenario(&s);
        SourceRays::index_looks(&mut rays, &s);
        let free = |ty: usize, c: Cell| s.on_lattice(c) && s.is_free(ty, c);
        let observed: Vec<Vec<Look>> = (0..24)
            .map(|step: i32| {
                (0..8)
                    .filter_map(|i: i32| {
                        let ty = i as usize % s.types.len();
                        let c = Cell {
                            col: (i * 7 + step * 3).rem_euclid(s.cols),
                            row: (i * 5 + step * 2).rem_euclid(s.rows),
                        };
                        free(ty, c).then(|| s.look(ty, c))
                    })
                    .collect()
            })
            .collect();
        let keys: Vec<Vec<_>> = if s.has_obstacles() {
            Vec::new()
        } else {
            observed
                .iter()
                .map(|step| step.iter().map(|l| look_key(&s, &l.region)).collect())
                .collect()
        };
        let sights: Vec<Vec<_>> = if s.has_obstacles() {
            observed
                .iter()
                .map(|step| step.iter().map(|l| s.sight(l)).collect())
                .collect()
        } else {
            Vec::new()
        };
        for sr in &rays {
            let speeds: Vec<f64> = s
                .classes_of(sr.source_index)
                .iter()
                .map(|c| c.speed)
                .collect();
            let together = RayHits::for_classes(sr, &observed, &keys, &sights, &speeds);
            assert_eq!(together.len(), speeds.len());
            for (hits, &speed) in together.iter().zip(&speeds) {
                let alone = RayHits::for_classes(sr, &observed, &keys, &sights, &[speed]);
                let bits = |h: &RayHits| -> Vec<(u64, u64)> {
                    h.hits
                        .iter()
                        .map(|&(p, q)| (p.to_bits(), q.to_bits()))
                        .collect()
                };
                assert_eq!(hits.offsets, alone[0].offsets, "{}", s.id);
                assert_eq!(bits(hits), bits(&alone[0]), "{}", s.id);
                for m in 0..sr.dirs.len() {
                    let detected = |h: &RayHits| {
                        h.detected(m)
                            .iter()
                            .map(|d| d.to_bits())
                            .collect::<Vec<_>>()
                    };
                    assert_eq!(detected(hits), detected(&alone[0]), "{} ray {m}", s.id);
                }
                if speeds.len() > 1 {
                    compared += hits.hits.len();
                }
            }
        }
    }
    assert!(compared > 1_000, "{compared}");
}

/// The seen sets' sweep of weighted intervals gives the pieces of
/// `detection_pieces`: the same ends, the same probabilities to rounding,
/// on random intervals that share ends and overlap in many ways.
#[test]
fn the_sweep_cuts_the_pieces_detection_pieces_cuts() {
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};
    let mut rng = StdRng::seed_from_u64(3);
    let mut sweep = Sweep::default();
    let mut events = Vec::new();
    let mut pieces = 0;
    for _ in 0..2000 {
        let n = rng.random_range(0..12);
        let intervals: Vec<(f64, f64, f64)> = (0..n)
            .map(|_| {
                // Ends on a coarse grid, so that many coincide.
                let a = f64::from(rng.random_range(0..40u32)) * 2.5;
                let len = f64::from(rng.random_range(0..12u32)) * 2.5;
                let p = [1.0, 0.9, 0.6, 0.3][rng.random_range(0..4)];
                (a, a + len, p)
            })
            .collect();
        let mut want = Vec::new();
        crate::geometry::detection_pieces(
            &intervals,
            f64::NEG_INFINITY,
            f64::INFINITY,
            &mut events,
            |a, b, d| want.push((a, b, d)),
        );
        let mut got = Vec::new();
        sweep.run(intervals.iter().copied(), |a, b, d| got.push((a, b, d)));
        assert_eq!(got.len(), want.len(), "{intervals:?}");
        for (g, w) in got.iter().zip(&want) {
            assert_eq!((g.0, g.1), (w.0, w.1), "{intervals:?}");
            assert!((g.2 - w.2).abs() <= 1e-12, "{intervals:?}: {g:?} {w:?}");
        }
        pieces += got.len();
    }
    assert!(pieces > 5000, "{pieces}");
}

/// With obstacles, the looks that see their whole squares take the
/// windows, and get the per-cell path's values to rounding: on
/// `site-campus`, drones and robots (some by buildings and screens, some
/// in the open) after 16 steps of history, reported targets (some
/// walking into buildings), fills and single values at every step,
/// against no excluded look, a drone's, a robot's that a building cuts,
/// one in the open and another cut one that overlaps the first; with the
/// rays' crossings indexed and without (the grid walk).
#[test]
fn windows_give_the_per_cell_values_with_obstacles() {
    let s = builtins()
        .into_iter()
        .find(|s| s.id == "site-campus")
        .expect("built in");
    let (drone, robot) = (
        s.type_index("drone").expect("drone"),
        s.type_index("robot").expect("robot"),
    );
    let cell = |col, row| Cell { col, row };
    let candidates = [
        (drone, cell(9, 20)),
        (robot, cell(14, 14)),
        (drone, cell(30, 8)),
        (robot, cell(25, 14)),
        (robot, cell(30, 1)),
        (drone, cell(20, 25)),
    ];
    let excluded_looks = [
        s.look(drone, cell(12, 18)),
        s.look(robot, cell(13, 15)),
        s.look(robot, cell(31, 3)),
        s.look(robot, cell(15, 13)),
    ];
    assert!(s.is_free(robot, cell(15, 13)));
    assert!(s.sight(&excluded_looks[3]).is_some());
    assert!(s.sight(&excluded_looks[1]).is_some());
    assert!(s.sight(&excluded_looks[2]).is_none());
    let (compared, windowed) = windows_against_per_cell(&s, &candidates, &excluded_looks);
    assert!(compared > 10_000, "{compared}");
    assert!(windowed > 50, "{windowed}");
}

/// The same on a yard whose two square sizes put the elementary grid's
/// breakpoints off the cells' edges: ground cameras (p 0.8, 70 m) and
/// elevated drones (p 0.6, 60 m, two cells a step), two gates with cones
/// and speed mixtures, a building in the middle, one across the east
/// fence and a hedge, with a camera standing in it.
#[test]
fn windows_give_the_per_cell_values_on_a_yard() {
    let spec: crate::scenario::ScenarioSpec = serde_json::from_value(serde_json::json!({
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
    }))
    .expect("a spec");
    let s = Scenario::new(spec).expect("valid");
    let (drone, camera) = (
        s.type_index("drone").expect("drone"),
        s.type_index("default").expect("default"),
    );
    let cell = |col, row| Cell { col, row };
    let candidates = [
        (camera, cell(6, 11)),
        (drone, cell(10, 10)),
        (camera, cell(14, 6)),
        (camera, cell(4, 4)),
        (drone, cell(3, 15)),
        (camera, cell(15, 15)),
    ];
    let excluded_looks = [
        s.look(camera, cell(7, 8)),
        s.look(drone, cell(9, 12)),
        s.look(camera, cell(13, 9)),
    ];
    assert!(s.sight(&excluded_looks[0]).is_some());
    // The camera at (4, 4) stands in the hedge.
    assert!(
        s.sight(&s.look(camera, cell(4, 4)))
            .is_some_and(|v| v.blind())
    );
    let (compared, windowed) = windows_against_per_cell(&s, &candidates, &excluded_looks);
    assert!(compared > 5_000, "{compared}");
    assert!(windowed > 20, "{windowed}");
}

/// Fills and single values of the sensors of `candidates` (those free to
/// stand there; at least five) with the windows against the per-cell
/// path: every step of a 3-step plan after 16 steps of history, reported
/// targets, against each prefix of `excluded_looks`, with the rays'
/// crossings indexed and walked. Returns the values compared and the
/// probes whose look and excluded looks all see whole squares.
fn windows_against_per_cell(
    s: &Scenario,
    candidates: &[(usize, Cell)],
    excluded_looks: &[Look],
) -> (usize, usize) {
    use crate::estimator::Target;
    use crate::geometry::Point;
    use crate::search::ValueGrid;
    let stats: Vec<Stats> = (0..s.fovs.len())
        .map(|slot| Stats::for_slot(s, slot))
        .collect();
    let mut rays = SourceRays::for_scenario(s);
    let grid =
        ElementaryGrid::with_mass(s, |g| SourceRays::alive_mass(&rays, s, g)).expect("squares");
    let walked = rays.clone();
    SourceRays::index_crossings(&mut rays, s, &grid);
    assert!(rays.iter().all(|sr| sr.crossings.is_some()));
    let free = |ty: usize, c: Cell| s.on_lattice(c) && s.is_free(ty, c);
    let (types, starts): (Vec<usize>, Vec<Cell>) = candidates
        .iter()
        .copied()
        .filter(|&(ty, c)| free(ty, c))
        .unzip();
    assert!(starts.len() >= 5, "{starts:?}");
    let observed: Vec<Vec<Look>> = (0..=16)
        .map(|step: i32| {
            starts
                .iter()
                .zip(&types)
                .map(|(&c, &ty)| {
                    let c = Cell {
                        col: (c.col + step % 5 - 2).clamp(0, s.cols - 1),
                        row: (c.row + step % 3 - 1).clamp(0, s.rows - 1),
                    };
                    if free(ty, c) {
                        s.look(ty, c)
                    } else {
                        s.look(ty, starts[0])
                    }
                })
                .collect()
        })
        .collect();
    let targets: Vec<Target> = (0..12)
        .map(|i| Target {
            pos: Point::new(30.0 + 31.0 * f64::from(i), 40.0 + 19.0 * f64::from(i % 7)),
            vel: Point::new(4.0 - f64::from(i % 3) * 4.0, 3.0 - f64::from(i % 4) * 2.0),
        })
        .collect();
    let horizon = 3;
    // The rays (indexed, walked) and the grid, if any.
    let index = super::SightIndex::new(s, &rays);
    assert!(index.is_some(), "a scenario this small is indexed");
    let build = |walk: bool, with_grid: bool, with_index: bool| {
        let rays = if walk { &walked } else { &rays };
        let grid = with_grid.then_some(&grid);
        let sights = index.as_ref().filter(|_| with_index);
        let est = ExactEstimator::new(
            Precomputed {
                scenario: s,
                stats: &stats,
                rays,
                grid,
                sights,
            },
            Situation {
                observed: &observed,
                targets: &targets,
                starts: &starts,
                types: &types,
                horizon,
            },
        );
        est.prepare();
        est
    };
    let per_cell = build(false, false, false);
    // Without the sight index, against which the index must give the
    // same values to the bit.
    let plain = build(false, true, false);
    let (mut windowed, mut compared) = (0, 0);
    for (label, walk, with_index) in [
        ("indexed", false, false),
        ("walked", true, false),
        ("sight index", false, true),
    ] {
        let est = build(walk, true, with_index);
        for (i, (&start, &ty)) in starts.iter().zip(&types).enumerate() {
            let speed = s.types[ty].speed;
            for x in 0..=excluded_looks.len() {
                let excluded = &excluded_looks[..x];
                let mut a = ValueGrid::with_motion(horizon, speed, |_, _| true);
                let mut b = ValueGrid::with_motion(horizon, speed, |_, _| true);
                for t in 1..=horizon {
                    est.fill(i, start, t, excluded, &mut a);
                    per_cell.fill(i, start, t, excluded, &mut b);
                }
                if with_index {
                    let mut c = ValueGrid::with_motion(horizon, speed, |_, _| true);
                    for t in 1..=horizon {
                        plain.fill(i, start, t, excluded, &mut c);
                    }
                    assert_eq!(a.to_nested(), c.to_nested(), "sensor {i} excluded {x}");
                }
                for (va, vb) in a
                    .to_nested()
                    .iter()
                    .flatten()
                    .flatten()
                    .zip(b.to_nested().iter().flatten().flatten())
                {
                    let (Some(va), Some(vb)) = (va, vb) else {
                        assert_eq!(va.is_some(), vb.is_some());
                        continue;
                    };
                    assert!(
                        (va - vb).abs() <= 1e-9 * (1.0 + vb.abs()),
                        "{label} sensor {i} excluded {x}: {va} against {vb}"
                    );
                    compared += 1;
                }
                let e = (speed * horizon) as i32;
                for t in 1..=horizon {
                    for (dc, dr) in [(0, 0), (e, 0), (-e, e), (1, -1)] {
                        let Some(k) = s.lattice_cell(start, dc, dr) else {
                            continue;
                        };
                        let (va, vb) = (
                            est.value(i, k, t, excluded),
                            per_cell.value(i, k, t, excluded),
                        );
                        if with_index {
                            let vc = plain.value(i, k, t, excluded);
                            assert_eq!(va.to_bits(), vc.to_bits(), "{k:?} t={t}");
                        }
                        assert!(
                            (va - vb).abs() <= 1e-9 * (1.0 + vb.abs()),
                            "{label} value sensor {i} {k:?} t={t} excluded {x}: {va} against {vb}"
                        );
                        let look = s.look(ty, k);
                        // A look from inside a screen sees nothing, exactly.
                        if s.sight(&look).is_some_and(|v| v.blind()) {
                            assert_eq!(va, 0.0, "{label} {k:?} t={t}");
                        }
                        if s.sight(&look).is_none()
                            && excluded.iter().all(|x| {
                                !x.region.may_overlap(&look.region) || s.sight(x).is_none()
                            })
                        {
                            windowed += 1;
                        }
                    }
                }
            }
        }
    }
    (compared, windowed)
}

/// `detected_upto` (its block-by-block count of the ends) against the
/// detected length up to `x` summed interval by interval, on rays of 0 to
/// 2,000 intervals (past the count's linear scan of block ends), at every
/// end, start and midpoint and outside the intervals.
#[test]
fn detected_upto_is_the_detected_length_up_to_a_point() {
    let lengths = [0usize, 1, 7, 15, 16, 17, 31, 32, 33, 100, 255, 2000];
    let (mut offsets, mut hits, mut detected) = (vec![0u32], Vec::new(), Vec::new());
    for (m, &n) in lengths.iter().enumerate() {
        let mut x = m as f64;
        for i in 0..n {
            // Gaps and lengths that vary, some intervals touching.
            let gap = if i % 3 == 0 {
                0.0
            } else {
                0.25 + (i % 5) as f64 * 0.1
            };
            let len = 0.5 + (i * 7 % 11) as f64 * 0.05;
            hits.push((x + gap, x + gap + len));
            detected.push(0.3 + (i % 7) as f64 * 0.1);
            x += gap + len;
        }
        offsets.push(hits.len() as u32);
    }
    let seen = RayHits::from_parts(offsets.clone(), hits.clone(), detected.clone()).with_prefix();
    for m in 0..lengths.len() {
        let ray = offsets[m] as usize..offsets[m + 1] as usize;
        let reference = |x: f64| -> f64 {
            hits[ray.clone()]
                .iter()
                .zip(&detected[ray.clone()])
                .map(|(&(a, b), &d)| (b.min(x) - a).max(0.0) * d)
                .sum()
        };
        let mut points = vec![-1.0, 1e9, f64::INFINITY, f64::NEG_INFINITY];
        for &(a, b) in &hits[ray.clone()] {
            points.extend([a, b, 0.5 * (a + b), a - 1e-9, b + 1e-9]);
        }
        for x in points {
            let (got, want) = (seen.detected_upto(m, x), reference(x));
            let tolerance = 1e-12 * want.abs().max(1.0);
            assert!(
                (got - want).abs() <= tolerance,
                "ray {m} of {} intervals at {x}: {got} against {want}",
                lengths[m]
            );
        }
    }
}

/// `Profile::ends_unless_detected` is `None` exactly when the union of the
/// certain pieces, merged where they touch, holds `[a, b]`, and otherwise
/// the detected length up to both ends: on random pieces with ends on a
/// grid of halves (so that touching is exact), with gaps, touching runs,
/// uncertain pieces inside runs, points on the pieces' ends and outside
/// every piece; keys of a few pieces and of more than `SCAN_PIECES` (whose
/// ends are bisected, not counted). `Profile::upto_pair` is the detected
/// length up to both ends, always.
#[test]
fn a_profile_leaves_out_an_interval_inside_its_certain_runs() {
    use rand::{RngExt, SeedableRng, rngs::StdRng};
    let mut rng = StdRng::seed_from_u64(5);
    let mut profile = Profile::default();
    let mut keys = Vec::new();
    for _ in 0..200 {
        let mut pieces = Vec::new();
        let mut x = f64::from(rng.random_range(-4..4)) * 0.5;
        let count = if rng.random_range(0..4) == 0 {
            rng.random_range(33..80)
        } else {
            rng.random_range(0..6)
        };
        for _ in 0..count {
            x += f64::from(rng.random_range(0..2)) * 0.5;
            let end = x + f64::from(rng.random_range(1..4)) * 0.5;
            let d = if rng.random_range(0..4) == 0 {
                0.5
            } else {
                1.0
            };
            pieces.push((x, end, d));
            x = end;
        }
        profile.push_key(pieces.iter().copied());
        keys.push(pieces);
    }
    for (i, pieces) in keys.iter().enumerate() {
        // The certain runs: certain pieces merged where one ends at the
        // next one's start.
        let mut runs: Vec<(f64, f64)> = Vec::new();
        for &(x0, x1, _) in pieces.iter().filter(|p| p.2 == 1.0) {
            match runs.last_mut() {
                Some(run) if run.1 == x0 => run.1 = x1,
                _ => runs.push((x0, x1)),
            }
        }
        let (lo, hi) = pieces
            .first()
            .zip(pieces.last())
            .map_or((0.0, 0.0), |(f, l)| (f.0, l.1));
        for _ in 0..50 {
            let a = lo - 2.0 + f64::from(rng.random_range(0..=4 * (hi - lo + 4.0) as i32)) * 0.25;
            let b =
                a + f64::from(rng.random_range(1..8)) * 0.25 * f64::from(rng.random_range(1..4));
            let upto = |x: f64| -> f64 {
                (pieces.iter())
                    .map(|&(x0, x1, d)| (x1.min(x) - x0).max(0.0) * d)
                    .sum()
            };
            let want = if runs.iter().any(|&(x0, x1)| x0 <= a && b <= x1) {
                None
            } else {
                Some((upto(a), upto(b)))
            };
            let got = profile.ends_unless_detected(i, a, b);
            assert_eq!(got, want, "key {i} {pieces:?}, [{a}, {b}]");
            let pair = profile.upto_pair(i, a, b);
            assert_eq!(pair, (upto(a), upto(b)), "key {i} {pieces:?}, [{a}, {b}]");
        }
    }
}

/// The known targets a windowed fill reads for each cell are those its
/// view's containment test holds, counted and summed in the targets'
/// order: the same to the bit as testing every cell against every target.
/// Targets on the views' edges, at the zone's edges and partly seen
/// included, for a square view and for one clipped by the zone; and the
/// same targets all by weight, as a fill of looks that see over obstacles
/// sums them.
#[test]
fn known_targets_in_views_are_those_each_view_holds() {
    use crate::geometry::Point;
    let s = Scenario::new(site_fleet_spec()).expect("valid");
    for ty in 0..s.types.len() {
        let FovSpec::Square { half_width } = s.types[ty].fov else {
            continue;
        };
        for start in [
            Cell { col: 3, row: 2 },
            Cell {
                col: s.cols / 2,
                row: s.rows / 2,
            },
        ] {
            let k = 4;
            let mut clear = Vec::new();
            let mut partial = Vec::new();
            for i in 0..400u32 {
                let c = s.centre(start.offset((i % 13) as i32 - 6, (i / 13 % 11) as i32 - 5));
                // On an edge, just inside or outside it, or in between.
                let dx = [
                    half_width,
                    -half_width,
                    half_width + 1e-9,
                    0.37 * half_width,
                ][i as usize % 4];
                let dy = [-half_width, 0.0, half_width - 1e-9, half_width][i as usize / 4 % 4];
                let p = Point::new(c.x + dx, c.y + dy);
                if !s.in_zone(p) {
                    continue;
                }
                if i % 3 == 0 {
                    partial.push((p, 0.1 + f64::from(i % 7) / 9.0));
                } else {
                    clear.push(p);
                }
            }
            // The zone's corner and edges.
            clear.extend([
                Point::new(0.0, 0.0),
                Point::new(s.width, 0.0),
                Point::new(0.0, 5.0),
            ]);
            let known = super::KnownInViews::new(&s, ty, start, k, &clear, &partial);
            // Every target by its weight (1 for the clear ones), in one
            // list, as a fill of looks that see over obstacles sums them.
            let weighted: Vec<(Point, f64)> = (clear.iter().map(|&p| (p, 1.0)))
                .chain(partial.iter().copied())
                .collect();
            let by_weight = super::KnownInViews::new(&s, ty, start, k, &[], &weighted);
            let mut fractional = 0;
            for dr in -k..=k {
                for dc in -k..=k {
                    let Some(cell) = s.lattice_cell(start, dc, dr) else {
                        continue;
                    };
                    let fk = s.fov_region_of(ty, cell);
                    let mut want = clear.iter().filter(|&&p| fk.contains(p)).count() as f64;
                    want += partial
                        .iter()
                        .filter(|(p, _)| fk.contains(*p))
                        .map(|&(_, miss)| miss)
                        .sum::<f64>();
                    assert_eq!(
                        known.at(dc, dr).to_bits(),
                        want.to_bits(),
                        "type {ty} start {start:?} offset ({dc}, {dr})"
                    );
                    let weight: f64 = weighted
                        .iter()
                        .filter(|(p, _)| fk.contains(*p))
                        .map(|&(_, w)| w)
                        .sum();
                    assert_eq!(
                        by_weight.at(dc, dr).to_bits(),
                        weight.to_bits(),
                        "weights: type {ty} start {start:?} offset ({dc}, {dr})"
                    );
                    fractional += usize::from(want.fract() != 0.0);
                }
            }
            assert!(
                fractional > 20,
                "type {ty}: {fractional} cells with partly seen targets"
            );
        }
    }
}
