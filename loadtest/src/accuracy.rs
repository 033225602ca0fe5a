//! The exact estimator's error against a fine angular grid.
//!
//! The estimator integrates over each source's takeoff angles by the
//! midpoint rule ([`SourceRays`]); "exact" means exact to the model, so its
//! error is measured against the same integral on
//! [`REFERENCE_RAYS_PER_PI`] rays per π, whose own error is about
//! `(128/4096)²` of the default grid's. The values compared are every
//! sensor's at every cell it can reach at each step `1..=T` (its type's
//! speed × `t` cells each way), with nothing excluded: what a plan reads.

use vigil::estimator::{Estimator, SourceRays};
use vigil::planner::{PlanInput, PlanRequest, Planner};

/// Rays per π of the reference grid.
pub const REFERENCE_RAYS_PER_PI: f64 = 4096.0;

/// The errors of a set of values against the reference.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Errors {
    /// Values compared.
    pub values: usize,
    /// Their mean (the reference's), targets.
    pub mean_value: f64,
    /// The largest absolute error, targets.
    pub max_abs: f64,
    /// The mean absolute error, targets.
    pub mean_abs: f64,
    /// The largest error relative to the reference value, over the values
    /// of at least a tenth of a target (below that a relative error says
    /// little: an almost fully seen cell).
    pub max_rel: f64,
    /// The mean of those relative errors.
    pub mean_rel: f64,
}

/// The values relative errors are taken over: at least this many targets.
pub const MIN_RELATIVE_VALUE: f64 = 0.1;

/// The errors of `planner`'s exact values for `reqs` against the same
/// values on `fine`, a finer grid of the planner's scenario
/// (`SourceRays::with_density(&planner.scenario, REFERENCE_RAYS_PER_PI)`).
///
/// # Panics
/// If a request is not valid for the planner's scenario.
pub fn errors(planner: &Planner, reqs: &[PlanRequest], fine: &[SourceRays]) -> Errors {
    let s = &planner.scenario;
    let (mut e, mut sum_value, mut rel_count) = (Errors::default(), 0.0, 0usize);
    for req in reqs {
        let input = PlanInput::new(s, req).expect("a valid request");
        let coarse = planner.exact_estimator(&input, None);
        let reference = planner.exact_estimator(&input, Some(fine));
        for (i, (&start, &ty)) in input.starts().iter().zip(input.types()).enumerate() {
            for t in 1..=input.horizon() {
                let reach = (s.types[ty].speed * t) as i32;
                for dr in -reach..=reach {
                    for dc in -reach..=reach {
                        let k = vigil::scenario::Cell {
                            col: start.col + dc,
                            row: start.row + dr,
                        };
                        if !s.on_lattice(k) {
                            continue;
                        }
                        let (v, r) = (coarse.value(i, k, t, &[]), reference.value(i, k, t, &[]));
                        let abs = (v - r).abs();
                        e.values += 1;
                        sum_value += r;
                        e.max_abs = e.max_abs.max(abs);
                        e.mean_abs += abs;
                        if r.abs() >= MIN_RELATIVE_VALUE {
                            rel_count += 1;
                            e.max_rel = e.max_rel.max(abs / r.abs());
                            e.mean_rel += abs / r.abs();
                        }
                    }
                }
            }
        }
    }
    let n = e.values.max(1) as f64;
    e.mean_value = sum_value / n;
    e.mean_abs /= n;
    e.mean_rel /= rel_count.max(1) as f64;
    e
}
