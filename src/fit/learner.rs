//! A session's running fit of its source rates: the sufficient statistics
//! of its whole life, folded in one step at a time.
//!
//! The exposure of a session's life is the sum over its steps `t` of the
//! exposure of the targets that a look of step `t` detects and no earlier
//! look does ([`WindowLooks::exposure`] with `fresh_from`). A target seen
//! at step `t` can only have been seen before while it was in the zone, so
//! only the looks of the last [`RateLearner::memory`] steps (the longest
//! time a target can stay in the zone) take part. Each track id counts once
//! for the session's life, through a [`TrackBook`].

use std::collections::VecDeque;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::exposure::WindowLooks;
use super::posterior::Prior;
use super::window::{Observed, Tolerances, TrackBook};
use super::wire::{DetectionIn, SourceRate};
use super::{Attribution, Unexplained};
use crate::limits::{LEARN_REPLAN_DRIFT, MAX_LEARN_MEMORY_STEPS, MAX_SESSION_TRACKS};
use crate::planner::{Planner, SensorIn, TargetIn};
use crate::scenario::{Look, Scenario, ValidationError};

/// A session's learnt rates and the planner at those rates.
#[derive(Debug, Clone)]
pub struct RateLearner {
    /// The scenario as registered (its rates are the prior's centre).
    base: Arc<Planner>,
    /// The planner plans are made with: `base` until the learnt rates
    /// drift from its rates, then a planner at the learnt rates.
    planner: Arc<Planner>,
    memory: usize,
    /// The looks of the last `memory` steps, oldest first.
    recent: VecDeque<Vec<Look>>,
    book: TrackBook,
    exposure: Vec<f64>,
    attribution: Attribution,
    step: u64,
    tolerances: Tolerances,
    /// The detections cover the whole zone (a session's `observed:
    /// zone`): each step's look is the zone, certain.
    whole_zone: bool,
}

/// A step folded into a learner, not yet recorded ([`RateLearner::commit`]).
#[derive(Debug)]
pub struct LearntStep {
    observed: Observed,
    exposure: Vec<f64>,
    /// This step's new targets, attributed.
    added: Attribution,
    rates: Vec<SourceRate>,
    planner: Option<Arc<Planner>>,
}

impl LearntStep {
    /// The rates after this step.
    pub fn rates(&self) -> &[SourceRate] {
        &self.rates
    }

    /// The planner at this step's rates, when they drifted from the
    /// learner's.
    pub fn planner(&self) -> Option<&Arc<Planner>> {
        self.planner.as_ref()
    }
}

/// What a learner holds apart from its scenario, tolerances and planners:
/// what a session's snapshot carries ([`RateLearner::snapshot`],
/// [`RateLearner::restore`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LearnerSnapshot {
    recent: VecDeque<Vec<Look>>,
    book: TrackBook,
    exposure: Vec<f64>,
    attribution: Attribution,
    step: u64,
    /// The source rates of the planner plans are made with.
    planned_rates: Vec<f64>,
}

impl RateLearner {
    /// Steps of looks a learning session on `s` must keep: the longest a
    /// target can stay in the zone (its diagonal at the slowest speed),
    /// plus one.
    pub fn memory_needed(s: &Scenario) -> f64 {
        (s.width.hypot(s.height) / s.min_speed()).ceil() + 1.0
    }

    /// Checks that a session on `s` can learn: that the looks its slowest
    /// targets need fit in [`MAX_LEARN_MEMORY_STEPS`]. Fewer would count a
    /// target seen again after them as new, and overstate the exposure.
    ///
    /// # Errors
    /// A [`ValidationError`] naming `learn_rates`.
    pub fn check(s: &Scenario) -> Result<(), ValidationError> {
        let needed = Self::memory_needed(s);
        if needed > MAX_LEARN_MEMORY_STEPS as f64 {
            return Err(ValidationError::new(
                "learn_rates",
                format!(
                    "the slowest targets (speed {}) may stay {needed:.0} steps in the zone; a learning session keeps the looks of at most {MAX_LEARN_MEMORY_STEPS} steps and would count such a target seen again as new; fit windows (POST /v1/scenarios/{{id}}/fit) have no such limit",
                    s.min_speed()
                ),
            ));
        }
        Ok(())
    }

    /// A learner with nothing observed: the scenario prior, and `base`'s
    /// planner. A scenario that fails [`RateLearner::check`] keeps only
    /// [`MAX_LEARN_MEMORY_STEPS`] steps of looks.
    /// With `whole_zone`, every step's detections are taken to cover the
    /// zone (a session's `observed: zone`).
    pub fn new(base: Arc<Planner>, tolerances: Tolerances, whole_zone: bool) -> Self {
        let s = &base.scenario;
        let memory = (Self::memory_needed(s).min(MAX_LEARN_MEMORY_STEPS as f64)) as usize;
        RateLearner {
            planner: base.clone(),
            memory,
            recent: VecDeque::new(),
            book: TrackBook::new(MAX_SESSION_TRACKS),
            exposure: vec![0.0; s.sources.len()],
            attribution: Attribution::new(s),
            step: 0,
            tolerances,
            whole_zone,
            base,
        }
    }

    /// Its state, less its scenario, tolerances and planners.
    pub fn snapshot(&self) -> LearnerSnapshot {
        LearnerSnapshot {
            recent: self.recent.clone(),
            book: self.book.clone(),
            exposure: self.exposure.clone(),
            attribution: self.attribution.clone(),
            step: self.step,
            planned_rates: rates_of(&self.planner),
        }
    }

    /// The learner of `snapshot` on `base` (as [`RateLearner::new`]),
    /// planning with `base`, with `reuse` if it plans at the snapshot's
    /// rates, or else with a planner built at them (a precomputation).
    ///
    /// # Errors
    /// A message when the snapshot does not fit `base`'s scenario.
    pub fn restore(
        base: Arc<Planner>,
        tolerances: Tolerances,
        whole_zone: bool,
        snapshot: LearnerSnapshot,
        reuse: Option<Arc<Planner>>,
    ) -> Result<Self, String> {
        let mut learner = RateLearner::new(base, tolerances, whole_zone);
        let sources = learner.base.scenario.sources.len();
        if [
            snapshot.exposure.len(),
            snapshot.attribution.own.len(),
            snapshot.planned_rates.len(),
        ] != [sources; 3]
        {
            return Err(format!(
                "a learner's snapshot does not have the scenario's {sources} sources"
            ));
        }
        learner.planner = if snapshot.planned_rates == rates_of(&learner.base) {
            learner.base.clone()
        } else if let Some(reuse) = reuse.filter(|p| rates_of(p) == snapshot.planned_rates) {
            reuse
        } else {
            learner
                .planner_at(&snapshot.planned_rates)
                .ok_or("a learner's snapshot has rates its scenario refuses")?
        };
        learner.recent = snapshot.recent;
        learner.book = snapshot.book;
        learner.exposure = snapshot.exposure;
        learner.attribution = snapshot.attribution;
        learner.step = snapshot.step;
        Ok(learner)
    }

    /// The scenario as registered.
    pub fn base(&self) -> &Arc<Planner> {
        &self.base
    }

    /// Its tolerances.
    pub fn tolerances(&self) -> Tolerances {
        self.tolerances
    }

    /// Whether each step's look is the whole zone.
    pub fn whole_zone(&self) -> bool {
        self.whole_zone
    }

    /// Steps of looks kept: the longest a target can stay in the zone.
    pub fn memory(&self) -> usize {
        self.memory
    }

    /// The planner to plan with.
    pub fn planner(&self) -> &Arc<Planner> {
        &self.planner
    }

    /// The rates now.
    pub fn rates(&self) -> Vec<SourceRate> {
        self.attribution
            .rates(&self.base.scenario, &self.exposure, Prior::Scenario)
    }

    /// Targets no source explains, so far.
    pub fn unexplained(&self) -> &[Unexplained] {
        &self.attribution.unexplained
    }

    /// Approximate heap memory held, bytes (the planners aside).
    pub fn memory_bytes(&self) -> usize {
        let looks: usize = self.recent.iter().map(|l| l.len()).sum();
        looks * std::mem::size_of::<Look>()
            + self.book.len() * 64
            + self.attribution.shared.len() * 48
            + self.attribution.unexplained.len() * 64
    }

    /// Folds this step's looks and detections in, without changing the
    /// learner: validates them (every detection needs an `id`, lies in a
    /// look, and moves no faster than a target flies), counts the
    /// exposure it adds and its new targets, and builds a planner at the
    /// new rates when they drifted more than [`LEARN_REPLAN_DRIFT`] from
    /// the planner's. Field names are those of a step request
    /// (`sensors[i]`, `detections[i]`).
    pub fn fold(
        &self,
        sensors: &[SensorIn],
        detections: &[TargetIn],
    ) -> Result<LearntStep, ValidationError> {
        let s = &self.base.scenario;
        let detections = detections
            .iter()
            .enumerate()
            .map(|(i, d)| {
                let id = d.id.clone().ok_or_else(|| {
                    ValidationError::new(
                        format!("detections[{i}].id"),
                        "required when the session learns rates: each target counts once",
                    )
                })?;
                Ok(DetectionIn {
                    id,
                    x: d.x,
                    y: d.y,
                    vx: d.vx,
                    vy: d.vy,
                })
            })
            .collect::<Result<Vec<_>, ValidationError>>()?;
        let observed = self.book.observe(
            s,
            "",
            self.step,
            sensors,
            &detections,
            &self.tolerances,
            self.whole_zone,
        )?;
        let mut window: Vec<Vec<Look>> = self.recent.iter().cloned().collect();
        window.push(observed.looks.clone());
        let fresh = window.len() - 1;
        let added = WindowLooks::new(s, &window).exposure(fresh);
        let exposure: Vec<f64> = self
            .exposure
            .iter()
            .zip(&added)
            .map(|(a, b)| a + b)
            .collect();
        let mut added = Attribution::new(s);
        added.add(s, &observed.firsts, &self.tolerances.traceback);
        let rates = self
            .attribution
            .rates_with(&added, s, &exposure, Prior::Scenario);
        let planner = self.replan(&rates);
        Ok(LearntStep {
            observed,
            exposure,
            added,
            rates,
            planner,
        })
    }

    /// A planner at `rates` when they drifted from the planner's, if the
    /// scenario at those rates is valid.
    fn replan(&self, rates: &[SourceRate]) -> Option<Arc<Planner>> {
        let planned = &self.planner.scenario.sources;
        let mean = planned.iter().map(|s| s.rate).sum::<f64>() / planned.len() as f64;
        let drifted = rates.iter().zip(planned).any(|(r, p)| {
            (r.rate - p.rate).abs() > LEARN_REPLAN_DRIFT * p.rate.max(mean).max(f64::MIN_POSITIVE)
        });
        if !drifted {
            return None;
        }
        let rates: Vec<f64> = rates.iter().map(|r| r.rate).collect();
        self.planner_at(&rates)
    }

    /// A planner of the scenario at source rates `rates`, if valid.
    fn planner_at(&self, rates: &[f64]) -> Option<Arc<Planner>> {
        let mut spec = self.base.scenario.spec.clone();
        for (src, &rate) in spec.sources.iter_mut().zip(rates) {
            src.rate = rate;
        }
        let scenario = Scenario::new(spec).ok()?;
        Some(Arc::new(Planner::new(scenario)))
    }

    /// Records a step that [`RateLearner::fold`] gave.
    pub fn commit(&mut self, mut step: LearntStep) {
        self.book.commit(&mut step.observed);
        self.recent
            .push_back(std::mem::take(&mut step.observed.looks));
        while self.recent.len() > self.memory {
            self.recent.pop_front();
        }
        self.exposure = step.exposure;
        self.attribution.extend(step.added);
        if let Some(planner) = step.planner {
            self.planner = planner;
        }
        self.step += 1;
    }
}

/// The source rates `planner`'s spec gives (as [`RateLearner::planner_at`]
/// sets them).
fn rates_of(planner: &Planner) -> Vec<f64> {
    planner
        .scenario
        .spec
        .sources
        .iter()
        .map(|s| s.rate)
        .collect()
}
