//! The open-loop engine.
//!
//! - A [`Schedule`] fixes every request's intended send time `t_i` before the
//!   run starts (constant spacing, or exponential gaps from a seeded RNG).
//! - A dispatcher thread sleeps until each `t_i` (`std::thread::sleep`,
//!   tens of microseconds late at most, unlike tokio's millisecond timer
//!   wheel) and queues the request.
//! - `connections` worker tasks take requests off the queue in order, each
//!   sending one at a time over a kept-alive HTTP/1.1 connection.
//! - A request's latency runs from its intended time `t_i` to the end of
//!   its response body, never from when a worker picked it up. When every
//!   connection is busy, requests wait in the queue and the wait counts:
//!   there is no coordinated omission.
//!
//! Only 2xx responses whose intended time falls in the measured window are
//! recorded in the latency histogram (microseconds, 3 significant digits).
//! A 503 counts as `shed`; any other status, a transport error and a
//! timeout count as `errors`. Neither is in the histogram: a fast 503 would
//! flatter it. Requests of the warm-up are sent but not counted at all.
//!
//! A request waits at most `timeout` from its intended time: a request that
//! has waited that long in the queue is not sent, and one in flight is
//! abandoned at that point; both count as errors (timeouts). So a run ends
//! at most `timeout` after the last intended time, however overloaded the
//! server.

use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use hdrhistogram::Histogram;
use reqwest::header::HeaderValue;
use serde::{Deserialize, Serialize};
use tokio::sync::mpsc;

use crate::schedule::{Arrivals, Schedule};

mod http;
mod sessions;
mod target;

pub use http::client;
use http::{auth_header, expect_ok, post, request, with_auth};
use sessions::{SessionSlot, close_sessions, open_sessions};
pub use target::{SessionTarget, Target};

/// One open-loop run.
#[derive(Debug, Clone)]
pub struct RunConfig {
    /// What to hit.
    pub target: Target,
    /// Intended requests per second.
    pub rate: f64,
    /// Arrival process.
    pub arrivals: Arrivals,
    /// Length of the measured window.
    pub duration: Duration,
    /// Length of the warm-up before it (sent, not recorded).
    pub warmup: Duration,
    /// Concurrent connections (worker tasks).
    pub connections: usize,
    /// Seed of the Poisson gaps.
    pub seed: u64,
    /// Longest a request may take from its intended send time.
    pub timeout: Duration,
    /// Sent as `Authorization: Bearer <key>`.
    pub api_key: Option<String>,
}

/// The figures of a run, as `--out` writes them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Intended requests per second.
    pub target_rate: f64,
    /// 2xx responses recorded per second of the measured duration.
    pub achieved_rate: f64,
    /// Measured duration, seconds: from the start of the window to the last
    /// recorded response, at least the configured duration.
    pub duration_s: f64,
    /// Requests intended in the window: 2xx + errors + shed.
    pub requests: u64,
    /// Transport errors, timeouts and non-2xx statuses other than 503.
    pub errors: u64,
    /// 503 responses (load shedding).
    pub shed: u64,
    /// Median latency of the 2xx responses, ms (from the intended time).
    pub p50_ms: f64,
    /// 90th percentile, ms.
    pub p90_ms: f64,
    /// 99th percentile, ms.
    pub p99_ms: f64,
    /// 99.9th percentile, ms.
    pub p999_ms: f64,
    /// Largest latency, ms.
    pub max_ms: f64,
}

/// Everything measured in a run.
#[derive(Debug, Clone)]
pub struct RunReport {
    /// The headline figures.
    pub summary: Summary,
    /// Arrival process used.
    pub arrivals: Arrivals,
    /// Latency of the recorded 2xx responses, µs from the intended time.
    pub latency: Histogram<u64>,
    /// Wait before sending of every request in the window, µs from the
    /// intended time to the moment a connection took it: the dispatcher's
    /// lateness plus the queueing for a free connection. Large values mean
    /// the generator (or its number of connections) is the bottleneck.
    pub send_wait: Histogram<u64>,
    /// Session mode: wait of every request in the window for its
    /// session's previous step to finish, µs (counted in its latency too).
    /// Empty in the other modes.
    pub session_wait: Histogram<u64>,
    /// 2xx responses recorded.
    pub ok: u64,
    /// Non-2xx statuses other than 503.
    pub status_errors: u64,
    /// Connection and protocol errors.
    pub transport_errors: u64,
    /// Requests that reached the timeout (queued or in flight).
    pub timeouts: u64,
    /// Requests sent over the whole run, warm-up included.
    pub sent: u64,
    /// The first error seen, for the report.
    pub first_error: Option<String>,
}

impl RunReport {
    /// A short human-readable report, several lines.
    pub fn describe(&self) -> String {
        let s = &self.summary;
        let mut out = format!(
            "target {:.1}/s ({}), achieved {:.1}/s over {:.2} s: {} requests, {} ok, {} errors, {} shed\n",
            s.target_rate,
            self.arrivals,
            s.achieved_rate,
            s.duration_s,
            s.requests,
            self.ok,
            s.errors,
            s.shed
        );
        out += &format!(
            "latency ms from the intended send time: p50 {:.3}  p90 {:.3}  p99 {:.3}  p99.9 {:.3}  max {:.3}\n",
            s.p50_ms, s.p90_ms, s.p99_ms, s.p999_ms, s.max_ms
        );
        out += &format!(
            "send wait ms (generator lateness + queueing for a connection): p50 {:.3}  p99 {:.3}  max {:.3}",
            ms(&self.send_wait, 0.5),
            ms(&self.send_wait, 0.99),
            max_ms(&self.send_wait)
        );
        if !self.session_wait.is_empty() {
            out += &format!(
                "\nsession wait ms (for the session's previous step): p50 {:.3}  p99 {:.3}  max {:.3}",
                ms(&self.session_wait, 0.5),
                ms(&self.session_wait, 0.99),
                max_ms(&self.session_wait)
            );
        }
        if s.errors > 0 {
            out += &format!(
                "\nerrors: {} bad status, {} transport, {} timeouts; first: {}",
                self.status_errors,
                self.transport_errors,
                self.timeouts,
                self.first_error.as_deref().unwrap_or("-")
            );
        }
        out
    }
}

fn ms(h: &Histogram<u64>, q: f64) -> f64 {
    if h.is_empty() {
        0.0
    } else {
        h.value_at_quantile(q) as f64 / 1e3
    }
}

fn max_ms(h: &Histogram<u64>) -> f64 {
    if h.is_empty() {
        0.0
    } else {
        h.max() as f64 / 1e3
    }
}

/// A latency histogram in microseconds, 3 significant digits, up to an hour
/// (larger values saturate).
fn histogram() -> Result<Histogram<u64>> {
    Histogram::new_with_bounds(1, 3_600_000_000, 3).context("cannot create a histogram")
}

/// Microseconds of `d`, at least 1 (the histogram's lowest value).
fn micros(d: Duration) -> u64 {
    u64::try_from(d.as_micros()).unwrap_or(u64::MAX).max(1)
}

/// Sends the first request once and checks it succeeds, so that a wrong
/// URL, scenario, key or body fails at once with a clear message rather
/// than as a run full of errors.
///
/// # Errors
/// If the server cannot be reached or does not answer 2xx.
pub async fn preflight(target: &Target, api_key: Option<&str>, timeout: Duration) -> Result<()> {
    let client = client(1)?;
    let auth = auth_header(api_key)?;
    if let Target::Session(t) = target {
        // One session, its first step, closed again.
        let one = Arc::new(SessionTarget {
            sessions_url: t.sessions_url.clone(),
            step_url: t.step_url.clone(),
            bases: t.bases.clone(),
            create: t.create.clone(),
            warmup: Vec::new(),
            steps: Vec::new(),
            sessions: 1,
            idempotency_keys: t.idempotency_keys,
        });
        let slots = open_sessions(&client, &one, auth.as_ref(), timeout).await?;
        let first = t.warmup.first().or(t.steps.first()).cloned();
        let stepped = match (&slots[..], first) {
            ([slot], Some(body)) => expect_ok(
                with_auth(post(&client, &slot.step_url, body), auth.as_ref()).timeout(timeout),
                &format!("POST {}", slot.step_url),
            )
            .await
            .map(|_| ()),
            _ => Ok(()),
        };
        close_sessions(&client, &slots, auth.as_ref(), timeout).await;
        return stepped;
    }
    let res = request(&client, target, 0, auth.as_ref())
        .timeout(timeout)
        .send()
        .await
        .with_context(|| format!("cannot reach {}", target.url()))?;
    let status = res.status();
    if !status.is_success() {
        let body = res.text().await.unwrap_or_default();
        let body: String = body.chars().take(500).collect();
        bail!("{} answered {status}: {body}", target.url());
    }
    res.bytes()
        .await
        .with_context(|| format!("reading the answer of {}", target.url()))?;
    Ok(())
}

/// A request handed to a worker.
#[derive(Debug, Clone, Copy)]
struct Job {
    seq: u64,
    intended: Instant,
    measured: bool,
}

/// What the workers record, shared (the lock is held for a few
/// instructions per response).
struct Recorder {
    latency: Histogram<u64>,
    send_wait: Histogram<u64>,
    session_wait: Histogram<u64>,
    ok: u64,
    shed: u64,
    status_errors: u64,
    transport_errors: u64,
    timeouts: u64,
    sent: u64,
    last_ok: Option<Instant>,
    first_error: Option<String>,
}

impl Recorder {
    fn error(&mut self, msg: impl FnOnce() -> String) {
        if self.first_error.is_none() {
            self.first_error = Some(msg());
        }
    }
}

/// Runs `cfg` on the current tokio runtime and reports it.
///
/// The intended times are `[0, warmup + duration)` from the start; requests
/// intended in `[warmup, warmup + duration)` are measured. The run returns
/// once every request has been answered or has timed out.
///
/// # Errors
/// If the configuration is invalid (rate, connections, API key) or the
/// HTTP client cannot be built. Failed requests are not errors of the run:
/// they are counted in the report.
pub async fn run(cfg: &RunConfig) -> Result<RunReport> {
    if cfg.connections == 0 {
        bail!("--connections must be at least 1");
    }
    if cfg.duration.is_zero() {
        bail!("--duration must be positive");
    }
    if cfg.timeout.is_zero() {
        bail!("--timeout must be positive");
    }
    let warmup_s = cfg.warmup.as_secs_f64();
    let schedule = Schedule::new(
        cfg.arrivals,
        cfg.rate,
        warmup_s + cfg.duration.as_secs_f64(),
        cfg.seed,
    )?;
    let client = client(cfg.connections)?;
    let auth = auth_header(cfg.api_key.as_deref())?;
    let recorder = Arc::new(Mutex::new(Recorder {
        latency: histogram()?,
        send_wait: histogram()?,
        session_wait: histogram()?,
        ok: 0,
        shed: 0,
        status_errors: 0,
        transport_errors: 0,
        timeouts: 0,
        sent: 0,
        last_ok: None,
        first_error: None,
    }));

    let sessions: Option<Arc<[SessionSlot]>> = match &cfg.target {
        Target::Session(t) => Some(
            open_sessions(&client, t, auth.as_ref(), cfg.timeout)
                .await?
                .into(),
        ),
        _ => None,
    };

    let (tx, rx) = mpsc::unbounded_channel::<Job>();
    let rx = Arc::new(tokio::sync::Mutex::new(rx));
    let target = Arc::new(cfg.target.clone());
    let mut workers = Vec::with_capacity(cfg.connections);
    for _ in 0..cfg.connections {
        let w = Worker {
            client: client.clone(),
            target: Arc::clone(&target),
            sessions: sessions.clone(),
            rx: Arc::clone(&rx),
            recorder: Arc::clone(&recorder),
            auth: auth.clone(),
            timeout: cfg.timeout,
        };
        workers.push(tokio::spawn(w.run()));
    }

    // A little lead so that the workers are waiting when the first request
    // is due.
    let start = Instant::now() + Duration::from_millis(20);
    let window_start = start + cfg.warmup;
    let dispatcher = std::thread::Builder::new()
        .name("vigil-loadtest-dispatch".into())
        .spawn(move || dispatch(schedule, start, warmup_s, tx))
        .context("cannot start the dispatcher thread")?;

    for w in workers {
        w.await.context("a worker task failed")?;
    }
    // The workers only stop once the dispatcher has dropped the queue's
    // sender, so this does not block.
    if dispatcher.join().is_err() {
        bail!("the dispatcher thread panicked");
    }
    if let Some(slots) = &sessions {
        close_sessions(&client, slots, auth.as_ref(), cfg.timeout).await;
    }

    let rec = Arc::try_unwrap(recorder)
        .map_err(|_| anyhow::anyhow!("a worker outlived the run"))?
        .into_inner()
        .unwrap_or_else(PoisonError::into_inner);
    let configured = cfg.duration.as_secs_f64();
    let duration_s = rec
        .last_ok
        .map(|t| t.saturating_duration_since(window_start).as_secs_f64())
        .unwrap_or(0.0)
        .max(configured);
    let errors = rec.status_errors + rec.transport_errors + rec.timeouts;
    let summary = Summary {
        target_rate: cfg.rate,
        achieved_rate: rec.ok as f64 / duration_s,
        duration_s,
        requests: rec.ok + errors + rec.shed,
        errors,
        shed: rec.shed,
        p50_ms: ms(&rec.latency, 0.5),
        p90_ms: ms(&rec.latency, 0.9),
        p99_ms: ms(&rec.latency, 0.99),
        p999_ms: ms(&rec.latency, 0.999),
        max_ms: max_ms(&rec.latency),
    };
    Ok(RunReport {
        summary,
        arrivals: cfg.arrivals,
        latency: rec.latency,
        send_wait: rec.send_wait,
        session_wait: rec.session_wait,
        ok: rec.ok,
        status_errors: rec.status_errors,
        transport_errors: rec.transport_errors,
        timeouts: rec.timeouts,
        sent: rec.sent,
        first_error: rec.first_error,
    })
}

/// Sleeps until each intended time and queues its request.
fn dispatch(schedule: Schedule, start: Instant, warmup_s: f64, tx: mpsc::UnboundedSender<Job>) {
    for (seq, t) in (0u64..).zip(schedule) {
        let intended = start + Duration::from_secs_f64(t);
        let now = Instant::now();
        if intended > now {
            std::thread::sleep(intended - now);
        }
        let job = Job {
            seq,
            intended,
            measured: t >= warmup_s,
        };
        if tx.send(job).is_err() {
            return;
        }
    }
}

fn lock(r: &Mutex<Recorder>) -> std::sync::MutexGuard<'_, Recorder> {
    r.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Session mode: request `seq` of a run over `sessions` sessions is step
/// `seq / sessions` of session `seq % sessions`, and that step sends body
/// `(seq / sessions) % bodies`: each session walks its own sequence of
/// bodies in order, cycled when exhausted.
///
/// Returns `(session, step, body)`.
pub fn session_step_of(seq: u64, sessions: usize, bodies: usize) -> (usize, u64, usize) {
    let k = sessions.max(1) as u64;
    let step = seq / k;
    (
        (seq % k) as usize,
        step,
        (step % bodies.max(1) as u64) as usize,
    )
}

/// One connection's task.
struct Worker {
    client: reqwest::Client,
    target: Arc<Target>,
    /// Session mode: the open sessions.
    sessions: Option<Arc<[SessionSlot]>>,
    rx: Arc<tokio::sync::Mutex<mpsc::UnboundedReceiver<Job>>>,
    recorder: Arc<Mutex<Recorder>>,
    auth: Option<HeaderValue>,
    timeout: Duration,
}

impl Worker {
    /// Takes the next queued request, sends it, records it; until the
    /// queue closes.
    ///
    /// In session mode, request `seq` first waits for the previous step of
    /// its session ([`session_step_of`]) to finish: a session's steps never
    /// overlap, and the wait counts in the latency (from the intended
    /// time), as queueing does. The previous step was taken off the queue
    /// earlier, by another worker, so the wait always ends, at the latest
    /// one timeout after that step's intended time.
    async fn run(self) {
        let Worker {
            client,
            target,
            sessions,
            rx,
            recorder,
            auth,
            timeout,
        } = self;
        loop {
            let next = { rx.lock().await.recv().await };
            let Some(job) = next else { return };
            let taken = Instant::now();
            let waited = taken.saturating_duration_since(job.intended);
            if job.measured {
                lock(&recorder).send_wait.saturating_record(micros(waited));
            }
            // Session mode: this step's session, and its place in it.
            let slot = match (&sessions, &*target) {
                (Some(slots), Target::Session(t)) => {
                    let (k, step, body) = session_step_of(job.seq, slots.len(), t.steps.len());
                    let slot = &slots[k];
                    let mut done = slot.done.subscribe();
                    // The sender lives in `slots`: the wait cannot fail.
                    let _ = done.wait_for(|&d| d >= step).await;
                    if job.measured {
                        let w = Instant::now().saturating_duration_since(taken);
                        lock(&recorder).session_wait.saturating_record(micros(w));
                    }
                    let url = &slot.step_urls[(k + step as usize) % slot.step_urls.len()];
                    let key = t.idempotency_keys.then(|| step.to_string());
                    Some((slot, url, step, t.steps[body].clone(), key))
                }
                _ => None,
            };
            let waited = Instant::now().saturating_duration_since(job.intended);
            let outcome = if waited >= timeout {
                // Waited its whole budget before sending: not sent.
                None
            } else {
                let rb = match &slot {
                    Some((_, url, _, body, key)) => {
                        let rb = post(&client, url, body.clone());
                        match key {
                            Some(key) => rb.header("Idempotency-Key", key.as_str()),
                            None => rb,
                        }
                    }
                    None => request(&client, &target, job.seq, None),
                };
                Some(
                    async {
                        let res = with_auth(rb, auth.as_ref())
                            .timeout(timeout - waited)
                            .send()
                            .await?;
                        let status = res.status();
                        res.bytes().await?;
                        Ok::<_, reqwest::Error>(status)
                    }
                    .await,
                )
            };
            let done = Instant::now();
            if let Some((slot, _, step, _, _)) = &slot {
                slot.done.send_replace(step + 1);
            }
            let mut r = lock(&recorder);
            let Some(outcome) = outcome else {
                if job.measured {
                    r.timeouts += 1;
                    r.error(|| {
                        format!(
                            "timed out after {timeout:?} waiting for a connection or its session"
                        )
                    });
                }
                continue;
            };
            r.sent += 1;
            if !job.measured {
                continue;
            }
            match outcome {
                Ok(status) if status.is_success() => {
                    r.ok += 1;
                    r.latency
                        .saturating_record(micros(done.saturating_duration_since(job.intended)));
                    r.last_ok = Some(r.last_ok.map_or(done, |t| t.max(done)));
                }
                Ok(status) if status == reqwest::StatusCode::SERVICE_UNAVAILABLE => r.shed += 1,
                Ok(status) => {
                    r.status_errors += 1;
                    r.error(|| format!("status {status}"));
                }
                Err(e) if e.is_timeout() => {
                    r.timeouts += 1;
                    r.error(|| format!("timed out after {timeout:?}: {e}"));
                }
                Err(e) => {
                    r.transport_errors += 1;
                    r.error(|| format!("{e}"));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_go_round_the_sessions_each_walking_its_bodies_in_order() {
        // 3 sessions, 2 bodies: 0,1,2 are step 0 of sessions 0,1,2 (body
        // 0); 3,4,5 their step 1 (body 1); 6 is session 0's step 2, body 0
        // again.
        let got: Vec<_> = (0..8).map(|i| session_step_of(i, 3, 2)).collect();
        assert_eq!(
            got,
            [
                (0, 0, 0),
                (1, 0, 0),
                (2, 0, 0),
                (0, 1, 1),
                (1, 1, 1),
                (2, 1, 1),
                (0, 2, 0),
                (1, 2, 0)
            ]
        );
        // Every session's steps are consecutive, whatever the counts.
        for (k, n) in [(1, 1), (4, 7), (32, 200)] {
            let mut next = vec![0u64; k];
            for i in 0..1000 {
                let (s, step, body) = session_step_of(i, k, n);
                assert_eq!(step, next[s]);
                assert_eq!(body as u64, step % n as u64);
                next[s] += 1;
            }
        }
    }
}
