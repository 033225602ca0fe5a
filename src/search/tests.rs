//! Tests of the search: DP = brute force (speeds, blocked cells, ties),
//! reachability against a search of the tests' own, and the motion model.

use super::*;
use proptest::prelude::*;
use std::collections::{HashSet, VecDeque};

fn grid_from(horizon: usize, vals: &[f64], holes: &[bool]) -> ValueGrid {
    let mut g = ValueGrid::new(horizon);
    let h = horizon as i32;
    let mut i = 0;
    for t in 1..=horizon {
        for dr in -h..=h {
            for dc in -h..=h {
                // A hole models the lattice edge, but the start column
                // and row stay open so that staying put is legal.
                let hole = holes[i % holes.len()] && (dc != 0 || dr != 0);
                if !hole {
                    g.set(t, dc, dr, vals[i % vals.len()]);
                }
                i += 1;
            }
        }
    }
    g
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn dp_equals_brute_force_on_integer_grids(
        horizon in 1usize..=4,
        vals in prop::collection::vec(0u8..4, 1..400),
        holes in prop::collection::vec(prop::bool::weighted(0.15), 1..50),
    ) {
        // Small integers: many ties, and exact sums, so the paths must match.
        let vals: Vec<f64> = vals.into_iter().map(f64::from).collect();
        let g = grid_from(horizon, &vals, &holes);
        let dp = best_path(&g);
        let bf = brute_force(&g);
        prop_assert_eq!(dp.value, bf.value);
        prop_assert_eq!(dp.moves, bf.moves);
    }

    #[test]
    fn dp_equals_brute_force_on_real_grids(
        horizon in 1usize..=4,
        vals in prop::collection::vec(-5.0f64..10.0, 1..400),
    ) {
        let g = grid_from(horizon, &vals, &[false]);
        let dp = best_path(&g);
        let bf = brute_force(&g);
        prop_assert!((dp.value - bf.value).abs() <= 1e-9 * bf.value.abs().max(1.0));
        prop_assert!((g.path_value(&dp.moves).unwrap_or(f64::NAN) - bf.value).abs() <= 1e-9 * bf.value.abs().max(1.0));
    }
}

#[test]
fn off_lattice_cells_are_never_entered() {
    // A sensor in a corner: only offsets with dc ≥ 0, dr ≥ 0 exist.
    let mut g = ValueGrid::new(3);
    for t in 1..=3 {
        for dr in 0..=t as i32 {
            for dc in 0..=t as i32 {
                g.set(t, dc, dr, 1.0);
            }
        }
    }
    g.set(3, 3, 3, 10.0);
    let p = best_path(&g);
    assert_eq!(p.offsets(), vec![(1, 1), (2, 2), (3, 3)]);
    assert_eq!(p.value, 12.0);
}

/// A free mask over the offsets of (speed, horizon): `blocked[i]` below
/// `density` blocks the i-th offset in row-major order; the start is free.
fn mask(speed: usize, horizon: usize, cells: &[u8], density: u8) -> impl Fn(i32, i32) -> bool {
    let e = (speed * horizon) as i32;
    let side = 2 * e + 1;
    let blocked: Vec<bool> = (0..side * side)
        .map(|i| cells[i as usize % cells.len()] < density)
        .collect();
    move |dc: i32, dr: i32| {
        assert!(
            dc.abs() <= e && dr.abs() <= e,
            "free({dc}, {dr}) outside the square"
        );
        (dc == 0 && dr == 0) || !blocked[((dr + e) * side + dc + e) as usize]
    }
}

/// Independent reference: the offsets within `speed` king moves of
/// `from` through free cells (inside the square of extent `e`).
fn one_step(
    free: &dyn Fn(i32, i32) -> bool,
    e: i32,
    from: (i32, i32),
    speed: usize,
) -> HashSet<(i32, i32)> {
    let ok = |c: i32, r: i32| c.abs() <= e && r.abs() <= e && free(c, r);
    let mut dist = std::collections::HashMap::new();
    dist.insert(from, 0usize);
    let mut queue = VecDeque::from([from]);
    while let Some((c, r)) = queue.pop_front() {
        let d = dist[&(c, r)];
        if d == speed {
            continue;
        }
        for dr in -1..=1 {
            for dc in -1..=1 {
                let p = (c + dc, r + dr);
                if ok(p.0, p.1) && !dist.contains_key(&p) {
                    dist.insert(p, d + 1);
                    queue.push_back(p);
                }
            }
        }
    }
    dist.into_keys().collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn dp_equals_brute_force_with_speeds_and_blocks(
        speed in 1usize..=3,
        horizon in 1usize..=3,
        cells in prop::collection::vec(0u8..10, 1..400),
        density in 0u8..7,
        vals in prop::collection::vec(0u8..4, 1..200),
        holes in prop::collection::vec(prop::bool::weighted(0.1), 1..60),
    ) {
        let free = mask(speed, horizon, &cells, density);
        let e = (speed * horizon) as i32;
        let mut g = ValueGrid::with_motion(horizon, speed, &free);
        prop_assert_eq!(g.side(), 2 * e as usize + 1);
        prop_assert_eq!((g.speed(), g.horizon()), (speed, horizon));
        // Reachability against an independent breadth-first search, and
        // the visiting order of for_each_reachable.
        let mut layer: HashSet<(i32, i32)> = HashSet::from([(0, 0)]);
        let mut i = 0;
        for t in 1..=horizon {
            layer = layer.iter().flat_map(|&p| one_step(&free, e, p, speed)).collect();
            let mut seen = Vec::new();
            g.for_each_reachable(t, |dc, dr| seen.push((dc, dr)));
            let mut expected: Vec<(i32, i32)> = layer.iter().copied().collect();
            expected.sort_by_key(|&(c, r)| (r, c));
            prop_assert_eq!(&seen, &expected);
            for dr in -e - 1..=e + 1 {
                for dc in -e - 1..=e + 1 {
                    prop_assert_eq!(g.reachable(t, dc, dr), layer.contains(&(dc, dr)));
                }
            }
            for (dc, dr) in seen {
                if !holes[i % holes.len()] {
                    g.set(t, dc, dr, f64::from(vals[i % vals.len()]));
                }
                i += 1;
            }
        }
        let dp = best_path(&g);
        let bf = brute_force(&g);
        prop_assert_eq!(dp.value, bf.value);
        prop_assert_eq!(&dp.moves, &bf.moves);
        prop_assert_eq!(dp.moves.len(), horizon);
        if dp.value > f64::NEG_INFINITY {
            prop_assert_eq!(g.path_value(&dp.moves), Some(dp.value));
            let mut at = (0, 0);
            for (&(dc, dr), &p) in dp.moves.iter().zip(&dp.offsets()) {
                prop_assert!(dc.abs().max(dr.abs()) <= speed as i32);
                prop_assert!(free(p.0, p.1), "stands on blocked {:?}", p);
                prop_assert!(one_step(&free, e, at, speed).contains(&p), "{:?} -> {:?}", at, p);
                at = p;
            }
        } else {
            prop_assert_eq!(dp.moves, vec![(0, 0); horizon]);
        }
    }
}

/// The largest square of offsets (fastest sensor, longest horizon) is
/// wider than a machine word: reachability still matches the tests' own
/// breadth-first search at every step, near every edge.
#[test]
fn reachability_holds_on_the_largest_square() {
    use crate::limits::MAX_HORIZON;
    let (speed, horizon) = (MAX_SENSOR_SPEED, MAX_HORIZON);
    let e = (speed * horizon) as i32;
    // A scatter of blocked cells (about one in eight) and a wall down one
    // column, with a gap.
    let cells: Vec<u8> = (0..997u64).map(|i| (i * i * 7919 % 97) as u8).collect();
    let scatter = mask(speed, horizon, &cells, 12);
    let free = move |dc: i32, dr: i32| scatter(dc, dr) && !(dc == e - 5 && dr != 3);
    let g = ValueGrid::with_motion(horizon, speed, &free);
    let mut layer: HashSet<(i32, i32)> = HashSet::from([(0, 0)]);
    for t in 1..=horizon {
        layer = layer
            .iter()
            .flat_map(|&p| one_step(&free, e, p, speed))
            .collect();
        for dr in -e..=e {
            for dc in -e..=e {
                assert_eq!(
                    g.reachable(t, dc, dr),
                    layer.contains(&(dc, dr)),
                    "t {t} ({dc}, {dr})"
                );
            }
        }
    }
    // The wall's far side is reached (through its gap).
    assert!(layer.iter().any(|&(dc, _)| dc > e - 5));
}

#[test]
fn step_displacements_are_rings_then_rows() {
    assert_eq!(step_displacements(1), &MOVES);
    for m in 1..=MAX_SENSOR_SPEED {
        let d = step_displacements(m);
        let mi = m as i32;
        assert_eq!(d.len(), (2 * m + 1) * (2 * m + 1));
        assert_eq!(d[0], (0, 0));
        let keys: Vec<_> = d
            .iter()
            .map(|&(c, r)| (c.abs().max(r.abs()), r, c))
            .collect();
        assert!(keys.windows(2).all(|w| w[0] < w[1]));
        assert!(d.iter().all(|&(c, r)| c.abs() <= mi && r.abs() <= mi));
    }
}

#[test]
fn new_is_speed_one_all_free() {
    for h in 0..=4 {
        assert_eq!(ValueGrid::new(h), ValueGrid::with_motion(h, 1, |_, _| true));
    }
    let g = ValueGrid::new(0);
    assert_eq!(
        best_path(&g),
        BestPath {
            moves: vec![],
            value: 0.0,
            violations: 0
        }
    );
}

#[test]
fn illegal_steps_have_no_value() {
    let mut g = ValueGrid::new(2);
    for t in 1..=2 {
        for dr in -2..=2 {
            for dc in -2..=2 {
                g.set(t, dc, dr, 1.0);
            }
        }
    }
    assert_eq!(g.get(1, 2, 0), None);
    assert_eq!(g.path_value(&[(1, 0), (1, 0)]), Some(2.0));
    assert_eq!(g.path_value(&[(1, 0), (-2, 0)]), None);
    assert_eq!(g.path_value(&[(2, 0)]), None);
    assert_eq!(g.path_value(&[(0, 0); 3]), None);
}

/// Speed 2, T = 2, cells east of dc = 1 worth 100, the rest 1.
fn eastern_prize(free: impl Fn(i32, i32) -> bool) -> ValueGrid {
    let mut g = ValueGrid::with_motion(2, 2, free);
    for t in 1..=2 {
        let mut cells = Vec::new();
        g.for_each_reachable(t, |dc, dr| cells.push((dc, dr)));
        for (dc, dr) in cells {
            g.set(t, dc, dr, if dc >= 2 { 100.0 } else { 1.0 });
        }
    }
    g
}

#[test]
fn speed_two_cannot_jump_a_wall() {
    let open = eastern_prize(|_, _| true);
    let p = best_path(&open);
    assert_eq!(p.moves, vec![(2, -2), (0, 0)]);
    assert_eq!(p.value, 200.0);
    // A wall along the whole column dc = 1: nothing east is reachable.
    let g = eastern_prize(|dc, _| dc != 1);
    for t in 1..=2 {
        for dr in -4..=4 {
            for dc in 1..=4 {
                assert!(!g.reachable(t, dc, dr));
            }
        }
    }
    let p = best_path(&g);
    assert_eq!(p, brute_force(&g));
    assert_eq!(p.moves, vec![(0, 0), (0, 0)]);
    assert_eq!(p.value, 2.0);
    // A short wall (|dr| ≤ 1): around it in two steps, not in one.
    let g = eastern_prize(|dc, dr| !(dc == 1 && dr.abs() <= 1));
    assert!(!g.reachable(1, 2, 0) && g.reachable(2, 2, 0));
    assert!(!g.reachable(1, 2, -2) && g.reachable(1, 1, -2));
    let p = best_path(&g);
    assert_eq!(p, brute_force(&g));
    // Step 1 to (0, -1), then past the wall's end via (1, -2).
    assert_eq!(p.moves, vec![(0, -1), (2, -2)]);
    assert_eq!(p.value, 101.0);
    assert!(
        p.offsets()
            .iter()
            .all(|&(dc, dr)| !(dc == 1 && dr.abs() <= 1))
    );
}

#[test]
fn speed_two_goes_around_a_single_block() {
    // (1, 0) blocked: (2, 0) is still one step away, via (1, ±1).
    let mut g = ValueGrid::with_motion(1, 2, |dc, dr| (dc, dr) != (1, 0));
    assert!(!g.reachable(1, 1, 0));
    assert!(g.reachable(1, 2, 0));
    g.set(1, 0, 0, 1.0);
    g.set(1, 1, 0, 9.0); // blocked: ignored
    g.set(1, 2, 0, 5.0);
    assert_eq!(g.get(1, 1, 0), None);
    let p = best_path(&g);
    assert_eq!(p.moves, vec![(2, 0)]);
    assert_eq!(p.value, 5.0);
    // Surrounded: the only legal step is to stay.
    let mut g = ValueGrid::with_motion(1, 2, |dc, dr| dc == 0 && dr == 0);
    for dr in -2..=2 {
        for dc in -2..=2 {
            g.set(1, dc, dr, 3.0);
        }
    }
    assert_eq!(
        best_path(&g),
        BestPath {
            moves: vec![(0, 0)],
            value: 3.0,
            violations: 0
        }
    );
    assert_eq!(g.path_value(&[(1, 0)]), None);
}

#[test]
fn unset_free_cells_are_passed_through_but_not_entered() {
    // (1, 0) free without a value: a stepping stone to (2, 0).
    let wall = |dc: i32, dr: i32| !(dc == 1 && dr != 0);
    let mut g = ValueGrid::with_motion(1, 2, wall);
    g.set(1, 0, 0, 0.0);
    g.set(1, 2, 0, 4.0);
    assert_eq!(best_path(&g).moves, vec![(2, 0)]);
    assert_eq!(g.path_value(&[(1, 0)]), None);
}

#[test]
fn to_nested_is_side_squared_with_nulls() {
    let blocked = [(1, 0), (-1, -1)];
    let mut g = ValueGrid::with_motion(2, 2, |dc, dr| !blocked.contains(&(dc, dr)));
    assert_eq!(g.side(), 9);
    for t in 1..=2 {
        for dr in -4..=4 {
            for dc in -4..=4 {
                g.set(t, dc, dr, f64::from(dc * 10 + dr));
            }
        }
    }
    let nested = g.to_nested();
    assert_eq!(nested.len(), 2);
    for (t, step) in nested.iter().enumerate() {
        let t = t + 1;
        assert_eq!(step.len(), 9);
        for (r, row) in step.iter().enumerate() {
            assert_eq!(row.len(), 9);
            for (c, v) in row.iter().enumerate() {
                let (dc, dr) = (c as i32 - 4, r as i32 - 4);
                let expect = (g.reachable(t, dc, dr)).then(|| f64::from(dc * 10 + dr));
                assert_eq!(*v, expect, "t={t} ({dc}, {dr})");
                if blocked.contains(&(dc, dr)) || dc.abs().max(dr.abs()) > 2 * t as i32 {
                    assert_eq!(*v, None);
                }
            }
        }
    }
    // Speed 2 reaches ring 2 at step 1 and everything free at step 2.
    assert!(nested[0][4 + 2][4 - 2].is_some());
    assert!(nested[0][4][4 + 3].is_none());
    assert!(nested[1][4 + 4][4 + 4].is_some());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// With violation counts, DP = brute force on (violations, −value) in
    /// lexicographic order, for every speed, blocked cells and open
    /// lattices (the separable maxima); and the optimum is checked against
    /// an enumeration of the tests' own over every legal path.
    #[test]
    fn lexicographic_dp_equals_brute_force_and_enumeration(
        speed in 1usize..=3,
        horizon in 1usize..=3,
        cells in prop::collection::vec(0u8..10, 1..400),
        density in 0u8..5,
        vals in prop::collection::vec(0u8..4, 1..200),
        boxes in prop::collection::vec((1usize..=3, -9i32..=9, -9i32..=9, 0i32..=2), 0..6),
    ) {
        let free = mask(speed, horizon, &cells, density);
        let e = (speed * horizon) as i32;
        let mut g = ValueGrid::with_motion(horizon, speed, &free);
        let mut i = 0;
        for t in 1..=horizon {
            let mut seen = Vec::new();
            g.for_each_reachable(t, |dc, dr| seen.push((dc, dr)));
            for (dc, dr) in seen {
                g.set(t, dc, dr, f64::from(vals[i % vals.len()]));
                i += 1;
            }
        }
        // Another sensor's cell at step t, with a square of radius r
        // around it too close.
        let mut counts = std::collections::HashMap::new();
        for &(t, c, r, rad) in &boxes {
            if t > horizon {
                continue;
            }
            g.add_violations(t, c - rad..=c + rad, r - rad..=r + rad);
            for dr in r - rad..=r + rad {
                for dc in c - rad..=c + rad {
                    *counts.entry((t, dc, dr)).or_insert(0u32) += 1;
                }
            }
        }
        for t in 1..=horizon {
            for dr in -e..=e {
                for dc in -e..=e {
                    let want = counts.get(&(t, dc, dr)).copied().unwrap_or(0);
                    prop_assert_eq!(g.violations(t, dc, dr), want);
                }
            }
        }
        let dp = best_path(&g);
        let bf = brute_force(&g);
        prop_assert_eq!(dp.value, bf.value);
        prop_assert_eq!(dp.violations, bf.violations);
        prop_assert_eq!(&dp.moves, &bf.moves);
        prop_assert_eq!(g.path_violations(&dp.moves), Some(dp.violations));
        // Every legal path by the tests' own enumeration (steps from the
        // independent breadth-first search): none is lexicographically
        // better.
        fn all_paths(
            free: &dyn Fn(i32, i32) -> bool, e: i32, speed: usize, h: usize,
            at: (i32, i32), path: &mut Vec<(i32, i32)>, out: &mut Vec<Vec<(i32, i32)>>,
        ) {
            if path.len() == h {
                out.push(path.clone());
                return;
            }
            for p in one_step(free, e, at, speed) {
                path.push(p);
                all_paths(free, e, speed, h, p, path, out);
                path.pop();
            }
        }
        let mut paths = Vec::new();
        all_paths(&free, e, speed, horizon, (0, 0), &mut Vec::new(), &mut paths);
        let score = |p: &[(i32, i32)]| {
            let mut v = 0.0;
            let mut k = 0u32;
            for (t, &(dc, dr)) in p.iter().enumerate() {
                v += g.get(t + 1, dc, dr).expect("every reachable cell has a value");
                k += counts.get(&(t + 1, dc, dr)).copied().unwrap_or(0);
            }
            (k, v)
        };
        let best = paths.iter().map(|p| score(p)).min_by(|a, b| {
            a.0.cmp(&b.0).then(b.1.total_cmp(&a.1))
        });
        prop_assert_eq!(best, Some((dp.violations, dp.value)));
        prop_assert_eq!(score(&dp.offsets()), (dp.violations, dp.value));
    }
}

#[test]
fn violations_are_clipped_and_cleared() {
    let mut g = ValueGrid::new(2);
    g.add_violations(1, -5..=-1, 0..=9);
    g.add_violations(3, -1..=1, -1..=1); // beyond the horizon: ignored
    assert!(g.has_violations());
    assert_eq!(g.violations(1, -1, 0), 1);
    assert_eq!(g.violations(1, -2, 2), 1);
    assert_eq!(g.violations(1, 0, 0), 0);
    assert_eq!(g.violations(2, -1, 0), 0);
    assert_eq!(g.violations(1, -1, -1), 0);
    g.clear_violations();
    assert!(!g.has_violations());
    assert_eq!(g.violations(1, -1, 0), 0);
}

#[test]
fn copy_step_copies_one_step_of_a_clone() {
    let base = ValueGrid::with_motion(3, 2, |dc, dr| (dc, dr) != (1, 0));
    let mut from = base.clone();
    for t in 1..=3 {
        from.fill_step(t, |dc, dr| Some(f64::from(dc * 10 + dr) + t as f64 / 8.0));
    }
    let mut to = base.clone();
    to.copy_step(2, &from);
    for t in 1..=3 {
        for dr in -6..=6 {
            for dc in -6..=6 {
                let want = if t == 2 { from.get(t, dc, dr) } else { None };
                assert_eq!(to.get(t, dc, dr), want, "t={t} ({dc},{dr})");
            }
        }
    }
    assert!(to.get(2, 2, 1).is_some());
}

#[test]
#[should_panic(expected = "different motions")]
fn copy_step_refuses_another_motion() {
    let mut a = ValueGrid::with_motion(3, 1, |_, _| true);
    let b = ValueGrid::with_motion(3, 1, |dc, _| dc != 1);
    a.copy_step(1, &b);
}
