//! `vigil-sim`: simulates the world and drives a Vigil planner over HTTP one
//! step at a time; reproduces the paper's tables against baselines.
//!
//! ```text
//! vigil-sim --experiment table1 --seeds 10          # the paper's Table 1
//! vigil-sim --experiment table2                     # every policy
//! vigil-sim --experiment table2 --policy exact-iterated,exact-joint --seeds 10
//! vigil-sim --experiment mixed                      # every policy on site-gates
//! vigil-sim --experiment fleet                      # every policy on site-fleet, three fleets
//! vigil-sim --scenario site-fleet --fleet drone:4,robot:6 --svg fleet.svg
//! vigil-sim --policy exact --sensors 10 --svg run.svg
//! vigil-sim --live --policy exact --sensors 10      # watch one run in a browser
//! vigil-sim --experiment table1 --min-separation 3 # sensors ≥ 3 cells apart
//! vigil-sim --policy exact --world-rates 3          # the world emits 3× what the planner is told
//! vigil-sim --policy exact --world-rates 3 --tell-world-rates   # … and the planner is told
//! vigil-sim --policy exact-learn --world-rates 3    # … or learns them from its detections
//! ```
//! Without `--server` it starts a server in-process on a loopback port and
//! still talks HTTP to it.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use vigil::scenario::{Scenario, ScenarioSpec};
use vigil_sim::client::{Client, spawn_local_server};
use vigil_sim::driver::{Start, default_warmup, fleet_size, fleet_types};
use vigil_sim::experiment::{
    EXPERIMENTS, RunConfig, chosen_policies, experiment_fleet, experiment_grid, run_all, run_one,
};
use vigil_sim::live::{Live, LiveOptions};
use vigil_sim::policy::Policy;
use vigil_sim::rates::{RateScales, WorldRates, world_scenario};
use vigil_sim::{report, svg};

/// Command-line options.
#[derive(Debug, Parser)]
#[command(
    version,
    about = "Drives the Vigil planner step by step over HTTP and reproduces the paper's tables"
)]
struct Args {
    /// Run an experiment grid: `table1` (paper vs paper-uncoordinated) or
    /// `table2` (every policy) over NS ∈ {10, 6} × TV ∈ {10, 15}, or `mixed`
    /// (every policy on `site-gates` with NS ∈ {10, 6}), or `fleet` (every
    /// policy on `site-fleet` with ten robots, four drones and six robots,
    /// ten drones). "Every policy" leaves out `exact-joint` and
    /// `exact-learn`; `--policy` picks the rows' policies instead, e.g.
    /// `--policy exact-iterated,exact-joint`.
    #[arg(long)]
    experiment: Option<String>,
    /// Policy of a single run (`exact` by default). With `--experiment`,
    /// the experiment runs these policies instead of its own (each keeps
    /// its row letter; `exact-joint` and `exact-learn`, in no experiment's
    /// own list, come after). Comma-separated or repeated; several without
    /// `--experiment` run one row each. `exact-learn` plans through a
    /// session that learns the sources' rates, with or without
    /// `--session`, and reports what it learnt under the table.
    #[arg(long, value_enum, value_delimiter = ',')]
    policy: Vec<Policy>,
    /// Number of sensors of a single run.
    #[arg(long, default_value_t = 10)]
    sensors: usize,
    /// Sensor types of a single run, `NAME:COUNT,…` (e.g. `drone:4,robot:6`,
    /// types of the scenario's `sensor_types`); sets the number of sensors.
    /// By default every sensor is of the type `default`.
    #[arg(long)]
    fleet: Option<String>,
    /// Scenario of a single run: a server id, or a ScenarioSpec JSON file.
    #[arg(long, default_value = "paper-v10")]
    scenario: String,
    /// Measured steps per run.
    #[arg(long, default_value_t = 150)]
    steps: usize,
    /// Steps before measuring; default: the steps a target needs to cross
    /// the zone's diagonal.
    #[arg(long)]
    warmup: Option<usize>,
    /// Seeds per configuration (runs `seed`, `seed+1`, …).
    #[arg(long, default_value_t = 5)]
    seeds: usize,
    /// First seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Plan horizon T; the scenario's by default.
    #[arg(long)]
    horizon: Option<usize>,
    /// Steps of history (sensor positions and tracks) reported to the planner.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u8).range(0..=vigil::limits::MAX_HISTORY_STEPS as i64))]
    history: u8,
    /// Where the sensors start.
    #[arg(long, value_enum, default_value_t = Start::Grid)]
    start: Start,
    /// Plan through sessions (`POST /v1/sessions/{id}/step`: the server
    /// keeps the history and the tracks) instead of stateless requests; the
    /// plans and metrics are the same. `exact-learn` always plans through
    /// a (learning) session.
    #[arg(long)]
    session: bool,
    /// A running vigil-server (e.g. http://127.0.0.1:8080); by default one
    /// is started in-process.
    #[arg(long)]
    server: Option<String>,
    /// Write the results as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Draw a single run (its first seed) as SVG.
    #[arg(long)]
    svg: Option<PathBuf>,
    /// Runs in flight at once.
    #[arg(long, default_value_t = 4)]
    jobs: usize,
    /// Watch a single run (seed `--seed`) in a browser: serves a page on
    /// `--live-bind` and steps at the rate the page sets. Closing the page
    /// does not stop the run; after its last step the final state stays
    /// served until Ctrl-C.
    #[arg(long)]
    live: bool,
    /// Address of the live view's page.
    #[arg(long, default_value = "127.0.0.1:8090")]
    live_bind: String,
    /// Steps per second of the live view at the start (the page changes it).
    #[arg(long, default_value_t = 10.0)]
    live_speed: f64,
    /// Minimum separation between sensors, cells (0..=16; Chebyshev
    /// distance at every step; 0: no rule); the scenario's by default.
    /// Planner policies send it with each plan request; the local policies
    /// (random, local-force, stationary) keep it by moving each sensor, in
    /// sensor order, to its intended cell, else staying, else the nearest
    /// allowed legal move.
    #[arg(long, value_parser = clap::value_parser!(u8).range(0..=vigil::limits::MAX_MIN_SEPARATION as i64))]
    min_separation: Option<u8>,
    /// A control for scenarios with obstacles: ask for plans of the same
    /// scenario told no obstacles (registered without them), and judge them
    /// in the world with them. A planned move the world forbids (a ground
    /// sensor onto a building's cell) becomes the legal move nearest to it.
    #[arg(long)]
    blind: bool,
    /// The world's sources emit at other rates than the planner is told:
    /// source j of the scenario emits at its rate (its total over its
    /// speeds) times the j-th factor. Comma-separated factors ≥ 0, one per
    /// source in the scenario's order (e.g. `3,0.3,1,0`; 0 silences a
    /// source), or one for every source (e.g. `2`). The planner is still
    /// told the scenario as it is, unless `--tell-world-rates`. With
    /// `--experiment`, applied to each row's scenario.
    #[arg(long, value_name = "SCALES", allow_hyphen_values = true, value_parser = RateScales::parse)]
    world_rates: Option<RateScales>,
    /// With `--world-rates`: tell the planner the world's rates, asking for
    /// plans of the scenario registered with them (the control of a
    /// planner told the wrong rates).
    #[arg(long)]
    tell_world_rates: bool,
    /// The world starts in its stationary state, as if its sources had
    /// always emitted (targets drawn from the world's own RNG, so every
    /// policy of a seed still sees the same ones), instead of empty; the
    /// warm-up still runs. A learning session (`exact-learn`) assumes a
    /// stationary world from its first step: in a world filling up from
    /// empty, what it learns during the fill is biased low.
    #[arg(long)]
    stationary_start: bool,
}

#[tokio::main]
async fn main() -> ExitCode {
    let args = Args::parse();
    match run(args).await {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("vigil-sim: {e}");
            ExitCode::FAILURE
        }
    }
}

async fn resolve(client: &Client, scenario: &str) -> Result<(String, Scenario), String> {
    let info = if scenario.ends_with(".json") || std::path::Path::new(scenario).is_file() {
        let text = std::fs::read_to_string(scenario).map_err(|e| format!("{scenario}: {e}"))?;
        let spec: ScenarioSpec =
            serde_json::from_str(&text).map_err(|e| format!("{scenario}: {e}"))?;
        client.register(&spec).await.map_err(|e| e.to_string())?
    } else {
        client.scenario(scenario).await.map_err(|e| e.to_string())?
    };
    let info = client
        .wait_ready(info, |i| {
            eprintln!(
                "vigil-sim: scenario {} is {} ({:.0}% done, about {:.0} s left)",
                i.id,
                i.status.as_deref().unwrap_or("pending"),
                100.0 * i.progress.unwrap_or(0.0),
                i.eta_s.unwrap_or(0.0)
            );
        })
        .await
        .map_err(|e| e.to_string())?;
    let local = Scenario::new(info.spec).map_err(|e| format!("{}: {e}", info.id))?;
    Ok((info.id, local))
}

/// Registers `spec` (or finds it registered), waits until it is ready and
/// gives its id.
async fn register(client: &Client, spec: &ScenarioSpec) -> Result<String, String> {
    let info = client.register(spec).await.map_err(|e| e.to_string())?;
    let info = client
        .wait_ready(info, |_| {})
        .await
        .map_err(|e| e.to_string())?;
    Ok(info.id)
}

/// What a run judges its plans in, and what its planner is told.
#[derive(Debug, Clone)]
struct WorldAndTold {
    /// The id of the scenario the planner is told.
    told_id: String,
    /// The world.
    world: Scenario,
    /// The world's rates, when they are not the scenario's.
    world_rates: Option<WorldRates>,
}

/// The world and the told scenario of a run on `scenario` (id `id`): the
/// world is `scenario` with its sources' rates scaled by `rates`, when
/// given; the planner is told `id` itself, or a spec registered with the
/// world's rates when `tell`, without obstacles when `blind`.
async fn world_and_told(
    client: &Client,
    id: String,
    scenario: Scenario,
    rates: Option<&RateScales>,
    tell: bool,
    blind: bool,
) -> Result<WorldAndTold, String> {
    if blind && !scenario.has_obstacles() {
        return Err(format!("--blind: {id} has no obstacles to be blind to"));
    }
    let world_rates = match rates {
        Some(rates) => {
            let scales = rates
                .per_source(scenario.sources.len())
                .map_err(|e| format!("--world-rates: {id}: {e}"))?;
            Some(WorldRates { scales, told: tell })
        }
        None => None,
    };
    let own = scenario.spec.clone();
    let world = match &world_rates {
        Some(w) => world_scenario(&scenario, &w.scales)
            .map_err(|e| format!("--world-rates: {id} at the world's rates: {e}"))?,
        None => scenario,
    };
    // The spec the planner is told, when not `id`'s own: the world's rates,
    // no obstacles, or both.
    let told = (tell || blind).then(|| {
        let spec = if tell { world.spec.clone() } else { own };
        if blind {
            ScenarioSpec {
                obstacles: None,
                ..spec
            }
        } else {
            spec
        }
    });
    let told_id = match told {
        Some(spec) => register(client, &spec).await?,
        None => id.clone(),
    };
    if let Some(w) = &world_rates {
        let scales: Vec<String> = w.scales.iter().map(f64::to_string).collect();
        let planner = if w.told {
            format!("the world's rates (registered as {told_id})")
        } else if told_id != id {
            format!("{id}'s own rates (as {told_id})")
        } else {
            format!("{id}'s own rates")
        };
        eprintln!(
            "vigil-sim: {id}'s sources emit at their rates × [{}] in the world; the planner is told {planner}",
            scales.join(", ")
        );
    }
    Ok(WorldAndTold {
        told_id,
        world,
        world_rates,
    })
}

async fn run(args: Args) -> Result<(), String> {
    if args.tell_world_rates && args.world_rates.is_none() {
        return Err(
            "--tell-world-rates tells the planner the world's rates: give them with --world-rates"
                .into(),
        );
    }
    let base = match &args.server {
        Some(url) => url.clone(),
        None => spawn_local_server()
            .await
            .map_err(|e| format!("cannot start a server: {e}"))?,
    };
    let client = Client::new(&base);
    let config =
        |label: String, policy: Policy, on: &WorldAndTold, sensors: usize, fleet: Option<&str>| {
            RunConfig {
                label,
                policy,
                warmup: args.warmup.unwrap_or_else(|| default_warmup(&on.world)),
                scenario_id: on.told_id.clone(),
                scenario: on.world.clone(),
                sensors,
                fleet: fleet.map(str::to_owned),
                steps: args.steps,
                horizon: args.horizon,
                history: args.history.into(),
                start: args.start,
                min_separation: args.min_separation.map(usize::from),
                session: args.session,
                blind: args.blind,
                world_rates: on.world_rates.clone(),
                stationary_start: args.stationary_start,
            }
        };
    if args.blind && args.experiment.is_some() {
        return Err("--blind is a control of a single run; drop --experiment".into());
    }
    let configs = match &args.experiment {
        Some(name) => {
            let unknown = || format!("unknown experiment `{name}` ({})", EXPERIMENTS.join(", "));
            let policies = chosen_policies(name, &args.policy).ok_or_else(unknown)?;
            let grid = experiment_grid(name).ok_or_else(unknown)?;
            let mut configs = Vec::new();
            // Each scenario of the grid once (rows share them).
            let mut resolved: Vec<(&str, WorldAndTold)> = Vec::new();
            for (n, &(sensors, name)) in grid.iter().enumerate() {
                let on = match resolved.iter().find(|r| r.0 == name) {
                    Some((_, on)) => on.clone(),
                    None => {
                        let (id, scenario) = resolve(&client, name).await?;
                        let on = world_and_told(
                            &client,
                            id,
                            scenario,
                            args.world_rates.as_ref(),
                            args.tell_world_rates,
                            false,
                        )
                        .await?;
                        resolved.push((name, on.clone()));
                        on
                    }
                };
                for &(letter, policy) in &policies {
                    configs.push(config(
                        format!("{}{letter}", n + 1),
                        policy,
                        &on,
                        sensors,
                        experiment_fleet(name, n),
                    ));
                }
            }
            configs
        }
        None => {
            let (id, scenario) = resolve(&client, &args.scenario).await?;
            let on = world_and_told(
                &client,
                id,
                scenario,
                args.world_rates.as_ref(),
                args.tell_world_rates,
                args.blind,
            )
            .await?;
            let sensors = match &args.fleet {
                Some(fleet) => fleet_size(fleet)
                    .ok_or_else(|| format!("--fleet {fleet:?}: expected NAME:COUNT,…"))?,
                None => args.sensors,
            };
            let mut policies: Vec<Policy> = Vec::new();
            for &policy in &args.policy {
                if !policies.contains(&policy) {
                    policies.push(policy);
                }
            }
            if policies.is_empty() {
                policies.push(Policy::Exact);
            }
            policies
                .into_iter()
                .map(|policy| {
                    config(
                        policy.name().to_owned(),
                        policy,
                        &on,
                        sensors,
                        args.fleet.as_deref(),
                    )
                })
                .collect()
        }
    };
    if configs.iter().any(|c| c.sensors == 0) {
        return Err("--sensors must be at least 1".into());
    }
    for c in &configs {
        fleet_types(&c.scenario, c.fleet.as_deref(), c.sensors)
            .map_err(|e| format!("--fleet: {e}"))?;
    }
    if configs.len() > 1 && args.experiment.is_none() && (args.live || args.svg.is_some()) {
        return Err("--live and --svg show a single run; give one --policy".into());
    }
    if args.live {
        if args.experiment.is_some() {
            return Err("--live shows a single run; drop --experiment".into());
        }
        if configs[0].policy.learns_rates() {
            return Err(format!(
                "--live plans with stateless requests, which learn no rates: {} needs a run without --live",
                configs[0].policy
            ));
        }
        let opts = LiveOptions {
            run: configs[0].clone(),
            seed: args.seed,
            speed: args.live_speed,
        };
        return live(client, opts, &args.live_bind).await;
    }
    let rows = run_all(&client, &configs, args.seed, args.seeds.max(1), args.jobs)
        .await
        .map_err(|e| e.to_string())?;
    print!("{}", report::table(&rows));
    if let Some(path) = &args.json {
        let text = report::json(&rows).map_err(|e| e.to_string())?;
        std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    if let Some(path) = &args.svg {
        if args.experiment.is_some() {
            return Err("--svg draws a single run; drop --experiment".into());
        }
        let (_, sim) = run_one(&client, &configs[0], args.seed, true)
            .await
            .map_err(|e| e.to_string())?;
        if let Some(sim) = sim {
            svg::draw(&sim, path)?;
        }
    }
    Ok(())
}

/// Serves the live view until Ctrl-C; a failed run ends it with the error.
async fn live(client: Client, opts: LiveOptions, bind: &str) -> Result<(), String> {
    let listener = tokio::net::TcpListener::bind(bind)
        .await
        .map_err(|e| format!("--live-bind {bind}: {e}"))?;
    let steps = opts.run.steps;
    let mut live = Live::start(listener, client, opts)
        .await
        .map_err(|e| e.to_string())?;
    println!(
        "live view: open {} (the run starts when the page opens; Ctrl-C stops)",
        live.url()
    );
    let mut running = true;
    loop {
        tokio::select! {
            signal = tokio::signal::ctrl_c() => {
                signal.map_err(|e| format!("cannot wait for Ctrl-C: {e}"))?;
                break;
            }
            done = live.finished(), if running => {
                running = false;
                match done {
                    Ok(()) => println!("live view: all {steps} steps done; showing the final state until Ctrl-C"),
                    Err(e) => {
                        live.shutdown().await?;
                        return Err(e.to_string());
                    }
                }
            }
        }
    }
    live.shutdown().await?;
    println!("live view: stopped");
    Ok(())
}
