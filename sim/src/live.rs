//! The live view: one run, stepped at a rate the page sets, watched in a
//! browser.
//!
//! [`Live::start`] serves a static page (HTML and JavaScript compiled into
//! the binary, nothing fetched from elsewhere) on a listener of the
//! caller's choosing and runs the simulation in a task of its own:
//! - `GET /` and `GET /live.js`: the page;
//! - `GET /events`: Server-Sent Events, an `init` event (the zone, the `d_hat`
//!   heat map, the sources and their cones, the no-go zones, the obstacles)
//!   and then a `frame` event for every state (sensors, their plans, traces
//!   and fields of view, with obstacles the part of each field of view a
//!   ground sensor sees, targets by status, running metrics and their
//!   series, the plan's certified gap, the planner's `explain` values).
//!   Every frame holds the whole state, so a slow page skips frames without
//!   losing anything;
//! - `GET /init` and `GET /frame`: the same as plain JSON;
//! - `POST /control`: `{"action": "pause" | "resume" | "step"}` or
//!   `{"action": "speed", "speed": steps_per_second}`.
//!
//! The run does its warm-up at once and then waits for the first page to
//! connect before its first measured step. Closing the page does not stop
//! it: it goes on at the last rate set, and a page opened later shows the
//! current state. After the last step the final state stays served until
//! [`Live::shutdown`] (Ctrl-C in `vigil-sim --live`), which ends every event
//! stream so the server stops cleanly.

use std::convert::Infallible;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use axum::Json;
use axum::Router;
use axum::extract::State;
use axum::http::{StatusCode, header};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use futures_util::stream::{self, Stream};
use serde::{Deserialize, Serialize};
use tokio::net::TcpListener;
use tokio::sync::watch;
use tokio::task::JoinHandle;
use tokio::time::Instant;
use vigil::obstacle::ObstacleKind;
use vigil::planner::{EstimatorKind, Explain, PlanResponse};
use vigil::scenario::{Cell, FovSpec};
use vigil::stats::Stats;

use crate::client::Client;
use crate::driver::{Sim, TargetStatus, checked_bound};
use crate::experiment::{RunConfig, RunError};

const PAGE: &str = include_str!("../static/live.html");
const SCRIPT: &str = include_str!("../static/live.js");

/// Rays of the outline of what a ground sensor sees (a frame sensor's `view`).
pub const VIEW_RAYS: usize = 180;

/// Slowest and fastest rates the page may set, steps per second.
pub const SPEED_RANGE: (f64, f64) = (0.2, 200.0);

/// What a live run needs besides the planner.
#[derive(Debug, Clone)]
pub struct LiveOptions {
    /// The run (policy, scenario, sensors, steps, warm-up, horizon, …).
    pub run: RunConfig,
    /// Its seed.
    pub seed: u64,
    /// Steps per second at the start; the page can change it.
    pub speed: f64,
}

/// A failure to start the live view.
#[derive(Debug, thiserror::Error)]
pub enum LiveError {
    /// The listener's address could not be read.
    #[error("live view: {0}")]
    Io(#[from] std::io::Error),
    /// The initial state could not be encoded.
    #[error("live view: {0}")]
    Json(#[from] serde_json::Error),
}

/// What the page asks for.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(tag = "action", rename_all = "lowercase", deny_unknown_fields)]
enum Command {
    Pause,
    Resume,
    Step,
    Speed { speed: f64 },
}

/// The controls, as the page last set them.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Control {
    paused: bool,
    speed: f64,
    /// Single steps asked for so far.
    step_requests: u64,
    /// A page has connected at least once.
    started: bool,
}

/// State shared by the handlers and the stepping task.
struct Shared {
    init: String,
    frames: watch::Sender<Arc<str>>,
    control: watch::Sender<Control>,
    shutdown: watch::Sender<bool>,
}

/// A running live view.
pub struct Live {
    addr: SocketAddr,
    shared: Arc<Shared>,
    server: JoinHandle<std::io::Result<()>>,
    sim: JoinHandle<Result<(), RunError>>,
}

impl Live {
    /// Serves the live view on `listener` and starts the run's task; the
    /// run steps once a page has connected. Returns at once.
    pub async fn start(
        listener: TcpListener,
        client: Client,
        opts: LiveOptions,
    ) -> Result<Live, LiveError> {
        let addr = listener.local_addr()?;
        let scenario = opts.run.scenario.clone();
        let stats = tokio::task::spawn_blocking(move || Stats::compute(&scenario))
            .await
            .map_err(std::io::Error::other)?;
        let init = serde_json::to_string(&Init::new(&opts, &stats))?;
        let speed = opts.speed.clamp(SPEED_RANGE.0, SPEED_RANGE.1);
        let (frames, _) = watch::channel(Arc::<str>::from("null"));
        let (control, _) = watch::channel(Control {
            paused: false,
            speed: if speed.is_finite() { speed } else { 10.0 },
            step_requests: 0,
            started: false,
        });
        let (shutdown, _) = watch::channel(false);
        let shared = Arc::new(Shared {
            init,
            frames,
            control,
            shutdown,
        });
        let app = Router::new()
            .route("/", get(page))
            .route("/live.js", get(script))
            .route("/events", get(events))
            .route("/init", get(init_json))
            .route("/frame", get(frame_json))
            .route("/control", post(control_handler))
            .with_state(shared.clone());
        let mut stop = shared.shutdown.subscribe();
        let server = tokio::spawn(async move {
            axum::serve(listener, app)
                .with_graceful_shutdown(async move {
                    let _ = stop.wait_for(|&s| s).await;
                })
                .await
        });
        let sim = tokio::spawn(drive(shared.clone(), client, opts));
        Ok(Live {
            addr,
            shared,
            server,
            sim,
        })
    }

    /// The address the page is served on.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// The page's URL.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// Waits until the run has done its last step (it stays served), or
    /// has failed.
    pub async fn finished(&mut self) -> Result<(), RunError> {
        match (&mut self.sim).await {
            Ok(result) => result,
            Err(e) => Err(RunError::Contract(format!("the live run panicked: {e}"))),
        }
    }

    /// Stops the run if it is still going, ends every event stream and
    /// stops the server once its connections are done.
    pub async fn shutdown(self) -> Result<(), String> {
        self.sim.abort();
        self.shared.shutdown.send_replace(true);
        match tokio::time::timeout(Duration::from_secs(5), self.server).await {
            Ok(Ok(Ok(()))) => Ok(()),
            Ok(Ok(Err(e))) => Err(format!("live view server: {e}")),
            Ok(Err(e)) => Err(format!("live view server: {e}")),
            Err(_) => Err("live view server did not stop within 5 s".into()),
        }
    }
}

async fn page() -> Response {
    ([(header::CONTENT_TYPE, "text/html; charset=utf-8")], PAGE).into_response()
}

async fn script() -> Response {
    (
        [(header::CONTENT_TYPE, "text/javascript; charset=utf-8")],
        SCRIPT,
    )
        .into_response()
}

async fn init_json(State(shared): State<Arc<Shared>>) -> Response {
    json_text(shared.init.clone())
}

async fn frame_json(State(shared): State<Arc<Shared>>) -> Response {
    let frame = shared.frames.borrow().clone();
    json_text(frame.to_string())
}

fn json_text(body: String) -> Response {
    ([(header::CONTENT_TYPE, "application/json")], body).into_response()
}

async fn control_handler(
    State(shared): State<Arc<Shared>>,
    Json(cmd): Json<Command>,
) -> StatusCode {
    if let Command::Speed { speed } = cmd
        && !speed.is_finite()
    {
        return StatusCode::UNPROCESSABLE_ENTITY;
    }
    shared.control.send_modify(|c| match cmd {
        Command::Pause => c.paused = true,
        Command::Resume => c.paused = false,
        Command::Step => {
            c.paused = true;
            c.step_requests += 1;
        }
        Command::Speed { speed } => c.speed = speed.clamp(SPEED_RANGE.0, SPEED_RANGE.1),
    });
    StatusCode::NO_CONTENT
}

/// The event stream of one page: `init`, then the latest frame whenever it
/// changes, until shutdown. A page that goes away just drops its stream.
async fn events(
    State(shared): State<Arc<Shared>>,
) -> Sse<impl Stream<Item = Result<Event, Infallible>>> {
    shared
        .control
        .send_if_modified(|c| !std::mem::replace(&mut c.started, true));
    let init = Event::default().event("init").data(shared.init.clone());
    let frames = shared.frames.subscribe();
    let controls = shared.control.subscribe();
    let stop = shared.shutdown.subscribe();
    let rest = stream::unfold(
        (frames, controls, stop, 0u8),
        |(mut frames, mut controls, mut stop, stage)| async move {
            if *stop.borrow() {
                return None;
            }
            let event = match stage {
                0 => control_event(&mut controls),
                1 => frame_event(&mut frames),
                _ => tokio::select! {
                    changed = frames.changed() => {
                        changed.ok()?;
                        frame_event(&mut frames)
                    }
                    changed = controls.changed() => {
                        changed.ok()?;
                        control_event(&mut controls)
                    }
                    _ = stop.wait_for(|&s| s) => return None,
                },
            };
            Some((Ok(event), (frames, controls, stop, stage.saturating_add(1))))
        },
    );
    let stream = futures_util::StreamExt::chain(stream::iter([Ok(init)]), rest);
    Sse::new(stream).keep_alive(KeepAlive::default())
}

/// The controls as the page shows them. The page takes them from these
/// events only: a frame may have been encoded just before a change.
fn control_event(controls: &mut watch::Receiver<Control>) -> Event {
    let c = *controls.borrow_and_update();
    let text = format!(r#"{{"paused":{},"speed":{}}}"#, c.paused, c.speed);
    Event::default().event("control").data(text)
}

fn frame_event(frames: &mut watch::Receiver<Arc<str>>) -> Event {
    let frame = frames.borrow_and_update().clone();
    Event::default().event("frame").data(&*frame)
}

/// The parts of the picture that never change.
#[derive(Serialize)]
struct Init {
    scenario: String,
    name: Option<String>,
    policy: &'static str,
    /// The policy's plans carry a certificate (the exact estimator), so
    /// every frame after the first has a certified gap.
    certified: bool,
    seed: u64,
    sensors: usize,
    steps: usize,
    warmup: usize,
    horizon: usize,
    /// Minimum separation in force, cells (0: none).
    min_separation: usize,
    width: f64,
    height: f64,
    cell_size: f64,
    cols: i32,
    rows: i32,
    fov: FovSpec,
    /// Row-major, index `row·cols + col`.
    d_hat: Vec<f64>,
    sources: Vec<SourceOut>,
    /// Rectangles sensors may not enter (the scenario's `no_go`).
    no_go: Vec<RectOut>,
    /// Buildings and screens, in the spec's order (empty when none).
    obstacles: Vec<ObstacleOut>,
}

#[derive(Serialize)]
struct ObstacleOut {
    /// Vertices `[x, y]`, counter-clockwise.
    polygon: Vec<[f64; 2]>,
    /// `building` or `screen`.
    kind: &'static str,
}

#[derive(Serialize)]
struct SourceOut {
    x: f64,
    y: f64,
    rate: f64,
    /// The cone's edges, radians counter-clockwise from east, when it is
    /// narrower than a half-plane.
    cone: Option<[f64; 2]>,
}

#[derive(Serialize)]
struct RectOut {
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
}

impl Init {
    fn new(opts: &LiveOptions, stats: &Stats) -> Self {
        let s = &opts.run.scenario;
        let sources = s
            .sources
            .iter()
            .map(|src| {
                let base = src.frame.y.atan2(src.frame.x);
                SourceOut {
                    x: src.pos.x,
                    y: src.pos.y,
                    rate: src.rate,
                    cone: (src.spread < std::f64::consts::PI - 1e-9)
                        .then_some([base + src.cone.0, base + src.cone.1]),
                }
            })
            .collect();
        Init {
            scenario: opts.run.scenario_id.clone(),
            name: s.spec.name.clone(),
            policy: opts.run.policy.name(),
            certified: opts
                .run
                .policy
                .planner()
                .is_some_and(|p| p.estimator == EstimatorKind::Exact),
            seed: opts.seed,
            sensors: opts.run.sensors,
            steps: opts.run.steps,
            warmup: opts.run.warmup,
            horizon: opts.run.horizon.unwrap_or(s.horizon),
            min_separation: opts.run.separation(),
            width: s.width,
            height: s.height,
            cell_size: s.cell_size,
            cols: s.cols,
            rows: s.rows,
            fov: s.fov,
            d_hat: stats.d_hat.clone(),
            sources,
            no_go: s
                .spec
                .no_go
                .iter()
                .flatten()
                .map(|r| RectOut {
                    x0: r.x0,
                    y0: r.y0,
                    x1: r.x1,
                    y1: r.y1,
                })
                .collect(),
            obstacles: s
                .obstacles
                .list()
                .iter()
                .map(|o| ObstacleOut {
                    polygon: o.polygon.vertices().iter().map(|v| [v.x, v.y]).collect(),
                    kind: match o.kind {
                        ObstacleKind::Building => "building",
                        ObstacleKind::Screen => "screen",
                    },
                })
                .collect(),
        }
    }
}

/// One state of the run.
#[derive(Serialize)]
struct Frame<'a> {
    /// Measured steps done.
    step: usize,
    steps: usize,
    paused: bool,
    speed: f64,
    finished: bool,
    sensors: Vec<SensorOut>,
    /// Per sensor, its cells since the warm-up: `[col, row, col, row, …]`.
    traces: Vec<Vec<i32>>,
    /// `[x, y, status]`, status 0 detected, 1 tracked, 2 lost, 3 unseen.
    targets: Vec<(f64, f64, u8)>,
    metrics: MetricsOut,
    series: &'a Series,
    /// Per sensor, the search values of its last plan (planner policies).
    explain: Vec<Option<ExplainOut<'a>>>,
}

#[derive(Serialize)]
struct SensorOut {
    col: i32,
    row: i32,
    /// Its type's name and field of view.
    #[serde(rename = "type")]
    sensor_type: String,
    fov: FovSpec,
    /// Rank in the last plan, 1 = highest.
    priority: Option<usize>,
    /// The last plan's path from the cell the sensor planned from:
    /// `[col, row, …]`.
    path: Vec<i32>,
    expected: Option<f64>,
    /// What the sensor sees, when obstacles can block its sight (a ground
    /// type in a scenario with obstacles): the outline of
    /// [`vigil::scenario::Scenario::view_outline`] with [`VIEW_RAYS`] rays,
    /// `[x, y, x, y, …]` counter-clockwise, rounded to 0.01. Absent
    /// otherwise: the sensor sees its whole field of view.
    #[serde(skip_serializing_if = "Option::is_none")]
    view: Option<Vec<f64>>,
}

#[derive(Serialize)]
struct ExplainOut<'a> {
    /// The cell the search started from.
    col: i32,
    row: i32,
    values: &'a [Vec<Vec<Option<f64>>>],
}

/// The metrics now (running values over the measured steps).
#[derive(Serialize, Default)]
struct MetricsOut {
    in_zone: usize,
    ad: usize,
    af: Option<f64>,
    ad_mean: f64,
    af_mean: f64,
    once: f64,
    /// The run's `delay` and `missed` so far ([`Sim::entries`]): `delay`
    /// is `None` until a counted target has been detected, `missed` until
    /// one has left the zone.
    delay: Option<f64>,
    missed: Option<f64>,
    calibration: Option<f64>,
    plan_ms: Option<f64>,
    plan_ms_mean: Option<f64>,
    /// Distinct cells the sensors occupy now, and its mean over the run.
    cells: usize,
    cells_mean: f64,
    /// The last plan's `separation_violations` (planner policies).
    violations: Option<u32>,
    /// The fraction of the run's plans with any (planner policies).
    violating_plans: Option<f64>,
    /// The last plan's certified gap, `bound.gap` (exact estimator), and
    /// its mean over the run's plans.
    gap: Option<f64>,
    gap_mean: Option<f64>,
    /// The last plan's rounds after `iterated` (joint coordination).
    joint_rounds: Option<usize>,
}

/// The metrics after every measured step, for the charts.
#[derive(Serialize, Default)]
struct Series {
    ad: Vec<f64>,
    af: Vec<f64>,
    once: Vec<f64>,
    delay: Vec<Option<f64>>,
    missed: Vec<Option<f64>>,
    calibration: Vec<Option<f64>>,
    plan_ms: Vec<Option<f64>>,
    gap: Vec<Option<f64>>,
}

/// Running sums over the measured steps.
#[derive(Default)]
struct Running {
    steps: usize,
    ad: f64,
    af: f64,
    af_steps: usize,
    predicted: f64,
    realized: f64,
    plan_ms: f64,
    plans: usize,
    cells: f64,
    plans_violating: usize,
    gap: f64,
    gaps: usize,
}

fn status_code(s: TargetStatus) -> u8 {
    match s {
        TargetStatus::Detected => 0,
        TargetStatus::Tracked => 1,
        TargetStatus::Lost => 2,
        TargetStatus::Unseen => 3,
    }
}

fn flat(cells: impl IntoIterator<Item = Cell>) -> Vec<i32> {
    cells.into_iter().flat_map(|c| [c.col, c.row]).collect()
}

/// Encodes and publishes the state now.
fn publish(
    shared: &Shared,
    sim: &Sim,
    cfg: &RunConfig,
    plan: Option<&PlanResponse>,
    metrics: MetricsOut,
    series: &Series,
    finished: bool,
) {
    let control = *shared.control.borrow();
    let warmup = cfg.warmup;
    let sensors = sim
        .sensors
        .iter()
        .enumerate()
        .map(|(i, &c)| {
            let planned = plan.and_then(|p| p.plans.get(i));
            let look = sim.scenario.look(sim.types[i], c);
            let view = look.from.is_some().then(|| {
                let round = |v: f64| (v * 100.0).round() / 100.0;
                sim.scenario
                    .view_outline(&look, VIEW_RAYS)
                    .iter()
                    .flat_map(|q| [round(q.x), round(q.y)])
                    .collect()
            });
            SensorOut {
                col: c.col,
                row: c.row,
                sensor_type: sim.scenario.types[sim.types[i]].name.clone(),
                fov: sim.scenario.types[sim.types[i]].fov,
                priority: planned.map(|p| p.priority),
                path: planned
                    .map(|p| {
                        flat(std::iter::once(&p.start).chain(&p.path).map(|o| Cell {
                            col: o.col,
                            row: o.row,
                        }))
                    })
                    .unwrap_or_default(),
                expected: planned.map(|p| p.expected_detections),
                view,
            }
        })
        .collect();
    let explain = match plan {
        Some(p) => p
            .plans
            .iter()
            .map(|p| {
                p.explain.as_ref().map(|Explain { values }| ExplainOut {
                    col: p.start.col,
                    row: p.start.row,
                    values,
                })
            })
            .collect(),
        None => Vec::new(),
    };
    let frame = Frame {
        step: sim.step.saturating_sub(warmup),
        steps: cfg.steps,
        paused: control.paused,
        speed: control.speed,
        finished,
        sensors,
        traces: sim
            .trace
            .iter()
            .map(|t| flat(t.iter().skip(warmup).copied()))
            .collect(),
        targets: sim
            .target_states()
            .into_iter()
            .map(|(p, s)| (p.x, p.y, status_code(s)))
            .collect(),
        metrics,
        series,
        explain,
    };
    match serde_json::to_string(&frame) {
        Ok(text) => {
            shared.frames.send_replace(Arc::from(text));
        }
        Err(e) => eprintln!("live view: a frame could not be encoded: {e}"),
    }
}

/// Waits until the controls allow the next step: a single step asked for,
/// or, running, `1/speed` s after the last. `None` once the controls are
/// gone.
async fn next_step_allowed(
    control: &mut watch::Receiver<Control>,
    consumed: &mut u64,
    last: Instant,
) -> Option<()> {
    loop {
        let c = *control.borrow_and_update();
        if c.step_requests > *consumed {
            *consumed = c.step_requests;
            return Some(());
        }
        if c.paused {
            control.changed().await.ok()?;
            continue;
        }
        let due = last + Duration::from_secs_f64(1.0 / c.speed);
        if Instant::now() >= due {
            return Some(());
        }
        tokio::select! {
            _ = tokio::time::sleep_until(due) => return Some(()),
            changed = control.changed() => changed.ok()?,
        }
    }
}

/// The run: warm-up at once, then one measured step whenever the controls
/// allow, publishing a frame after each.
async fn drive(shared: Arc<Shared>, client: Client, opts: LiveOptions) -> Result<(), RunError> {
    let cfg = &opts.run;
    let mut sim = cfg.warmed_up(opts.seed);
    let mut series = Series::default();
    let mut run = Running::default();
    let mut plan: Option<PlanResponse> = None;
    publish(
        &shared,
        &sim,
        cfg,
        None,
        MetricsOut::default(),
        &series,
        cfg.steps == 0,
    );
    let mut control = shared.control.subscribe();
    if control.wait_for(|c| c.started).await.is_err() {
        return Ok(());
    }
    let mut consumed = control.borrow().step_requests;
    let mut last = Instant::now();
    for k in 0..cfg.steps {
        if next_step_allowed(&mut control, &mut consumed, last)
            .await
            .is_none()
        {
            return Ok(());
        }
        last = Instant::now();
        sim.observe();
        let mut plan_ms = None;
        let mut predicted = None;
        let mut violations = None;
        let mut gap = None;
        let mut joint_rounds = None;
        let next = if cfg.policy.planner().is_some() {
            let mut req = sim.plan_request(cfg.policy, cfg.horizon);
            req.explain = Some(true);
            let (resp, ms) = client.plan(&cfg.scenario_id, &req).await?;
            let next = sim.moves_from_plan(&resp).map_err(RunError::Contract)?;
            plan_ms = Some(ms);
            predicted = resp.expected_by_step.first().copied();
            violations = Some(resp.separation_violations);
            gap = checked_bound(&resp)
                .map_err(RunError::Contract)?
                .map(|b| b.gap);
            joint_rounds = resp.joint.map(|j| j.rounds);
            plan = Some(resp);
            next
        } else {
            sim.local_moves(cfg.policy)
        };
        let count = sim.advance(next);
        run.steps += 1;
        run.ad += count.detected as f64;
        run.cells += count.cells as f64;
        run.plans_violating += usize::from(violations.is_some_and(|v| v > 0));
        let af = (count.in_zone > 0).then(|| count.detected as f64 / count.in_zone as f64);
        if let Some(af) = af {
            run.af += af;
            run.af_steps += 1;
        }
        if let Some(p) = predicted {
            run.predicted += p;
            run.realized += crate::experiment::realized(cfg.policy, &count) as f64;
        }
        if let Some(ms) = plan_ms {
            run.plan_ms += ms;
            run.plans += 1;
        }
        if let Some(g) = gap {
            run.gap += g;
            run.gaps += 1;
        }
        let calibration = (run.predicted > 0.0).then(|| run.realized / run.predicted);
        let entries = sim.entries();
        let (once, delay, missed) = (entries.detected_once(), entries.delay(), entries.missed());
        series.ad.push(count.detected as f64);
        series.af.push(af.unwrap_or(0.0));
        series.once.push(once);
        series.delay.push(delay);
        series.missed.push(missed);
        series.calibration.push(calibration);
        series.plan_ms.push(plan_ms);
        series.gap.push(gap);
        let metrics = MetricsOut {
            in_zone: count.in_zone,
            ad: count.detected,
            af,
            ad_mean: run.ad / run.steps as f64,
            af_mean: if run.af_steps > 0 {
                run.af / run.af_steps as f64
            } else {
                0.0
            },
            once,
            delay,
            missed,
            calibration,
            plan_ms,
            plan_ms_mean: (run.plans > 0).then(|| run.plan_ms / run.plans as f64),
            cells: count.cells,
            cells_mean: run.cells / run.steps as f64,
            violations,
            violating_plans: (run.plans > 0).then(|| run.plans_violating as f64 / run.plans as f64),
            gap,
            gap_mean: (run.gaps > 0).then(|| run.gap / run.gaps as f64),
            joint_rounds,
        };
        publish(
            &shared,
            &sim,
            cfg,
            plan.as_ref(),
            metrics,
            &series,
            k + 1 == cfg.steps,
        );
    }
    Ok(())
}
