//! `--world-rates` and `--tell-world-rates` on the command line: the world's
//! sources emit at scaled rates (a silent world has no targets, three times
//! the rates about three times the targets), the planner is told the
//! scenario's rates or, with `--tell-world-rates`, the world's (its
//! forecasts are off, or calibrated), in single runs, sessions and
//! experiments; the JSON report records the scales; bad values are errors.

mod common;

use serde_json::Value;

use common::{TempDir, args, rows, run_all};
use vigil_sim::client::{Client, spawn_local_server};

/// `paper-v10`: eight sources of rate 0.3; targets at speed 10 in a 300 m
/// square.
const PAPER_SOURCES: usize = 8;
const PAPER_RATE: f64 = 0.3;

fn metric(row: &Value, key: &str) -> f64 {
    row["metrics"][key]
        .as_f64()
        .unwrap_or_else(|| panic!("metrics.{key} in {row}"))
}

/// Targets in the zone per step, averaged over the run's steps and seeds.
fn in_zone(row: &Value) -> f64 {
    metric(row, "ad") + metric(row, "zd")
}

/// `x` for each of `paper-v10`'s sources, as the report has them.
fn scales(x: f64) -> Value {
    serde_json::json!(vec![x; PAPER_SOURCES])
}

/// A world whose every source is silenced sees no target at any step,
/// with a local policy and with the planner (still told the scenario's
/// rates, through sessions); the report records the scales.
#[test]
fn a_silent_world_has_no_targets() {
    let dir = TempDir::new("silent");
    let common = [
        "--steps",
        "30",
        "--warmup",
        "10",
        "--seeds",
        "2",
        "--sensors",
        "6",
    ];
    let silent = dir.json("silent");
    let list = dir.json("list");
    let heard = dir.json("heard");
    let outs = run_all(&[
        args(
            &[
                &common[..],
                &[
                    "--policy",
                    "stationary,exact",
                    "--session",
                    "--world-rates",
                    "0",
                ],
            ]
            .concat(),
            &silent,
        ),
        args(
            &[
                &common[..],
                &["--policy", "stationary", "--world-rates"],
                &["0,0,0,0,0,0,0,0"],
            ]
            .concat(),
            &list,
        ),
        // One source heard: targets again.
        args(
            &[
                &common[..],
                &["--policy", "stationary", "--world-rates", "0,0,0,0,0,0,0,1"],
            ]
            .concat(),
            &heard,
        ),
    ]);
    let silent_rows = rows(&outs[0], &silent);
    assert_eq!(silent_rows.len(), 2);
    for row in silent_rows.iter().chain(&rows(&outs[1], &list)) {
        assert_eq!(in_zone(row), 0.0, "{row}");
        assert_eq!(row["world_rates"], scales(0.0));
        assert_eq!(row["told_world_rates"], false);
        assert_eq!(row["scenario"], "paper-v10");
    }
    // The planner ran (and planned for an empty zone).
    assert!(silent_rows[1]["metrics"]["plan_ms_p50"].is_number());
    let heard = &rows(&outs[2], &heard)[0];
    assert!(in_zone(heard) > 0.0, "{heard}");
    let stderr = String::from_utf8_lossy(&outs[0].stderr);
    assert!(stderr.contains("× [0, 0, 0, 0, 0, 0, 0, 0]"), "{stderr}");
}

/// Three times the rates, about three times the targets in the zone; the
/// per-source form and the single number agree exactly; silencing the
/// north and south sources halves the targets (the zone is square, the
/// sources symmetric); scale 1 is the world of no flag, exactly.
///
/// The tolerance: over a run's measured steps the sum `T` of the targets
/// in the zone at each step is the sum, over the targets of a Poisson
/// process, of the steps each spends in the zone in the window (at most
/// `D`, the zone's diagonal over the target speed, plus one). By
/// Campbell's theorem `Var T = E[Σ f²] ≤ D·E[T]`; over independent seeds
/// the same holds for the total. So `T` has a relative standard error of
/// at most `√(D/T)`, and a ratio of two totals at most
/// `√(D/T₁ + D/T₂)` (the seeds being shared only correlates them, which
/// narrows the ratio). Each check allows four of those.
#[test]
fn three_times_the_rates_about_three_times_the_targets() {
    let dir = TempDir::new("triple");
    let (steps, seeds) = (1000, 4);
    let common = [
        "--policy",
        "stationary",
        "--steps",
        &steps.to_string(),
        "--seeds",
        &seeds.to_string(),
    ]
    .map(str::to_owned);
    let common: Vec<&str> = common.iter().map(String::as_str).collect();
    let cases: [(&str, Option<&str>); 5] = [
        ("none", None),
        ("one", Some("1")),
        ("three", Some("3")),
        ("threes", Some("3,3,3,3,3,3,3,3")),
        // Sources 0–3 are on the west and east edges.
        ("half", Some("1,1,1,1,0,0,0,0")),
    ];
    let commands: Vec<Vec<String>> = cases
        .iter()
        .map(|&(name, scales)| {
            let mut words = common.clone();
            if let Some(s) = scales {
                words.extend(["--world-rates", s]);
            }
            args(&words, &dir.json(name))
        })
        .collect();
    let outs = run_all(&commands);
    let row = |k: usize| rows(&outs[k], &dir.json(cases[k].0)).remove(0);
    let (none, one, three, threes, half) = (row(0), row(1), row(2), row(3), row(4));

    // No flag and scale 1: the same world, the same counts.
    assert_eq!(none["metrics"], one["metrics"]);
    assert_eq!(none["world_rates"], Value::Null);
    assert_eq!(one["world_rates"], scales(1.0));
    // The single number is one scale per source.
    assert_eq!(three["metrics"], threes["metrics"]);
    assert_eq!(three["world_rates"], threes["world_rates"]);
    assert_eq!(
        half["world_rates"],
        serde_json::json!([1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0])
    );

    let d = (300f64.hypot(300.0) / 10.0).ceil() + 1.0;
    let total = |r: &Value| in_zone(r) * (steps * seeds) as f64;
    let (t1, t3, th) = (total(&one), total(&three), total(&half));
    assert!(t1 > 100_000.0, "{t1} target-steps: too few for the check");
    for (t, expected, name) in [(t3, 3.0, "3×"), (th, 0.5, "half")] {
        let ratio = t / t1;
        let se = expected * (d / t + d / t1).sqrt();
        assert!(
            (ratio - expected).abs() <= 4.0 * se,
            "{name}: {ratio:.4} the targets of scale 1, expected {expected} ± {:.4}",
            4.0 * se
        );
    }
}

/// Told the scenario's rates while the world emits three times (or 0.3
/// times) as many targets, the planner forecasts too few (too many)
/// detections for its next step: `calibration`, realised over forecast,
/// is above (below) 1. Told the world's rates (`--tell-world-rates`, the
/// scaled spec registered on the server, which the test reads back), its
/// forecasts are calibrated. A session plans as the stateless requests do
/// with the told rates too.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_planner_told_wrong_or_true_rates() {
    let base = spawn_local_server().await.expect("server");
    let client = Client::new(&base);
    let dir = TempDir::new("told");
    // One run at a time each: five of them share the server, whose
    // queue sheds requests beyond 8 waiting per core.
    let common = [
        "--server", &base, "--policy", "exact", "--steps", "60", "--seeds", "4", "--jobs", "1",
    ];
    // (name, scale, told, session)
    let cases = [
        ("wrong3", "3", false, false),
        ("true3", "3", true, false),
        ("wrong03", "0.3", false, false),
        ("true03", "0.3", true, false),
        ("true3s", "3", true, true),
    ];
    let commands: Vec<Vec<String>> = cases
        .iter()
        .map(|&(name, scale, told, session)| {
            let mut words = common.to_vec();
            words.extend(["--world-rates", scale]);
            if told {
                words.push("--tell-world-rates");
            }
            if session {
                words.push("--session");
            }
            args(&words, &dir.json(name))
        })
        .collect();
    let outs = tokio::task::spawn_blocking(move || run_all(&commands))
        .await
        .expect("runs");
    let mut calibration = Vec::new();
    for (k, &(name, scale, told, _)) in cases.iter().enumerate() {
        let row = rows(&outs[k], &dir.json(name)).remove(0);
        let scale: f64 = scale.parse().expect("a number");
        assert_eq!(row["world_rates"], scales(scale));
        assert_eq!(row["told_world_rates"], told);
        let id = row["scenario"].as_str().expect("an id");
        let info = client.scenario(id).await.expect("registered");
        let told_rate = if told { PAPER_RATE * scale } else { PAPER_RATE };
        assert_eq!(id == "paper-v10", !told, "{name}: {id}");
        assert_eq!(info.spec.sources.len(), PAPER_SOURCES);
        for src in &info.spec.sources {
            assert!((src.rate - told_rate).abs() < 1e-12, "{name}: {}", src.rate);
        }
        calibration.push((metric(&row, "calibration"), row));
    }
    let c = |k: usize| calibration[k].0;
    let (wrong3, true3, wrong03, true03) = (c(0), c(1), c(2), c(3));
    assert!(
        wrong3 > 1.02 && wrong3 > true3 + 0.02,
        "3×: told wrong {wrong3:.3}, told true {true3:.3}"
    );
    assert!(
        wrong03 < 0.95 && wrong03 < true03 - 0.03,
        "0.3×: told wrong {wrong03:.3}, told true {true03:.3}"
    );
    for (name, x) in [("3×", true3), ("0.3×", true03)] {
        assert!((x - 1.0).abs() < 0.03, "{name}: told true {x:.3}");
    }
    // Through sessions: the same plans, so the same counts.
    for key in ["ad", "zd", "calibration", "detected_once"] {
        assert_eq!(
            calibration[1].1["metrics"][key], calibration[4].1["metrics"][key],
            "{key}"
        );
    }
}

/// An experiment grid takes the scales for each row's scenario, registers
/// each scenario once with the world's rates when told, and records them
/// in every row.
#[test]
fn experiments_take_world_rates() {
    let dir = TempDir::new("grid");
    let json = dir.json("grid");
    let outs = run_all(&[args(
        &[
            "--experiment",
            "table1",
            "--world-rates",
            "2",
            "--tell-world-rates",
            "--steps",
            "5",
            "--warmup",
            "3",
            "--seeds",
            "1",
        ],
        &json,
    )]);
    let rows = rows(&outs[0], &json);
    // Four grid rows of two policies: paper-v10 (rows 1, 2) and paper-v15
    // (3, 4), each registered with doubled rates.
    assert_eq!(rows.len(), 8);
    let ids: Vec<&str> = rows
        .iter()
        .map(|r| r["scenario"].as_str().expect("an id"))
        .collect();
    for row in &rows {
        assert_eq!(row["world_rates"], scales(2.0));
        assert_eq!(row["told_world_rates"], true);
    }
    assert!(ids[..4].iter().all(|&id| id == ids[0]), "{ids:?}");
    assert!(ids[4..].iter().all(|&id| id == ids[4]), "{ids:?}");
    assert_ne!(ids[0], ids[4]);
    assert!(!ids.contains(&"paper-v10") && !ids.contains(&"paper-v15"));
    let stderr = String::from_utf8_lossy(&outs[0].stderr);
    assert_eq!(stderr.matches("registered as").count(), 2, "{stderr}");
}

/// Bad scales, counts that fit neither one nor the scenario's sources, a
/// world with too many targets, and `--tell-world-rates` alone: each an
/// error naming the flag, never a panic.
#[test]
fn bad_world_rates_are_refused() {
    let quick = ["--policy", "stationary", "--steps", "2", "--seeds", "1"];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--world-rates", "-1"], "negative"),
        (vec!["--world-rates=-0.5"], "negative"),
        (vec!["--world-rates", "1,-2"], "negative"),
        (vec!["--world-rates", "nan"], "not finite"),
        (vec!["--world-rates", "inf"], "not finite"),
        (vec!["--world-rates", "1,NaN"], "not finite"),
        (vec!["--world-rates", ""], "empty"),
        (vec!["--world-rates", "1,,1"], "empty"),
        (vec!["--world-rates", "three"], "not a number"),
        (vec!["--world-rates", "1,2,3"], "3 scales for 8 sources"),
        (
            vec!["--world-rates", "1,1,1,1,1,1,1,1", "--experiment", "mixed"],
            "site-gates: 8 scales for 4 sources",
        ),
        (vec!["--world-rates", "1e12"], "too many targets"),
        (vec!["--tell-world-rates"], "--tell-world-rates"),
        (vec!["--world-rates"], "--world-rates"),
    ];
    let commands: Vec<Vec<String>> = cases
        .iter()
        .map(|(words, _)| quick.iter().chain(words).map(|&w| w.to_owned()).collect())
        .collect();
    let outs = run_all(&commands);
    for ((words, says), out) in cases.iter().zip(&outs) {
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{words:?} ran");
        assert!(stderr.contains("--world-rates"), "{words:?}: {stderr}");
        assert!(stderr.contains(says), "{words:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{words:?}: {stderr}");
        assert!(out.stdout.is_empty(), "{words:?}: a table");
    }
}
