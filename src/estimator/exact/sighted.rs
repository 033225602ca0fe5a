//! Values in a scenario with obstacles: every integral of the exact
//! estimator restricted to what each look sees and to the targets whose
//! flight no building has ended.
//!
//! A look at cell `k` counts, on each ray of each class crossing `F_k`, the
//! part of the ray inside `F_k`, before the ray's stop (where a building
//! ends the flights along it) and visible from `k` ([`Sight::visible`]);
//! on that part a target is still unseen with probability
//! `(1 − d(r))·(1 − q(r))`: `d` the detection profile of the seen set
//! (which holds only what each past look saw), `q` that of the excluded
//! looks' visible pieces. So
//! `U(k,t) = Σ_c w_c Σ_rays [∫ (1 − d) − ∫ q (1 − d)]` over those parts:
//! the first integral by the seen set's prefix sums
//! ([`RayHits::detected_upto`](super::seen::RayHits::detected_upto), a
//! binary search), the second over the few pieces where excluded looks
//! hold the ray. The same interval arithmetic and midpoint rule as without
//! obstacles, evaluated per cell.
//!
//! A look that sees its whole square (elevated, or a ground look no
//! obstacle meets), against excluded looks that see theirs, takes the
//! windows instead: its square is then a union of elementary rectangles,
//! each holding its unseen mass (the grid's stationary mass is measured
//! on the same rays, up to their stops, and the seen pieces are clipped
//! there too), so its value is a block sum, the same to rounding. Blocked
//! sight lines cut rectangles, so every other look stays per cell.

use super::ExactEstimator;
use super::windows::BlockSums;
use crate::estimator::elementary::ElementaryGrid;
use crate::geometry::{Point, detection_pieces};
use crate::limits::MAX_SPEED_CLASSES;
use crate::obstacle::Sight;
use crate::scenario::{Cell, Look};
use crate::search::ValueGrid;

/// A look that excludes part of the targets, with what it cannot see.
type Excluded<'a> = (&'a Look, Option<Sight>);

/// The windows' prefix sums over a block, masked by the excluded looks
/// that see their whole squares: the unseen mass of every field of view
/// in the block that sees its whole square and meets no other excluded
/// look.
type Windowed<'a> = Option<(&'a ElementaryGrid, BlockSums)>;

/// The excluded looks of `near` that see their whole squares.
fn whole_squares(near: &[Excluded<'_>]) -> Vec<Look> {
    near.iter()
        .filter(|(_, v)| v.is_none())
        .map(|(x, _)| **x)
        .collect()
}

/// Scratch space of one value, kept across the cells of a fill.
#[derive(Default)]
struct Scratch {
    buf: Vec<Point>,
    parts: Vec<(f64, f64)>,
    cut: Vec<(f64, f64)>,
    pieces: Vec<(f64, f64, f64)>,
    segments: Vec<(f64, f64, f64)>,
    events: Vec<(f64, f64, bool)>,
}

impl ExactEstimator<'_> {
    /// True when the `i`-th reported target still flies at step `t`: its
    /// straight path from now has not entered a building.
    #[inline]
    fn known_alive(&self, i: usize, t: usize) -> bool {
        let (speed, stop) = self.flights[i];
        stop > speed * t as f64
    }

    /// The looks of `excluded` that may meet `region`'s, each with what it
    /// cannot see.
    fn excluded_sights<'x>(
        &self,
        excluded: &'x [Look],
        region: &crate::geometry::Region,
    ) -> Vec<Excluded<'x>> {
        excluded
            .iter()
            .filter(|x| x.region.may_overlap(region))
            .map(|x| (x, self.scenario.sight(x)))
            .collect()
    }

    /// The value of `sensor` at `k` at step `t` against `excluded`, with
    /// obstacles: `p_detect ×` (the reported targets it sees, each weighed
    /// by the chance that every excluded look that sees it misses it, plus
    /// the unseen targets in the part of `F_k` it sees).
    pub(super) fn value_sighted(&self, sensor: usize, k: Cell, t: usize, excluded: &[Look]) -> f64 {
        let fk = self.scenario.fov_region_of(self.types[sensor], k);
        let near = self.excluded_sights(excluded, &fk);
        let refs: Vec<&Excluded<'_>> = near.iter().collect();
        let windowed = self.block(sensor, k, t).and_then(|win| {
            let grid = self.grid?;
            let block = grid.span(self.scenario.types[self.types[sensor]].fov_slot, k);
            Some((grid, win.block_sums(grid, block, &whole_squares(&near))))
        });
        self.sighted_at(sensor, k, t, &refs, &windowed, &mut Scratch::default())
    }

    /// [`Estimator::fill`](crate::estimator::Estimator::fill) with
    /// obstacles: the excluded looks' sights once for the whole reach.
    pub(super) fn fill_sighted(
        &self,
        sensor: usize,
        start: Cell,
        t: usize,
        excluded: &[Look],
        out: &mut ValueGrid,
    ) {
        let s = self.scenario;
        let ty = self.types[sensor];
        // Every look that may meet a field of view of the reach.
        let reach = crate::geometry::Region {
            rect: self.reach(sensor, start, t),
            disk: None,
        };
        let near = self.excluded_sights(excluded, &reach);
        let windowed = self
            .window_of(sensor, t)
            .filter(|_| self.starts.get(sensor) == Some(&start))
            .map(|(grid, win)| {
                let block = self.reach_block(grid, sensor, start, t);
                (grid, win.block_sums(grid, block, &whole_squares(&near)))
            });
        let mut scratch = Scratch::default();
        let mut refs = Vec::with_capacity(near.len());
        out.fill_step(t, |dc, dr| {
            let k = Cell {
                col: start.col + dc,
                row: start.row + dr,
            };
            if !s.on_lattice(k) {
                return None;
            }
            let fk = s.fov_region_of(ty, k);
            refs.clear();
            refs.extend(near.iter().filter(|(x, _)| x.region.may_overlap(&fk)));
            Some(self.sighted_at(sensor, k, t, &refs, &windowed, &mut scratch))
        });
    }

    /// The value of `sensor` at `k` at step `t` against the excluded looks
    /// `near` (those that may meet its field of view), by the windows when
    /// `windowed` holds `k`'s block and the looks see whole squares.
    fn sighted_at(
        &self,
        sensor: usize,
        k: Cell,
        t: usize,
        near: &[&Excluded<'_>],
        windowed: &Windowed<'_>,
        scratch: &mut Scratch,
    ) -> f64 {
        let s = self.scenario;
        let ty = &s.types[self.types[sensor]];
        let look = s.look(self.types[sensor], k);
        let fk = look.region;
        let sight = s.sight(&look);
        let sees = |sight: &Option<Sight>, p: Point| sight.as_ref().is_none_or(|v| v.sees(p));
        let known: f64 = self
            .known
            .iter()
            .enumerate()
            .map(|(i, tg)| (i, tg.at(t)))
            .filter(|&(i, p)| fk.contains(p) && self.known_alive(i, t) && sees(&sight, p))
            .map(|(_, p)| p)
            .map(|p| {
                near.iter()
                    .filter(|(x, v)| x.region.contains(p) && sees(v, p))
                    .map(|(x, _)| x.miss())
                    .product::<f64>()
            })
            .sum();
        let unseen = match windowed {
            Some((grid, sums)) if sight.is_none() && near.iter().all(|(_, v)| v.is_none()) => {
                sums.sum(grid.span(ty.fov_slot, k))
            }
            _ => self.unseen_sighted(&look, sight.as_ref(), t, near, scratch),
        };
        ty.p_detect * (known + unseen)
    }

    /// `U` of `look` at step `t` (see the module docs).
    fn unseen_sighted(
        &self,
        look: &Look,
        sight: Option<&Sight>,
        t: usize,
        excluded: &[&Excluded<'_>],
        scratch: &mut Scratch,
    ) -> f64 {
        let fk = &look.region;
        let Scratch {
            buf,
            parts,
            cut,
            pieces,
            segments,
            events,
        } = scratch;
        let mut unseen = 0.0;
        // The classes of a source are consecutive and share its rays.
        let mut first = 0;
        while first < self.classes.len() {
            let ri = self.classes[first].rays;
            let last = first
                + self.classes[first..]
                    .iter()
                    .take_while(|c| c.rays == ri)
                    .count();
            let classes = first..last;
            first = last;
            let sr = &self.rays[ri];
            let o = sr.source.pos;
            let Some((a, b)) = sr.range(fk, buf) else {
                continue;
            };
            // A source has at most MAX_SPEED_CLASSES classes.
            let mut sums = [0.0; MAX_SPEED_CLASSES];
            for m in a..b {
                let (d, inv) = sr.dirs[m];
                let Some((lo, hi)) = fk.ray(o, d, inv) else {
                    continue;
                };
                let hi = hi.min(sr.stop(m));
                if hi <= lo {
                    continue;
                }
                parts.clear();
                match sight {
                    Some(v) => v.visible(o, d, lo, hi, parts),
                    None => parts.push((lo, hi)),
                }
                if parts.is_empty() {
                    continue;
                }
                // Where the excluded looks hold this ray, cut into pieces
                // of one detection probability each.
                pieces.clear();
                for (x, v) in excluded {
                    let Some((p, q)) = x.region.ray(o, d, inv) else {
                        continue;
                    };
                    let (p, q) = (p.max(lo), q.min(hi));
                    if q <= p {
                        continue;
                    }
                    match v {
                        Some(v) => {
                            cut.clear();
                            v.visible(o, d, p, q, cut);
                            pieces.extend(cut.iter().map(|&(p, q)| (p, q, x.p_detect)));
                        }
                        None => pieces.push((p, q, x.p_detect)),
                    }
                }
                segments.clear();
                if !pieces.is_empty() {
                    detection_pieces(pieces, lo, hi, events, |u, v, q| segments.push((u, v, q)));
                }
                for (slot, c) in classes.clone().enumerate() {
                    let (class, hits) = (&self.classes[c], &self.seen[c]);
                    let lift = class.speed * t as f64;
                    let seen = |u: f64, v: f64| {
                        hits.detected_upto(m, v - lift) - hits.detected_upto(m, u - lift)
                    };
                    let mut sum = 0.0;
                    for &(p, q) in parts.iter() {
                        sum += (q - p) - seen(p, q);
                        for &(u, v, qx) in segments.iter() {
                            let (u, v) = (u.max(p), v.min(q));
                            if v > u {
                                sum -= qx * ((v - u) - seen(u, v));
                            }
                        }
                    }
                    sums[slot] += sum;
                }
            }
            for (slot, c) in classes.enumerate() {
                unseen += self.classes[c].weight * sums[slot];
            }
        }
        unseen
    }
}
