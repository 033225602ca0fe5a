//! Runs: one seed of one policy, many seeds in parallel, and the paper's
//! experiment grids.

use std::io::IsTerminal;
use std::sync::Arc;

use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use tokio::sync::Semaphore;
use vigil::coordination::Objective;
use vigil::fit::SourceRate;
use vigil::scenario::Scenario;

use crate::client::{Client, ClientError};
use crate::driver::{Sim, Start, checked_bound, fleet_types};
use crate::learn::{Learning, Learnt, Tracker};
use crate::metrics::{Metrics, RunAccumulator, StepCount, summarize};
use crate::policy::{ALL_POLICIES, Policy};
use crate::rates::WorldRates;

/// Everything that defines one run but its seed.
#[derive(Debug, Clone)]
pub struct RunConfig {
    /// Row label (e.g. `1a`).
    pub label: String,
    /// How the sensors move.
    pub policy: Policy,
    /// The scenario's id on the server.
    pub scenario_id: String,
    /// The scenario, validated locally.
    pub scenario: Scenario,
    /// Number of sensors.
    pub sensors: usize,
    /// Their types, as `NAME:COUNT,…` (e.g. `drone:4,robot:6`, adding up to
    /// `sensors`, checked by [`fleet_types`] before runs start); `None`:
    /// every sensor is `default`.
    pub fleet: Option<String>,
    /// Measured steps.
    pub steps: usize,
    /// Steps before measuring (sensors observe but hold still).
    pub warmup: usize,
    /// Plan horizon; the scenario's by default.
    pub horizon: Option<usize>,
    /// Steps of history reported to the planner.
    pub history: usize,
    /// Sensors' starting positions.
    pub start: Start,
    /// Minimum separation between sensors, cells (0..=16); `None`: the
    /// scenario's. Planner policies send it with each plan request (only
    /// when set); the local policies keep it through
    /// [`crate::policy::keep_apart`].
    pub min_separation: Option<usize>,
    /// Planner policies plan through a session (`POST /v1/sessions/…/step`,
    /// every step of the run, warm-up included) instead of stateless plan
    /// requests; the plans, and so the metrics, are the same.
    pub session: bool,
    /// `scenario_id` is `scenario` told no obstacles (a control): plans
    /// come from a model that sees through walls and flies targets through
    /// buildings, and are judged in the world with them. A planned move
    /// the world forbids (a ground sensor onto a building's cell) becomes
    /// the legal move nearest to it ([`Sim::blind`]).
    pub blind: bool,
    /// The world's sources emit at other rates than the planner is told
    /// (`--world-rates`): `scenario`, the world, already has its sources'
    /// rates scaled by these factors (see [`crate::rates::world_scenario`]);
    /// `scenario_id` is the scenario as given unless `told`, when it was
    /// registered with the world's rates. Recorded in the report; `None`:
    /// the world emits at the rates the planner is told.
    pub world_rates: Option<WorldRates>,
    /// The world starts in its stationary state ([`Sim::start_stationary`])
    /// instead of empty (`--stationary-start`); the warm-up still runs. A
    /// learning session assumes a stationary world from its first step.
    pub stationary_start: bool,
}

impl RunConfig {
    /// The run of `seed` after its warm-up: the zone has filled to its
    /// stationary state while the sensors watched from their starting
    /// cells, building tracks and history; the measured window starts now.
    pub fn warmed_up(&self, seed: u64) -> Sim {
        let mut sim = self.fresh(seed);
        for _ in 0..self.warmup {
            sim.observe();
            let stay = sim.sensors.clone();
            sim.advance(stay);
        }
        sim.start_window();
        sim
    }

    /// The run of `seed` before its warm-up.
    pub fn fresh(&self, seed: u64) -> Sim {
        let mut sim = Sim::with_types(
            self.scenario.clone(),
            self.types(),
            self.start,
            seed,
            self.history,
        );
        sim.min_separation = self.min_separation;
        sim.blind = self.blind;
        if self.stationary_start {
            sim.start_stationary();
        }
        sim
    }
}

impl RunConfig {
    /// The minimum separation in force, cells: this configuration's or the
    /// scenario's.
    pub fn separation(&self) -> usize {
        self.min_separation.unwrap_or(self.scenario.min_separation)
    }

    /// Each sensor's type. A fleet that does not fit the scenario (which
    /// [`fleet_types`] reports before runs start) falls back to `default`.
    pub fn types(&self) -> Vec<usize> {
        fleet_types(&self.scenario, self.fleet.as_deref(), self.sensors)
            .unwrap_or_else(|_| vec![0; self.sensors])
    }
}

/// A failed run.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The planner could not be reached or refused a request.
    #[error(transparent)]
    Client(#[from] ClientError),
    /// The planner broke its contract.
    #[error("{0}")]
    Contract(String),
}

/// Runs one seed. Returns the run's averages and, when `keep` is set, the
/// finished simulation (for pictures). [`run_learning`] also gives what a
/// learning policy learnt.
pub async fn run_one(
    client: &Client,
    cfg: &RunConfig,
    seed: u64,
    keep: bool,
) -> Result<(Metrics, Option<Sim>), RunError> {
    let out = run_learning(client, cfg, seed, keep).await?;
    Ok((out.metrics, out.sim))
}

/// One seed's run, all it gives.
pub struct RunOutcome {
    /// The run's averages.
    pub metrics: Metrics,
    /// A policy that learns the rates ([`Policy::learns_rates`]): what it
    /// learnt.
    pub learnt: Option<Learnt>,
    /// The session's rates before its first step (its prior's means: the
    /// rates the planner was told), for a learning policy.
    pub prior_rates: Option<Vec<f64>>,
    /// The finished simulation, when asked for.
    pub sim: Option<Sim>,
}

/// The world's rate of each source: `cfg.scenario`'s, the world's (with
/// `--world-rates` already applied).
pub fn true_rates(cfg: &RunConfig) -> Vec<f64> {
    cfg.scenario.sources.iter().map(|s| s.rate).collect()
}

/// Runs one seed, as [`run_one`], and for a policy that learns the rates
/// follows them step by step: it plans through a learning session
/// (`learn_rates: true`) whatever `cfg.session` says, and checks that
/// every step's response has `rates`.
pub async fn run_learning(
    client: &Client,
    cfg: &RunConfig,
    seed: u64,
    keep: bool,
) -> Result<RunOutcome, RunError> {
    let planner = cfg.policy.planner().is_some();
    let learns = cfg.policy.learns_rates();
    let session = (cfg.session && planner) || learns;
    let mut tracker = learns.then(|| Tracker::new(true_rates(cfg)));
    // A learning session's step must report its rates.
    let mut follow = |rates: Option<&[SourceRate]>| -> Result<(), RunError> {
        match (tracker.as_mut(), rates) {
            (Some(t), Some(rates)) => t.add(rates).map_err(RunError::Contract),
            (Some(_), None) => Err(RunError::Contract(
                "a learning session's step without its rates".into(),
            )),
            (None, _) => Ok(()),
        }
    };
    let mut prior_rates = None;
    let (mut sim, session) = if session {
        // The session must see every step, the warm-up's too, to hold the
        // history and tracks the stateless requests would carry (and, when
        // learning, to count every target and look).
        let mut sim = cfg.fresh(seed);
        let settings = sim.session_settings(cfg.policy, cfg.horizon, cfg.history);
        let info = client.open_session(&cfg.scenario_id, &settings).await?;
        if learns {
            let rates = info
                .rates
                .as_deref()
                .ok_or_else(|| RunError::Contract("a learning session without its rates".into()))?;
            prior_rates = Some(rates.iter().map(|r| r.rate).collect());
        }
        let id = info.id;
        for _ in 0..cfg.warmup {
            sim.observe();
            let (resp, _) = client
                .step(&id, &sim.step_request(cfg.policy, cfg.horizon))
                .await?;
            follow(resp.rates.as_deref())?;
            let stay = sim.sensors.clone();
            sim.advance(stay);
        }
        sim.start_window();
        (sim, Some(id))
    } else {
        (cfg.warmed_up(seed), None)
    };
    let mut acc = RunAccumulator::default();
    for _ in 0..cfg.steps {
        sim.observe();
        let (next, predicted) = if planner {
            let (resp, ms) = match &session {
                Some(id) => {
                    let (resp, ms) = client
                        .step(id, &sim.step_request(cfg.policy, cfg.horizon))
                        .await?;
                    follow(resp.rates.as_deref())?;
                    (resp.plan, ms)
                }
                None => {
                    let req = sim.plan_request(cfg.policy, cfg.horizon);
                    client.plan(&cfg.scenario_id, &req).await?
                }
            };
            acc.add_plan_time(ms);
            if let Some(bound) = checked_bound(&resp).map_err(RunError::Contract)? {
                acc.add_gap(bound.gap);
            }
            if let Some(joint) = &resp.joint {
                acc.add_joint(joint);
            }
            acc.add_plan_violations(
                resp.separation_violations,
                resp.plans.iter().map(|p| p.separation_violations),
            );
            let next = sim.moves_from_plan(&resp).map_err(RunError::Contract)?;
            (next, resp.expected_by_step.first().copied())
        } else {
            (sim.local_moves(cfg.policy), None)
        };
        let count = sim.advance(next);
        acc.add(count);
        if let Some(p) = predicted {
            acc.add_calibration(p, realized(cfg.policy, &count));
        }
    }
    if let Some(id) = &session {
        client.close_session(id).await?;
    }
    let metrics = acc.finish(sim.entries());
    Ok(RunOutcome {
        metrics,
        learnt: tracker.map(|t| t.finish(seed)),
        prior_rates,
        sim: keep.then_some(sim),
    })
}

/// What a plan's first step predicts, as it happened: the targets detected
/// (for a policy maximising first detections, those detected for the first
/// time).
pub fn realized(policy: Policy, count: &StepCount) -> usize {
    match policy.planner().map(|p| p.objective) {
        Some(Objective::FirstDetections) => count.first_detected,
        _ => count.detected,
    }
}

/// One row of a report: a configuration averaged over seeds.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// Row label.
    pub label: String,
    /// Policy name.
    pub policy: String,
    /// Scenario id.
    pub scenario: String,
    /// Number of sensors.
    pub sensors: usize,
    /// Their types (`drone:4,robot:6`), when given.
    pub fleet: Option<String>,
    /// Target speed, when every target flies at one speed (null for a
    /// speed mixture).
    pub target_speed: Option<f64>,
    /// Measured steps per run.
    pub steps: usize,
    /// Minimum separation in force, cells (0: none).
    pub min_separation: usize,
    /// Seeds averaged.
    pub seeds: usize,
    /// The factors of the world's sources' rates over the scenario's, one
    /// per source (`--world-rates`); null when the world emits at the
    /// scenario's rates.
    pub world_rates: Option<Vec<f64>>,
    /// The planner was told the world's rates (`--tell-world-rates`:
    /// `scenario` is the spec registered with them), not the scenario's.
    pub told_world_rates: bool,
    /// The world started in its stationary state (`--stationary-start`);
    /// absent when it started empty.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub stationary_start: bool,
    /// Means over seeds.
    pub metrics: Metrics,
    /// Half-widths of the 95% confidence intervals.
    pub ci95: Metrics,
    /// A policy that learns the rates (`exact-learn`): what it learnt,
    /// against the world's rates. Absent for the other policies.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub learning: Option<Learning>,
}

/// Runs every configuration for seeds `seed..seed+seeds` (the same seeds,
/// hence the same target streams, for every configuration), at most `jobs`
/// runs at a time.
pub async fn run_all(
    client: &Client,
    configs: &[RunConfig],
    seed: u64,
    seeds: usize,
    jobs: usize,
) -> Result<Vec<Row>, RunError> {
    let total = (configs.len() * seeds) as u64;
    let bar = if std::io::stderr().is_terminal() {
        let bar = ProgressBar::new(total);
        if let Ok(style) =
            ProgressStyle::with_template("{bar:40} {pos}/{len} runs  {elapsed} (eta {eta}) {msg}")
        {
            bar.set_style(style);
        }
        bar
    } else {
        ProgressBar::hidden()
    };
    let permits = Arc::new(Semaphore::new(jobs.max(1)));
    let mut tasks = tokio::task::JoinSet::new();
    for (ci, cfg) in configs.iter().enumerate() {
        for k in 0..seeds {
            let (client, cfg, permits, bar) =
                (client.clone(), cfg.clone(), permits.clone(), bar.clone());
            tasks.spawn(async move {
                let _permit = permits.acquire_owned().await;
                let out = run_learning(&client, &cfg, seed + k as u64, false).await;
                bar.inc(1);
                bar.set_message(cfg.label.clone());
                (ci, k, out)
            });
        }
    }
    let mut results: Vec<Vec<Option<RunOutcome>>> = (0..configs.len())
        .map(|_| (0..seeds).map(|_| None).collect())
        .collect();
    while let Some(joined) = tasks.join_next().await {
        let (ci, k, out) =
            joined.map_err(|e| RunError::Contract(format!("a run panicked: {e}")))?;
        results[ci][k] = Some(out?);
    }
    bar.finish_and_clear();
    Ok(configs
        .iter()
        .zip(results)
        .map(|(cfg, outcomes)| {
            let outcomes: Vec<RunOutcome> = outcomes.into_iter().flatten().collect();
            let runs: Vec<Metrics> = outcomes.iter().map(|o| o.metrics).collect();
            let (metrics, ci95) = summarize(&runs);
            let prior_rates = outcomes.iter().find_map(|o| o.prior_rates.clone());
            let learnt: Vec<Learnt> = outcomes.into_iter().filter_map(|o| o.learnt).collect();
            let learning = (!learnt.is_empty()).then(|| {
                crate::learn::summarize(
                    learnt,
                    true_rates(cfg),
                    prior_rates.unwrap_or_default(),
                    cfg.warmup,
                )
            });
            Row {
                label: cfg.label.clone(),
                policy: cfg.policy.name().to_owned(),
                scenario: cfg.scenario_id.clone(),
                sensors: cfg.sensors,
                fleet: cfg.fleet.clone(),
                target_speed: cfg.scenario.single_speed(),
                steps: cfg.steps,
                min_separation: cfg.separation(),
                seeds: runs.len(),
                world_rates: cfg.world_rates.as_ref().map(|w| w.scales.clone()),
                told_world_rates: cfg.world_rates.as_ref().is_some_and(|w| w.told),
                stationary_start: cfg.stationary_start,
                metrics,
                ci95,
                learning,
            }
        })
        .collect())
}

/// The paper's experiment grid: (number of sensors, scenario id), numbered
/// 1–4 as our table rows.
pub const GRID: [(usize, &str); 4] = [
    (10, "paper-v10"),
    (6, "paper-v10"),
    (10, "paper-v15"),
    (6, "paper-v15"),
];

/// The `mixed` experiment's grid: the `site-gates` scenario (walkers,
/// cyclists and vehicles from directed gates) with 10 and 6 sensors.
pub const MIXED_GRID: [(usize, &str); 2] = [(10, "site-gates"), (6, "site-gates")];

/// The `fleet` experiment's grid: the built-in `site-fleet` (robots and
/// drones around no-go zones) with ten sensors, in the fleets of
/// [`FLEETS`].
pub const FLEET_GRID: [(usize, &str); 3] =
    [(10, "site-fleet"), (10, "site-fleet"), (10, "site-fleet")];

/// The fleets of the `fleet` experiment's rows: ten robots, four drones
/// and six robots, ten drones.
pub const FLEETS: [&str; 3] = ["robot:10", "drone:4,robot:6", "drone:10"];

/// The experiments, by name.
pub const EXPERIMENTS: [&str; 4] = ["table1", "table2", "mixed", "fleet"];

/// The grid of an experiment: [`GRID`] for the paper's tables,
/// [`MIXED_GRID`] for `mixed`, [`FLEET_GRID`] for `fleet`.
pub fn experiment_grid(name: &str) -> Option<&'static [(usize, &'static str)]> {
    match name {
        "table1" | "table2" => Some(&GRID),
        "mixed" => Some(&MIXED_GRID),
        "fleet" => Some(&FLEET_GRID),
        _ => None,
    }
}

/// The fleet of row `n` of an experiment's grid, if its sensors have types.
pub fn experiment_fleet(name: &str, n: usize) -> Option<&'static str> {
    (name == "fleet").then(|| FLEETS.get(n).copied()).flatten()
}

/// The policies of an experiment, with their row letters: Table 1 compares
/// the paper's method with (a) and without (b) coordination; Table 2,
/// `mixed` and `fleet` run every policy of [`ALL_POLICIES`].
pub fn experiment_policies(name: &str) -> Option<Vec<(char, Policy)>> {
    match name {
        "table1" => Some(vec![
            ('a', Policy::Paper),
            ('b', Policy::PaperUncoordinated),
        ]),
        "table2" | "mixed" | "fleet" => Some(('a'..).zip(ALL_POLICIES).collect()),
        _ => None,
    }
}

/// The rows of an experiment that runs only the policies `chosen`, in the
/// order given (repeats dropped), or all of its own when `chosen` is empty.
/// A policy keeps its letter from the experiment's own list, so `1d` is
/// `exact-iterated` in every Table 2; one outside it (`exact-joint`, `exact-learn`) takes
/// the letters after that list's, in the order given.
pub fn chosen_policies(name: &str, chosen: &[Policy]) -> Option<Vec<(char, Policy)>> {
    let own = experiment_policies(name)?;
    if chosen.is_empty() {
        return Some(own);
    }
    let mut extra = ('a'..).skip(own.len());
    let mut rows: Vec<(char, Policy)> = Vec::new();
    for &policy in chosen {
        if rows.iter().any(|&(_, p)| p == policy) {
            continue;
        }
        let letter = match own.iter().find(|&&(_, p)| p == policy) {
            Some(&(letter, _)) => letter,
            None => extra.next()?,
        };
        rows.push((letter, policy));
    }
    Some(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chosen_policies_keep_their_letters() {
        let all = chosen_policies("table2", &[]).expect("table2");
        assert_eq!(all.len(), ALL_POLICIES.len());
        assert!(!all.iter().any(|&(_, p)| p == Policy::ExactJoint));
        assert!(!all.iter().any(|&(_, p)| p.learns_rates()));
        let two = chosen_policies(
            "table2",
            &[
                Policy::ExactJoint,
                Policy::ExactIterated,
                Policy::ExactJoint,
            ],
        );
        assert_eq!(
            two,
            Some(vec![
                ('j', Policy::ExactJoint),
                ('d', Policy::ExactIterated)
            ])
        );
        assert_eq!(
            chosen_policies("table1", &[Policy::Paper, Policy::ExactJoint]),
            Some(vec![('a', Policy::Paper), ('c', Policy::ExactJoint)])
        );
        assert_eq!(
            chosen_policies(
                "mixed",
                &[
                    Policy::ExactLearn,
                    Policy::ExactIterated,
                    Policy::ExactJoint
                ]
            ),
            Some(vec![
                ('j', Policy::ExactLearn),
                ('d', Policy::ExactIterated),
                ('k', Policy::ExactJoint)
            ])
        );
        assert_eq!(chosen_policies("table3", &[Policy::Paper]), None);
    }
}
