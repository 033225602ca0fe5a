//! A picture of one run, like the paper's Figure 3: the zone over a heat map
//! of `d_hat`, the sources, every sensor's trace and final position with its
//! field of view, and the targets at the last step.

use plotters::prelude::*;
use vigil::stats::Stats;

use crate::driver::Sim;

/// Draws the run into an SVG file.
pub fn draw(sim: &Sim, path: &std::path::Path) -> Result<(), String> {
    let s = &sim.scenario;
    let stats = Stats::compute(s);
    let scale = 800.0 / s.width.max(s.height);
    let (w, h) = (
        (s.width * scale) as u32 + 60,
        (s.height * scale) as u32 + 60,
    );
    let root = SVGBackend::new(path, (w, h)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    // Zone coordinates → pixels, y up, with a 30 px margin.
    let px = |x: f64, y: f64| -> (i32, i32) {
        (
            (30.0 + x * scale) as i32,
            (30.0 + (s.height - y) * scale) as i32,
        )
    };
    let err = |e: DrawingAreaErrorKind<_>| e.to_string();
    let top = stats.d_hat.iter().copied().fold(0.0, f64::max).max(1e-12);
    for i in 0..s.cell_count() {
        let c = s.cell_at(i);
        let v = stats.d_hat[i] / top;
        let shade = (255.0 * (1.0 - 0.6 * v)) as u8;
        let (x0, y0) = (c.col as f64 * s.cell_size, c.row as f64 * s.cell_size);
        let color = RGBColor(255, shade, shade);
        root.draw(&Rectangle::new(
            [px(x0, y0 + s.cell_size), px(x0 + s.cell_size, y0)],
            color.filled(),
        ))
        .map_err(err)?;
    }
    root.draw(&Rectangle::new(
        [px(0.0, s.height), px(s.width, 0.0)],
        BLACK.stroke_width(2),
    ))
    .map_err(err)?;
    for src in &s.sources {
        let (x, y) = px(src.pos.x, src.pos.y);
        root.draw(&Cross::new((x, y), 6, BLACK.stroke_width(2)))
            .map_err(err)?;
    }
    for t in sim.world.in_zone(s) {
        root.draw(&Circle::new(px(t.pos.x, t.pos.y), 3, BLACK.filled()))
            .map_err(err)?;
    }
    for (i, trace) in sim.trace.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let points: Vec<(i32, i32)> = trace
            .iter()
            .map(|&c| {
                let p = s.centre(c);
                px(p.x, p.y)
            })
            .collect();
        root.draw(&PathElement::new(points, color.stroke_width(2)))
            .map_err(err)?;
        if let Some(&last) = trace.last() {
            let r = s.fov_region(last).rect;
            root.draw(&Rectangle::new(
                [px(r.x0, r.y1), px(r.x1, r.y0)],
                color.stroke_width(1),
            ))
            .map_err(err)?;
            let p = s.centre(last);
            root.draw(&Circle::new(px(p.x, p.y), 7, color.filled()))
                .map_err(err)?;
        }
    }
    root.present().map_err(|e| e.to_string())
}
