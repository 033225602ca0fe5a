//! Realistic plan requests: the states of a `vigil-sim` run in which the
//! sensors follow the exact + priority planner (in process), each turned
//! into the request a simulator would send at that step.
//!
//! The reference workload of the performance targets is
//! [`Workload::reference`]: `paper-v10`, 10 sensors on a grid, 16 steps of
//! history and the targets seen within it (about 50), exact + priority,
//! T = 3.

use vigil::planner::{PlanRequest, Planner, TargetIn};
use vigil::scenario::{
    SITE_CYCLIST, SITE_VEHICLE, SITE_WALKER, Scenario, SourceSpec, SpeedSpec, site_gates_spec,
};
use vigil::session::{SessionSettings, StepRequest};
use vigil_sim::driver::{Sim, Start, default_warmup};
use vigil_sim::policy::Policy;

/// What a run of the simulator looks like.
#[derive(Debug, Clone)]
pub struct Workload {
    /// Sensors.
    pub sensors: usize,
    /// Steps of history in each request.
    pub history: usize,
    /// Horizon T of each request.
    pub horizon: usize,
    /// Seed of the target process.
    pub seed: u64,
}

impl Workload {
    /// The reference workload: 10 sensors, 16 steps of history, T = 3.
    pub fn reference() -> Self {
        Workload {
            sensors: 10,
            history: 16,
            horizon: 3,
            seed: 1,
        }
    }

    /// `count` consecutive requests of one run on `planner`'s scenario,
    /// after the warm-up (the zone at its stationary population, the history
    /// full). Between requests the sensors move along the planner's answer,
    /// so the requests are the ones a simulator would send.
    ///
    /// # Panics
    /// If the planner refuses a request the simulator built (a bug).
    pub fn requests(&self, planner: &Planner, count: usize) -> Vec<PlanRequest> {
        self.requests_of_fleet(planner, count, vec![0; self.sensors])
    }

    /// The same with sensors of the scenario's types `types` (one entry per
    /// sensor; `self.sensors` is ignored).
    ///
    /// # Panics
    /// As [`Workload::requests`].
    pub fn requests_of_fleet(
        &self,
        planner: &Planner,
        count: usize,
        types: Vec<usize>,
    ) -> Vec<PlanRequest> {
        self.replay(planner, count, types, false).0
    }

    /// The session steps of the same run as [`Workload::requests`]: every
    /// step from the run's start, so that a session replaying them holds
    /// at timed step `k` exactly the state of stateless request `k` (its
    /// history full, its tracks those of the request), and the settings of
    /// that session (exact + priority, T, `history` steps kept).
    ///
    /// # Panics
    /// As [`Workload::requests`].
    pub fn session(&self, planner: &Planner, count: usize) -> SessionWorkload {
        self.replay(planner, count, vec![0; self.sensors], true).1
    }

    /// Both at once, from one run: the stateless requests and the session
    /// steps of the same states (`requests[k]` is the state of
    /// `session.steps[k]`).
    ///
    /// # Panics
    /// As [`Workload::requests`].
    pub fn requests_and_session(
        &self,
        planner: &Planner,
        count: usize,
    ) -> (Vec<PlanRequest>, SessionWorkload) {
        self.requests_and_session_of_fleet(planner, count, vec![0; self.sensors])
    }

    /// The same with sensors of the scenario's types `types` (one entry per
    /// sensor; `self.sensors` is ignored).
    ///
    /// # Panics
    /// As [`Workload::requests`].
    pub fn requests_and_session_of_fleet(
        &self,
        planner: &Planner,
        count: usize,
        types: Vec<usize>,
    ) -> (Vec<PlanRequest>, SessionWorkload) {
        self.replay(planner, count, types, true)
    }

    /// The run behind [`Workload::requests_of_fleet`] and
    /// [`Workload::session`]: the warm-up (sensors staying put while the
    /// zone fills), then `count` steps moving along the planner's answer.
    /// With `steps`, every step's session body is recorded too (building
    /// it draws nothing, so the stateless requests are the same either
    /// way).
    fn replay(
        &self,
        planner: &Planner,
        count: usize,
        types: Vec<usize>,
        steps: bool,
    ) -> (Vec<PlanRequest>, SessionWorkload) {
        let s: &Scenario = &planner.scenario;
        let mut sim = Sim::with_types(s.clone(), types, Start::Grid, self.seed, self.history);
        let mut session = SessionWorkload {
            settings: sim.session_settings(Policy::Exact, Some(self.horizon), self.history),
            warmup: Vec::new(),
            steps: Vec::new(),
        };
        for _ in 0..default_warmup(s).max(self.history) {
            sim.observe();
            if steps {
                session
                    .warmup
                    .push(sim.step_request(Policy::Exact, Some(self.horizon)));
            }
            let stay = sim.sensors.clone();
            sim.advance(stay);
        }
        let mut out = Vec::with_capacity(count);
        while out.len() < count {
            sim.observe();
            let req = sim.plan_request(Policy::Exact, Some(self.horizon));
            if steps {
                session
                    .steps
                    .push(sim.step_request(Policy::Exact, Some(self.horizon)));
            }
            let resp = planner
                .plan_request(&req)
                .expect("the simulator's requests are valid");
            let next = sim
                .moves_from_plan(&resp)
                .expect("the planner's moves are legal");
            sim.advance(next);
            out.push(req);
        }
        (out, session)
    }
}

/// A session's replay of a simulator run: what `POST /v1/sessions` and its
/// steps send.
#[derive(Debug, Clone)]
pub struct SessionWorkload {
    /// The session's settings (exact + priority, T, the history kept).
    pub settings: SessionSettings,
    /// The steps of the run's warm-up, before the first timed step: replayed
    /// untimed into a fresh session so that its history and tracks are
    /// full when timing starts.
    pub warmup: Vec<StepRequest>,
    /// The timed steps: step `k` leads to the state of the stateless
    /// request `k` of the same run.
    pub steps: Vec<StepRequest>,
}

/// `req` with exactly `n` targets: its own first ones, then more on a
/// deterministic spiral through the zone of `s`, moving at its fastest
/// targets' speed (more than the model would put there: a stress test of
/// the cost of reported targets).
pub fn with_targets(s: &Scenario, req: &PlanRequest, n: usize) -> PlanRequest {
    let mut targets: Vec<TargetIn> = req.targets.iter().take(n).cloned().collect();
    let mut k = 0usize;
    while targets.len() < n {
        let a = k as f64 * 2.399_963;
        let f = ((k % 997) as f64 + 0.5) / 997.0;
        targets.push(TargetIn {
            id: None,
            x: s.width * (0.5 + 0.49 * f.sqrt() * a.cos()),
            y: s.height * (0.5 + 0.49 * f.sqrt() * a.sin()),
            vx: s.max_speed() * a.sin(),
            vy: -s.max_speed() * a.cos(),
        });
        k += 1;
    }
    PlanRequest {
        targets,
        ..req.clone()
    }
}

/// `site-gates` with every source's speed distribution replaced by `k`
/// classes spread over the walkers' to the vehicles' speed (equal weights):
/// k = 1 is the walkers' speed alone, 2 walkers and vehicles, 4 (or more)
/// walkers, cyclists, 8 m/step and vehicles; cones and rates unchanged.
pub fn site_with_classes(k: usize) -> Scenario {
    let mut spec = site_gates_spec();
    let speeds: Vec<f64> = match k {
        1 => vec![SITE_WALKER],
        2 => vec![SITE_WALKER, SITE_VEHICLE],
        _ => vec![SITE_WALKER, SITE_CYCLIST, 8.0, SITE_VEHICLE],
    };
    for src in &mut spec.sources {
        src.speeds = Some(
            speeds
                .iter()
                .map(|&speed| SpeedSpec { speed, weight: 1.0 })
                .collect(),
        );
    }
    // Valid: only the speed distributions of a valid spec changed.
    Scenario::new(spec).unwrap_or_else(|e| panic!("site-gates with {k} classes: {e}"))
}

/// The paper's eight sources (two beside each edge, at thirds, rate 0.3)
/// around a square zone of side `w`.
pub fn paper_like_sources(w: f64) -> Vec<SourceSpec> {
    let src = |x: f64, y: f64| SourceSpec::at(x, y, 0.3);
    vec![
        src(-1.0, w / 3.0),
        src(-1.0, 2.0 * w / 3.0),
        src(w + 1.0, w / 3.0),
        src(w + 1.0, 2.0 * w / 3.0),
        src(w / 3.0, -1.0),
        src(2.0 * w / 3.0, -1.0),
        src(w / 3.0, w + 1.0),
        src(2.0 * w / 3.0, w + 1.0),
    ]
}
