//! Values in a scenario with obstacles: every integral of the exact
//! estimator restricted to what each look sees and to the targets whose
//! flight no building has ended.
//!
//! A look at cell `k` counts, on each ray of each class crossing `F_k`, the
//! part of the ray inside `F_k`, before the ray's stop (where a building
//! ends the flights along it) and visible from `k` ([`Sight::visible`]);
//! on that part a target is still unseen with probability `Π (1 − p)` over
//! the seen pieces (which hold only what each past look saw) and the
//! excluded looks' visible pieces. So `U(k,t) = Σ_c w_c Σ_rays ∫ (1 − D)`
//! over those parts, `D` the detection profile of [`detection_within`]:
//! the same interval arithmetic and midpoint rule as without obstacles,
//! evaluated per cell (the elementary grid's block sums assume fields of
//! view that are unions of rectangles, which blocked sight lines break).

use super::ExactEstimator;
use crate::estimator::Target;
use crate::geometry::{Point, detection_within};
use crate::obstacle::Sight;
use crate::scenario::{Cell, Look};

impl ExactEstimator<'_> {
    /// True when the reported target `tg` still flies at step `t`: its
    /// straight path from now has not entered a building.
    fn known_alive(&self, tg: &Target, t: usize) -> bool {
        let obstacles = &self.scenario.obstacles;
        let speed = tg.vel.x.hypot(tg.vel.y);
        if speed == 0.0 {
            return !obstacles.inside_building(tg.pos);
        }
        let d = Point::new(tg.vel.x / speed, tg.vel.y / speed);
        obstacles.stop(tg.pos, d) > speed * t as f64
    }

    /// The value of `sensor` at `k` at step `t` against `excluded`, with
    /// obstacles: `p_detect ×` (the reported targets it sees, each weighed
    /// by the chance that every excluded look that sees it misses it, plus
    /// the unseen targets in the part of `F_k` it sees).
    pub(super) fn value_sighted(&self, sensor: usize, k: Cell, t: usize, excluded: &[Look]) -> f64 {
        let s = self.scenario;
        let ty = &s.types[self.types[sensor]];
        let look = s.look(self.types[sensor], k);
        let fk = look.region;
        let sight = s.sight(&look);
        let near: Vec<(&Look, Option<Sight>)> = excluded
            .iter()
            .filter(|x| x.region.may_overlap(&fk))
            .map(|x| (x, s.sight(x)))
            .collect();
        let sees = |sight: &Option<Sight>, p: Point| sight.as_ref().is_none_or(|v| v.sees(p));
        let known: f64 = self
            .known
            .iter()
            .filter(|tg| self.known_alive(tg, t))
            .map(|tg| tg.at(t))
            .filter(|&p| fk.contains(p) && sees(&sight, p))
            .map(|p| {
                near.iter()
                    .filter(|(x, v)| x.region.contains(p) && sees(v, p))
                    .map(|(x, _)| x.miss())
                    .product::<f64>()
            })
            .sum();
        ty.p_detect * (known + self.unseen_sighted(&look, sight.as_ref(), t, &near))
    }

    /// `U` of `look` at step `t` (see the module docs).
    fn unseen_sighted(
        &self,
        look: &Look,
        sight: Option<&Sight>,
        t: usize,
        excluded: &[(&Look, Option<Sight>)],
    ) -> f64 {
        let fk = &look.region;
        let mut buf = Vec::new();
        let mut parts: Vec<(f64, f64)> = Vec::new();
        let mut cut: Vec<(f64, f64)> = Vec::new();
        let mut pieces: Vec<(f64, f64, f64)> = Vec::new();
        let mut events = Vec::new();
        let mut unseen = 0.0;
        for (class, hits) in self.classes.iter().zip(&self.seen) {
            let sr = &self.rays[class.rays];
            let o = sr.source.pos;
            let lift = class.speed * t as f64;
            let Some((a, b)) = sr.range(fk, &mut buf) else {
                continue;
            };
            let mut sum = 0.0;
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
                    Some(v) => v.visible(o, d, lo, hi, &mut parts),
                    None => parts.push((lo, hi)),
                }
                if parts.is_empty() {
                    continue;
                }
                // What was seen (pushed to step t) and what the excluded
                // looks see on this ray.
                pieces.clear();
                let (iv, detected) = (hits.of(m), hits.detected(m));
                for (i, &(p, q)) in iv.iter().enumerate() {
                    if q + lift > lo && p + lift < hi {
                        let pd = detected.get(i).copied().unwrap_or(1.0);
                        pieces.push((p + lift, q + lift, pd));
                    }
                }
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
                            v.visible(o, d, p, q, &mut cut);
                            pieces.extend(cut.iter().map(|&(p, q)| (p, q, x.p_detect)));
                        }
                        None => pieces.push((p, q, x.p_detect)),
                    }
                }
                for &(p, q) in &parts {
                    sum += q - p;
                    if !pieces.is_empty() {
                        sum -= detection_within(&pieces, p, q, &mut events);
                    }
                }
            }
            unseen += class.weight * sum;
        }
        unseen
    }
}
