//! `vigil-loadtest`: open-loop load against a Vigil server (see the crate's
//! README for the method).
//!
//! ```text
//! vigil-loadtest [OPTIONS]                 one run, or --sweep
//! vigil-loadtest --endpoint session [...]  the same with the steps of --sessions sessions
//! vigil-loadtest gen --out FILE [...]      write generated request bodies
//! vigil-loadtest inproc [...]              in-process plan time of the same requests
//! vigil-loadtest inproc --session [...]    in-process session step time of the same states
//! vigil-loadtest summarize [...]           combine run.sh's results, HTTP efficiency
//! vigil-loadtest certify [...]             certified gap and plan time per coordination
//! ```

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand, ValueEnum};
use serde::Serialize;
use std::sync::Arc;

use vigil::coordination::{Coordination, Objective};
use vigil::planner::{PlanRequest, Planner};

use vigil_loadtest::certify;
use vigil_loadtest::generator::{self, RunConfig, Target};
use vigil_loadtest::inproc;
use vigil_loadtest::report::Session;
use vigil_loadtest::requests;
use vigil_loadtest::schedule::Arrivals;
use vigil_loadtest::session;
use vigil_loadtest::sweep::{self, SweepConfig};
use vigil_loadtest::workload::{SessionWorkload, Workload};

/// The server's allocator, so that `inproc` times plans as the server
/// makes them (its allocations are a few percent of a plan).
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Open-loop load generator for the Vigil planning API.
///
/// Without a subcommand, replays plan requests (generated from vigil-sim
/// states, or read with --requests) at --rate per second, open loop: the
/// send times are fixed in advance and latency runs from each request's
/// intended send time, so queueing in the generator counts. With --sweep,
/// climbs the rate until p99 passes --slo-ms and reports the knee. With
/// --endpoint session, sends the steps of --sessions sessions of the same
/// simulator run instead (request i to session i mod N, a session's steps
/// one at a time).
#[derive(Debug, Parser)]
#[command(
    name = "vigil-loadtest",
    version,
    args_conflicts_with_subcommands = true
)]
struct Cli {
    #[command(subcommand)]
    cmd: Option<Cmd>,
    #[command(flatten)]
    run: RunArgs,
}

#[derive(Debug, Subcommand)]
enum Cmd {
    /// Generate request bodies from vigil-sim states and write them to a
    /// file (a JSON array, or JSON lines if it ends in .jsonl/.ndjson).
    Gen(GenArgs),
    /// Time the same requests in process (single thread, no HTTP): the
    /// median feeds the HTTP efficiency.
    Inproc(InprocArgs),
    /// Combine the results of run.sh (each file optional) and derive the
    /// HTTP efficiency.
    Summarize(SummarizeArgs),
    /// Plan the same requests with each coordination (in process, one
    /// thread) and report the certified gap and the plan time of each.
    Certify(CertifyArgs),
}

#[derive(Debug, Args)]
struct CertifyArgs {
    /// File of plan request bodies; generated when absent.
    #[arg(long)]
    requests: Option<PathBuf>,
    /// Coordinations to compare, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "priority,iterated,joint")]
    coordinations: Vec<String>,
    /// `joint`'s time budget, ms (the server's default when absent).
    #[arg(long)]
    budget_ms: Option<usize>,
    /// `joint`'s gap target (the server's default when absent).
    #[arg(long)]
    gap_target: Option<f64>,
    /// Write the figures as JSON to this file.
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    workload: WorkloadArgs,
}

/// Which endpoint a run hits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Endpoint {
    /// POST /v1/scenarios/{scenario}/plan with the request bodies.
    Plan,
    /// GET /healthz: the HTTP stack's ceiling.
    Healthz,
    /// POST /v1/sessions/{id}/step: the steps of --sessions sessions, each
    /// opened and warmed before the run (untimed) and closed after it.
    Session,
}

/// The requests: generated from vigil-sim states.
#[derive(Debug, Args)]
struct WorkloadArgs {
    /// Built-in scenario: requests are generated for it and sent to it.
    #[arg(long, default_value = "paper-v10")]
    scenario: String,
    /// Sensors per generated request.
    #[arg(long, default_value_t = 10)]
    sensors: usize,
    /// Sensors of the scenario's types instead, such as `drone:4,robot:6`
    /// for `site-fleet` (the first four drones, the next six robots); sets
    /// the number of sensors in place of `--sensors`.
    #[arg(long, conflicts_with = "sensors")]
    fleet: Option<String>,
    /// Steps of history per generated request.
    #[arg(long, default_value_t = 16)]
    history: usize,
    /// Horizon T of the generated requests.
    #[arg(long, default_value_t = 3)]
    horizon: usize,
    /// Distinct requests to generate (consecutive steps of one simulation).
    #[arg(long, default_value_t = 100)]
    count: usize,
    /// Seed of the simulated target process, and of the Poisson arrivals.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Objective every request asks for (`detections` or
    /// `first_detections`); the requests' own by default. The states are
    /// the same either way.
    #[arg(long, value_parser = parse_objective)]
    objective: Option<Objective>,
    /// Coordination every request asks for (`none`, `priority`,
    /// `iterated`, `joint`); the requests' own by default.
    #[arg(long, value_parser = parse_coordination)]
    coordination: Option<Coordination>,
    /// `certify` every request sends (`true` or `false`: with `false` an
    /// exact plan skips its certificate); the requests' own by default.
    #[arg(long)]
    certify: Option<bool>,
}

fn parse_objective(s: &str) -> Result<Objective, String> {
    serde_json::from_value(serde_json::Value::String(s.to_owned())).map_err(|e| e.to_string())
}

fn parse_coordination(s: &str) -> Result<Coordination, String> {
    serde_json::from_value(serde_json::Value::String(s.to_owned())).map_err(|e| e.to_string())
}

impl WorkloadArgs {
    /// `reqs` with the objective, coordination and certificate asked for.
    fn override_settings(&self, mut reqs: Vec<PlanRequest>) -> Vec<PlanRequest> {
        for req in &mut reqs {
            req.objective = self.objective.or(req.objective);
            req.coordination = self.coordination.or(req.coordination);
            req.certify = self.certify.or(req.certify);
        }
        reqs
    }

    /// The generated requests' fleet.
    fn fleet(&self) -> requests::Fleet<'_> {
        self.fleet
            .as_deref()
            .map_or(requests::Fleet::Default, requests::Fleet::Typed)
    }

    /// The sensors of a generated request, as the output names them.
    fn who(&self) -> String {
        match &self.fleet {
            Some(fleet) => format!("fleet {fleet}"),
            None => format!("{} sensors", self.sensors),
        }
    }

    fn workload(&self) -> Workload {
        Workload {
            sensors: self.sensors,
            history: self.history,
            horizon: self.horizon,
            seed: self.seed,
        }
    }

    /// The requests: read from `file`, or generated.
    fn requests(&self, file: Option<&Path>) -> Result<Vec<PlanRequest>> {
        self.requests_as_given(file)
            .map(|reqs| self.override_settings(reqs))
    }

    /// The requests: read from `file`, or generated, as they are.
    fn requests_as_given(&self, file: Option<&Path>) -> Result<Vec<PlanRequest>> {
        match file {
            Some(f) => requests::load(f),
            None => {
                let planner = requests::planner_for(&self.scenario)?;
                let t = Instant::now();
                let reqs =
                    requests::generate(&planner, &self.workload(), self.fleet(), self.count)?;
                eprintln!(
                    "generated {} requests ({}, {} steps of history, T = {}, mean {:.1} targets) in {:.1} s",
                    reqs.len(),
                    self.who(),
                    self.history,
                    self.horizon,
                    mean_targets(&reqs),
                    t.elapsed().as_secs_f64()
                );
                Ok(reqs)
            }
        }
    }
}

impl WorkloadArgs {
    /// The session replay of the run (and its stateless requests, the same
    /// states), generated.
    fn session(&self, planner: &Planner) -> Result<(Vec<PlanRequest>, SessionWorkload)> {
        let t = Instant::now();
        let (reqs, wl) =
            requests::generate_session(planner, &self.workload(), self.fleet(), self.count)?;
        eprintln!(
            "generated a session of {} warm-up and {} timed steps ({}, {} steps of history, T = {}, mean {:.1} targets) in {:.1} s",
            wl.warmup.len(),
            wl.steps.len(),
            self.who(),
            self.history,
            self.horizon,
            mean_targets(&reqs),
            t.elapsed().as_secs_f64()
        );
        Ok((reqs, wl))
    }
}

fn mean_targets(reqs: &[PlanRequest]) -> f64 {
    reqs.iter().map(|r| r.targets.len()).sum::<usize>() as f64 / reqs.len().max(1) as f64
}

#[derive(Debug, Args)]
struct RunArgs {
    /// Base URL of the server (http only).
    #[arg(long, default_value = "http://127.0.0.1:8080")]
    url: String,
    /// With `--endpoint session`: the base URL of another replica on the
    /// same database (repeat for more). Sessions are opened through
    /// `--url`; step `j` of session `i` goes to replica `(i + j) mod n`, as
    /// a plain load balancer spreads them.
    #[arg(long)]
    also_url: Vec<String>,
    /// Endpoint to load.
    #[arg(long, value_enum, default_value_t = Endpoint::Plan)]
    endpoint: Endpoint,
    /// Intended requests per second.
    #[arg(long, default_value_t = 100.0)]
    rate: f64,
    /// Arrival process.
    #[arg(long, value_enum, default_value_t = Arrivals::Poisson)]
    arrivals: Arrivals,
    /// Measured duration (e.g. 30, 30s, 500ms, 2m).
    #[arg(long, default_value = "10s", value_parser = parse_duration)]
    duration: Duration,
    /// Warm-up before it: sent, not recorded.
    #[arg(long, default_value = "2s", value_parser = parse_duration)]
    warmup: Duration,
    /// Concurrent connections. A request waits in the generator's queue
    /// while all are busy, and the wait counts in its latency.
    #[arg(long, default_value_t = 32)]
    connections: usize,
    /// Sessions of `--endpoint session`: request i is the next step of
    /// session i mod N, and waits for that session's previous step.
    #[arg(long, default_value_t = 32)]
    sessions: usize,
    /// With `--endpoint session`: each step sends an `Idempotency-Key`
    /// header (its step number, unique in its session), as the Python
    /// client does, so that the server also keeps its answer for a retry.
    #[arg(long)]
    idempotency_keys: bool,
    /// Longest a request may take from its intended send time; past it, it
    /// counts as an error.
    #[arg(long, default_value = "5s", value_parser = parse_duration)]
    timeout: Duration,
    /// File of plan request bodies (a JSON array, or JSON lines); generated
    /// from vigil-sim states when absent.
    #[arg(long)]
    requests: Option<PathBuf>,
    /// API key, sent as `Authorization: Bearer <key>`.
    #[arg(long, env = "VIGIL_API_KEY", hide_env_values = true)]
    api_key: Option<String>,
    /// Runtime threads of the generator (1: a current-thread runtime, for a
    /// generator pinned to one core).
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Write the figures as JSON to this file (with --sweep: every step and
    /// the knee).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Climb the rate until p99 passes --slo-ms, and report the knee.
    #[arg(long)]
    sweep: bool,
    /// SLO on the p99 latency, ms (for --sweep).
    #[arg(long, default_value_t = 2.0)]
    slo_ms: f64,
    /// First rate of the sweep.
    #[arg(long, default_value_t = 100.0)]
    sweep_start: f64,
    /// Rate multiplier between sweep steps.
    #[arg(long, default_value_t = 1.25)]
    sweep_factor: f64,
    /// Highest rate of the sweep.
    #[arg(long, default_value_t = 100_000.0)]
    sweep_max: f64,
    /// Bisection steps between the last passing and the first failing rate.
    #[arg(long, default_value_t = 0)]
    sweep_refine: u32,
    /// Least achieved / target rate of a step that meets the SLO.
    #[arg(long, default_value_t = 0.95)]
    sweep_min_achieved: f64,
    /// Idle time between sweep steps.
    #[arg(long, default_value = "1s", value_parser = parse_duration)]
    sweep_pause: Duration,
    #[command(flatten)]
    workload: WorkloadArgs,
}

#[derive(Debug, Args)]
struct GenArgs {
    /// File to write (JSON lines if it ends in .jsonl or .ndjson).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    workload: WorkloadArgs,
}

#[derive(Debug, Args)]
struct InprocArgs {
    /// File of plan request bodies; generated when absent.
    #[arg(long, conflicts_with = "session")]
    requests: Option<PathBuf>,
    /// Time session steps instead (prepare + plan + commit, in fresh
    /// sessions warmed untimed), each beside the stateless plan of the same
    /// state.
    #[arg(long)]
    session: bool,
    /// With `--session`: sessions that learn the rates (`learn_rates`), so
    /// each step also folds its looks and detections into the posteriors
    /// and plans at the learnt rates (docs/learning.md).
    #[arg(long, requires = "session")]
    learn: bool,
    /// Timed plans (or session steps), cycling through the requests.
    #[arg(long, default_value_t = 2000)]
    iterations: usize,
    /// Sleep this long before each timed plan (stateless plans only), as a
    /// server's planner idles between requests at a low rate.
    #[arg(long, default_value_t = 0, conflicts_with = "session")]
    pause_ms: u64,
    /// Write the figures as JSON to this file.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Plan on the scenario with this `rays_per_pi` in its spec (the
    /// accuracy knob; see docs/performance.md, Accuracy). The requests are
    /// the same states as without it.
    #[arg(long)]
    rays_per_pi: Option<u32>,
    #[command(flatten)]
    workload: WorkloadArgs,
}

impl InprocArgs {
    /// The planner to time: the scenario's, with `--rays-per-pi` if given.
    fn planner(&self) -> Result<Planner> {
        requests::planner_with(&self.workload.scenario, self.rays_per_pi)
    }
}

#[derive(Debug, Args)]
struct SummarizeArgs {
    /// Cores the server was pinned to.
    #[arg(long, default_value_t = 1.0)]
    server_cores: f64,
    /// `inproc --out` file.
    #[arg(long)]
    inproc: Option<PathBuf>,
    /// `--endpoint healthz --sweep --out` file.
    #[arg(long)]
    healthz_sweep: Option<PathBuf>,
    /// Fixed-rate plan run `--out` file.
    #[arg(long)]
    fixed: Option<PathBuf>,
    /// Plan `--sweep --out` file.
    #[arg(long)]
    plan_sweep: Option<PathBuf>,
    /// `inproc --session --out` file.
    #[arg(long)]
    session_inproc: Option<PathBuf>,
    /// Fixed-rate `--endpoint session` run `--out` file.
    #[arg(long)]
    session_fixed: Option<PathBuf>,
    /// `--endpoint session --sweep --out` file.
    #[arg(long)]
    session_sweep: Option<PathBuf>,
    /// Write the combined figures as JSON to this file.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// `30`, `30s`, `2.5s`, `500ms` or `2m`.
fn parse_duration(s: &str) -> Result<Duration, String> {
    let s = s.trim();
    let (num, scale) = if let Some(n) = s.strip_suffix("ms") {
        (n, 1e-3)
    } else if let Some(n) = s.strip_suffix('s') {
        (n, 1.0)
    } else if let Some(n) = s.strip_suffix('m') {
        (n, 60.0)
    } else {
        (s, 1.0)
    };
    let v: f64 = num
        .trim()
        .parse()
        .map_err(|_| format!("{s:?} is not a duration (e.g. 30, 30s, 500ms, 2m)"))?;
    Duration::try_from_secs_f64(v * scale).map_err(|_| format!("{s:?} is not a valid duration"))
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.cmd {
        Some(Cmd::Gen(a)) => gen_cmd(&a),
        Some(Cmd::Inproc(a)) => inproc_cmd(&a),
        Some(Cmd::Summarize(a)) => summarize_cmd(&a),
        Some(Cmd::Certify(a)) => certify_cmd(&a),
        None => run_cmd(&cli.run),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("vigil-loadtest: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    let mut text = serde_json::to_string_pretty(value)?;
    text.push('\n');
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}

fn gen_cmd(a: &GenArgs) -> Result<()> {
    let reqs = a.workload.requests(None)?;
    requests::save(&a.out, &reqs)?;
    println!("wrote {} requests to {}", reqs.len(), a.out.display());
    Ok(())
}

fn inproc_cmd(a: &InprocArgs) -> Result<()> {
    if a.session {
        return inproc_session_cmd(a);
    }
    let planner = a.planner()?;
    let reqs = a.workload.requests(a.requests.as_deref())?;
    let pause = std::time::Duration::from_millis(a.pause_ms);
    let r = inproc::measure_paced(&planner, &reqs, a.iterations, pause)?;
    println!(
        "in process, {} plans of {} requests (mean {:.1} targets) on {}: median {:.3} ms  p90 {:.3}  p99 {:.3}  mean {:.3}  max {:.3}  => {:.0} plans/s per core",
        r.iterations,
        r.requests,
        mean_targets(&reqs),
        planner.scenario.id,
        r.median_ms,
        r.p90_ms,
        r.p99_ms,
        r.mean_ms,
        r.max_ms,
        r.plans_per_s_per_core
    );
    if let Some(out) = &a.out {
        write_json(out, &r)?;
    }
    Ok(())
}

fn certify_cmd(a: &CertifyArgs) -> Result<()> {
    let planner = requests::planner_for(&a.workload.scenario)?;
    let reqs: Vec<PlanRequest> = a
        .workload
        .requests(a.requests.as_deref())?
        .into_iter()
        .map(|r| PlanRequest {
            budget_ms: a.budget_ms.map(Into::into).or(r.budget_ms),
            gap_target: a.gap_target.or(r.gap_target),
            ..r
        })
        .collect();
    let modes = a
        .coordinations
        .iter()
        .map(|c| {
            serde_json::from_value(serde_json::Value::String(c.clone()))
                .with_context(|| format!("unknown coordination {c:?}"))
        })
        .collect::<Result<Vec<_>>>()?;
    let rows = certify::measure(&planner, &reqs, &modes)?;
    println!(
        "certified gap on {} ({} requests, mean {:.1} targets), one thread:",
        planner.scenario.id,
        reqs.len(),
        mean_targets(&reqs)
    );
    for r in &rows {
        println!(
            "  {:<9} gap median {:.4}%  p95 {:.4}%  max {:.4}%   value mean {:.4}   plan median {:.3} ms  p95 {:.3} ms",
            serde_json::to_value(r.coordination)?
                .as_str()
                .unwrap_or("?"),
            100.0 * r.median_gap,
            100.0 * r.p95_gap,
            100.0 * r.max_gap,
            r.mean_value,
            r.median_ms,
            r.p95_ms
        );
    }
    if let Some(out) = &a.out {
        write_json(out, &rows)?;
    }
    Ok(())
}

fn inproc_session_cmd(a: &InprocArgs) -> Result<()> {
    let (reqs, mut wl) = a
        .workload
        .session(&requests::planner_for(&a.workload.scenario)?)?;
    if a.learn {
        wl.settings.learn_rates = Some(true);
    }
    let planner = Arc::new(a.planner()?);
    let r = session::measure(&planner, &wl, Some(&reqs), a.iterations)?;
    let s = &r.steps;
    println!(
        "in process, {} session steps ({} distinct, {} fresh sessions each warmed by {} untimed steps) on {}: median {:.3} ms  p90 {:.3}  p99 {:.3}  mean {:.3}  max {:.3}  => {:.0} steps/s per core",
        s.iterations,
        s.requests,
        r.sessions,
        r.warmup_steps,
        planner.scenario.id,
        s.median_ms,
        s.p90_ms,
        s.p99_ms,
        s.mean_ms,
        s.max_ms,
        r.steps_per_s_per_core
    );
    if let Some(p) = &r.stateless {
        println!(
            "  the stateless plans of the same states, timed alternately: median {:.3} ms  p90 {:.3}  p99 {:.3}  => {:.0} plans/s per core",
            p.median_ms, p.p90_ms, p.p99_ms, p.plans_per_s_per_core
        );
    }
    if let Some(out) = &a.out {
        write_json(out, &r)?;
    }
    Ok(())
}

fn summarize_cmd(a: &SummarizeArgs) -> Result<()> {
    if !(a.server_cores.is_finite() && a.server_cores > 0.0) {
        bail!("--server-cores must be positive");
    }
    let s = Session::from_files(
        a.server_cores,
        a.inproc.as_deref(),
        a.healthz_sweep.as_deref(),
        a.fixed.as_deref(),
        a.plan_sweep.as_deref(),
    )?
    .with_sessions(
        a.session_inproc.as_deref(),
        a.session_fixed.as_deref(),
        a.session_sweep.as_deref(),
    )?;
    println!("{}", s.describe());
    if let Some(out) = &a.out {
        write_json(out, &s)?;
    }
    Ok(())
}

fn run_cmd(a: &RunArgs) -> Result<()> {
    let url = reqwest::Url::parse(&a.url).with_context(|| format!("--url {:?}", a.url))?;
    if url.scheme() != "http" {
        bail!(
            "--url {:?}: only http:// is supported (built without TLS)",
            a.url
        );
    }
    if a.threads == 0 {
        bail!("--threads must be at least 1");
    }
    if !a.also_url.is_empty() && a.endpoint != Endpoint::Session {
        bail!("--also-url spreads the steps of sessions: it needs --endpoint session");
    }
    if a.idempotency_keys && a.endpoint != Endpoint::Session {
        bail!("--idempotency-keys names the steps of sessions: it needs --endpoint session");
    }
    let target = match a.endpoint {
        Endpoint::Healthz => Target::healthz(&a.url),
        Endpoint::Plan => {
            let reqs = a.workload.requests(a.requests.as_deref())?;
            Target::plan(&a.url, &a.workload.scenario, requests::bodies(&reqs)?)?
        }
        Endpoint::Session => {
            if a.requests.is_some() {
                bail!(
                    "--endpoint session generates its steps from a vigil-sim run; --requests holds plan bodies"
                );
            }
            if a.sessions == 0 {
                bail!("--sessions must be at least 1");
            }
            let planner = requests::planner_for(&a.workload.scenario)?;
            let (_, wl) = a.workload.session(&planner)?;
            Target::session(
                &a.url,
                &a.also_url,
                &a.workload.scenario,
                &wl,
                a.sessions,
                a.idempotency_keys,
            )?
        }
    };
    let cfg = RunConfig {
        target,
        rate: a.rate,
        arrivals: a.arrivals,
        duration: a.duration,
        warmup: a.warmup,
        connections: a.connections,
        seed: a.workload.seed,
        timeout: a.timeout,
        api_key: a.api_key.clone().filter(|k| !k.is_empty()),
    };
    let runtime = if a.threads == 1 {
        tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
    } else {
        tokio::runtime::Builder::new_multi_thread()
            .worker_threads(a.threads)
            .enable_all()
            .build()
    }
    .context("cannot start the tokio runtime")?;
    runtime.block_on(async {
        generator::preflight(&cfg.target, cfg.api_key.as_deref(), cfg.timeout).await?;
        if a.sweep {
            let sc = SweepConfig {
                start: a.sweep_start,
                factor: a.sweep_factor,
                max: a.sweep_max,
                slo_ms: a.slo_ms,
                min_achieved: a.sweep_min_achieved,
                refine: a.sweep_refine,
                pause: a.sweep_pause,
            };
            eprintln!(
                "sweep of {} from {}/s ×{} up to {}/s, {:?} per step (+{:?} warm-up), SLO p99 ≤ {} ms",
                cfg.target.url(),
                sc.start,
                sc.factor,
                sc.max,
                cfg.duration,
                cfg.warmup,
                sc.slo_ms
            );
            let report = sweep::sweep(&cfg, &sc, |r| {
                let s = &r.summary;
                let verdict = if sweep::meets_slo(s, sc.slo_ms, sc.min_achieved) {
                    "ok"
                } else {
                    "FAIL"
                };
                println!(
                    "{:>10.1}/s -> {:>10.1}/s  p50 {:>8.3}  p99 {:>8.3}  p99.9 {:>8.3}  max {:>8.3} ms  errors {}  shed {}  wait p99 {:.3} ms  {verdict}",
                    s.target_rate,
                    s.achieved_rate,
                    s.p50_ms,
                    s.p99_ms,
                    s.p999_ms,
                    s.max_ms,
                    s.errors,
                    s.shed,
                    r.send_wait.value_at_quantile(0.99) as f64 / 1e3
                );
            })
            .await?;
            match &report.knee {
                Some(k) => println!(
                    "knee: {:.1}/s target, {:.1}/s achieved, p99 {:.3} ms ({})",
                    k.target_rate, k.achieved_rate, k.p99_ms, report.stopped
                ),
                None => println!(
                    "knee: none, the first step ({}/s) failed the SLO; lower --sweep-start or raise --slo-ms",
                    sc.start
                ),
            }
            if let Some(out) = &a.out {
                write_json(out, &report)?;
            }
        } else {
            eprintln!(
                "{} at {}/s ({}) for {:?} after {:?} of warm-up, {} connections{}",
                cfg.target.url(),
                cfg.rate,
                cfg.arrivals,
                cfg.duration,
                cfg.warmup,
                cfg.connections,
                match &cfg.target {
                    Target::Session(t) => format!(
                        ", {} sessions each warmed by {} steps",
                        t.sessions,
                        t.warmup.len()
                    ),
                    _ => String::new(),
                }
            );
            let report = generator::run(&cfg).await?;
            println!("{}", report.describe());
            if let Some(out) = &a.out {
                write_json(out, &report.summary)?;
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_parse_with_and_without_units() {
        assert_eq!(parse_duration("30").unwrap(), Duration::from_secs(30));
        assert_eq!(parse_duration("2.5s").unwrap(), Duration::from_millis(2500));
        assert_eq!(parse_duration("500ms").unwrap(), Duration::from_millis(500));
        assert_eq!(parse_duration("2m").unwrap(), Duration::from_secs(120));
        assert!(parse_duration("fast").is_err());
        assert!(parse_duration("-1").is_err());
    }

    #[test]
    fn session_mode_parses() {
        let cli = Cli::try_parse_from([
            "vigil-loadtest",
            "--endpoint",
            "session",
            "--sessions",
            "8",
            "--rate",
            "2000",
        ])
        .expect("valid");
        assert!(cli.cmd.is_none());
        assert_eq!(cli.run.endpoint, Endpoint::Session);
        assert_eq!(cli.run.sessions, 8);
        let cli = Cli::try_parse_from(["vigil-loadtest"]).expect("valid");
        assert_eq!(cli.run.endpoint, Endpoint::Plan);
        assert_eq!(cli.run.sessions, 32);
        let cli = Cli::try_parse_from([
            "vigil-loadtest",
            "inproc",
            "--session",
            "--iterations",
            "10",
        ])
        .expect("valid");
        match cli.cmd {
            Some(Cmd::Inproc(a)) => {
                assert!(a.session);
                assert_eq!(a.iterations, 10);
            }
            other => panic!("not inproc: {other:?}"),
        }
        // Session steps are generated: no file of plan bodies.
        assert!(
            Cli::try_parse_from([
                "vigil-loadtest",
                "inproc",
                "--session",
                "--requests",
                "r.json"
            ])
            .is_err()
        );
        let cli = Cli::try_parse_from([
            "vigil-loadtest",
            "summarize",
            "--session-inproc",
            "a.json",
            "--session-fixed",
            "b.json",
            "--session-sweep",
            "c.json",
        ])
        .expect("valid");
        match cli.cmd {
            Some(Cmd::Summarize(a)) => {
                assert_eq!(a.session_inproc, Some(PathBuf::from("a.json")));
                assert_eq!(a.session_fixed, Some(PathBuf::from("b.json")));
                assert_eq!(a.session_sweep, Some(PathBuf::from("c.json")));
            }
            other => panic!("not summarize: {other:?}"),
        }
    }

    #[test]
    fn the_cli_is_consistent() {
        use clap::CommandFactory;
        Cli::command().debug_assert();
    }
}
