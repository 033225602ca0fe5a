//! Coordination of several sensors' searches (the paper's steps 5–7, and ours).
//!
//! - [`Coordination::None`]: each sensor searches alone.
//! - [`Coordination::Priority`]: each sensor searches alone; sensors are
//!   ranked by the value of their path, highest first (ties: request order);
//!   each next sensor searches again with its values reduced for the fields
//!   of view of all higher-ranked sensors at the same step.
//! - [`Coordination::Iterated`]: starts from `Priority`, then in rounds every
//!   sensor, in rank order, searches again against all the others' current
//!   paths, taking the new path only if it raises the total; it stops when a
//!   round changes nothing, or after 10 rounds.
//! - [`Coordination::Joint`]: starts from `Iterated`, then alternately
//!   tightens the certificate and restarts best-response rounds from other
//!   joint plans, keeping a better one, until the certified gap reaches a
//!   target or a time budget runs out ([`joint`]). With the paper
//!   estimator, which has no certificate, it is `Iterated`.
//!
//! Every plan with an order-independent (exact) estimator carries its
//! certificate: an upper bound on the best joint plan ([`certificate`]).
//!
//! With [`Objective::FirstDetections`] (a fleet made with
//! [`Fleet::with_first_detections`]) every search above is the bounded
//! search of [`Fleet::first_search`]: a sensor's value for a path is its
//! exact marginal, the first detections it adds to those of the paths it
//! plans against over the whole horizon (a target another sensor detects
//! at step 1 is not there for it at step 3). The priority pass, the repair
//! rounds and the best-response rounds run as above on those marginals;
//! `Joint` runs as `Iterated`, and the certificate is the smaller of the
//! solo searches' bounds summed and the marginal bound
//! ([`certificate::first_marginal_bound`]).
//!
//! The total is `Σ_t Σ_p value(p, cell_p(t), t, looks of the sensors ranked
//! above p at t)`: for the exact estimator the expected number of
//! (target, step) pairs detected by at least one sensor, whatever the order
//! (with detection probabilities, `Σ 1 − Π (1 − p)` over the sensors whose
//! field of view holds the target). In `Iterated` a sensor's value for a
//! cell is the change in that total when it stands there (its marginal
//! against all the others for the exact estimator; for the paper estimator
//! also the change in the lower-ranked sensors' overlap reductions), so each
//! accepted change raises the total and it never ends below `Priority`.
//!
//! With a minimum separation `d > 0` ([`crate::separation`]) every mode
//! keeps the sensors apart: paths are fixed in rank order, and each sensor
//! after the first searches with the fixed paths' cells marked as
//! violations, minimising (violations, −value) lexicographically. `None`
//! still ignores the others' values, but not their positions.
//!
//! That pass never revisits a higher-ranked sensor, which may corner a
//! lower one (push it against the zone's edge, say) although it could
//! have stood back. So while some pair is too close, a repair round (at
//! most [`MAX_REPAIRS`], and [`MAX_REPAIR_SEARCHES_PER_SENSOR`] searches per
//! sensor in all) takes the highest-ranked sensor in a violation
//! whose search around *every* other path has fewer violations than its
//! own, gives it that path, lets the ranks below it plan again in order,
//! and keeps the result if fewer pairs are too close in all. The last
//! sensor still plans last, around the others' final paths.
//!
//! In `Iterated` a sensor's search counts violations against every other
//! sensor's current path, and a new path is taken when it has fewer
//! violations, or as many and more value, so each change lowers the
//! number of pairs too close or keeps it and raises the total.

pub mod certificate;
mod fleet;
pub mod joint;
mod priority;
mod rounds;

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;
use utoipa::ToSchema;

use crate::cancel::Cancelled;
use crate::scenario::Cell;
use crate::search::ValueGrid;
use crate::separation::{self, Violations};

pub use certificate::Bound;
use certificate::Certifier;
use fleet::path_slices;
pub use fleet::{Fleet, SensorPlan, first_search_budget, path_moves, sensor_motion};
pub use joint::{JointReport, JointSettings};
use priority::Ranking;
pub use priority::{MAX_REPAIR_SEARCHES_PER_SENSOR, MAX_REPAIRS};
pub use rounds::MAX_ROUNDS;

/// How sensors' searches are coordinated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, ToSchema)]
#[serde(rename_all = "lowercase")]
pub enum Coordination {
    /// Every sensor plans alone (the paper's 'b' rows).
    None,
    /// The paper's priority scheme (the 'a' rows).
    #[default]
    Priority,
    /// Priority, then best-response rounds against all others.
    Iterated,
    /// Iterated, then restarts until the certified gap reaches its target
    /// or the time budget runs out.
    Joint,
}

crate::by_name::by_name!(Coordination {
    "none" => Coordination::None,
    "priority" => Coordination::Priority,
    "iterated" => Coordination::Iterated,
    "joint" => Coordination::Joint,
});

/// What a plan maximises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum Objective {
    /// The paper's J: expected detections summed over the steps (a target
    /// seen at two steps counts twice).
    #[default]
    Detections,
    /// Expected targets not yet detected (not reported, unseen in the
    /// history) that the plan detects at least once over steps 1..=T: the
    /// intrusion objective. Needs the `exact` estimator.
    FirstDetections,
}

crate::by_name::by_name!(Objective {
    "detections" => Objective::Detections,
    "first_detections" => Objective::FirstDetections,
});

/// Plans of every sensor, in request order, with their ranks.
#[derive(Debug, Clone)]
pub struct Coordinated {
    /// Per sensor, in request order.
    pub plans: Vec<SensorPlan>,
    /// Sensor indices from highest to lowest priority.
    pub order: Vec<usize>,
    /// Estimated distinct detections at steps 1..=T.
    pub by_step: Vec<f64>,
    /// Best-response rounds run (iterated only).
    pub rounds: usize,
    /// Repair rounds of the separation run (see the module docs).
    pub repairs: usize,
    /// The searches those rounds made.
    pub repair_searches: usize,
    /// Breaches of the minimum separation among the final paths.
    pub violations: Violations,
    /// The plan's certificate, for an order-independent (exact) estimator.
    pub bound: Option<Bound>,
    /// What `Joint` did after `Iterated` (with a certificate).
    pub joint: Option<JointReport>,
}

/// Plans the fleet's sensors over its horizon; each moves at its type's
/// speed through the scenario's free cells, and keeps the fleet's minimum
/// separation from the others wherever it can (see the module docs). With
/// an order-independent (exact) estimator the plan carries its
/// [certificate] when `certify` asks for it (`joint` always does).
///
/// # Errors
/// [`Cancelled`] once the fleet's token is cancelled: it is checked before
/// every step's values of every search and between sensors and rounds, so
/// the work stops within one sensor-step's fill.
pub fn coordinate(
    fleet: &Fleet,
    mode: Coordination,
    joint: JointSettings,
    certify: bool,
    started: Instant,
) -> Result<Coordinated, Cancelled> {
    let certify = certify || mode == Coordination::Joint;
    let Fleet {
        est,
        starts,
        min_separation: d,
        cancel,
        ..
    } = *fleet;
    let n = starts.len();
    // Every sensor alone (for first detections, with the upper bound of
    // its search, which the certificate sums).
    let (mut plans, solo_upper): (Vec<SensorPlan>, f64) = if fleet.first.is_some() {
        let found: Vec<_> = (0..n)
            .into_par_iter()
            .with_min_len(crate::parallel::min_len())
            .map(|i| fleet.first_search(i, &[], &[], Vec::new(), None))
            .collect();
        let upper = found.iter().map(|f| f.upper).sum();
        (found.into_iter().map(|f| f.plan).collect(), upper)
    } else {
        let plans = (0..n)
            .into_par_iter()
            .with_min_len(crate::parallel::min_len())
            .map(|i| fleet.plan_one(i, &mut |t, g| est.fill(i, starts[i], t, &[], g), Vec::new()))
            .collect();
        (plans, f64::INFINITY)
    };
    cancel.check()?;
    let solo: Vec<(f64, Vec<Cell>)> = plans.iter().map(|p| (p.value, p.path.clone())).collect();
    let mut order: Vec<usize> = (0..n).collect();
    // Stable sort: ties keep request order.
    order.sort_by(|&a, &b| plans[b].value.total_cmp(&plans[a].value));
    // Each sensor's lone values, which the later passes start from; an
    // exact plan's certificate starts from them too.
    let grids_wanted = mode != Coordination::None || d > 0 || (certify && est.order_independent());
    let alone: Vec<ValueGrid> = if fleet.first.is_none() && grids_wanted {
        plans.iter().map(|p| p.grid.clone()).collect()
    } else {
        Vec::new()
    };
    let ranking = Ranking {
        fleet,
        order,
        alone: &alone,
        independent: mode == Coordination::None,
    };
    let mut rounds = 0;
    let (mut repairs, mut repair_searches) = (0, 0);
    if mode != Coordination::None || d > 0 {
        ranking.priority_pass(&mut plans)?;
    }
    if d > 0 {
        (repairs, repair_searches) = ranking.repair(&mut plans)?;
    }
    let order = ranking.order;
    if matches!(mode, Coordination::Iterated | Coordination::Joint) {
        rounds = rounds::best_responses(fleet, &mut plans, &order, MAX_ROUNDS, None)?.rounds;
    }
    let mut by_step = fleet.by_step(&path_slices(&plans), &order);
    cancel.check()?;
    let mut report = None;
    let bound = if !certify {
        None
    } else if fleet.first.is_some() {
        let value: f64 = by_step.iter().sum();
        Some(Bound::new(
            value,
            [
                solo_upper,
                certificate::first_marginal_bound(
                    fleet,
                    &path_slices(&plans),
                    value,
                    &order,
                    solo_upper,
                )?,
            ],
        ))
    } else if est.order_independent() {
        let mut value: f64 = by_step.iter().sum();
        let mut certifier = Certifier::new(fleet, solo, &alone);
        if mode == Coordination::Joint {
            report = Some(joint::improve(
                fleet,
                &mut plans,
                &order,
                &mut certifier,
                joint,
                started,
            )?);
            by_step = fleet.by_step(&path_slices(&plans), &order);
            value = by_step.iter().sum();
        } else {
            certifier.tighten(&path_slices(&plans), value)?;
        }
        Some(Bound::new(value, [certifier.upper()]))
    } else {
        None
    };
    let violations = separation::count(&path_slices(&plans), d);
    Ok(Coordinated {
        plans,
        order,
        by_step,
        rounds,
        repairs,
        repair_searches,
        violations,
        bound,
        joint: report,
    })
}
