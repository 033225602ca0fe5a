//! Reports: the paper's table layout on stdout, and JSON.

use std::fmt::Write as _;

use serde::Serialize;

use crate::experiment::Row;

fn pm(mean: f64, ci: f64, decimals: usize) -> String {
    format!("{mean:.decimals$}±{ci:.decimals$}")
}

fn opt(mean: Option<f64>, ci: Option<f64>, decimals: usize) -> String {
    match (mean, ci) {
        (Some(m), Some(c)) => pm(m, c, decimals),
        _ => "-".to_owned(),
    }
}

/// The rows as a table: the paper's columns (EN NS AD ZD AF D1S D2S D3S,
/// then D4+S, detected by four or more sensors, TV), then ours (policy,
/// `once`: the fraction of the targets entering during the window detected
/// at least once, `delay`: the mean steps from entry to first detection of
/// those detected, `missed`: the fraction of those that left the zone never
/// detected (`-` when no run defines them), calibration, plan round trip
/// p50/p99, distinct cells
/// occupied by the sensors, `viol%`: the percentage of plan responses with
/// a separation violation, `sviol%`: the percentage of sensor plans
/// with one, `-` for local policies, and `gap%` and `gap50%`: the mean and
/// the median over a run's plans of the certified gap, in percent, `-`
/// without a certificate (the paper estimator, local policies)); NS shows
/// the fleet
/// (`drone:4,robot:6`) when the sensors have types, each mean ± the
/// half-width of its 95% confidence interval over seeds. Rows of a policy
/// that learns the rates add [`learning`]'s lines under the table.
pub fn table(rows: &[Row]) -> String {
    let header = [
        "EN", "NS", "AD", "ZD", "AF", "D1S", "D2S", "D3S", "D4+S", "TV", "policy", "once", "delay",
        "missed", "calib", "p50 ms", "p99 ms", "cells", "viol%", "sviol%", "gap%", "gap50%",
    ];
    let percent = |x: Option<f64>| x.map(|x| 100.0 * x);
    let body: Vec<[String; 22]> = rows
        .iter()
        .map(|r| {
            let (m, c) = (&r.metrics, &r.ci95);
            [
                r.label.clone(),
                r.fleet.clone().unwrap_or_else(|| r.sensors.to_string()),
                pm(m.ad, c.ad, 1),
                pm(m.zd, c.zd, 1),
                pm(m.af, c.af, 2),
                pm(m.d1s, c.d1s, 1),
                pm(m.d2s, c.d2s, 2),
                pm(m.d3s, c.d3s, 2),
                pm(m.d4s, c.d4s, 2),
                r.target_speed
                    .map_or_else(|| "mix".to_owned(), |v| v.to_string()),
                r.policy.clone(),
                pm(m.detected_once, c.detected_once, 2),
                opt(m.delay, c.delay, 2),
                opt(m.missed, c.missed, 2),
                opt(m.calibration, c.calibration, 2),
                opt(m.plan_ms_p50, c.plan_ms_p50, 2),
                opt(m.plan_ms_p99, c.plan_ms_p99, 2),
                pm(m.cells, c.cells, 2),
                opt(percent(m.violating_plans), percent(c.violating_plans), 1),
                opt(
                    percent(m.violating_sensor_plans),
                    percent(c.violating_sensor_plans),
                    1,
                ),
                opt(percent(m.gap_mean), percent(c.gap_mean), 2),
                opt(percent(m.gap_p50), percent(c.gap_p50), 2),
            ]
        })
        .collect();
    let mut widths: Vec<usize> = header.iter().map(|h| h.chars().count()).collect();
    for row in &body {
        for (w, cell) in widths.iter_mut().zip(row) {
            *w = (*w).max(cell.chars().count());
        }
    }
    let mut out = String::new();
    let line = |cells: &mut dyn Iterator<Item = &str>, out: &mut String| {
        let parts: Vec<String> = cells
            .zip(&widths)
            .map(|(c, &w)| format!("{c:>w$}"))
            .collect();
        let _ = writeln!(out, "{}", parts.join("  ").trim_end());
    };
    line(&mut header.iter().copied(), &mut out);
    for row in &body {
        line(&mut row.iter().map(String::as_str), &mut out);
    }
    out.push_str(&learning(rows));
    out
}

/// The lines under the table for the rows of a policy that learns the
/// rates (none without one): per row, `steps_to_20pct` (the mean over the
/// seeds that reached it ± its 95% interval, and how many did), then each
/// source's last learnt rate (mean ± 95% interval over seeds) and, in
/// brackets, the world's.
pub fn learning(rows: &[Row]) -> String {
    let mut out = String::new();
    for r in rows {
        let Some(l) = &r.learning else { continue };
        if out.is_empty() {
            let _ = writeln!(
                out,
                "learnt rates: steps_to_20pct counts steps from the first warm-up step \
                 (1), warm-up included; last rate per source (world's rate):"
            );
        }
        let reached = match (l.steps_to_20pct, l.steps_to_20pct_ci95) {
            (Some(m), Some(c)) => format!("{m:.1}±{c:.1}"),
            _ => "never".to_owned(),
        };
        let rates: Vec<String> = l
            .rates
            .iter()
            .zip(&l.rates_ci95)
            .zip(&l.true_rates)
            .map(|((m, c), t)| format!("{m:.3}±{c:.3} ({t:.3})"))
            .collect();
        // A single run's label is its policy's name.
        let name = if r.label == r.policy {
            r.policy.clone()
        } else {
            format!("{} {}", r.label, r.policy)
        };
        let _ = writeln!(
            out,
            "  {name}: steps_to_20pct {reached} ({}/{} seeds reached it; {} warm-up + {} measured steps); {}",
            l.reached_20pct,
            l.seeds,
            l.warmup,
            l.steps.saturating_sub(l.warmup),
            rates.join(", ")
        );
    }
    out
}

/// The JSON report: `{"runs":[{label, policy, scenario, sensors, fleet,
/// target_speed, steps, min_separation, seeds, world_rates,
/// told_world_rates, metrics, ci95}]}`, and `learning`
/// ([`crate::learn::Learning`]) in the rows of a policy that learns the
/// rates.
pub fn json(rows: &[Row]) -> serde_json::Result<String> {
    #[derive(Serialize)]
    struct Report<'a> {
        runs: &'a [Row],
    }
    serde_json::to_string_pretty(&Report { runs: rows })
}
