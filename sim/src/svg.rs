//! A picture of one run, like the paper's Figure 3: the zone over a heat map
//! of `d_hat`, the no-go zones (grey, hatched), the buildings (dark) and
//! screens (green), the sources, every sensor's trace and final position
//! with its own type's field of view (one marker per type: a disk for
//! `default`, then a square, a triangle, …, named in a legend; with
//! obstacles, the part of it the sensor sees, shaded), and the targets at
//! the last step.

use plotters::prelude::*;
use vigil::obstacle::ObstacleKind;
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
    let grey = RGBColor(150, 150, 150);
    for r in s.spec.no_go.iter().flatten() {
        let (x0, x1) = (r.x0.clamp(0.0, s.width), r.x1.clamp(0.0, s.width));
        let (y0, y1) = (r.y0.clamp(0.0, s.height), r.y1.clamp(0.0, s.height));
        if x1 <= x0 || y1 <= y0 {
            continue;
        }
        root.draw(&Rectangle::new(
            [px(x0, y1), px(x1, y0)],
            RGBColor(215, 215, 215).filled(),
        ))
        .map_err(err)?;
        // Hatching at 45°, every 8 px.
        let (a, b) = (px(x0, y1), px(x1, y0));
        let mut k = 0;
        while k < (b.0 - a.0) + (b.1 - a.1) {
            let start = (a.0 + k.min(b.0 - a.0), a.1 + (k - (b.0 - a.0)).max(0));
            let end = (a.0 + (k - (b.1 - a.1)).max(0), a.1 + k.min(b.1 - a.1));
            root.draw(&PathElement::new(vec![start, end], grey.stroke_width(1)))
                .map_err(err)?;
            k += 8;
        }
        root.draw(&Rectangle::new([a, b], grey.stroke_width(1)))
            .map_err(err)?;
    }
    for ob in s.obstacles.list() {
        let points: Vec<(i32, i32)> = ob.polygon.vertices().iter().map(|v| px(v.x, v.y)).collect();
        let fill = match ob.kind {
            ObstacleKind::Building => RGBColor(90, 90, 100).filled(),
            ObstacleKind::Screen => RGBColor(120, 180, 110).mix(0.7).filled(),
        };
        root.draw(&Polygon::new(points, fill)).map_err(err)?;
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
            let ty = sim.types[i];
            let look = s.look(ty, last);
            if look.from.is_some() {
                // What the sensor sees of its field of view, shaded.
                let seen: Vec<(i32, i32)> = s
                    .view_outline(&look, 180)
                    .iter()
                    .map(|q| px(q.x, q.y))
                    .collect();
                root.draw(&Polygon::new(seen, color.mix(0.25).filled()))
                    .map_err(err)?;
            }
            let region = look.region;
            match region.disk {
                Some(d) => root.draw(&Circle::new(
                    px(d.c.x, d.c.y),
                    (d.r * scale) as i32,
                    color.stroke_width(1),
                )),
                None => root.draw(&Rectangle::new(
                    [
                        px(region.rect.x0, region.rect.y1),
                        px(region.rect.x1, region.rect.y0),
                    ],
                    color.stroke_width(1),
                )),
            }
            .map_err(err)?;
            let p = s.centre(last);
            marker(&root, ty, px(p.x, p.y), color.filled()).map_err(err)?;
        }
    }
    // A legend of the types in the run.
    let mut used: Vec<usize> = sim.types.clone();
    used.sort_unstable();
    used.dedup();
    if used != [0] {
        for (k, &ty) in used.iter().enumerate() {
            let at = (40 + 200 * k as i32, 14);
            marker(&root, ty, at, BLACK.filled()).map_err(err)?;
            let t = &s.types[ty];
            root.draw(&Text::new(
                format!("{} (speed {}, p {})", t.name, t.speed, t.p_detect),
                (at.0 + 10, at.1 - 6),
                ("sans-serif", 12),
            ))
            .map_err(err)?;
        }
    }
    root.present().map_err(|e| e.to_string())
}

/// The marker of sensor type `ty` at pixel `at`: a disk, a square, a
/// triangle, then a cross.
fn marker<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    ty: usize,
    at: (i32, i32),
    style: ShapeStyle,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (x, y) = at;
    match ty % 4 {
        0 => root.draw(&Circle::new(at, 7, style)),
        1 => root.draw(&Rectangle::new([(x - 6, y - 6), (x + 6, y + 6)], style)),
        2 => root.draw(&Polygon::new(
            vec![(x, y - 8), (x - 7, y + 6), (x + 7, y + 6)],
            style,
        )),
        _ => root.draw(&Cross::new(at, 7, style.stroke_width(3))),
    }
}
