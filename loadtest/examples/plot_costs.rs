//! Plots the cost curves measured by `cargo bench -p vigil-loadtest --bench
//! cost` (criterion's `target/criterion/<group>/<x>/new/estimates.json`)
//! into `docs/cost-<group>.svg`, and prints each curve as a Markdown table
//! with the power law `time ∝ x^k` fitted by least squares on log–log
//! scales (over the points with x > 0).
//!
//! `cargo run --release -p vigil-loadtest --example plot_costs`
#![allow(missing_docs)]

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One curve: its criterion group, axis label and whether x is on a log scale.
const CURVES: [(&str, &str, bool); 5] = [
    ("plan_vs_horizon", "horizon T (steps)", false),
    ("plan_vs_sensors", "sensors", true),
    ("plan_vs_targets", "reported targets", true),
    ("plan_vs_history", "history (steps)", false),
    ("precompute_vs_cells", "lattice cells", true),
];

/// (x, median, lower, upper) in seconds, sorted by x.
fn read(dir: &Path) -> Result<Vec<(f64, f64, f64, f64)>, String> {
    let mut points = Vec::new();
    let entries = std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    for entry in entries.flatten() {
        let Ok(x) = entry.file_name().to_string_lossy().parse::<f64>() else {
            continue;
        };
        let path = entry.path().join("new/estimates.json");
        let text =
            std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
        let m = &v["median"];
        let get =
            |p: &serde_json::Value| p.as_f64().ok_or(format!("{}: no median", path.display()));
        points.push((
            x,
            get(&m["point_estimate"])? * 1e-9,
            get(&m["confidence_interval"]["lower_bound"])? * 1e-9,
            get(&m["confidence_interval"]["upper_bound"])? * 1e-9,
        ));
    }
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(points)
}

/// Least-squares slope of log(y) against log(x), over x > 0.
fn exponent(points: &[(f64, f64, f64, f64)]) -> Option<f64> {
    let xy: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.0 > 0.0)
        .map(|p| (p.0.ln(), p.1.ln()))
        .collect();
    if xy.len() < 2 {
        return None;
    }
    let n = xy.len() as f64;
    let (mx, my) = (
        xy.iter().map(|p| p.0).sum::<f64>() / n,
        xy.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx).powi(2)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

fn human(s: f64) -> String {
    if s >= 1.0 {
        format!("{s:.2} s")
    } else if s >= 1e-3 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{:.0} µs", s * 1e6)
    }
}

/// A log-y line chart with error bars, as plain SVG.
fn svg(title: &str, xlabel: &str, log_x: bool, points: &[(f64, f64, f64, f64)]) -> String {
    let (w, h, left, right, top, bottom) = (640.0, 400.0, 80.0, 20.0, 40.0, 60.0);
    let fx = |x: f64| if log_x { x.max(0.5).log10() } else { x };
    let (x0, x1) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
            (a.0.min(fx(p.0)), a.1.max(fx(p.0)))
        });
    let (x0, x1) = if x1 > x0 {
        (x0, x1)
    } else {
        (x0 - 1.0, x0 + 1.0)
    };
    let lo = points
        .iter()
        .map(|p| p.2)
        .fold(f64::INFINITY, f64::min)
        .log10()
        .floor();
    let hi = points
        .iter()
        .map(|p| p.3)
        .fold(0.0, f64::max)
        .log10()
        .ceil()
        .max(lo + 1.0);
    let px = |x: f64| left + (fx(x) - x0) / (x1 - x0) * (w - left - right);
    let py = |y: f64| top + (hi - y.log10()) / (hi - lo) * (h - top - bottom);
    let mut out = String::new();
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(out, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    let _ = writeln!(
        out,
        r#"<text x="{}" y="22" text-anchor="middle" font-size="15">{title}</text>"#,
        w / 2.0
    );
    // Decades on y.
    let mut e = lo;
    while e <= hi {
        let y = top + (hi - e) / (hi - lo) * (h - top - bottom);
        let _ = writeln!(
            out,
            r##"<line x1="{left}" x2="{}" y1="{y}" y2="{y}" stroke="#ddd"/><text x="{}" y="{}" text-anchor="end">{}</text>"##,
            w - right,
            left - 6.0,
            y + 4.0,
            human(10f64.powf(e))
        );
        e += 1.0;
    }
    for p in points {
        let x = px(p.0);
        let label = if p.0 >= 1e6 {
            format!("{}M", p.0 / 1e6)
        } else if p.0 >= 1e3 {
            format!("{}k", p.0 / 1e3)
        } else {
            format!("{}", p.0)
        };
        let _ = writeln!(
            out,
            r##"<line x1="{x}" x2="{x}" y1="{top}" y2="{}" stroke="#eee"/><text x="{x}" y="{}" text-anchor="middle">{label}</text>"##,
            h - bottom,
            h - bottom + 16.0
        );
        let _ = writeln!(
            out,
            r##"<line x1="{x}" x2="{x}" y1="{}" y2="{}" stroke="#1f77b4"/>"##,
            py(p.2),
            py(p.3)
        );
    }
    let path: Vec<String> = points
        .iter()
        .map(|p| format!("{:.1},{:.1}", px(p.0), py(p.1)))
        .collect();
    let _ = writeln!(
        out,
        r##"<polyline points="{}" fill="none" stroke="#1f77b4" stroke-width="2"/>"##,
        path.join(" ")
    );
    for p in points {
        let _ = writeln!(
            out,
            r##"<circle cx="{:.1}" cy="{:.1}" r="3.5" fill="#1f77b4"/>"##,
            px(p.0),
            py(p.1)
        );
    }
    let _ = writeln!(
        out,
        r##"<line x1="{left}" x2="{left}" y1="{top}" y2="{}" stroke="black"/><line x1="{left}" x2="{}" y1="{}" y2="{}" stroke="black"/>"##,
        h - bottom,
        w - right,
        h - bottom,
        h - bottom
    );
    let _ = writeln!(
        out,
        r#"<text x="{}" y="{}" text-anchor="middle">{xlabel}{}</text>"#,
        (left + w - right) / 2.0,
        h - 18.0,
        if log_x { " (log scale)" } else { "" }
    );
    let _ = writeln!(
        out,
        r#"<text x="18" y="{}" text-anchor="middle" transform="rotate(-90 18 {})">median time (log scale)</text>"#,
        h / 2.0,
        h / 2.0
    );
    out.push_str("</svg>\n");
    out
}

fn main() -> Result<(), String> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let criterion = std::env::var_os("CARGO_TARGET_DIR")
        .map_or(root.join("target"), PathBuf::from)
        .join("criterion");
    for (group, xlabel, log_x) in CURVES {
        let points = read(&criterion.join(group))?;
        if points.is_empty() {
            return Err(format!(
                "no measurements for {group}: run the cost bench first"
            ));
        }
        let k = exponent(&points);
        let title = format!(
            "{group}: time ∝ x^{}",
            k.map_or("?".into(), |k| format!("{k:.2}"))
        );
        let file = root.join(format!("docs/cost-{}.svg", group.replace('_', "-")));
        std::fs::write(&file, svg(&title, xlabel, log_x, &points))
            .map_err(|e| format!("{}: {e}", file.display()))?;
        println!(
            "\n{group} (fitted exponent {}), {}:",
            k.map_or("n/a".into(), |k| format!("{k:.2}")),
            file.display()
        );
        println!("| {xlabel} | median | 95% CI |\n|---:|---:|---:|");
        for p in &points {
            println!(
                "| {} | {} | {} – {} |",
                p.0,
                human(p.1),
                human(p.2),
                human(p.3)
            );
        }
    }
    Ok(())
}
