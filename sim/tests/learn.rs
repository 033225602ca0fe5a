//! `--policy exact-learn`: the planner learns the sources' rates through a
//! learning session (whatever `--session` says). In a world that emits
//! three times (0.3 times) the rates it is told, every source's learnt rate
//! ends well above (below) the told one; the report records the learnt
//! rates, the world's and `steps_to_20pct`; the policy runs in an
//! experiment when named, in no experiment's default rows, and not live.

mod common;

use serde_json::Value;

use common::{TempDir, args, rows, run_all};

/// `paper-v10`: eight sources of rate 0.3; targets at speed 10 in a 300 m
/// square, so the default warm-up is ⌈300·√2 / 10⌉ = 43 steps.
const PAPER_SOURCES: usize = 8;
const PAPER_RATE: f64 = 0.3;
const PAPER_WARMUP: usize = 43;

fn numbers(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("an array: {v}"))
        .iter()
        .map(|x| x.as_f64().unwrap_or_else(|| panic!("a number: {x}")))
        .collect()
}

fn close(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9)
}

/// Four sensors, 60 measured steps after the 43 of warm-up, seeds 1 and 2,
/// without `--session`: the world at three times the told rates, and at
/// 0.3 times. The session starts from the told rates (its prior's means)
/// and learns from about 20 steps of exposure per source: every source's
/// last rate lies above 1.5× the told 0.3 at 3× (0.53–1.0 on seeds 1–12
/// when this was written) and below 0.25 at 0.3× (0.03–0.18). Plain
/// `exact-iterated` in the same run learns nothing and reports no
/// `learning`.
#[test]
fn exact_learn_learns_rates_above_and_below_the_told_ones() {
    let dir = TempDir::new("learn-rates");
    let common = [
        "--scenario",
        "paper-v10",
        "--sensors",
        "4",
        "--steps",
        "60",
        "--seeds",
        "2",
        "--jobs",
        "2",
    ];
    let (up, down) = (dir.json("up"), dir.json("down"));
    let outs = run_all(&[
        args(
            &[
                &common[..],
                &[
                    "--policy",
                    "exact-learn,exact-iterated",
                    "--world-rates",
                    "3",
                ],
            ]
            .concat(),
            &up,
        ),
        args(
            &[
                &common[..],
                &["--policy", "exact-learn", "--world-rates", "0.3"],
            ]
            .concat(),
            &down,
        ),
    ]);
    let up_rows = rows(&outs[0], &up);
    let down_rows = rows(&outs[1], &down);
    assert_eq!(up_rows.len(), 2);
    assert_eq!(up_rows[0]["policy"], "exact-learn");
    assert_eq!(up_rows[1]["policy"], "exact-iterated");
    assert!(up_rows[1].get("learning").is_none(), "{}", up_rows[1]);

    for (row, scale, check) in [
        (
            &up_rows[0],
            3.0,
            (|r: f64| r > 1.5 * PAPER_RATE) as fn(f64) -> bool,
        ),
        (&down_rows[0], 0.3, |r: f64| r < 0.25),
    ] {
        let l = &row["learning"];
        assert!(l.is_object(), "no learning in {row}");
        // The world's rates and the told ones (the session's prior).
        assert!(close(
            &numbers(&l["true_rates"]),
            &[PAPER_RATE * scale; PAPER_SOURCES]
        ));
        assert!(close(
            &numbers(&l["prior_rates"]),
            &[PAPER_RATE; PAPER_SOURCES]
        ));
        assert_eq!(l["warmup"], PAPER_WARMUP);
        assert_eq!(l["steps"], PAPER_WARMUP + 60);
        assert_eq!(l["seeds"], 2);
        let runs = l["runs"].as_array().expect("runs");
        assert_eq!(runs.len(), 2);
        for (k, run) in runs.iter().enumerate() {
            assert_eq!(run["seed"], k + 1);
            assert_eq!(run["steps"], PAPER_WARMUP + 60);
            let s = &run["steps_to_20pct"];
            assert!(
                s.is_null() || s.as_u64().is_some_and(|s| (1..=103).contains(&s)),
                "{s}"
            );
            let rates = run["rates"].as_array().expect("rates");
            assert_eq!(rates.len(), PAPER_SOURCES);
            for (j, r) in rates.iter().enumerate() {
                assert_eq!(r["index"], j);
                let rate = r["rate"].as_f64().expect("rate");
                assert!(
                    check(rate),
                    "world at {scale}×: seed {}, source {j} learnt {rate}",
                    k + 1
                );
                // As the server gives them: a proper posterior, exposed.
                assert!(r["interval"].is_array(), "{r}");
                assert!(r["exposure"].as_f64().is_some_and(|e| e > 0.0), "{r}");
            }
        }
        // The mean over seeds of each source's last rate, as in the table.
        for (j, m) in numbers(&l["rates"]).into_iter().enumerate() {
            assert!(check(m), "world at {scale}×: source {j}'s mean {m}");
        }
        // The plans were made and forecast.
        assert!(row["metrics"]["calibration"].is_number(), "{row}");
    }
    // The table says what was learnt, under it.
    let stdout = String::from_utf8_lossy(&outs[0].stdout);
    assert!(stdout.contains("learnt rates:"), "{stdout}");
    assert!(
        stdout.contains("exact-learn: steps_to_20pct")
            && stdout.contains("43 warm-up + 60 measured steps")
            && stdout.contains("(0.900)"),
        "{stdout}"
    );
    // No learning line for exact-iterated.
    assert_eq!(stdout.matches("steps_to_20pct").count(), 2, "{stdout}");
}

/// In an experiment `exact-learn` is named, takes the letter after the
/// experiment's own list (`c` in Table 1), and reports its learning in its
/// rows only; the default rows leave it out. `--live`, which plans
/// statelessly, refuses it.
#[test]
fn exact_learn_in_an_experiment_when_named_and_not_live() {
    let dir = TempDir::new("learn-experiment");
    let (named, default) = (dir.json("named"), dir.json("default"));
    let outs = run_all(&[
        args(
            &[
                "--experiment",
                "table1",
                "--policy",
                "paper,exact-learn",
                "--world-rates",
                "2",
                "--steps",
                "4",
                "--warmup",
                "3",
                "--seeds",
                "1",
            ],
            &named,
        ),
        args(
            &[
                "--experiment",
                "table1",
                "--steps",
                "2",
                "--warmup",
                "1",
                "--seeds",
                "1",
            ],
            &default,
        ),
        vec![
            "--live".into(),
            "--policy".into(),
            "exact-learn".into(),
            "--live-bind".into(),
            "127.0.0.1:0".into(),
        ],
    ]);
    let named_rows = rows(&outs[0], &named);
    let labels: Vec<&str> = named_rows
        .iter()
        .map(|r| r["label"].as_str().expect("label"))
        .collect();
    assert_eq!(labels, ["1a", "1c", "2a", "2c", "3a", "3c", "4a", "4c"]);
    for row in &named_rows {
        let learns = row["policy"] == "exact-learn";
        assert_eq!(row.get("learning").is_some(), learns, "{row}");
        if learns {
            let l = &row["learning"];
            assert_eq!(
                (l["warmup"].as_u64(), l["steps"].as_u64()),
                (Some(3), Some(7))
            );
            assert!(close(
                &numbers(&l["true_rates"]),
                &numbers(&l["prior_rates"])
                    .iter()
                    .map(|r| 2.0 * r)
                    .collect::<Vec<_>>()
            ));
        }
    }
    let default_rows = rows(&outs[1], &default);
    assert!(
        default_rows
            .iter()
            .all(|r| r["policy"] != "exact-learn" && r.get("learning").is_none())
    );
    let live = &outs[2];
    assert!(!live.status.success());
    let stderr = String::from_utf8_lossy(&live.stderr);
    assert!(
        stderr.contains("learn no rates") && stderr.contains("exact-learn"),
        "{stderr}"
    );
}

/// `--stationary-start`: the world starts full, as if its sources had
/// always emitted, not empty. With no warm-up, the first step's zone holds
/// `paper-v10`'s stationary population (about 8 × 0.3 targets per step ×
/// some 20 steps in the zone, every seed) where an empty start holds the
/// few targets of one step; the report marks the row.
#[test]
fn a_stationary_start_fills_the_zone_at_once() {
    let dir = TempDir::new("learn-stationary");
    let (full, empty) = (dir.json("full"), dir.json("empty"));
    let common = [
        "--policy",
        "stationary",
        "--warmup",
        "0",
        "--steps",
        "1",
        "--seeds",
        "4",
    ];
    let outs = run_all(&[
        args(&[&common[..], &["--stationary-start"]].concat(), &full),
        args(&common, &empty),
    ]);
    let in_zone = |row: &Value| {
        row["metrics"]["ad"].as_f64().expect("ad") + row["metrics"]["zd"].as_f64().expect("zd")
    };
    let full = &rows(&outs[0], &full)[0];
    let empty = &rows(&outs[1], &empty)[0];
    assert_eq!(full["stationary_start"], true);
    assert!(empty.get("stationary_start").is_none(), "{empty}");
    assert!(in_zone(full) > 20.0, "{full}");
    assert!(in_zone(empty) < 5.0, "{empty}");
}
