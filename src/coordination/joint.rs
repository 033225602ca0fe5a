//! Joint coordination: from `Iterated`'s plan, alternately tighten the
//! certificate and look for a better joint plan, until the certified gap is
//! at most the target or the time budget runs out.
//!
//! Each round:
//! 1. tightens the bound by a few steps of the relaxation (each one search
//!    per sensor, see [`super::certificate`]);
//! 2. restarts best-response rounds from another joint plan and keeps the
//!    result if it has no more separation violations and more value. The
//!    starts alternate between the paths the relaxation's weights draw
//!    each sensor to (where the bound says value may be left) and the
//!    current plan with a third of the sensors, chosen at random, sent to
//!    the relaxation's paths: a large-neighbourhood search.
//!
//! The returned plan never has less value or more violations than
//! `Iterated`'s. The random choices come from a generator seeded from the
//! round, so with the same rounds the plan is the same; how many rounds fit
//! the budget depends on the machine.

use std::time::{Duration, Instant};

use rand::rngs::SmallRng;
use rand::{RngExt, SeedableRng};
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use super::certificate::{Bound, Certifier};
use super::fleet::{Fleet, SensorPlan, path_slices};
use super::rounds::{MAX_ROUNDS, best_responses};
use crate::cancel::Cancelled;
use crate::limits::{DEFAULT_BUDGET_MS, DEFAULT_GAP_TARGET};
use crate::separation;

/// Steps of the relaxation per round: each costs about one search per
/// sensor, a restart several rounds of them, and the bound needs tens of
/// steps to settle.
const BOUND_STEPS: usize = 3;
/// Rounds in a row that find neither a smaller bound nor a better plan
/// after which `joint` stops early.
const PATIENCE: usize = 12;

/// When `joint` stops.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointSettings {
    /// Stop once the certified gap is at most this, in `[0, 1]`.
    pub gap_target: f64,
    /// Stop once this much time has passed since the plan started.
    pub budget: Duration,
}

impl Default for JointSettings {
    fn default() -> Self {
        Self {
            gap_target: DEFAULT_GAP_TARGET,
            budget: Duration::from_millis(DEFAULT_BUDGET_MS),
        }
    }
}

/// Why `joint` stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "lowercase")]
pub enum JointStop {
    /// The certified gap reached the target.
    Gap,
    /// The time budget ran out.
    Budget,
    /// Several rounds in a row found neither a smaller bound nor a better
    /// plan.
    Settled,
}

/// What `joint` did.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct JointReport {
    /// Rounds of tightening and restarting run after `Iterated`.
    pub rounds: usize,
    /// Why it stopped.
    pub stopped: JointStop,
    /// Time from the plan's start to the end of the last round,
    /// microseconds.
    pub micros: u64,
}

/// Improves `plans` (request order, `Iterated`'s result with sensors in
/// `order`) and tightens `certifier` until the certified gap is at most the
/// target or the budget, counted from `started`, runs out (see the module
/// docs).
///
/// # Errors
/// [`Cancelled`] once the fleet's token is cancelled.
pub fn improve(
    fleet: &Fleet,
    plans: &mut Vec<SensorPlan>,
    order: &[usize],
    certifier: &mut Certifier,
    settings: JointSettings,
    started: Instant,
) -> Result<JointReport, Cancelled> {
    let deadline = started + settings.budget;
    let d = fleet.min_separation;
    let score = |plans: &[SensorPlan]| -> (u32, f64) {
        let paths = path_slices(plans);
        let value = fleet.by_step(&paths, order).iter().sum();
        (separation::count(&paths, d).pairs, value)
    };
    let (mut pairs, mut value) = score(plans);
    let mut rounds = 0;
    let mut idle = 0;
    let stopped = loop {
        if Bound::new(value, [certifier.upper()]).gap <= settings.gap_target {
            break JointStop::Gap;
        }
        if Instant::now() >= deadline {
            break JointStop::Budget;
        }
        if idle >= PATIENCE {
            break JointStop::Settled;
        }
        rounds += 1;
        let before = certifier.upper();
        for _ in 0..BOUND_STEPS {
            if Instant::now() >= deadline {
                break;
            }
            certifier.tighten(&path_slices(plans), value)?;
        }
        let mut progress = certifier.upper() < before - 1e-12 * before.abs();
        // A restart: from the relaxation's paths on odd rounds, else from
        // the current plan with a few sensors sent back to where the
        // relaxation draws them.
        let drawn = certifier.drawn_paths();
        let mut trial = plans.clone();
        if rounds % 2 == 1 {
            for (p, path) in trial.iter_mut().zip(drawn) {
                p.path.clone_from(path);
            }
        } else {
            let mut rng = SmallRng::seed_from_u64(rounds as u64);
            let k = (plans.len() / 3).max(1);
            for _ in 0..k {
                let i = rng.random_range(0..plans.len());
                trial[i].path.clone_from(&drawn[i]);
            }
        }
        if Instant::now() < deadline {
            best_responses(fleet, &mut trial, order, MAX_ROUNDS, Some(deadline))?;
            let (trial_pairs, trial_value) = score(&trial);
            let tol = 1e-9 * value.abs().max(1.0);
            if trial_pairs <= pairs && trial_value > value + tol {
                (*plans, pairs, value) = (trial, trial_pairs, trial_value);
                progress = true;
            }
        }
        idle = if progress { 0 } else { idle + 1 };
    };
    Ok(JointReport {
        rounds,
        stopped,
        micros: started.elapsed().as_micros() as u64,
    })
}
