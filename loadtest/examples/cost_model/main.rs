//! Measures the CPU time of plans and scenario precomputations, one thread
//! each, fits the cost models of `vigil::cost` to them, and prints
//! predicted against measured time for every case.
//!
//! Cases: the load test's workloads (the reference workload of `paper-v10`
//! and each quantity varied from it: horizon, sensors, reported targets,
//! history, coordination, minimum separation, estimator, `site-gates`' speed
//! classes, `site-fleet`'s fleets), more plans that spread the fit (larger
//! lattices, circular fields of view, combinations, crowded fleets,
//! uncertain looks through circles, many obstacles, many drones among
//! many targets), the issue's large
//! plans, plans that maximise first detections (horizons, coordinations,
//! sensors, the built-ins' fleets; `cases::first_cases`), and
//! precomputations (lattice size, fields of view, sources, sensor types,
//! cones), and precomputations with obstacles (`--only obstacles`; these
//! are predicted by `cost::precompute_ms` whole, whose obstacle terms are
//! fitted apart).
//!
//! Each case runs inside a one-thread rayon pool; its time is the CPU time
//! of that thread (`/proc/thread-self/schedstat`, after a `sched_yield` so
//! the kernel's count is current). A case under half a second runs again
//! in batches of at least 40 ms, and the median of five batches is kept;
//! every case is measured in each of `--passes` rounds (2) and its least
//! time kept (cases of 2 s and more once): on this shared 2-core machine
//! one pass's time of a case varied from one run to the next by −30 % to
//! +58 % (caches and memory shared with the other core's work); the least
//! of two passes, by ±10 %.
//!
//! The fit is non-negative least squares on relative error (every row
//! divided by its measured time), refitted with the cases predicted low
//! weighted twice, per model: the plan cases for the plan model, the
//! first-detections cases for the first-detections model (its estimator
//! term held at 1), the precompute cases for the precompute model. It
//! prints the refitted constants in the form of `src/cost.rs`, then each
//! case with the prediction of the model in `src/cost.rs` and of the
//! refit, and the median, lowest and highest ratio predicted/measured per
//! group. About 3 min 15 s and 30 s more for the first-detections cases
//! (whose names start with `first`: `--only first` runs them alone); 15 s
//! more with `--large`.
//!
//! ```text
//! taskset -c 1 cargo run --release -p vigil-loadtest --example cost_model -- [--large] [--passes N] [--cache FILE] [--only TEXT] [--terms]
//! ```
//! - `--large`: also the largest precomputations (4 000 000 cells of
//!   squares, and of circles with one source; 40 000 cells of circles × 64
//!   sources). The issue's 4 000 000 cells × 64 sources of circles (about
//!   11 CPU-minutes) is only predicted.
//! - `--cache FILE`: measured times by case name, read first (cases found
//!   there are not run again) and written at the end.
//! - `--only TEXT`: only the cases whose name contains TEXT (the fit too).
//! - `--passes N`: rounds of measurement (2).
//! - `--terms`: print each case's terms.
#![allow(missing_docs, clippy::unwrap_used)]

mod cases;
mod fit;

use std::collections::BTreeMap;
use std::fmt::Write as _;

use cases::{Builder, Group, Model, Work};
use fit::{fit, median};
use vigil::cost;
use vigil::planner::{PlanInput, Planner};

/// CPU time of the calling thread, nanoseconds. `sched_yield` first: the
/// kernel brings a running thread's count up to date when it schedules.
fn cpu_ns() -> u64 {
    std::thread::yield_now();
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").unwrap();
    text.split_whitespace().next().unwrap().parse().unwrap()
}

/// Median CPU milliseconds of `f` on the calling thread (see the module
/// docs for the repetitions).
fn cpu_ms(mut f: impl FnMut()) -> f64 {
    let t0 = cpu_ns();
    f();
    let first = (cpu_ns() - t0) as f64 / 1e6;
    if first >= 500.0 {
        return first;
    }
    let reps = (40.0 / first.max(1e-3)).ceil() as usize;
    let mut batches: Vec<f64> = (0..5)
        .map(|_| {
            let t0 = cpu_ns();
            for _ in 0..reps {
                f();
            }
            (cpu_ns() - t0) as f64 / 1e6 / reps as f64
        })
        .collect();
    batches.sort_by(f64::total_cmp);
    batches[2]
}
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let flag = |f: &str| args.iter().any(|a| a == f);
    let value = |f: &str| {
        args.iter()
            .position(|a| a == f)
            .and_then(|i| args.get(i + 1).cloned())
    };
    let large = flag("--large");
    let passes: usize = value("--passes").map_or(2, |v| v.parse().unwrap());
    let cache_path = value("--cache");
    let mut cache: BTreeMap<String, f64> = cache_path
        .as_deref()
        .and_then(|p| std::fs::read_to_string(p).ok())
        .map(|text| {
            text.lines()
                .filter_map(|l| {
                    let (name, ms) = l.rsplit_once('\t')?;
                    Some((name.to_owned(), ms.parse().ok()?))
                })
                .collect()
        })
        .unwrap_or_default();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let started = std::time::Instant::now();
    let mut b = Builder {
        planners: Vec::new(),
        cases: Vec::new(),
        only: value("--only"),
    };
    // Requests are generated on the global pool (both cores); only the
    // timed work runs on the one-thread pool.
    cases::plan_cases(&mut b);
    cases::first_cases(&mut b);
    cases::precompute_cases(&mut b, large);
    cases::obstacle_cases(&mut b);
    eprintln!(
        "{} cases built in {:.0} s",
        b.cases.len(),
        started.elapsed().as_secs_f64()
    );

    // (case, terms, measured ms or NaN)
    let mut results: Vec<(usize, Vec<f64>, f64)> = Vec::new();
    // The slowest plan prediction and the reference's, microseconds.
    let mut predict_us = (String::new(), 0.0f64);
    let mut reference_us = f64::NAN;
    // Terms (and the time to predict) of every case first, then the
    // measurements: `passes` rounds over all the cases, keeping each one's
    // least time (other work on the machine only adds to it, and a second
    // pass minutes later rarely meets the same disturbance). Cases of 2 s
    // and more run once.
    for (ci, case) in b.cases.iter().enumerate() {
        let terms = match &case.work {
            Work::Plan { planner, req } => {
                let planner = &b.planners[*planner];
                let input = PlanInput::new(&planner.scenario, req).unwrap();
                let t0 = std::time::Instant::now();
                for _ in 0..100 {
                    std::hint::black_box(cost::plan_ms(planner, std::hint::black_box(&input)));
                }
                let us = t0.elapsed().as_secs_f64() * 1e4;
                if us > predict_us.1 {
                    predict_us = (case.name.clone(), us);
                }
                if case.name == "reference#0" {
                    reference_us = us;
                }
                let terms = cost::plan_terms(planner, &input).to_array();
                if case.group.model() == Model::First {
                    let k = cost::ESTIMATOR_TERMS;
                    let estimator = dot(&cost::PLAN_MODEL.map(|(_, c)| c)[..k], &terms[..k]);
                    cost::first_terms(planner, &input, estimator)
                        .to_array()
                        .to_vec()
                } else {
                    terms.to_vec()
                }
            }
            Work::Precompute(s) | Work::PredictOnly(s) if case.group.model() == Model::Whole => {
                vec![cost::precompute_ms(s)]
            }
            Work::Precompute(s) | Work::PredictOnly(s) => {
                cost::precompute_terms(s).to_array().to_vec()
            }
        };
        results.push((ci, terms, f64::NAN));
    }
    let cached: Vec<Option<f64>> = b
        .cases
        .iter()
        .map(|c| cache.get(&c.name).copied())
        .collect();
    for pass in 0..passes {
        for (ci, case) in b.cases.iter().enumerate() {
            let best = &mut results[ci].2;
            if let Some(ms) = cached[ci] {
                *best = ms;
                continue;
            }
            if pass > 0 && *best >= 2000.0 {
                continue;
            }
            let ms = match &case.work {
                Work::Plan { planner, req } => {
                    let planner = &b.planners[*planner];
                    let input = PlanInput::new(&planner.scenario, req).unwrap();
                    pool.install(|| {
                        cpu_ms(|| {
                            std::hint::black_box(planner.plan(&input));
                        })
                    })
                }
                Work::Precompute(s) => pool.install(|| {
                    cpu_ms(|| {
                        std::hint::black_box(Planner::new((**s).clone()));
                    })
                }),
                Work::PredictOnly(_) => continue,
            };
            *best = best.min(ms);
            eprintln!("pass {pass}: {:<50} {:>12.3} ms", case.name, ms);
        }
    }
    for (ci, _, ms) in &results {
        if ms.is_finite() {
            cache.insert(b.cases[*ci].name.clone(), *ms);
        }
    }
    if let Some(p) = &cache_path {
        let mut text = String::new();
        for (name, ms) in &cache {
            writeln!(text, "{name}\t{ms}").unwrap();
        }
        std::fs::write(p, text).unwrap();
    }

    // Each model: its name in src/cost.rs, its terms' names and its
    // coefficients there.
    let models = |m: Model| -> (&str, Vec<&str>, Vec<f64>) {
        let split = |table: &[(&'static str, f64)]| -> (Vec<&'static str>, Vec<f64>) {
            table.iter().copied().unzip()
        };
        let (what, (names, coef)) = match m {
            Model::Plan => ("PLAN_MODEL", split(&cost::PLAN_MODEL)),
            Model::First => ("FIRST_MODEL", split(&cost::FIRST_MODEL)),
            Model::Precompute => ("PRECOMPUTE_MODEL", split(&cost::PRECOMPUTE_MODEL)),
            Model::Whole => ("precompute_ms", (vec!["predicted ms"], vec![1.0])),
        };
        (what, names, coef)
    };
    let mut refits = BTreeMap::new();
    for m in [Model::Precompute, Model::Plan, Model::First] {
        // (`Model::Whole` is the prediction itself: nothing to refit.)
        let rows: Vec<(Vec<f64>, f64)> = results
            .iter()
            .filter(|(ci, _, ms)| b.cases[*ci].group.model() == m && ms.is_finite())
            .map(|(_, t, ms)| (t.clone(), *ms))
            .collect();
        if rows.is_empty() {
            continue;
        }
        let (what, names, _) = models(m);
        let coef = if m == Model::First {
            // The estimator's coefficient is held at 1 (src/cost.rs):
            // the others are fitted to what is left.
            let rest: Vec<(Vec<f64>, f64)> = rows
                .iter()
                .map(|(t, ms)| (t[1..].to_vec(), (ms - t[0]).max(1e-6)))
                .collect();
            std::iter::once(1.0)
                .chain(fit(&rest, names.len() - 1))
                .collect()
        } else {
            fit(&rows, names.len())
        };
        // In the form of src/cost.rs, to paste there.
        println!("refitted {what} (ms per unit):");
        for (name, c) in names.iter().zip(&coef) {
            println!("    ({name:?}, {c:.3e}),");
        }
        refits.insert(m as usize, coef);
    }
    let show_terms = flag("--terms");
    let mut by_group: BTreeMap<Group, (Vec<f64>, Vec<f64>)> = BTreeMap::new();
    println!();
    println!(
        "{:<50} {:>12} {:>12} {:>12} {:>7} {:>7}",
        "case", "model ms", "refit ms", "measured ms", "model", "refit"
    );
    for (ci, terms, ms) in &results {
        let case = &b.cases[*ci];
        let (_, names, coef) = models(case.group.model());
        let refit = refits.get(&(case.group.model() as usize)).unwrap_or(&coef);
        let (model, refit) = (dot(&coef, terms), dot(refit, terms));
        println!(
            "{:<50} {:>12.3} {:>12.3} {:>12.3} {:>7.2} {:>7.2}",
            case.name,
            model,
            refit,
            ms,
            model / ms,
            refit / ms
        );
        if show_terms {
            for (n, t) in names.iter().zip(terms) {
                if *t != 0.0 {
                    println!("      {n:<28} {t:.4e}");
                }
            }
        }
        if ms.is_finite() {
            let e = by_group.entry(case.group).or_default();
            e.0.push(model / ms);
            e.1.push(refit / ms);
        }
    }
    println!();
    println!("predicted/measured: median, worst low, worst high (model in src/cost.rs | refit)");
    for (g, (mut model, mut refit)) in by_group {
        let lo = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
        println!(
            "  {:<34} n={:<3} {:.2} {:.2} {:.2} | {:.2} {:.2} {:.2}",
            g.label(),
            model.len(),
            median(&mut model),
            lo(&model),
            hi(&model),
            median(&mut refit),
            lo(&refit),
            hi(&refit)
        );
    }
    println!(
        "plan prediction time: reference#0 {reference_us:.1} µs, slowest {:.1} µs ({})",
        predict_us.1, predict_us.0
    );
    eprintln!("took {:.0} s", started.elapsed().as_secs_f64());
}

fn dot(c: &[f64], t: &[f64]) -> f64 {
    c.iter().zip(t).map(|(a, b)| a * b).sum()
}
