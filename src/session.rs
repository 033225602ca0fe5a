//! Sessions for step-by-step clients: the server keeps what a simulator
//! would otherwise resend every step (the sensors' past looks and the
//! targets' tracks) and turns each step into the stateless plan request of
//! the same state.
//!
//! A step gives the sensors now and the targets detected now. The session
//! then, in this order:
//! 1. moves every track one step along its straight line (`pos += vel`, as
//!    targets fly);
//! 2. takes each detection as the new state of its track: the track with
//!    its `id`, else (no id) the anonymous track at the same position and
//!    velocity, else a new track;
//! 3. drops the tracks that left the zone or were last detected more than
//!    `history_steps` steps ago;
//! 4. plans from the sensors now, the tracks, and the sensors' positions
//!    1, 2, …, `history_steps` steps ago;
//! 5. once the plan is made, records this step: the sensors' positions
//!    join the history and the step number advances. A step whose plan is
//!    not made (invalid, refused, cancelled) changes nothing, so a client
//!    may send it again.
//!
//! That is the rule the simulation client applies to build its stateless
//! requests, so a session's plan equals the stateless plan of the same run.
//!
//! A session created with `learn_rates` also learns the sources' rates
//! ([`crate::fit::RateLearner`]): each step is folded in before its plan,
//! which is then made at the learnt rates (the stateless plan of the same
//! state on the scenario at those rates).
//!
//! ```
//! use std::sync::Arc;
//! use vigil::planner::{Planner, SensorIn, TargetIn, Id};
//! use vigil::scenario::builtins;
//! use vigil::session::{Session, SessionSettings, StepRequest};
//!
//! let planner = Arc::new(Planner::new(builtins().remove(0)));
//! let mut session = Session::new(planner.clone(), SessionSettings::default());
//! let step = StepRequest {
//!     sensors: vec![SensorIn { id: Id::Text("a".into()), x: 150.0, y: 150.0, sensor_type: None }],
//!     detections: vec![TargetIn { id: None, x: 160.0, y: 150.0, vx: 10.0, vy: 0.0 }],
//!     ..StepRequest::default()
//! };
//! let next = session.prepare(&step);
//! let plan = planner.plan_request(&next.request).unwrap();
//! session.commit(next);
//! assert_eq!(session.step(), 1);
//! assert_eq!(session.tracks().len(), 1);
//! assert_eq!(plan.plans.len(), 1);
//! ```

use std::collections::VecDeque;
use std::sync::Arc;

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use utoipa::ToSchema;

use crate::coordination::{Coordination, Objective};
use crate::fit::{FitTolerance, LearnerSnapshot, LearntStep, RateLearner, Tolerances};
use crate::geometry::Point;
use crate::limits::{DEFAULT_HISTORY_STEPS, MAX_HISTORY_STEPS, MAX_TARGETS};
use crate::planner::{
    EstimatorKind, Id, Observed, PlanRequest, Planner, PositionIn, SensorIn, TargetIn,
};
use crate::planner::{check_certify, check_objective};
use crate::scenario::{Integer, Scenario, ValidationError};

/// A session's defaults for its steps; a step may override each but
/// `history_steps`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct SessionSettings {
    /// Horizon T; the scenario's by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>, minimum = 1)]
    pub horizon: Option<Integer>,
    /// Estimator; `exact` by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator: Option<EstimatorKind>,
    /// Coordination; `priority` by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coordination: Option<Coordination>,
    /// What the detections cover; `sensors` by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub observed: Option<Observed>,
    /// What the plans maximise; `detections` by default
    /// (`first_detections` needs the `exact` estimator).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub objective: Option<Objective>,
    /// Minimum separation between sensors, cells (0..=16); the scenario's
    /// by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>, minimum = 0)]
    pub min_separation: Option<Integer>,
    /// Steps of history kept (0..=128, 16 by default): the sensors' past
    /// positions planned with, and how long a track lives undetected.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>, minimum = 0)]
    pub history_steps: Option<Integer>,
    /// Certify each step's plan (true by default; see the plan request's
    /// `certify`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub certify: Option<bool>,
    /// Learn the sources' rates from the detections (false by default):
    /// every step then needs an `id` on each detection, folds its looks
    /// and new targets into each source's posterior (the scenario's prior;
    /// see `docs/learning.md`), plans with the posterior means and reports
    /// them as `rates`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub learn_rates: Option<bool>,
    /// With `learn_rates`: the tolerances of a noisy tracker, as in a fit
    /// (exact data by default).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "FitTolerance::from_object"
    )]
    pub tolerance: Option<FitTolerance>,
}

impl SessionSettings {
    /// The learning tolerances against scenario `s`.
    ///
    /// # Errors
    /// A [`ValidationError`] naming `tolerance.traceback` (…).
    pub fn tolerances(&self, s: &Scenario) -> Result<Tolerances, ValidationError> {
        Tolerances::new(s, self.tolerance.as_ref())
    }

    /// With `learn_rates`, checks that a session on `s` can learn
    /// ([`RateLearner::check`]).
    ///
    /// # Errors
    /// A [`ValidationError`] naming `learn_rates`.
    pub fn check_learning(&self, s: &Scenario) -> Result<(), ValidationError> {
        if self.learn_rates == Some(true) {
            RateLearner::check(s)?;
        }
        Ok(())
    }

    /// Checks what can be checked before any step: `history_steps`, an
    /// `objective` the `estimator` cannot serve, and `certify: false` with
    /// `joint` (the rest is checked with every step's plan request). Gives
    /// the history length.
    ///
    /// # Errors
    /// A [`ValidationError`] naming `history_steps`, `objective` or
    /// `certify`.
    pub fn history_len(&self) -> Result<usize, ValidationError> {
        check_objective(
            "objective",
            self.objective,
            self.estimator.unwrap_or_default(),
        )?;
        check_certify(
            "certify",
            self.certify,
            self.coordination.unwrap_or_default(),
        )?;
        match &self.history_steps {
            None => Ok(DEFAULT_HISTORY_STEPS),
            Some(n) => n.check("history_steps", 0..=MAX_HISTORY_STEPS),
        }
    }
}

/// Body of a session's step.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct StepRequest {
    /// Sensors now.
    #[schema(min_items = 1)]
    pub sensors: Vec<SensorIn>,
    /// Targets detected this step (by any sensor), their position and
    /// displacement per step now; with an `id` when the client tracks
    /// identities.
    #[serde(default)]
    pub detections: Vec<TargetIn>,
    /// Horizon T of this step; the session's by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>, minimum = 1)]
    pub horizon: Option<Integer>,
    /// Estimator of this step; the session's by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator: Option<EstimatorKind>,
    /// Coordination of this step; the session's by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coordination: Option<Coordination>,
    /// Objective of this step; the session's by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub objective: Option<Objective>,
    /// Minimum separation of this step; the session's by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>, minimum = 0)]
    pub min_separation: Option<Integer>,
    /// Include the search values in the response.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub explain: Option<bool>,
    /// With `coordination: joint`: the certified gap at which it stops, in
    /// `[0, 1]`; 0.001 by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(minimum = 0.0, maximum = 1.0)]
    pub gap_target: Option<f64>,
    /// With `coordination: joint`: the most time the step's plan may take,
    /// milliseconds (1..=1000, 20 by default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>, minimum = 1)]
    pub budget_ms: Option<Integer>,
    /// Certify this step's plan; the session's setting by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub certify: Option<bool>,
}

impl StepRequest {
    /// Checks what the plan request built from it cannot name: the number
    /// of detections and their numbers (the sensors are checked with the
    /// plan request, under their own names).
    ///
    /// # Errors
    /// A [`ValidationError`] naming `detections` or `detections[i].x` (…).
    pub fn check(&self) -> Result<(), ValidationError> {
        if self.detections.len() > MAX_TARGETS {
            return Err(ValidationError::new(
                "detections",
                format!(
                    "at most {MAX_TARGETS} detections, got {}",
                    self.detections.len()
                ),
            ));
        }
        for (i, d) in self.detections.iter().enumerate() {
            for (name, v) in [("x", d.x), ("y", d.y), ("vx", d.vx), ("vy", d.vy)] {
                if !v.is_finite() {
                    return Err(ValidationError::new(
                        format!("detections[{i}].{name}"),
                        "must be a finite number",
                    ));
                }
            }
        }
        Ok(())
    }

    /// The SHA-256 of this request as JSON (fields in declaration order):
    /// what tells a retry of a step, which has the same digest, from a new
    /// step sent with the retried step's `Idempotency-Key`. Bodies that
    /// differ only in layout, field order or number spelling have one
    /// digest.
    pub fn digest(&self) -> [u8; 32] {
        // Integers keep their spelling (a fraction is refused naming it):
        // a retry may spell 3 as 3.0.
        let mut req = self.clone();
        for n in [
            &mut req.horizon,
            &mut req.min_separation,
            &mut req.budget_ms,
        ]
        .into_iter()
        .flatten()
        {
            *n = n.canonical();
        }
        let json = serde_json::to_vec(&req).unwrap_or_default();
        Sha256::digest(&json).into()
    }
}

/// A target the session follows: its last detection moved on along its
/// straight line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct Track {
    /// The id the client gave it, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub id: Option<Id>,
    /// East coordinate now.
    pub x: f64,
    /// North coordinate now.
    pub y: f64,
    /// East displacement per step.
    pub vx: f64,
    /// North displacement per step.
    pub vy: f64,
    /// The step it was last detected at.
    pub last_detected: u64,
}

impl Track {
    fn target(&self) -> TargetIn {
        TargetIn {
            id: self.id.clone(),
            x: self.x,
            y: self.y,
            vx: self.vx,
            vy: self.vy,
        }
    }
}

/// A step made ready: the stateless request of the session's state with
/// this step, and the tracks to keep once its plan is made
/// ([`Session::commit`]).
#[derive(Debug, Clone)]
pub struct PreparedStep {
    /// The equivalent stateless plan request.
    pub request: PlanRequest,
    tracks: Vec<Track>,
}

/// One client's session on one scenario (see the module docs).
#[derive(Debug)]
pub struct Session {
    planner: Arc<Planner>,
    settings: SessionSettings,
    history_len: usize,
    step: u64,
    /// Sensors' positions 1, 2, … steps ago.
    history: VecDeque<Vec<PositionIn>>,
    tracks: Vec<Track>,
    /// With `learn_rates`: the rates learnt so far. Shared so a step can
    /// fold into it off the async workers; unique again once it is done.
    learner: Option<Arc<RateLearner>>,
}

/// What a session holds apart from its planner: what one replica stores
/// for another to carry the session on ([`Session::snapshot`],
/// [`Session::restore`]). Encoded as CBOR, which keeps every `f64` to the
/// bit, so a restored session plans exactly as the one it was taken from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Snapshot {
    settings: SessionSettings,
    history_len: usize,
    step: u64,
    history: VecDeque<Vec<PositionIn>>,
    tracks: Vec<Track>,
    /// With `learn_rates`: what it learnt.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    learner: Option<LearnerSnapshot>,
}

impl Snapshot {
    /// The version of the encoding [`Snapshot::encode`] writes; a stored
    /// snapshot of another version is not read.
    pub const FORMAT: i32 = 1;

    /// The snapshot as bytes.
    pub fn encode(&self) -> Vec<u8> {
        let mut bytes = Vec::new();
        ciborium::into_writer(self, &mut bytes)
            .unwrap_or_else(|e| unreachable!("a snapshot encodes to memory: {e}"));
        bytes
    }

    /// A snapshot from [`Snapshot::encode`]'s bytes.
    ///
    /// # Errors
    /// A message when the bytes are not a snapshot.
    pub fn decode(bytes: &[u8]) -> Result<Self, String> {
        ciborium::from_reader(bytes).map_err(|e| format!("not a session snapshot: {e}"))
    }
}

impl Session {
    /// A session at step 0 with no history and no tracks. `settings` must
    /// have passed [`SessionSettings::history_len`] (an out-of-bounds
    /// `history_steps` is clamped).
    pub fn new(planner: Arc<Planner>, settings: SessionSettings) -> Self {
        let history_len = settings
            .history_len()
            .unwrap_or(DEFAULT_HISTORY_STEPS)
            .min(MAX_HISTORY_STEPS);
        let learner = (settings.learn_rates == Some(true)).then(|| {
            // Checked at creation (`SessionSettings::tolerances`); the
            // defaults otherwise.
            let tolerances = settings
                .tolerances(&planner.scenario)
                .or_else(|_| Tolerances::new(&planner.scenario, None))
                .unwrap_or_else(|_| unreachable!("the default tolerances are valid"));
            let whole_zone = settings.observed == Some(Observed::Zone);
            Arc::new(RateLearner::new(planner.clone(), tolerances, whole_zone))
        });
        Self {
            planner,
            settings,
            history_len,
            step: 0,
            history: VecDeque::new(),
            tracks: Vec::new(),
            learner,
        }
    }

    /// Its state, less its planner.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            settings: self.settings.clone(),
            history_len: self.history_len,
            step: self.step,
            history: self.history.clone(),
            tracks: self.tracks.clone(),
            learner: self.learner.as_ref().map(|l| l.snapshot()),
        }
    }

    /// The session of `snapshot` on `planner`, its scenario's. A learning
    /// session plans with `reuse` (the planner of the session it was
    /// before, say) if that is at the rates it planned at, else with a
    /// planner built at them: CPU work, up to a precomputation.
    ///
    /// # Errors
    /// A message when the snapshot does not fit `planner`'s scenario.
    pub fn restore(
        planner: Arc<Planner>,
        snapshot: Snapshot,
        reuse: Option<Arc<Planner>>,
    ) -> Result<Self, String> {
        let mut session = Session::new(planner, snapshot.settings);
        session.history_len = snapshot.history_len.min(MAX_HISTORY_STEPS);
        session.step = snapshot.step;
        session.history = snapshot.history;
        session.history.truncate(session.history_len);
        session.tracks = snapshot.tracks;
        session.learner = match (session.learner.take(), snapshot.learner) {
            (None, None) => None,
            (Some(fresh), Some(learnt)) => Some(Arc::new(RateLearner::restore(
                fresh.base().clone(),
                fresh.tolerances(),
                fresh.whole_zone(),
                learnt,
                reuse,
            )?)),
            _ => return Err("a snapshot's learnt state does not match its settings".into()),
        };
        Ok(session)
    }

    /// With `learn_rates`: its learnt rates.
    pub fn learner(&self) -> Option<&Arc<RateLearner>> {
        self.learner.as_ref()
    }

    /// The planner of a step: its scenario's, or the one at the rates it
    /// learnt (`learnt`, this step's fold, first).
    pub fn planner_for(&self, learnt: Option<&LearntStep>) -> Arc<Planner> {
        learnt
            .and_then(LearntStep::planner)
            .or_else(|| self.learner.as_ref().map(|l| l.planner()))
            .unwrap_or(&self.planner)
            .clone()
    }

    /// Records this step's fold ([`RateLearner::fold`]) once its plan is
    /// made.
    pub fn commit_learnt(&mut self, learnt: LearntStep) {
        if let Some(learner) = &mut self.learner {
            Arc::make_mut(learner).commit(learnt);
        }
    }

    /// The planner of its scenario.
    pub fn planner(&self) -> &Arc<Planner> {
        &self.planner
    }

    /// Its defaults.
    pub fn settings(&self) -> &SessionSettings {
        &self.settings
    }

    /// Steps of history kept.
    pub fn history_len(&self) -> usize {
        self.history_len
    }

    /// Steps made so far (the next step's number).
    pub fn step(&self) -> u64 {
        self.step
    }

    /// The tracks after the last step.
    pub fn tracks(&self) -> &[Track] {
        &self.tracks
    }

    /// Steps of history held now (up to [`Session::history_len`]).
    pub fn history_held(&self) -> usize {
        self.history.len()
    }

    /// Approximate heap memory held, bytes (its planner, shared, aside):
    /// counted from what it holds, not from its buffers' capacity, so that
    /// every replica reports the same for the same state.
    pub fn memory_bytes(&self) -> usize {
        let positions: usize = self
            .history
            .iter()
            .map(|step| {
                std::mem::size_of_val(step.as_slice())
                    + step
                        .iter()
                        .filter_map(|p| p.sensor_type.as_ref())
                        .map(String::len)
                        .sum::<usize>()
            })
            .sum();
        std::mem::size_of::<Self>()
            + self.history.len() * std::mem::size_of::<Vec<PositionIn>>()
            + positions
            + std::mem::size_of_val(self.tracks.as_slice())
            + self.learner.as_ref().map_or(0, |l| l.memory_bytes())
    }

    /// Steps 1–4 of the module docs: the tracks this step leads to and the
    /// stateless request of the state, without changing the session.
    pub fn prepare(&self, step: &StepRequest) -> PreparedStep {
        let s = &self.planner.scenario;
        let now = self.step;
        let mut tracks: Vec<Track> = self
            .tracks
            .iter()
            .map(|t| Track {
                x: t.x + t.vx,
                y: t.y + t.vy,
                ..t.clone()
            })
            .collect();
        // Tracks that existed before this step: an anonymous detection may
        // only match one of them, not another detection of this step.
        let before = tracks.len();
        for d in &step.detections {
            let detected = Track {
                id: d.id.clone(),
                x: d.x,
                y: d.y,
                vx: d.vx,
                vy: d.vy,
                last_detected: now,
            };
            let same = match &d.id {
                Some(id) => tracks.iter().position(|t| t.id.as_ref() == Some(id)),
                None => tracks[..before].iter().position(|t| {
                    t.id.is_none()
                        && t.last_detected < now
                        && t.vx == d.vx
                        && t.vy == d.vy
                        && (t.x - d.x).abs().max((t.y - d.y).abs()) <= 1e-6 * s.cell_size
                }),
            };
            match same {
                Some(i) => tracks[i] = detected,
                None => tracks.push(detected),
            }
        }
        let oldest = now.saturating_sub(self.history_len as u64);
        tracks.retain(|t| {
            t.last_detected >= oldest
                && t.x.is_finite()
                && t.y.is_finite()
                && s.in_zone(Point::new(t.x, t.y))
        });
        let history: Vec<Vec<PositionIn>> = self.history.iter().cloned().collect();
        let request = PlanRequest {
            sensors: step.sensors.clone(),
            targets: tracks.iter().map(Track::target).collect(),
            history: (!history.is_empty()).then_some(history),
            horizon: step
                .horizon
                .clone()
                .or_else(|| self.settings.horizon.clone()),
            estimator: step.estimator.or(self.settings.estimator),
            coordination: step.coordination.or(self.settings.coordination),
            objective: step.objective.or(self.settings.objective),
            observed: self.settings.observed,
            explain: step.explain,
            min_separation: step
                .min_separation
                .clone()
                .or_else(|| self.settings.min_separation.clone()),
            gap_target: step.gap_target,
            budget_ms: step.budget_ms.clone(),
            certify: step.certify.or(self.settings.certify),
        };
        PreparedStep { request, tracks }
    }

    /// Step 5 of the module docs: records a step whose plan was made.
    pub fn commit(&mut self, prepared: PreparedStep) {
        remember(&mut self.history, self.history_len, &prepared);
        self.tracks = prepared.tracks;
        self.step += 1;
    }

    /// The snapshot of this session once `prepared` is committed
    /// ([`Session::commit`]), the session unchanged, so that it can be
    /// stored while the step's plan is made. `None` for a session that
    /// learns rates: its step also commits what its fold learnt.
    pub fn snapshot_after(&self, prepared: &PreparedStep) -> Option<Snapshot> {
        if self.learner.is_some() {
            return None;
        }
        let mut history = self.history.clone();
        remember(&mut history, self.history_len, prepared);
        Some(Snapshot {
            settings: self.settings.clone(),
            history_len: self.history_len,
            step: self.step + 1,
            history,
            tracks: prepared.tracks.clone(),
            learner: None,
        })
    }
}

/// Puts the sensors' positions of step `prepared` first in `history`, which
/// keeps `len` steps.
fn remember(history: &mut VecDeque<Vec<PositionIn>>, len: usize, prepared: &PreparedStep) {
    if len == 0 {
        return;
    }
    let looks = prepared
        .request
        .sensors
        .iter()
        .map(|s| PositionIn {
            x: s.x,
            y: s.y,
            sensor_type: s.sensor_type.clone(),
        })
        .collect();
    history.push_front(looks);
    history.truncate(len);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::builtins;

    /// A retry's body may lay out, order and spell its numbers otherwise,
    /// integers included; another value is another step.
    #[test]
    fn a_step_digest_reads_values_not_spelling() {
        let parse = |text: &str| -> StepRequest { serde_json::from_str(text).expect("a step") };
        let one =
            parse(r#"{"sensors": [{"id": "a", "x": 75, "y": 75}], "horizon": 3, "budget_ms": 20}"#);
        let same = parse(
            r#"{"budget_ms": 2e1, "horizon": 3.0, "sensors": [{"y": 7.5e1, "x": 75.0, "id": "a"}]}"#,
        );
        assert_eq!(one.digest(), same.digest());
        let other =
            parse(r#"{"sensors": [{"id": "a", "x": 75, "y": 75}], "horizon": 4, "budget_ms": 20}"#);
        assert_ne!(one.digest(), other.digest());
    }

    fn session(history: usize) -> Session {
        let planner = Arc::new(Planner::new(builtins().remove(0)));
        Session::new(
            planner,
            SessionSettings {
                history_steps: Some(history.into()),
                ..SessionSettings::default()
            },
        )
    }

    fn step(detections: Vec<TargetIn>) -> StepRequest {
        StepRequest {
            sensors: vec![SensorIn {
                id: Id::Text("a".into()),
                x: 150.0,
                y: 150.0,
                sensor_type: None,
            }],
            detections,
            ..StepRequest::default()
        }
    }

    fn anonymous(x: f64, y: f64, vx: f64) -> TargetIn {
        TargetIn {
            id: None,
            x,
            y,
            vx,
            vy: 0.0,
        }
    }

    #[test]
    fn anonymous_detections_continue_their_tracks_and_tracks_expire() {
        let mut s = session(2);
        let first = s.prepare(&step(vec![
            anonymous(100.0, 50.0, 10.0),
            anonymous(200.0, 80.0, -5.0),
        ]));
        s.commit(first);
        // The first target again where its track says; a new one elsewhere.
        let second = s.prepare(&step(vec![
            anonymous(110.0, 50.0, 10.0),
            anonymous(20.0, 20.0, 1.0),
        ]));
        assert_eq!(second.request.targets.len(), 3);
        s.commit(second);
        let detected_at: Vec<u64> = s.tracks().iter().map(|t| t.last_detected).collect();
        assert_eq!(detected_at, [1, 0, 1]);
        // Undetected for more than 2 steps: the second target's track goes.
        s.commit(s.prepare(&step(vec![])));
        assert_eq!(s.tracks().len(), 3);
        s.commit(s.prepare(&step(vec![])));
        assert_eq!(s.tracks().len(), 2);
        assert!(s.tracks().iter().all(|t| t.last_detected == 1));
        // Positions moved on one step at a time.
        assert_eq!((s.tracks()[0].x, s.tracks()[0].y), (130.0, 50.0));
        assert_eq!(s.history_held(), 2);
        assert_eq!(s.step(), 4);
    }

    #[test]
    fn two_anonymous_detections_at_one_place_are_two_targets() {
        let s = session(4);
        let prepared = s.prepare(&step(vec![
            anonymous(100.0, 50.0, 1.0),
            anonymous(100.0, 50.0, 1.0),
        ]));
        assert_eq!(prepared.request.targets.len(), 2);
    }

    #[test]
    fn tracks_leaving_the_zone_are_dropped() {
        let mut s = session(16);
        s.commit(s.prepare(&step(vec![anonymous(295.0, 50.0, 10.0)])));
        assert_eq!(s.tracks().len(), 1);
        s.commit(s.prepare(&step(vec![])));
        assert!(s.tracks().is_empty());
    }

    #[test]
    fn bad_detections_are_named() {
        let mut req = step(vec![anonymous(1.0, f64::NAN, 0.0)]);
        let e = req.check().unwrap_err();
        assert_eq!(e.field, "detections[0].y");
        req.detections = vec![anonymous(1.0, 1.0, 0.0); MAX_TARGETS + 1];
        assert_eq!(req.check().unwrap_err().field, "detections");
    }

    /// What a step stores while its plan is made is what committing it
    /// leaves, history full or not, and for no history at all.
    #[test]
    fn a_snapshot_after_a_step_is_the_committed_one() {
        for history in [0, 2] {
            let mut s = session(history);
            for k in 0..4u32 {
                let x = 50.0 + f64::from(k) * 7.0;
                let prepared = s.prepare(&step(vec![anonymous(x, 30.0, 1.5)]));
                let after = s
                    .snapshot_after(&prepared)
                    .expect("a session that does not learn");
                assert_eq!(s.step(), u64::from(k), "unchanged until committed");
                s.commit(prepared);
                assert_eq!(after, s.snapshot());
            }
        }
    }

    #[test]
    fn a_snapshot_restores_the_session_to_the_bit() {
        let mut s = session(3);
        for k in 0..5 {
            let x = 100.0 / 3.0 + f64::from(k) * 0.1;
            s.commit(s.prepare(&step(vec![anonymous(x, 1.0 / 7.0, 0.3)])));
        }
        let bytes = s.snapshot().encode();
        let back = Snapshot::decode(&bytes).unwrap();
        assert_eq!(back, s.snapshot());
        let restored = Session::restore(s.planner().clone(), back, None).unwrap();
        let next = step(vec![anonymous(10.0, 20.0, 1.0)]);
        assert_eq!(restored.prepare(&next).request, s.prepare(&next).request);
        assert_eq!(restored.step(), 5);
        assert!(Snapshot::decode(&bytes[..bytes.len() / 2]).is_err());
    }

    #[test]
    fn history_steps_is_bounded() {
        let settings = SessionSettings {
            history_steps: Some((MAX_HISTORY_STEPS + 1).into()),
            ..SessionSettings::default()
        };
        assert_eq!(settings.history_len().unwrap_err().field, "history_steps");
        assert_eq!(
            SessionSettings::default().history_len(),
            Ok(DEFAULT_HISTORY_STEPS)
        );
    }
}
