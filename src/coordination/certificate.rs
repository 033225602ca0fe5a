//! The certificate of a plan: an upper bound on the value of the best joint
//! plan, so that every exact plan says how far from the optimum it can be.
//!
//! For the exact estimator the objective `f(S)` of a set of sensor paths is
//! the expected number of (target, step) pairs that some path detects:
//! `Σ_t ∫ (1 − Π_{p ∈ S} (1 − p_detect·[x in p's look at t])) dμ_t(x)`
//! over the (nonnegative) measure of the targets expected at step `t`. A
//! coverage function of that kind is monotone (another path never loses a
//! detection) and submodular (a path adds less on top of more). For the
//! returned paths `S` and any joint plan `O = {o_1, …, o_n}`, one legal
//! path per sensor:
//!
//! `f(O) ≤ f(O ∪ S) ≤ f(S) + Σ_i [f(S ∪ {o_i}) − f(S)]
//!        ≤ f(S) + Σ_i max_p [f(S ∪ {p}) − f(S)]`,
//!
//! the first by monotonicity, the second by submodularity (adding the
//! `o_i` one by one, each adds at most what it adds to `S` alone), the
//! third as `o_i` is one of sensor `i`'s legal paths. `S ∪ {p}` adds `p` as
//! one more path on top of all of `S`, sensor `i`'s own path included.
//! Each max is one dynamic programme over the marginal values against every
//! path of `S` ([`marginal_bound`]). With `S` empty the same argument gives
//! the sum of every sensor's best path alone. A Lagrangian relaxation over
//! the pieces the estimator counts ([`Relaxation`]) spans both and goes
//! below them: its first weights give the solo sum, and each subgradient
//! step costs one search per sensor. [`Certifier`] keeps the smallest bound
//! computed: every exact plan takes the solo sum and one step of the
//! relaxation (or, where the estimator cannot list its pieces, the marginal
//! bound); `joint` takes more.
//!
//! Legal paths here follow the sensor's speed and the free cells, and
//! nothing else: the minimum separation is left out (a relaxation), so the
//! bound holds for plans that keep it too. The values are the estimator's
//! quadrature of the model, itself a coverage over a nonnegative measure,
//! so the inequalities hold for them up to floating-point rounding.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use super::fleet::{Fleet, SensorPlan, search};
use crate::cancel::Cancelled;
use crate::estimator::Elements;
use crate::geometry::Point;
use crate::scenario::Cell;
use crate::search::ValueGrid;

/// An upper bound on the best joint plan's value, beside a plan's value.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct Bound {
    /// No joint plan (one legal path per sensor, the minimum separation
    /// ignored) expects more detections over steps 1..=T than this.
    pub upper: f64,
    /// `(upper − value) / upper` for the plan's value (0 when `upper` is
    /// 0): the plan is within this fraction of the best joint plan.
    pub gap: f64,
}

impl Bound {
    /// The certificate of a plan of value `value` from the smallest of the
    /// valid bounds `uppers`. Rounding may put a bound a few ulps below a
    /// plan that meets it; the upper bound is then the plan's value.
    pub fn new(value: f64, uppers: impl IntoIterator<Item = f64>) -> Self {
        let upper = uppers.into_iter().fold(f64::INFINITY, f64::min).max(value);
        let gap = if upper > 0.0 {
            ((upper - value) / upper).max(0.0)
        } else {
            0.0
        };
        Bound { upper, gap }
    }
}

/// `f(S) + Σ_i max_p [f(S ∪ {p}) − f(S)]` for the paths `paths` (one per
/// sensor, in request order) of value `value` (`f(S)`): one search per
/// sensor against the looks of every path, its own included.
///
/// # Errors
/// [`Cancelled`] once the fleet's token is cancelled.
pub fn marginal_bound(fleet: &Fleet, paths: &[&[Cell]], value: f64) -> Result<f64, Cancelled> {
    let all: Vec<usize> = (0..fleet.len()).collect();
    let gains: Vec<f64> = (0..fleet.len())
        .into_par_iter()
        .with_min_len(crate::parallel::min_len())
        .map(|i| {
            fleet
                .best_against(i, &fleet.looks_by_step(paths, &all, i))
                .value
        })
        .collect();
    fleet.cancel.check()?;
    // In request order, so the sum has the same bits on any pool.
    Ok(value + gains.iter().sum::<f64>())
}

/// [`marginal_bound`] for first detections: each sensor's bounded search
/// against every path's looks at every step, its own included, gives an
/// upper bound on what one more path of it could add (see
/// [`Fleet::first_search`]); the same argument holds, the objective being
/// a coverage of the targets over the whole horizon.
///
/// The searches run in `order` (every sensor's index once), a batch at a
/// time, and stop once `value` and the gains so far reach `enough` (the
/// caller's other bound): every gain is at least 0, so this bound is then
/// at least `enough`, and the sum so far is returned. It is not a bound
/// itself then; only the smaller of it and `enough` is, which is
/// `enough`, as it would have been with every search made.
///
/// # Errors
/// [`Cancelled`] once the fleet's token is cancelled.
pub fn first_marginal_bound(
    fleet: &Fleet,
    paths: &[&[Cell]],
    value: f64,
    order: &[usize],
    enough: f64,
) -> Result<f64, Cancelled> {
    let all: Vec<usize> = (0..fleet.len()).collect();
    let mut gains = vec![0.0; fleet.len()];
    let mut so_far = value;
    for batch in order.chunks(crate::parallel::width()) {
        if so_far >= enough {
            return Ok(so_far);
        }
        let found: Vec<f64> = batch
            .par_iter()
            .with_min_len(crate::parallel::min_len())
            .map(|&i| fleet.first_search(i, paths, &all, Vec::new(), None).upper)
            .collect();
        fleet.cancel.check()?;
        for (&i, gain) in batch.iter().zip(found) {
            gains[i] = gain;
            so_far += gain;
        }
    }
    // Every search made: summed in request order, as before, so that a
    // bound that is the smaller stays the same to the bit.
    Ok(value + gains.iter().sum::<f64>())
}

/// A plan's certificate as it is worked out: the sum of the solo bests,
/// and then either the relaxation's steps (when the estimator lists its
/// pieces) or the marginal bound of each plan it is asked about.
pub struct Certifier<'f, 'a> {
    fleet: &'f Fleet<'a>,
    upper: f64,
    relaxation: Option<Relaxation<'f, 'a>>,
    /// The solo bests' paths, until the relaxation's first step.
    solo_paths: Vec<Vec<Cell>>,
}

impl<'f, 'a> Certifier<'f, 'a> {
    /// Starts from the solo bests (each sensor's best path alone, a search
    /// with no exclusion: `solo` its value and path, `grids` its values),
    /// their sum the first bound. It is also the relaxation's value at its
    /// first weights (`μ = w`), so its first step starts from them at no
    /// search's cost.
    pub fn new(fleet: &'f Fleet<'a>, solo: Vec<(f64, Vec<Cell>)>, grids: &'f [ValueGrid]) -> Self {
        let upper = solo.iter().map(|(v, _)| v).sum();
        let paths: Vec<Vec<Cell>> = solo.into_iter().map(|(_, p)| p).collect();
        let relaxation = Relaxation::new(fleet, grids).map(|mut r| {
            r.record(upper, paths.clone());
            r
        });
        Self {
            fleet,
            upper,
            relaxation,
            solo_paths: paths,
        }
    }

    /// One more search per sensor to tighten the bound, for the plan
    /// `paths` of value `value`: a step of the relaxation, or the marginal
    /// bound of `paths`. Returns the smallest bound so far.
    ///
    /// # Errors
    /// [`Cancelled`] once the fleet's token is cancelled.
    pub fn tighten(&mut self, paths: &[&[Cell]], value: f64) -> Result<f64, Cancelled> {
        let upper = match &mut self.relaxation {
            Some(r) => r.step(value)?,
            None => marginal_bound(self.fleet, paths, value)?,
        };
        self.upper = self.upper.min(upper);
        Ok(self.upper)
    }

    /// The smallest bound so far.
    pub fn upper(&self) -> f64 {
        self.upper
    }

    /// The paths that maximised the relaxation's last step (the solo bests
    /// before any): where its weights draw each sensor.
    pub fn drawn_paths(&self) -> &[Vec<Cell>] {
        self.relaxation
            .as_ref()
            .map_or(&self.solo_paths, |r| &r.paths)
    }
}

/// What the weights cut from the pieces' weights at one step.
struct Cut {
    /// Prefix sums of `w − μ` over the block's rectangles.
    prefix: Vec<f64>,
    /// The known targets whose weight is cut, and by how much.
    known: Vec<(Point, f64)>,
}

/// Subgradient steps without a smaller bound after which the step length
/// halves.
const STALL: usize = 3;

/// The Lagrangian bound of the linear programme over the estimator's
/// pieces ([`Elements`]), improved by subgradient steps.
///
/// For weights `μ_e ∈ [0, w_e]` on the pieces `e` (of weight `w_e`), any
/// joint plan `O` satisfies, piece by piece, `w_e·(1 − Π_i (1 − p_i·[e in
/// o_i])) ≤ w_e·min(1, Σ_i p_i·[e in o_i]) ≤ (w_e − μ_e) + μ_e·Σ_i p_i·[e
/// in o_i]`, so `f(O) ≤ U(μ) = Σ_e (w_e − μ_e) + Σ_i max_p Σ_t p_i·μ(F_{p_t})`:
/// one dynamic programme per sensor over the weights `μ`. `μ = w` is the
/// sum of the solo bests; the smallest `U(μ)` is the bound of the linear
/// programme that lets each sensor mix its paths. Each [`Relaxation::step`]
/// computes `U` at the current weights and moves them along a subgradient
/// (`∂U/∂μ_e = Σ_i p_i·[e in p_i*] − 1` for the maximising paths `p_i*`),
/// with Polyak's step towards a known plan value.
pub struct Relaxation<'f, 'a> {
    fleet: &'f Fleet<'a>,
    /// Each sensor's values with no exclusion: its values at `μ = w`.
    solo: &'f [ValueGrid],
    steps: Vec<Elements<'a>>,
    /// Per step, `μ_e / w_e` of each rectangle, then of each known target.
    ratio: Vec<Vec<f64>>,
    /// Per step, whether some sensor can hold each rectangle, and the known
    /// targets (their indices) some sensor can hold.
    active_rects: Vec<Vec<bool>>,
    active_known: Vec<Vec<usize>>,
    /// Step length multiplier in (0, 1].
    lambda: f64,
    /// The smallest `U` so far, and steps since it last fell.
    best: f64,
    stalled: usize,
    /// `U` at the current weights and its maximising paths, once known.
    upper: f64,
    paths: Vec<Vec<Cell>>,
}

impl<'f, 'a> Relaxation<'f, 'a> {
    /// Starts at `μ = w` (the solo bound), when the fleet's estimator lists
    /// its pieces at every step; `solo` holds each sensor's values with no
    /// exclusion (its grid of the search alone).
    pub fn new(fleet: &'f Fleet<'a>, solo: &'f [ValueGrid]) -> Option<Self> {
        let steps = (1..=fleet.horizon)
            .map(|t| fleet.est.elements(t))
            .collect::<Option<Vec<_>>>()?;
        let ratio = steps
            .iter()
            .map(|e| vec![1.0; e.mass.len() + e.known.len()])
            .collect();
        let s = fleet.scenario;
        // The pieces some sensor can hold at each step; the others keep
        // μ = w, which no path's value sees.
        let mut active_rects = Vec::with_capacity(steps.len());
        let mut active_known = Vec::with_capacity(steps.len());
        for (t0, el) in steps.iter().enumerate() {
            let t = t0 + 1;
            let mut mask = vec![false; el.mass.len()];
            for i in 0..fleet.len() {
                let ty = &s.types[fleet.types[i]];
                let (lo, hi) = s.reach_corners(fleet.starts[i], (ty.speed * t) as i32);
                let ((a0, _, b0, _), (_, a1, _, b1)) =
                    (el.block(ty.fov_slot, lo), el.block(ty.fov_slot, hi));
                for b in b0..b1 {
                    mask[b * el.na + a0..b * el.na + a1].fill(true);
                }
            }
            let reach: Vec<_> = (0..fleet.len())
                .map(|i| fleet.reach_box(i, t).rect)
                .collect();
            active_known.push(
                (0..el.known.len())
                    .filter(|&j| reach.iter().any(|r| r.contains(el.known[j])))
                    .collect(),
            );
            active_rects.push(mask);
        }
        Some(Self {
            fleet,
            solo,
            steps,
            ratio,
            active_rects,
            active_known,
            lambda: 1.0,
            best: f64::INFINITY,
            stalled: 0,
            upper: f64::INFINITY,
            paths: Vec::new(),
        })
    }

    /// One subgradient step from the last weights evaluated towards
    /// `lower` (a plan's value, at most the optimum), then `U` at the new
    /// weights (a valid bound), which it returns.
    ///
    /// # Errors
    /// [`Cancelled`] once the fleet's token is cancelled.
    pub fn step(&mut self, lower: f64) -> Result<f64, Cancelled> {
        if !self.paths.is_empty() {
            self.advance(lower);
        }
        let (upper, best) = self.evaluate()?;
        self.record(upper, best.into_iter().map(|p| p.path).collect());
        Ok(upper)
    }

    /// Takes `upper` as `U` at the current weights, with its maximising
    /// `paths`: Polyak's step length `λ` halves after `STALL` values in a
    /// row that found no smaller bound.
    pub fn record(&mut self, upper: f64, paths: Vec<Vec<Cell>>) {
        if upper < self.best {
            self.best = upper;
            self.stalled = 0;
        } else {
            self.stalled += 1;
            if self.stalled >= STALL {
                self.lambda /= 2.0;
                self.stalled = 0;
            }
        }
        self.upper = upper;
        self.paths = paths;
    }

    /// `U` at the current weights, and each sensor's maximising path.
    fn evaluate(&self) -> Result<(f64, Vec<SensorPlan>), Cancelled> {
        let fleet = self.fleet;
        let s = fleet.scenario;
        // A sensor's value for a cell is its solo value (at μ = w) less
        // what the weights cut: per step, prefix sums of (w − μ) over the
        // block's rectangles, and the known targets whose weight is cut.
        let cuts: Vec<Cut> = self
            .steps
            .iter()
            .zip(&self.ratio)
            .map(|(el, ratio)| {
                let w = el.na + 1;
                let mut p = vec![0.0; w * (el.nb + 1)];
                for b in 0..el.nb {
                    let mut row = 0.0;
                    for a in 0..el.na {
                        let e = b * el.na + a;
                        row += (1.0 - ratio[e]) * el.mass[e];
                        p[(b + 1) * w + a + 1] = p[b * w + a + 1] + row;
                    }
                }
                let known = el
                    .known
                    .iter()
                    .zip(&ratio[el.mass.len()..])
                    .filter(|&(_, &r)| r < 1.0)
                    .map(|(&q, &r)| (q, 1.0 - r))
                    .collect();
                Cut { prefix: p, known }
            })
            .collect();
        let best: Vec<SensorPlan> = (0..fleet.len())
            .into_par_iter()
            .with_min_len(crate::parallel::min_len())
            .map(|i| {
                let ty = &s.types[fleet.types[i]];
                let start = fleet.starts[i];
                let solo = &self.solo[i];
                let mut grid = fleet.motion(i);
                for t in 1..=fleet.horizon {
                    if fleet.cancel.is_cancelled() {
                        break;
                    }
                    let (el, Cut { prefix: p, known }) = (&self.steps[t - 1], &cuts[t - 1]);
                    let w = el.na + 1;
                    let reach = fleet.reach_box(i, t).rect;
                    let known: Vec<(Point, f64)> = known
                        .iter()
                        .filter(|(q, _)| reach.contains(*q))
                        .copied()
                        .collect();
                    grid.fill_step(t, |dc, dr| {
                        let v = solo.get(t, dc, dr)?;
                        let k = start.offset(dc, dr);
                        let (a0, a1, b0, b1) = el.block(ty.fov_slot, k);
                        let mut cut =
                            p[b1 * w + a1] - p[b0 * w + a1] - p[b1 * w + a0] + p[b0 * w + a0];
                        if !known.is_empty() {
                            let fk = s.fov_region_of(fleet.types[i], k);
                            cut += known
                                .iter()
                                .filter(|(q, _)| fk.contains(*q))
                                .map(|&(_, c)| c)
                                .sum::<f64>();
                        }
                        Some(v - ty.p_detect * cut)
                    });
                }
                search(grid, start)
            })
            .collect();
        fleet.cancel.check()?;
        let mut upper: f64 = best.iter().map(|p| p.value).sum();
        for (el, ratio) in self.steps.iter().zip(&self.ratio) {
            // Inactive pieces keep a ratio of 1.
            let pieces = el
                .mass
                .iter()
                .chain(std::iter::repeat_n(&1.0, el.known.len()));
            upper += pieces.zip(ratio).map(|(w, r)| (1.0 - r) * w).sum::<f64>();
        }
        Ok((upper, best))
    }

    /// Moves the weights one subgradient step from the last `U` recorded
    /// towards `lower`: Polyak's step `λ·(U − lower)/|g|²`.
    fn advance(&mut self, lower: f64) {
        let fleet = self.fleet;
        let s = fleet.scenario;
        let (upper, paths) = (self.upper, &self.paths);
        // Each piece's cover: Σ p_i over the paths whose look holds it, by
        // a 2-D difference array over the rectangles.
        let covers: Vec<Vec<f64>> = self
            .steps
            .iter()
            .enumerate()
            .map(|(t, el)| {
                let w = el.na + 1;
                let mut cover = vec![0.0; w * (el.nb + 1) + el.known.len()];
                let (rects, known) = cover.split_at_mut(w * (el.nb + 1));
                for (i, path) in paths.iter().enumerate() {
                    let ty = &s.types[fleet.types[i]];
                    let k = path[t];
                    let (a0, a1, b0, b1) = el.block(ty.fov_slot, k);
                    rects[b0 * w + a0] += ty.p_detect;
                    rects[b0 * w + a1] -= ty.p_detect;
                    rects[b1 * w + a0] -= ty.p_detect;
                    rects[b1 * w + a1] += ty.p_detect;
                    let fk = s.fov_region_of(fleet.types[i], k);
                    for (c, q) in known.iter_mut().zip(&el.known) {
                        if fk.contains(*q) {
                            *c += ty.p_detect;
                        }
                    }
                }
                for row in rects.chunks_exact_mut(w) {
                    let mut acc = 0.0;
                    for x in row {
                        acc += *x;
                        *x = acc;
                    }
                }
                for b in 1..=el.nb {
                    let (done, rest) = rects.split_at_mut(b * w);
                    for (x, above) in rest[..w].iter_mut().zip(&done[(b - 1) * w..]) {
                        *x += *above;
                    }
                }
                cover
            })
            .collect();
        // The subgradient in the ratios μ_e / w_e, `w_e·(cover_e − 1)` on
        // the active pieces (0 elsewhere): its norm, then the step.
        // Row by row: rectangle (a, b) is `b·na + a` in the weights and
        // `b·(na + 1) + a` in the covers.
        let rows = |t: usize| {
            let (el, na) = (&self.steps[t], self.steps[t].na);
            el.mass
                .chunks_exact(na)
                .zip(self.active_rects[t].chunks_exact(na))
                .zip(covers[t].chunks_exact(na + 1))
        };
        let mut norm = 0.0;
        for (t, el) in self.steps.iter().enumerate() {
            let (w, cover) = (el.na + 1, &covers[t]);
            for ((mass, mask), cover) in rows(t) {
                for ((&m, &on), &c) in mass.iter().zip(mask).zip(cover) {
                    if on {
                        norm += (m * (c - 1.0)).powi(2);
                    }
                }
            }
            let known = &cover[w * (el.nb + 1)..];
            norm += self.active_known[t]
                .iter()
                .map(|&j| (known[j] - 1.0).powi(2))
                .sum::<f64>();
        }
        if norm > 0.0 {
            let theta = self.lambda * (upper - lower).max(0.0) / norm;
            let mut ratios = std::mem::take(&mut self.ratio);
            for (t, el) in self.steps.iter().enumerate() {
                let (w, cover) = (el.na + 1, &covers[t]);
                let ratio = &mut ratios[t];
                let (rect_ratios, _) = ratio.split_at_mut(el.mass.len());
                for (((mass, mask), cover), ratio) in
                    rows(t).zip(rect_ratios.chunks_exact_mut(el.na))
                {
                    for (((&m, &on), &c), r) in mass.iter().zip(mask).zip(cover).zip(ratio) {
                        if on {
                            *r = (*r - theta * (m * (c - 1.0))).clamp(0.0, 1.0);
                        }
                    }
                }
                let known = &cover[w * (el.nb + 1)..];
                for &j in &self.active_known[t] {
                    let r = &mut ratio[el.mass.len() + j];
                    *r = (*r - theta * (known[j] - 1.0)).clamp(0.0, 1.0);
                }
            }
            self.ratio = ratios;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Bound;

    #[test]
    fn the_gap_is_the_fraction_of_the_smallest_bound_left_to_gain() {
        let b = Bound::new(9.0, [12.0, 10.0, f64::INFINITY]);
        assert_eq!(b.upper, 10.0);
        assert!((b.gap - 0.1).abs() < 1e-15);
        // A bound rounded below the plan's value is the value.
        let b = Bound::new(5.0, [5.0 - 1e-15]);
        assert_eq!((b.upper, b.gap), (5.0, 0.0));
        assert_eq!(Bound::new(0.0, [0.0]).gap, 0.0);
    }
}
