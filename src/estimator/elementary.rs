//! The elementary-rectangle grid of a scenario with square fields of view.
//!
//! Every clipped square field of view at a cell centre has its edges in
//! `{centre ± half_width} ∪ {0, W}` (and likewise in y). Those values cut the
//! zone into elementary rectangles such that every `F_k`, every observed
//! field of view and every excluded one is an exact union of them. Sums over
//! a field of view then become sums over a block of rectangles, and with
//! prefix sums, four lookups.
//!
//! The stationary mass of a block (`∫ ρ`, summed over sources) comes from the
//! closed-form antiderivative of `1/r`, tabulated at the grid's corners once
//! per scenario.

use rayon::prelude::*;

use crate::codec::{CodecError, Reader, Writer, expect_len};
use crate::geometry::{Point, Rect, wedge_inv_r_integral};
use crate::scenario::{Cell, FovSpec, Heading, Scenario, Source};

/// Elementary rectangles a grid may always have, whatever the lattice
/// (a 32 MB prefix table). The cost model predicts with it.
pub const MAX_SMALL_GRID: usize = 1 << 22;

/// The grid, its prefix table of stationary mass, and each cell's block.
#[derive(Debug, Clone)]
pub struct ElementaryGrid {
    /// Breakpoints in x, ascending, from 0 to W.
    pub xs: Vec<f64>,
    /// Breakpoints in y, ascending, from 0 to H.
    pub ys: Vec<f64>,
    /// Per field of view (the scenario's `fovs`) and column, the half-open
    /// range of x-intervals `F_k` covers.
    col_span: Vec<Vec<(usize, usize)>>,
    /// The same per row, in y.
    row_span: Vec<Vec<(usize, usize)>>,
    /// `prefix[b·nx + a]`: stationary targets in `[0, xs[a]] × [0, ys[b]]`.
    prefix: Vec<f64>,
    /// Lookup tables that find a coordinate's interval in O(1) on average:
    /// bucket `i` of width `1/scale` holds the interval at its lower end.
    x_buckets: Vec<u32>,
    x_scale: f64,
    y_buckets: Vec<u32>,
    y_scale: f64,
}

/// Buckets over `[0, extent]`, two per interval on average.
fn buckets(bp: &[f64]) -> (Vec<u32>, f64) {
    let n = 2 * (bp.len() - 1);
    let extent = bp[bp.len() - 1];
    let scale = n as f64 / extent;
    let mut j = 0;
    let table = (0..=n)
        .map(|i| {
            let x = i as f64 / scale;
            while j + 2 < bp.len() && bp[j + 1] <= x {
                j += 1;
            }
            j as u32
        })
        .collect();
    (table, scale)
}

#[inline]
fn locate(bp: &[f64], table: &[u32], scale: f64, x: f64, dir: f64) -> usize {
    let n = bp.len() - 1;
    let slot = ((x * scale).max(0.0) as usize).min(table.len() - 1);
    let mut i = table[slot] as usize;
    while i + 1 < n && bp[i + 1] <= x {
        i += 1;
    }
    while i > 0 && bp[i] > x {
        i -= 1;
    }
    if dir < 0.0 && i > 0 && bp[i] == x {
        i - 1
    } else {
        i
    }
}

/// Antiderivative of `1/√(x²+y²)` valid on `x ≥ 0`, any `y`:
/// `∂²G/∂x∂y = 1/r` with `G = x·asinh(y/x) + y·ln(x + r)`.
fn g_half_plane(x: f64, y: f64) -> f64 {
    let r = x.hypot(y);
    let a = if x > 0.0 { x * (y / x).asinh() } else { 0.0 };
    let b = if r > 0.0 && y != 0.0 {
        y * (x + r).ln()
    } else {
        0.0
    };
    a + b
}

fn breakpoints(centres: impl Iterator<Item = f64>, halves: &[f64], extent: f64) -> Vec<f64> {
    let mut v: Vec<f64> = centres
        .flat_map(|c| {
            halves
                .iter()
                .flat_map(move |&h| [(c - h).max(0.0), (c + h).min(extent)])
        })
        .chain([0.0, extent])
        .collect();
    v.sort_by(f64::total_cmp);
    let tol = 1e-9 * extent;
    v.dedup_by(|a, b| (*a - *b).abs() <= tol);
    v
}

fn nearest(xs: &[f64], x: f64) -> usize {
    let i = xs.partition_point(|&v| v < x);
    if i == 0 {
        0
    } else if i == xs.len() || (x - xs[i - 1]) <= (xs[i] - x) {
        i - 1
    } else {
        i
    }
}

/// `prefix[b·nx + a]`: the stationary targets in `[0, xs[a]] × [0, ys[b]]`,
/// summed over the target classes. A source whose cone holds the whole zone
/// uses the antiderivative of `1/r` in an axis-aligned frame that holds the
/// zone in its half-plane `x' ≥ 0` (a quarter turn flips orientation); one
/// whose cone cuts the zone integrates each prefix rectangle over the cone
/// ([`wedge_inv_r_integral`]).
fn stationary_prefix(s: &Scenario, xs: &[f64], ys: &[f64]) -> Vec<f64> {
    let (nx, ny) = (xs.len(), ys.len());
    struct Frame {
        x: f64,
        y: f64,
        ux: f64,
        uy: f64,
        /// `Σ_c λ_c/(spread·v_c)`, signed by orientation for the G path.
        c: f64,
        source: Source,
    }
    let frames: Vec<Frame> = s
        .sources
        .iter()
        .enumerate()
        .filter(|(_, src)| src.rate > 0.0)
        .map(|(j, src)| {
            let u = src.half_plane.unit();
            let sign = match src.half_plane {
                Heading::East | Heading::West => 1.0,
                Heading::North | Heading::South => -1.0,
            };
            let c = s
                .classes_of(j)
                .iter()
                .map(|class| sign * class.rate / (src.spread * class.speed))
                .sum::<f64>();
            Frame {
                x: src.pos.x,
                y: src.pos.y,
                ux: u.x,
                uy: u.y,
                c: if src.covers_zone { c } else { sign * c },
                source: *src,
            }
        })
        .collect();
    let g = |f: &Frame, x: f64, y: f64| {
        let (dx, dy) = (x - f.x, y - f.y);
        g_half_plane(dx * f.ux + dy * f.uy, -dx * f.uy + dy * f.ux)
    };
    let (x0, y0) = (xs[0], ys[0]);
    let bottom: Vec<Vec<f64>> = frames
        .iter()
        .map(|f| xs.iter().map(|&x| g(f, x, y0)).collect())
        .collect();
    (0..ny)
        .into_par_iter()
        .flat_map_iter(|b| {
            let y = ys[b];
            let left: Vec<f64> = frames.iter().map(|f| g(f, x0, y)).collect();
            let (frames, bottom) = (&frames, &bottom);
            (0..nx).map(move |a| {
                frames
                    .iter()
                    .enumerate()
                    .map(|(j, f)| {
                        if f.source.covers_zone {
                            f.c * (g(f, xs[a], y) - left[j] - bottom[j][a] + bottom[j][0])
                        } else {
                            let rect = Rect {
                                x0,
                                y0,
                                x1: xs[a],
                                y1: y,
                            };
                            let src = &f.source;
                            f.c * wedge_inv_r_integral(
                                src.pos, &rect, src.frame, src.cone.0, src.cone.1,
                            )
                        }
                    })
                    .sum::<f64>()
            })
        })
        .collect()
}

impl ElementaryGrid {
    /// Writes this grid ([`crate::codec`]).
    pub fn encode(&self, w: &mut Writer) {
        w.f64s(&self.xs);
        w.f64s(&self.ys);
        for spans in [&self.col_span, &self.row_span] {
            w.len(spans.len());
            for per_fov in spans {
                let flat: Vec<usize> = per_fov.iter().flat_map(|&(a, b)| [a, b]).collect();
                w.usizes(&flat);
            }
        }
        w.f64s(&self.prefix);
        w.u32s(&self.x_buckets);
        w.f64(self.x_scale);
        w.u32s(&self.y_buckets);
        w.f64(self.y_scale);
    }

    /// Reads a grid [`ElementaryGrid::encode`] wrote for scenario `s`.
    ///
    /// # Errors
    /// A [`CodecError`] for bytes that are not such a grid.
    pub fn decode(r: &mut Reader, s: &Scenario) -> Result<Self, CodecError> {
        let xs = r.f64s()?;
        let ys = r.f64s()?;
        let mut spans = [Vec::new(), Vec::new()];
        for ((axis, lines), breaks) in spans
            .iter_mut()
            .zip([s.cols as usize, s.rows as usize])
            .zip([xs.len(), ys.len()])
        {
            let n = r.len()?;
            expect_len("grid spans", n, s.fovs.len())?;
            for _ in 0..n {
                let flat = r.usizes()?;
                expect_len("grid span", flat.len(), 2 * lines)?;
                if flat.iter().any(|&i| i >= breaks) {
                    return Err(CodecError("a grid span out of range".into()));
                }
                axis.push(flat.chunks_exact(2).map(|p| (p[0], p[1])).collect());
            }
        }
        let [col_span, row_span] = spans;
        let grid = ElementaryGrid {
            prefix: r.f64s()?,
            x_buckets: r.u32s()?,
            x_scale: r.f64()?,
            y_buckets: r.u32s()?,
            y_scale: r.f64()?,
            xs,
            ys,
            col_span,
            row_span,
        };
        if grid.xs.len() < 2 || grid.ys.len() < 2 {
            return Err(CodecError("a grid without intervals".into()));
        }
        expect_len(
            "grid prefix",
            grid.prefix.len(),
            grid.xs.len() * grid.ys.len(),
        )?;
        let in_range = |b: &[u32], n: usize| b.iter().all(|&i| (i as usize) + 1 < n);
        if !in_range(&grid.x_buckets, grid.xs.len()) || !in_range(&grid.y_buckets, grid.ys.len()) {
            return Err(CodecError("grid buckets out of range".into()));
        }
        Ok(grid)
    }

    /// The grid of a scenario whose sensor types all have square fields of
    /// view (the breakpoints of every size), with the closed-form
    /// stationary mass; `None` when one is a circle, or when several sizes
    /// on a large lattice would make it larger than one size can (then
    /// every value takes the general path), and with obstacles, whose
    /// buildings end flights where no closed form follows them (see
    /// [`ElementaryGrid::with_mass`]).
    pub fn new(s: &Scenario) -> Option<Self> {
        if s.has_obstacles() {
            return None;
        }
        let mut grid = Self::layout(s)?;
        grid.prefix = stationary_prefix(s, &grid.xs, &grid.ys);
        Some(grid)
    }

    /// The grid of a scenario as [`ElementaryGrid::new`] lays it out, with
    /// the stationary mass of each rectangle that `mass` gives (row by
    /// row, `b·nx + a`, from the laid-out grid): for scenarios whose mass
    /// the rays measure (obstacles).
    pub fn with_mass(s: &Scenario, mass: impl FnOnce(&Self) -> Vec<f64>) -> Option<Self> {
        let mut grid = Self::layout(s)?;
        let (nx, ny) = grid.dims();
        let per_rect = mass(&grid);
        assert_eq!(per_rect.len(), nx * ny, "one mass per rectangle");
        let mut prefix = vec![0.0; (nx + 1) * (ny + 1)];
        for b in 0..ny {
            let mut row = 0.0;
            for a in 0..nx {
                row += per_rect[b * nx + a];
                prefix[(b + 1) * (nx + 1) + a + 1] = prefix[b * (nx + 1) + a + 1] + row;
            }
        }
        grid.prefix = prefix;
        Some(grid)
    }

    /// The breakpoints, spans and lookup tables of the grid, without its
    /// stationary mass (`prefix` empty).
    fn layout(s: &Scenario) -> Option<Self> {
        let halves = s
            .fovs
            .iter()
            .map(|f| match *f {
                FovSpec::Square { half_width } => Some(half_width),
                FovSpec::Circle { .. } => None,
            })
            .collect::<Option<Vec<f64>>>()?;
        let xc = |c: i32| (c as f64 + 0.5) * s.cell_size;
        let xs = breakpoints((0..s.cols).map(xc), &halves, s.width);
        let ys = breakpoints((0..s.rows).map(xc), &halves, s.height);
        // Several square sizes multiply the breakpoints. Past what one size
        // can give on this lattice (or a small table), the grid's memory
        // would grow with the number of sizes: such scenarios take the
        // general path instead.
        let one_size = (2 * s.cols as usize + 1) * (2 * s.rows as usize + 1);
        if (xs.len() - 1) * (ys.len() - 1) > one_size.max(MAX_SMALL_GRID) {
            return None;
        }
        let span = |bp: &[f64], n: i32, extent: f64, h: f64| -> Vec<(usize, usize)> {
            (0..n)
                .map(|c| {
                    (
                        nearest(bp, (xc(c) - h).max(0.0)),
                        nearest(bp, (xc(c) + h).min(extent)),
                    )
                })
                .collect()
        };
        let col_span = halves
            .iter()
            .map(|&h| span(&xs, s.cols, s.width, h))
            .collect();
        let row_span = halves
            .iter()
            .map(|&h| span(&ys, s.rows, s.height, h))
            .collect();
        let (x_buckets, x_scale) = buckets(&xs);
        let (y_buckets, y_scale) = buckets(&ys);
        Some(ElementaryGrid {
            xs,
            ys,
            col_span,
            row_span,
            prefix: Vec::new(),
            x_buckets,
            x_scale,
            y_buckets,
            y_scale,
        })
    }

    /// Approximate heap memory held, bytes.
    pub fn memory_bytes(&self) -> usize {
        8 * (self.xs.len() + self.ys.len() + self.prefix.len())
            + 16 * self
                .col_span
                .iter()
                .chain(&self.row_span)
                .map(Vec::len)
                .sum::<usize>()
            + 4 * (self.x_buckets.len() + self.y_buckets.len())
    }

    /// Number of elementary intervals in x and in y.
    pub fn dims(&self) -> (usize, usize) {
        (self.xs.len() - 1, self.ys.len() - 1)
    }

    /// The smallest block `[a0, a1) × [b0, b1)` of rectangles that covers
    /// the part of `r` inside the grid (at least one rectangle).
    pub fn covering(&self, r: &Rect) -> (usize, usize, usize, usize) {
        let span = |edges: &[f64], lo: f64, hi: f64| {
            let n = edges.len() - 1;
            let a0 = edges
                .partition_point(|&e| e <= lo)
                .saturating_sub(1)
                .min(n - 1);
            let a1 = edges.partition_point(|&e| e < hi).clamp(a0 + 1, n);
            (a0, a1)
        };
        let (a0, a1) = span(&self.xs, r.x0, r.x1);
        let (b0, b1) = span(&self.ys, r.y0, r.y1);
        (a0, a1, b0, b1)
    }

    /// The block `[a0, a1) × [b0, b1)` of rectangles that makes up `F_k`
    /// for the field of view `fov_slot` (an index into the scenario's
    /// `fovs`; 0 is the type `default`'s).
    #[inline]
    pub fn span(&self, fov_slot: usize, k: Cell) -> (usize, usize, usize, usize) {
        let (a0, a1) = self.col_span[fov_slot][k.col as usize];
        let (b0, b1) = self.row_span[fov_slot][k.row as usize];
        (a0, a1, b0, b1)
    }

    /// Stationary expected targets in the block `[a0, a1) × [b0, b1)`.
    #[inline]
    pub fn mass(&self, a0: usize, a1: usize, b0: usize, b1: usize) -> f64 {
        let nx = self.xs.len();
        let p = |a: usize, b: usize| self.prefix[b * nx + a];
        p(a1, b1) - p(a0, b1) - p(a1, b0) + p(a0, b0)
    }

    /// Index of the x-interval holding `x`, moving in direction `dir` (on a
    /// breakpoint, the interval the motion enters).
    #[inline]
    pub(crate) fn locate_x(&self, x: f64, dir: f64) -> usize {
        locate(&self.xs, &self.x_buckets, self.x_scale, x, dir)
    }

    /// As [`ElementaryGrid::locate_x`], in y.
    #[inline]
    pub(crate) fn locate_y(&self, y: f64, dir: f64) -> usize {
        locate(&self.ys, &self.y_buckets, self.y_scale, y, dir)
    }
}

/// A half-open block `[a0, a1) × [b0, b1)` of elementary rectangles.
pub(crate) type Block = (usize, usize, usize, usize);

/// The part `[from, to]` (distances from `origin`) of the ray from
/// `origin` along the unit direction `dir`; `inv` is `dir`'s componentwise
/// inverse, computed once per ray.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Segment {
    pub origin: Point,
    pub dir: Point,
    pub inv: Point,
    pub from: f64,
    pub to: f64,
}

/// Calls `f(a, b, from, to)` for each elementary rectangle `(a, b)` of
/// `block` the ray segment crosses, in order, with the part of the segment
/// inside it: a 2-D DDA over the breakpoints. The segment lies inside the
/// block; rounding at its edge is clamped.
pub(crate) fn trace(
    grid: &ElementaryGrid,
    block: Block,
    segment: Segment,
    mut f: impl FnMut(usize, usize, f64, f64),
) {
    let Segment {
        origin: o,
        dir: d,
        inv,
        from: r0,
        to: r1,
    } = segment;
    let (xs, ys) = (&grid.xs, &grid.ys);
    let (a_lo, a_hi, b_lo, b_hi) = (block.0, block.1 - 1, block.2, block.3 - 1);
    let start = Point::new(o.x + d.x * r0, o.y + d.y * r0);
    let mut a = grid.locate_x(start.x, d.x).clamp(a_lo, a_hi);
    let mut b = grid.locate_y(start.y, d.y).clamp(b_lo, b_hi);
    // Distance to the next boundary on each axis (infinite along an axis
    // the ray runs parallel to).
    let forward_x = d.x >= 0.0;
    let forward_y = d.y >= 0.0;
    let next_x = |a: usize| {
        if d.x == 0.0 {
            f64::INFINITY
        } else {
            (xs[if forward_x { a + 1 } else { a }] - o.x) * inv.x
        }
    };
    let next_y = |b: usize| {
        if d.y == 0.0 {
            f64::INFINITY
        } else {
            (ys[if forward_y { b + 1 } else { b }] - o.y) * inv.y
        }
    };
    let (mut tx, mut ty) = (next_x(a), next_y(b));
    let mut r = r0;
    loop {
        let step_x = tx <= ty;
        let boundary = if step_x { tx } else { ty };
        let end = if boundary < r1 { boundary } else { r1 };
        if end > r {
            f(a, b, r, end);
            r = end;
        }
        if boundary >= r1 {
            break;
        }
        if step_x {
            if (forward_x && a == a_hi) || (!forward_x && a == a_lo) {
                break;
            }
            if forward_x {
                a += 1;
            } else {
                a -= 1;
            }
            tx = next_x(a);
        } else {
            if (forward_y && b == b_hi) || (!forward_y && b == b_lo) {
                break;
            }
            if forward_y {
                b += 1;
            } else {
                b -= 1;
            }
            ty = next_y(b);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::inv_r_integral;
    use crate::scenario::{Scenario, SourceSpec, builtins, paper_spec};
    use crate::stats::Stats;

    #[test]
    fn several_square_sizes_share_one_grid_within_a_bound() {
        use crate::scenario::SensorTypeSpec;
        let with_sizes = |cells: f64, sizes: &[f64]| {
            let mut spec = paper_spec(10.0);
            spec.cell_size = 300.0 / cells;
            spec.sensor_types = Some(
                sizes
                    .iter()
                    .enumerate()
                    .map(|(i, &h)| {
                        (
                            format!("t{i}"),
                            SensorTypeSpec {
                                fov: FovSpec::Square { half_width: h },
                                speed: None,
                                p_detect: None,
                                elevated: None,
                            },
                        )
                    })
                    .collect(),
            );
            Scenario::new(spec).expect("valid")
        };
        // Small lattice: one grid holds every size's edges, and each size's
        // blocks are its cells' fields of view.
        let s = with_sizes(30.0, &[17.3, 41.9]);
        let g = ElementaryGrid::new(&s).expect("a grid");
        for slot in 0..s.fovs.len() {
            let c = Cell { col: 12, row: 7 };
            let (a0, a1, b0, b1) = g.span(slot, c);
            let r = s.fov_with(s.fovs[slot], s.centre(c)).rect;
            assert!((g.xs[a0] - r.x0).abs() < 1e-9 && (g.xs[a1] - r.x1).abs() < 1e-9);
            assert!((g.ys[b0] - r.y0).abs() < 1e-9 && (g.ys[b1] - r.y1).abs() < 1e-9);
        }
        // A large lattice with many sizes off the cell grid would need far
        // more rectangles than one size: no grid (the general path).
        let s = with_sizes(1000.0, &[3.3, 5.7, 7.1, 9.9, 11.3]);
        assert!(ElementaryGrid::new(&s).is_none());
    }

    #[test]
    fn block_masses_are_the_cells_d_hat() {
        let mut spec = paper_spec(10.0);
        // Off-grid half width, so the x breakpoints interleave.
        spec.fov = FovSpec::Square { half_width: 23.0 };
        spec.sources.push(SourceSpec {
            x: -7.0,
            y: -9.0,
            rate: 0.4,
            heading: Some(Heading::North),
            ..SourceSpec::default()
        });
        spec.sources.push(SourceSpec {
            x: 340.0,
            y: 310.0,
            rate: 0.2,
            heading: Some(Heading::West),
            ..SourceSpec::default()
        });
        for s in [
            Scenario::new(spec).expect("valid"),
            builtins().remove(1),
            builtins().remove(2),
        ] {
            let grid = ElementaryGrid::new(&s).expect("square");
            let stats = Stats::compute(&s);
            for i in 0..s.cell_count() {
                let (a0, a1, b0, b1) = grid.span(0, s.cell_at(i));
                let m = grid.mass(a0, a1, b0, b1);
                assert!(
                    (m - stats.d_hat[i]).abs() < 1e-9 * stats.d_hat[i].max(1.0),
                    "cell {i}: {m} vs {}",
                    stats.d_hat[i]
                );
            }
            // The whole zone.
            let (nx, ny) = grid.dims();
            let zone = grid.mass(0, nx, 0, ny);
            assert!((zone - stats.expected_targets_in_zone).abs() < 1e-9 * zone);
        }
    }

    #[test]
    fn locate_finds_the_interval_entered() {
        let mut spec = paper_spec(10.0);
        spec.fov = FovSpec::Square { half_width: 23.0 };
        let s = Scenario::new(spec).expect("valid");
        let g = ElementaryGrid::new(&s).expect("square");
        for i in 0..3000 {
            let x = i as f64 * 0.1;
            let slow =
                g.xs.partition_point(|&v| v <= x)
                    .saturating_sub(1)
                    .min(g.xs.len() - 2);
            assert_eq!(g.locate_x(x, 1.0), slow, "x = {x}");
            let back = if slow > 0 && g.xs[slow] == x {
                slow - 1
            } else {
                slow
            };
            assert_eq!(g.locate_x(x, -1.0), back, "x = {x}");
        }
        assert_eq!(g.locate_y(300.0, 1.0), g.ys.len() - 2);
        assert_eq!(g.locate_y(-1e-12, 1.0), 0);
    }

    #[test]
    fn antiderivative_matches_the_quadrant_form() {
        for &(x0, x1, y0, y1) in &[
            (1.0, 3.0, -2.0, 5.0),
            (0.0, 4.0, -3.0, -0.5),
            (0.5, 60.0, 0.0, 60.0),
        ] {
            let g = g_half_plane;
            let v = g(x1, y1) - g(x0, y1) - g(x1, y0) + g(x0, y0);
            let e = inv_r_integral(x0, x1, y0, y1);
            assert!((v - e).abs() < 1e-10 * e, "{v} vs {e}");
        }
    }
}
