//! Realistic plan requests: the states of a `vigil-sim` run in which the
//! sensors follow the exact + priority planner (in process), each turned
//! into the request a simulator would send at that step.
//!
//! The reference workload of the performance targets is
//! [`Workload::reference`]: `paper-v10`, 10 sensors on a grid, 16 steps of
//! history and the targets seen within it (about 50), exact + priority,
//! T = 3.

use vigil::planner::{PlanRequest, Planner};
use vigil::scenario::Scenario;
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
        let s: &Scenario = &planner.scenario;
        let mut sim = Sim::with_types(s.clone(), types, Start::Grid, self.seed, self.history);
        for _ in 0..default_warmup(s).max(self.history) {
            sim.observe();
            let stay = sim.sensors.clone();
            sim.advance(stay);
        }
        let mut out = Vec::with_capacity(count);
        while out.len() < count {
            sim.observe();
            let req = sim.plan_request(Policy::Exact, Some(self.horizon));
            let resp = planner
                .plan_request(&req)
                .expect("the simulator's requests are valid");
            let next = sim
                .moves_from_plan(&resp)
                .expect("the planner's moves are legal");
            sim.advance(next);
            out.push(req);
        }
        out
    }
}
