//! Tests of the minimum separation in the simulator: the local policies'
//! rule ([`keep_apart`]), the local baselines' traces, and closed-loop
//! runs of the planner over HTTP.

use rand::{RngExt, SeedableRng, rngs::StdRng};
use vigil::scenario::{Cell, Scenario, builtins};
use vigil::separation::too_close;
use vigil_sim::client::{Client, spawn_local_server};
use vigil_sim::driver::{Sim, Start, fleet_types};
use vigil_sim::experiment::{RunConfig, run_one};
use vigil_sim::metrics::{Metrics, summarize};
use vigil_sim::policy::{Policy, keep_apart, legal_moves, random_move};

fn at(col: i32, row: i32) -> Cell {
    Cell { col, row }
}

fn paper() -> Scenario {
    builtins().remove(0)
}

#[test]
fn keep_apart_takes_intended_cells_that_keep_apart() {
    let s = paper();
    let current = [at(5, 5), at(9, 5), at(20, 20)];
    let intended = [at(6, 5), at(8, 5), at(21, 21)];
    // Two cells apart: allowed at d = 2, not at d = 3.
    assert_eq!(keep_apart(&s, &current, &intended, &[0; 3], 2), intended);
    assert_ne!(keep_apart(&s, &current, &intended, &[0; 3], 3), intended);
}

#[test]
fn keep_apart_stays_when_the_intended_cell_is_too_close() {
    let s = paper();
    // Sensor 1 would step next to sensor 0's new cell; staying keeps 2.
    let out = keep_apart(
        &s,
        &[at(10, 10), at(12, 10)],
        &[at(10, 10), at(11, 10)],
        &[0, 0],
        2,
    );
    assert_eq!(out, vec![at(10, 10), at(12, 10)]);
    // Sensor order decides: sensor 0 is never moved for sensor 1.
    let out = keep_apart(
        &s,
        &[at(12, 10), at(10, 10)],
        &[at(11, 10), at(10, 10)],
        &[0, 0],
        2,
    );
    assert_eq!(out[0], at(11, 10));
}

#[test]
fn keep_apart_takes_the_nearest_allowed_neighbour() {
    let s = paper();
    // Neither the intended cell (10, 11) nor staying at (11, 10) is two
    // cells from (10, 10); of the allowed moves (12, 9), (12, 10) and
    // (12, 11), (12, 11) is nearest (10, 11).
    let out = keep_apart(
        &s,
        &[at(10, 10), at(11, 10)],
        &[at(10, 10), at(10, 11)],
        &[0, 0],
        2,
    );
    assert_eq!(out, vec![at(10, 10), at(12, 11)]);
    // A tie: from (11, 11) toward (10, 10), (12, 10) and (10, 12) are both
    // √4 away; the first in `legal_moves`' order wins.
    let moves = legal_moves(&s, at(11, 11), 0);
    let pos = |c| moves.iter().position(|&m| m == c).expect("a legal move");
    assert!(pos(at(12, 10)) < pos(at(10, 12)));
    let out = keep_apart(
        &s,
        &[at(10, 10), at(11, 11)],
        &[at(10, 10), at(10, 10)],
        &[0, 0],
        2,
    );
    assert_eq!(out[1], at(12, 10));
}

#[test]
fn keep_apart_with_no_separation_is_the_identity() {
    let s = paper();
    let current = [at(3, 3), at(3, 3), at(4, 3), at(0, 0)];
    let intended = [at(4, 4), at(4, 4), at(4, 4), at(0, 0)];
    assert_eq!(keep_apart(&s, &current, &intended, &[0; 4], 0), intended);
    // The same sensors at d = 1 get off the shared cell.
    let out = keep_apart(&s, &current, &intended, &[0; 4], 1);
    assert_eq!(out[0], at(4, 4));
    assert_ne!(out[1], at(4, 4));
    assert_ne!(out[2], at(4, 4));
    assert_ne!(out[1], out[2]);
}

#[test]
fn keep_apart_cornered_takes_the_intended_cell() {
    let s = paper();
    // Every cell within one step of (10, 10) is closer than 3 to (10, 10):
    // the rule cannot be kept, so the sensor moves as it meant to.
    let out = keep_apart(
        &s,
        &[at(10, 10), at(10, 10)],
        &[at(10, 10), at(11, 10)],
        &[0, 0],
        3,
    );
    assert_eq!(out, vec![at(10, 10), at(11, 10)]);
    // In the open, a sensor next to another at d = 2 gets clear: of the
    // five cells two from (11, 11), (9, 11) is nearest its intent.
    let out = keep_apart(
        &s,
        &[at(11, 11), at(10, 10)],
        &[at(11, 11), at(10, 11)],
        &[0, 0],
        2,
    );
    assert_eq!(out[1], at(9, 11));
    // In the lattice's corner the same sensor has nowhere to go.
    let out = keep_apart(&s, &[at(1, 1), at(0, 0)], &[at(1, 1), at(0, 1)], &[0, 0], 2);
    assert_eq!(out[1], at(0, 1));
}

/// Random fleets (drones at speed 2, robots at 1) around no-go zones:
/// every sensor takes its intended cell when that keeps apart, else a
/// legal move; and wherever some legal move keeps apart from the sensors
/// before it, the one it takes does.
#[test]
fn keep_apart_keeps_the_rule_wherever_it_can() {
    let s = builtins()
        .into_iter()
        .find(|s| s.id == "site-fleet")
        .expect("built-in");
    let types = fleet_types(&s, Some("drone:4,robot:6"), 10).expect("fleet");
    let mut rng = StdRng::seed_from_u64(17);
    let (mut moved, mut kept) = (0, 0);
    for _ in 0..2_000 {
        // Sensors bunched around the largest no-go zone, so the rule
        // often bites.
        let current: Vec<Cell> = types
            .iter()
            .map(|&ty| {
                loop {
                    let c = at(rng.random_range(8..30), rng.random_range(4..24));
                    if s.is_free(ty, c) {
                        break c;
                    }
                }
            })
            .collect();
        let intended: Vec<Cell> = current
            .iter()
            .zip(&types)
            .map(|(&c, &ty)| random_move(&s, c, ty, &mut rng))
            .collect();
        let d = rng.random_range(1..=4);
        let out = keep_apart(&s, &current, &intended, &types, d);
        for i in 0..out.len() {
            let before = &out[..i];
            let allowed = |c: Cell| before.iter().all(|&o| !too_close(c, o, d));
            let legal = legal_moves(&s, current[i], types[i]);
            assert!(out[i] == intended[i] || legal.contains(&out[i]));
            if allowed(intended[i]) {
                assert_eq!(out[i], intended[i]);
            } else if legal.iter().any(|&c| allowed(c)) {
                assert!(allowed(out[i]), "{i}: {:?} too close at d = {d}", out[i]);
                moved += 1;
            } else {
                assert_eq!(out[i], intended[i]);
                kept += 1;
            }
        }
    }
    // Both branches were exercised.
    eprintln!("moved {moved}, cornered {kept}");
    assert!(moved > 1_000 && kept > 10, "moved {moved}, cornered {kept}");
}

/// `(step, i, j)` for every pair of sensors on one cell after a move.
fn shared_cells(sim: &Sim) -> Vec<(usize, usize, usize)> {
    let steps = sim.trace[0].len();
    let mut out = Vec::new();
    for k in 1..steps {
        for i in 0..sim.trace.len() {
            for j in 0..i {
                if sim.trace[i][k] == sim.trace[j][k] {
                    out.push((k, j, i));
                }
            }
        }
    }
    out
}

fn run_local(s: &Scenario, policy: Policy, n: usize, d: Option<usize>, steps: usize) -> Sim {
    let mut sim = Sim::new(s.clone(), n, Start::Random, 11, 0);
    sim.min_separation = d;
    for _ in 0..steps {
        sim.observe();
        let next = sim.local_moves(policy);
        sim.advance(next);
    }
    sim
}

/// The random policy with 150 sensors on 900 cells: unconstrained, sensors
/// share cells at every step; at d = 1 no two share a cell after any move
/// where the rule could be kept (a sensor on an earlier sensor's cell had
/// every legal move taken).
#[test]
fn random_sensors_at_separation_one_never_share_a_cell() {
    let s = paper();
    let (n, steps) = (150, 12);
    let free = run_local(&s, Policy::Random, n, Some(0), steps);
    eprintln!(
        "random, unconstrained: {} shared cells",
        shared_cells(&free).len()
    );
    assert!(
        shared_cells(&free).len() >= steps,
        "unconstrained: only {} shared cells",
        shared_cells(&free).len()
    );
    let apart = run_local(&s, Policy::Random, n, Some(1), steps);
    let (shared, avoidable) = breaches(&apart, 1);
    assert_eq!(avoidable, 0, "{shared:?}");
    // At this density nobody is cornered: no cell is ever shared.
    assert_eq!(shared_cells(&apart), vec![]);
    // Every move is still a legal king move.
    for t in &apart.trace {
        for w in t.windows(2) {
            assert!(legal_moves(&s, w[0], 0).contains(&w[1]), "{w:?}");
        }
    }
}

/// At d = 0 the random policy's trace is the unconstrained one: the same
/// draws from the sensors' RNG (seeded as [`Sim::with_types`] seeds it),
/// each applied as drawn. And the scenario's default (0) is the same.
#[test]
fn random_sensors_without_separation_move_as_drawn() {
    let s = paper();
    let (n, steps, seed) = (60, 20, 5);
    let mut sim = Sim::new(s.clone(), n, Start::Grid, seed, 0);
    sim.min_separation = Some(0);
    let mut rng = StdRng::seed_from_u64(seed ^ 0x5e45_0125_u64.rotate_left(17));
    let mut cells = sim.sensors.clone();
    let mut shared = 0;
    for _ in 0..steps {
        sim.observe();
        let next = sim.local_moves(Policy::Random);
        cells = cells
            .iter()
            .map(|&c| random_move(&s, c, 0, &mut rng))
            .collect();
        assert_eq!(next, cells);
        let mut distinct = cells.clone();
        distinct.sort_unstable();
        distinct.dedup();
        shared += n - distinct.len();
        sim.advance(next);
    }
    // Sensors did share cells, so d = 0 did not keep them apart.
    eprintln!("random at d = 0: {shared} shared cells");
    assert!(shared > 0);
    let default = run_local(&s, Policy::Random, 40, None, steps);
    assert_eq!(
        default.trace,
        run_local(&s, Policy::Random, 40, Some(0), steps).trace
    );
}

/// Stationary sensors started on shared cells spread out at d = 1 on the
/// first move and then hold still; at d = 0 they never move.
#[test]
fn stationary_sensors_get_apart_once() {
    let s = paper();
    let still = run_local(&s, Policy::Stationary, 300, None, 3);
    assert!(still.trace.iter().all(|t| t.iter().all(|&c| c == t[0])));
    let first: Vec<Cell> = still.trace.iter().map(|t| t[0]).collect();
    let mut distinct = first.clone();
    distinct.sort_unstable();
    distinct.dedup();
    assert!(distinct.len() < first.len(), "random starts shared no cell");
    let apart = run_local(&s, Policy::Stationary, 300, Some(1), 3);
    assert_eq!(shared_cells(&apart), vec![]);
    assert!(apart.trace.iter().any(|t| t[1] != t[0]));
    assert!(apart.trace.iter().all(|t| t[1] == t[2] && t[2] == t[3]));
}

/// The breaches of separation `d` after each move of a local run:
/// `(step, j, i)` for every pair `j < i` closer than `d`, and how many of
/// them sensor `i` could have avoided (some legal move of it kept `d` from
/// every sensor before it).
fn breaches(sim: &Sim, d: usize) -> (Vec<(usize, usize, usize)>, usize) {
    let (mut close, mut avoidable) = (Vec::new(), 0);
    for k in 1..sim.trace[0].len() {
        for i in 0..sim.trace.len() {
            let earlier: Vec<Cell> = sim.trace[..i].iter().map(|t| t[k]).collect();
            let near: Vec<usize> = (0..i)
                .filter(|&j| too_close(sim.trace[i][k], earlier[j], d))
                .collect();
            if near.is_empty() {
                continue;
            }
            let escape = legal_moves(&sim.scenario, sim.trace[i][k - 1], sim.types[i])
                .into_iter()
                .any(|c| earlier.iter().all(|&e| !too_close(c, e, d)));
            avoidable += usize::from(escape);
            close.extend(near.into_iter().map(|j| (k, j, i)));
        }
    }
    (close, avoidable)
}

/// The local force law at d = 2 with 80 sensors started at random: they
/// end moves closer than 2 cells only when cornered, whereas without the
/// rule they often do.
#[test]
fn local_force_keeps_apart() {
    let s = paper();
    let (free, _) = breaches(&run_local(&s, Policy::LocalForce, 80, None, 15), 2);
    let (close, avoidable) = breaches(&run_local(&s, Policy::LocalForce, 80, Some(2), 15), 2);
    eprintln!(
        "local force: {} close pairs unconstrained, {} at d = 2",
        free.len(),
        close.len()
    );
    assert_eq!(avoidable, 0, "{close:?}");
    assert!(
        free.len() >= 10 * close.len().max(1),
        "{} vs {}",
        free.len(),
        close.len()
    );
}

/// Closed loop over HTTP: `paper-uncoordinated` (each sensor plans alone)
/// with ten sensors on `paper-v10` for 30 measured steps, four seeds. At
/// `--min-separation 3` at most 2% of the plans have a violation, sensors
/// never end a step closer than 3 cells in more than 5% of the steps, and
/// they occupy ≥ 9.5 distinct cells on average; without the rule the same
/// runs bunch up (fewer distinct cells, more targets seen by four or more).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn uncoordinated_planner_keeps_apart_in_closed_loop() {
    let base = spawn_local_server().await.expect("server");
    let client = Client::new(&base);
    let info = client.scenario("paper-v10").await.expect("built-in");
    let scenario = Scenario::new(info.spec).expect("valid");
    let cfg = |d: usize| RunConfig {
        label: format!("d{d}"),
        policy: Policy::PaperUncoordinated,
        scenario_id: info.id.clone(),
        scenario: scenario.clone(),
        sensors: 10,
        fleet: None,
        steps: 30,
        warmup: 10,
        horizon: None,
        history: 16,
        start: Start::Grid,
        min_separation: Some(d),
        session: false,
        blind: false,
        world_rates: None,
        stationary_start: false,
    };
    let mut means = Vec::new();
    for d in [0, 3] {
        let cfg = cfg(d);
        let mut runs: Vec<Metrics> = Vec::new();
        let (mut steps, mut close_steps) = (0, 0);
        for seed in 1..=4 {
            let (m, sim) = run_one(&client, &cfg, seed, true).await.expect("run");
            let sim = sim.expect("kept");
            for k in cfg.warmup + 1..sim.trace[0].len() {
                let cells: Vec<Cell> = sim.trace.iter().map(|t| t[k]).collect();
                let close = cells
                    .iter()
                    .enumerate()
                    .any(|(i, &a)| cells[..i].iter().any(|&b| too_close(a, b, 3)));
                steps += 1;
                close_steps += usize::from(close);
            }
            runs.push(m);
        }
        assert_eq!(steps, 4 * 30);
        let (mean, _) = summarize(&runs);
        let violating = mean.violating_plans.expect("a planner policy");
        eprintln!(
            "d = {d}: violating plans {violating:.3}, {:.3} pairs per plan, cells {:.2}, \
             D4+S {:.3}, AD {:.2}, steps too close {close_steps}/{steps}",
            mean.violations_per_plan.unwrap_or(f64::NAN),
            mean.cells,
            mean.d4s,
            mean.ad
        );
        if d == 3 {
            assert!(violating <= 0.02, "{violating} of the plans violate");
            assert!(mean.cells >= 9.5, "{} distinct cells", mean.cells);
            assert!(
                close_steps as f64 <= 0.05 * steps as f64,
                "{close_steps} of {steps} steps too close"
            );
        } else {
            // No rule, nothing to violate; but sensors do end up close.
            assert_eq!(violating, 0.0);
            assert!(close_steps > steps / 2, "{close_steps} of {steps}");
        }
        means.push(mean);
    }
    let (free, apart) = (&means[0], &means[1]);
    assert!(
        free.cells + 0.8 <= apart.cells,
        "cells: {} without the rule, {} with",
        free.cells,
        apart.cells
    );
    assert!(
        free.d4s > apart.d4s,
        "D4+S: {} without the rule, {} with",
        free.d4s,
        apart.d4s
    );
}

/// The command line: `--min-separation` takes 0..=16, reaches the runs
/// (the JSON report names it) and the new metrics are reported.
#[test]
fn the_command_line_takes_a_minimum_separation() {
    let bin = env!("CARGO_BIN_EXE_vigil-sim");
    let out = std::process::Command::new(bin)
        .args(["--min-separation", "17"])
        .output()
        .expect("vigil-sim runs");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--min-separation"));
    let dir = std::env::temp_dir().join(format!("vigil-sim-sep-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let json = dir.join("report.json");
    let out = std::process::Command::new(bin)
        .args([
            "--policy",
            "paper",
            "--sensors",
            "6",
            "--steps",
            "4",
            "--warmup",
            "2",
        ])
        .args([
            "--seeds",
            "1",
            "--jobs",
            "1",
            "--min-separation",
            "2",
            "--json",
        ])
        .arg(&json)
        .output()
        .expect("vigil-sim runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let table = String::from_utf8_lossy(&out.stdout);
    let header = table.lines().next().expect("a header");
    let columns: Vec<&str> = header.split_whitespace().collect();
    let col = |name| columns.iter().position(|&c| c == name);
    assert_eq!(col("D4+S"), col("D3S").map(|i| i + 1), "{header}");
    assert_eq!(col("delay"), col("once").map(|i| i + 1), "{header}");
    assert_eq!(col("missed"), col("once").map(|i| i + 2), "{header}");
    assert_eq!(
        &columns[columns.len() - 5..],
        ["cells", "viol%", "sviol%", "gap%", "gap50%"],
        "{header}"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("report")).expect("JSON");
    let _ = std::fs::remove_dir_all(&dir);
    let run = &report["runs"][0];
    assert_eq!(run["min_separation"], 2);
    assert!(run["metrics"]["cells"].as_f64().is_some_and(|c| c > 0.0));
    assert!(run["metrics"]["d4s"].is_number());
    assert!(run["metrics"]["violating_plans"].is_number());
    assert!(run["metrics"]["violations_per_plan"].is_number());
    assert!(run["metrics"]["violating_sensor_plans"].is_number());
    // Four steps may leave no target detected or gone: null then, but
    // always there.
    for key in ["delay", "missed"] {
        for part in ["metrics", "ci95"] {
            let v = run[part].get(key).unwrap_or_else(|| panic!("{part}.{key}"));
            assert!(v.is_null() || v.is_number(), "{part}.{key}: {v}");
        }
    }
    // The paper estimator has no certificate: no gap, shown as `-`.
    assert!(run["metrics"]["gap_mean"].is_null());
    let row = table.lines().nth(1).expect("a row");
    assert_eq!(row.split_whitespace().last(), Some("-"), "{row}");
}
