//! Memory a session holds on the reference workload (`paper-v10`, 10
//! sensors, exact + priority, T = 3), against its history window: a run of
//! `vigil-sim`'s world is stepped through an in-process session (the
//! warm-up, then 100 planned steps), and `Session::memory_bytes` is read
//! after every planned step.
//!
//! `cargo run --release -p vigil-loadtest --example session_memory`
#![allow(missing_docs, clippy::unwrap_used)]

use std::sync::Arc;

use vigil::planner::Planner;
use vigil::scenario::builtins;
use vigil::session::Session;
use vigil_sim::driver::{Sim, Start, default_warmup};
use vigil_sim::policy::Policy;

fn main() {
    let planner = Arc::new(Planner::new(builtins().remove(0)));
    let s = &planner.scenario;
    println!("history  tracks (mean)  bytes (mean)  bytes (max)");
    for history in [0, 4, 8, 16, 32] {
        let mut sim = Sim::new(s.clone(), 10, Start::Grid, 1, history);
        let settings = sim.session_settings(Policy::Exact, Some(3), history);
        let mut session = Session::new(planner.clone(), settings);
        let warmup = default_warmup(s).max(history);
        let (mut bytes, mut most, mut tracks, mut n) = (0usize, 0usize, 0usize, 0usize);
        for step in 0..warmup + 100 {
            sim.observe();
            let prepared = session.prepare(&sim.step_request(Policy::Exact, Some(3)));
            let plan = planner.plan_request(&prepared.request).unwrap();
            session.commit(prepared);
            let next = if step < warmup {
                sim.sensors.clone()
            } else {
                let m = session.memory_bytes();
                bytes += m;
                most = most.max(m);
                tracks += session.tracks().len();
                n += 1;
                sim.moves_from_plan(&plan).unwrap()
            };
            sim.advance(next);
        }
        println!(
            "{history:>7}  {:>13.1}  {:>12.0}  {most:>11}",
            tracks as f64 / n as f64,
            bytes as f64 / n as f64
        );
    }
}
