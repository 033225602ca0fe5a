//! Exposure: how many of a source's targets a window of looks detects at
//! least once, per unit of its rate.
//!
//! A target of source `j`, class `c` (speed `v_c`), takeoff angle `α` and
//! emission time `τ` is at distance `v_c·(t − τ)` from its source at step
//! `t`. A look at step `t` whose field of view (the part it sees, before
//! the ray's stop at a building) holds the ray's distances `[a, b]` so
//! detects, with its `p_detect`, the emission times `[t − b/v_c, t − a/v_c]`.
//! The chance that the window detects the target is `1 − Π (1 − p)` over
//! the looks that hold its emission time, so the exposure is
//! `E_j = Σ_c share_c ∫ dα/spread_j ∫ (1 − Π (1 − p)) dτ`, steps of
//! emission per unit rate: the window detects `λ_j·E_j` of the source's
//! targets on average. Every emission time counts, so targets already in
//! the zone at the window's first step are included.
//!
//! `τ` is integrated exactly (a sweep over interval ends); `α` by the
//! midpoint rule over the source's cone, on the rays per π of the
//! scenario's exact estimator (its error is in `docs/learning.md`).

use rayon::prelude::*;

use crate::geometry::{Point, detection_within};
use crate::obstacle::Sight;
use crate::scenario::{Look, Scenario};

/// The looks of a window, oldest step first, with each look's sight (what
/// its obstacles hide) computed once.
pub struct WindowLooks<'a> {
    s: &'a Scenario,
    /// Rays per π of the angular grid.
    rays_per_pi: usize,
    /// `(step, look, sight)`, in step order.
    looks: Vec<(usize, Look, Option<Sight>)>,
}

impl<'a> WindowLooks<'a> {
    /// The looks of `steps` (step `i` at time `i`), integrated over the
    /// rays per π of the scenario's exact estimator
    /// ([`Scenario::rays_per_pi`]).
    pub fn new(s: &'a Scenario, steps: &[Vec<Look>]) -> Self {
        Self::with_rays_per_pi(s, steps, s.rays_per_pi())
    }

    /// The same over `rays_per_pi` rays per π.
    pub fn with_rays_per_pi(s: &'a Scenario, steps: &[Vec<Look>], rays_per_pi: usize) -> Self {
        let looks = steps
            .iter()
            .enumerate()
            .flat_map(|(t, looks)| looks.iter().map(move |l| (t, *l)))
            .map(|(t, l)| (t, l, s.sight(&l)))
            .collect();
        WindowLooks {
            s,
            rays_per_pi,
            looks,
        }
    }

    /// The number of (look, ray, class) triples the exposure walks: its
    /// cost.
    pub fn work(&self) -> usize {
        (0..self.s.sources.len())
            .map(|j| {
                let grid = RayGrid::of(self.s, j, self.rays_per_pi);
                let per_ray = self.s.classes_of(j).len();
                self.looks
                    .iter()
                    .map(|(_, l, _)| {
                        let (lo, hi) = grid.span(self.s, j, l);
                        hi.saturating_sub(lo) * per_ray
                    })
                    .sum::<usize>()
            })
            .sum()
    }

    /// `E_j` for every source, counting only the targets that a look at a
    /// step `≥ fresh_from` detects and no earlier look of the window does
    /// (`fresh_from = 0`: every target the window detects). Targets can be
    /// counted step by step this way: the exposure of steps `0..=t` is the
    /// sum over `t' ≤ t` of the exposure of the window ending at `t'` with
    /// `fresh_from = t'`, and a window only needs the steps in which a
    /// target seen at its last step can have been in the zone.
    pub fn exposure(&self, fresh_from: usize) -> Vec<f64> {
        (0..self.s.sources.len())
            .map(|j| self.exposure_of(j, fresh_from))
            .collect()
    }

    fn exposure_of(&self, j: usize, fresh_from: usize) -> f64 {
        let s = self.s;
        let src = &s.sources[j];
        let classes = s.classes_of(j);
        let grid = RayGrid::of(s, j, self.rays_per_pi);
        // Looks bucketed by the rays that may cross them (compressed rows).
        let mut spans: Vec<(usize, usize)> = self
            .looks
            .iter()
            .map(|(_, l, _)| grid.span(s, j, l))
            .collect();
        if fresh_from > 0 {
            // Only the rays that a fresh look may cross can hold a target
            // it detects: the older looks matter on those rays only.
            let (lo, hi) = self
                .looks
                .iter()
                .zip(&spans)
                .filter(|((t, _, _), _)| *t >= fresh_from)
                .fold((usize::MAX, 0), |(lo, hi), (_, &(a, b))| {
                    if b > a {
                        (lo.min(a), hi.max(b))
                    } else {
                        (lo, hi)
                    }
                });
            for span in &mut spans {
                *span = (span.0.max(lo), span.1.min(hi));
            }
        }
        let mut starts = vec![0usize; grid.n + 1];
        for &(lo, hi) in &spans {
            for i in lo..hi {
                starts[i + 1] += 1;
            }
        }
        for i in 0..grid.n {
            starts[i + 1] += starts[i];
        }
        let mut fill = starts.clone();
        let mut bucket = vec![0u32; starts[grid.n]];
        for (li, &(lo, hi)) in spans.iter().enumerate() {
            for i in lo..hi {
                bucket[fill[i]] = li as u32;
                fill[i] += 1;
            }
        }
        // Summed in ray order, so that a fit is the same to the bit on any
        // number of threads (a registered fit's id depends on it).
        let per_ray: Vec<f64> = (0..grid.n)
            .into_par_iter()
            .map_init(RayScratch::default, |sc, i| {
                let looks = &bucket[starts[i]..starts[i + 1]];
                if !looks
                    .iter()
                    .any(|&li| self.looks[li as usize].0 >= fresh_from)
                {
                    return 0.0;
                }
                let d = src.direction(grid.angle(i));
                let inv = Point::new(1.0 / d.x, 1.0 / d.y);
                let stop = s.obstacles.stop(src.pos, d);
                sc.pieces.clear();
                for &li in looks {
                    let (t, look, sight) = &self.looks[li as usize];
                    let Some((a, b)) = look.region.ray(src.pos, d, inv) else {
                        continue;
                    };
                    let b = b.min(stop);
                    if b <= a {
                        continue;
                    }
                    let first = sc.parts.len();
                    match sight {
                        Some(sight) => sight.visible(src.pos, d, a, b, &mut sc.parts),
                        None => sc.parts.push((a, b)),
                    }
                    for &(a, b) in &sc.parts[first..] {
                        sc.pieces.push((*t, a, b, look.p_detect));
                    }
                    sc.parts.truncate(first);
                }
                classes
                    .iter()
                    .map(|c| {
                        let v = c.speed;
                        let times = |&(t, a, b, p): &(usize, f64, f64, f64)| {
                            (t as f64 - b / v, t as f64 - a / v, p)
                        };
                        let (inf, sc) = (f64::INFINITY, &mut *sc);
                        if fresh_from == 0 {
                            sc.times.clear();
                            sc.times.extend(sc.pieces.iter().map(times));
                            return c.share
                                * detection_within(&sc.times, -inf, inf, &mut sc.events);
                        }
                        // Only the fresh looks' emission times can hold a
                        // target they detect: the older pieces matter
                        // there only, and elsewhere both sums agree.
                        let (lo, hi) = sc
                            .pieces
                            .iter()
                            .filter(|p| p.0 >= fresh_from)
                            .map(times)
                            .fold((inf, -inf), |(lo, hi), (a, b, _)| (lo.min(a), hi.max(b)));
                        sc.times.clear();
                        sc.times.extend(
                            sc.pieces
                                .iter()
                                .filter(|p| p.0 < fresh_from)
                                .map(times)
                                .filter(|&(a, b, _)| b > lo && a < hi),
                        );
                        let old = detection_within(&sc.times, lo, hi, &mut sc.events);
                        sc.times
                            .extend(sc.pieces.iter().filter(|p| p.0 >= fresh_from).map(times));
                        let all = detection_within(&sc.times, lo, hi, &mut sc.events);
                        c.share * (all - old).max(0.0)
                    })
                    .sum::<f64>()
            })
            .collect();
        per_ray.iter().sum::<f64>() * grid.h / src.spread
    }
}

#[derive(Default)]
struct RayScratch {
    parts: Vec<(f64, f64)>,
    pieces: Vec<(usize, f64, f64, f64)>,
    times: Vec<(f64, f64, f64)>,
    events: Vec<(f64, f64, bool)>,
}

/// The midpoint grid of takeoff angles over a source's cone.
struct RayGrid {
    /// Number of rays.
    n: usize,
    /// Angle between rays.
    h: f64,
    /// The cone's first angle.
    lo: f64,
}

impl RayGrid {
    fn of(s: &Scenario, j: usize, rays_per_pi: usize) -> Self {
        let src = &s.sources[j];
        let n = ((src.spread / std::f64::consts::PI * rays_per_pi as f64).ceil() as usize).max(1);
        RayGrid {
            n,
            h: src.spread / n as f64,
            lo: src.cone.0,
        }
    }

    fn angle(&self, i: usize) -> f64 {
        self.lo + (i as f64 + 0.5) * self.h
    }

    /// The rays `lo..hi` whose angles lie within the directions of the
    /// look's bounding square (a superset of those that cross it).
    fn span(&self, s: &Scenario, j: usize, look: &Look) -> (usize, usize) {
        let src = &s.sources[j];
        let r = &look.region.rect;
        let (mut a, mut b) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in [(r.x0, r.y0), (r.x1, r.y0), (r.x0, r.y1), (r.x1, r.y1)] {
            let angle = src.angle_to(Point::new(p.0, p.1));
            a = a.min(angle);
            b = b.max(angle);
        }
        // Ray i has angle lo + (i + ½)h.
        let first = ((a - self.lo) / self.h - 0.5).ceil().max(0.0);
        let last = ((b - self.lo) / self.h - 0.5).floor();
        if last < first || first >= self.n as f64 {
            return (0, 0);
        }
        (first as usize, (last as usize + 1).min(self.n))
    }
}
