//! The cost model of plans that maximise first detections
//! ([`super::plan_ms`] with `"objective": "first_detections"`): their
//! searches, not the fill and programme of [`super::PLAN_MODEL`], are the
//! work.

use super::reach::{
    half, iterated_rounds, near_by_step, obstructed_share, rays_per_look, repair_passes,
    source_rays,
};
use crate::coordination::{Coordination, first_search_budget};
use crate::planner::{PlanInput, Planner};
use crate::scenario::Scenario;

/// The most of a search's work that a long certain history saves: the
/// stops leave out the pieces it detected for certain
/// ([`crate::estimator::FirstDetections`]), and on the reference workload
/// the plans took 0.58 of their time at 16 steps of history, 0.56 at 32.
const HISTORY_SAVES: f64 = 0.44;

/// Steps of certain history over which that saving builds up,
/// `1 − e^{−H/HISTORY_STEPS}` of it at `H` steps (measured: 0.86, 0.76,
/// 0.66 of the time at 1, 4 and 8 steps).
const HISTORY_STEPS: f64 = 6.0;

/// The share of a first-detections search's work left by `input`'s
/// history: [`HISTORY_SAVES`] built up over its steps, in proportion to
/// its looks that detect for certain (an uncertain look leaves every piece
/// in). A whole observed zone is counted as its looks only: a low share
/// would err the unsafe way.
fn kept_share(s: &Scenario, input: &PlanInput) -> f64 {
    let looks = input.history.iter().map(Vec::len).sum::<usize>();
    if looks == 0 {
        return 1.0;
    }
    let certain = (input.history.iter().flatten())
        .filter(|&&(_, ty)| s.types[ty].p_detect >= 1.0)
        .count();
    let steps = input.history.len() as f64;
    let built = 1.0 - (-steps / HISTORY_STEPS).exp();
    1.0 - HISTORY_SAVES * built * certain as f64 / looks as f64
}

/// The first-detections plan model ([`plan_ms`](super::plan_ms) of a
/// plan with `"objective": "first_detections"`): each term's name and
/// coefficient, milliseconds per unit, in the order of [`FirstTerms`]. The
/// estimator's coefficient is held at 1 ([`PLAN_MODEL`](super::PLAN_MODEL)
/// predicts that work; it is a few percent of these plans, and a free fit
/// gives it 0); the others are fitted like `PLAN_MODEL`'s, on
/// first-detections plans alone (`--only first`).
pub const FIRST_MODEL: [(&str, f64); 5] = [
    ("estimator (PLAN_MODEL's seen and windows)", 1.0),
    ("searches: backgrounds, n × T × rays per look", 8.983e-6),
    ("searches: pair gains × t × rays per look", 1.991e-6),
    (
        "searches: paths within the budget × T × rays per look",
        1.661e-7,
    ),
    (
        "searches: reach cells near obstacles × rays per look",
        3.575e-5,
    ),
];

/// The units of work of one first-detections plan, one per term of
/// [`FIRST_MODEL`] (same order). Per sensor, `k` searches (alone, ranked,
/// the certificate's, and `iterated`'s rounds, counted as for the paper
/// estimator in [`PLAN_MODEL`](super::PLAN_MODEL)). Each search reads the
/// sensor's stops (every reachable cell at every step, a piece per ray its
/// look meets, less the share a certain history leaves out, `kept_share`)
/// against a background of the other sensors' looks, computes the gains
/// of pairs of consecutive stops (a pair into step `t` meets `t` stops'
/// pieces) and at most its budget of gains past them
/// ([`first_search_budget`]); a ground look near an obstacle is cut into
/// its visible parts.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FirstTerms {
    /// The [`PLAN_MODEL`](super::PLAN_MODEL) prediction of the estimator
    /// the plan builds ([`ESTIMATOR_TERMS`](super::ESTIMATOR_TERMS))
    /// (`FIRST_MODEL[0]`).
    pub estimator: f64,
    /// searches: backgrounds, n × T × rays per look (`FIRST_MODEL[1]`).
    pub backgrounds: f64,
    /// searches: pair gains × t × rays per look (`FIRST_MODEL[2]`).
    pub pairs: f64,
    /// searches: paths within the budget × T × rays per look
    /// (`FIRST_MODEL[3]`).
    pub paths: f64,
    /// searches: reach cells near obstacles × rays per look
    /// (`FIRST_MODEL[4]`).
    pub sighted: f64,
}

impl FirstTerms {
    /// The terms in the order of [`FIRST_MODEL`].
    pub fn to_array(&self) -> [f64; 5] {
        [
            self.estimator,
            self.backgrounds,
            self.pairs,
            self.paths,
            self.sighted,
        ]
    }
}

/// The terms of [`FIRST_MODEL`] for `input` on `planner`, `estimator`
/// being the [`PLAN_MODEL`](super::PLAN_MODEL) prediction of its first
/// [`ESTIMATOR_TERMS`](super::ESTIMATOR_TERMS).
pub fn first_terms(planner: &Planner, input: &PlanInput, estimator: f64) -> FirstTerms {
    let s = &planner.scenario;
    let (n, big_t) = (input.starts.len(), input.horizon);
    // Pieces a search walks per look: the rays it meets, less those the
    // history detected for certain.
    let per_look = rays_per_look(s, input, &source_rays(s)) * kept_share(s, input);
    let certificate = if input.certify { 1.0 } else { 0.0 };
    let searches = certificate
        + repair_passes(s, input)
        + match input.coordination {
            Coordination::None => 1.0,
            Coordination::Priority => 2.0,
            Coordination::Iterated | Coordination::Joint => {
                2.0 + iterated_rounds(&near_by_step(s, input), n, false)
            }
        };
    let budget = first_search_budget(big_t) as f64;
    let mut t = FirstTerms {
        estimator,
        backgrounds: searches * (n * n.saturating_sub(1) * big_t) as f64 * per_look,
        ..FirstTerms::default()
    };
    for (&start, &ty) in input.starts.iter().zip(&input.types) {
        let ty = &s.types[ty];
        let successors = ((2 * ty.speed + 1) as f64).powi(2);
        let reach = |step: usize| {
            let (lo, hi) = s.reach_corners(start, (ty.speed * step) as i32);
            (
                lo,
                hi,
                f64::from((hi.col - lo.col + 1) * (hi.row - lo.row + 1)),
            )
        };
        let paths = successors.powi(big_t as i32).min(budget);
        t.paths += searches * paths * big_t as f64 * per_look;
        for step in 1..=big_t {
            let (_, _, before) = reach(step - 1);
            let (lo, hi, cells) = reach(step);
            t.pairs += searches * before * successors * step as f64 * per_look;
            if !ty.elevated && !s.obstacles.list().is_empty() {
                t.sighted +=
                    searches * cells * obstructed_share(s, lo, hi, half(ty.fov)) * per_look;
            }
        }
    }
    t
}
