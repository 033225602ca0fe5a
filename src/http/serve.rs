//! Serving connections: the accept loop, with the limits `axum::serve` does
//! not offer (hyper's own header timer also runs while a keep-alive
//! connection waits for its next request, so it cannot tell the two apart):
//! - a connection that has not sent a whole request head within
//!   [`ConnLimits::header_timeout`] of its first byte (or of opening) is
//!   closed;
//! - a keep-alive connection idle (no request under way, nothing sent) for
//!   [`ConnLimits::idle_timeout`] is closed;
//! - at most [`ConnLimits::max_connections`] are open at once: past that, a
//!   new connection is closed at once, and the open ones are served as
//!   usual.
//!
//! Each connection's phase (reading a head, busy, idle) is kept by a
//! wrapper around its socket (bytes read while idle start a head) and by
//! the service (a request in progress is busy). On shutdown the loop stops
//! accepting, asks every connection to finish its requests and close, and
//! returns once all have.

use std::convert::Infallible;
use std::future::Future;
use std::io;
use std::pin::Pin;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::task::{Context, Poll};
use std::time::Duration;

use crate::metric_names;
use axum::Router;
use axum::body::Body;
use hyper::body::Incoming;
use hyper_util::rt::{TokioExecutor, TokioIo};
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{Notify, Semaphore, watch};
use tokio::time::Instant;
use tower::ServiceExt;

/// Limits on connections.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ConnLimits {
    /// Time to send a whole request head, from its first byte (or from
    /// opening the connection).
    pub header_timeout: Duration,
    /// Time a keep-alive connection may wait idle for its next request.
    pub idle_timeout: Duration,
    /// Most connections open at once.
    pub max_connections: usize,
}

impl ConnLimits {
    /// The defaults, which `vigil-server`'s flags also start from.
    pub const DEFAULT: ConnLimits = ConnLimits {
        header_timeout: Duration::from_secs(10),
        idle_timeout: Duration::from_secs(60),
        max_connections: 10_000,
    };
}

impl Default for ConnLimits {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Where a connection is.
#[derive(Debug, Clone, Copy)]
enum Phase {
    /// Waiting for a request head since then (opened, or a first byte
    /// after idling).
    Head(Instant),
    /// Requests under way.
    Busy,
    /// Nothing under way since then.
    Idle(Instant),
}

/// A connection's phase, shared by its socket wrapper, its service and
/// its watchdog.
#[derive(Debug)]
struct Watch {
    phase: Mutex<Phase>,
    in_flight: AtomicUsize,
    changed: Notify,
}

impl Watch {
    fn new() -> Self {
        Watch {
            phase: Mutex::new(Phase::Head(Instant::now())),
            in_flight: AtomicUsize::new(0),
            changed: Notify::new(),
        }
    }

    fn set(&self, phase: Phase) {
        *self.phase.lock().unwrap_or_else(PoisonError::into_inner) = phase;
        self.changed.notify_one();
    }

    fn get(&self) -> Phase {
        *self.phase.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Bytes arrived: an idle connection starts a request head.
    fn read_some(&self) {
        let mut phase = self.phase.lock().unwrap_or_else(PoisonError::into_inner);
        if let Phase::Idle(_) = *phase {
            *phase = Phase::Head(Instant::now());
            drop(phase);
            self.changed.notify_one();
        }
    }

    fn begin(&self) {
        self.in_flight.fetch_add(1, Ordering::SeqCst);
        self.set(Phase::Busy);
    }

    fn end(&self) {
        if self.in_flight.fetch_sub(1, Ordering::SeqCst) == 1 {
            self.set(Phase::Idle(Instant::now()));
        }
    }

    /// When the connection is to be closed unless its phase changes, and
    /// why; `None` while busy.
    fn deadline(&self, limits: &ConnLimits) -> Option<(Instant, &'static str)> {
        match self.get() {
            Phase::Head(t) => Some((t + limits.header_timeout, "header_timeout")),
            Phase::Idle(t) => Some((t + limits.idle_timeout, "idle_timeout")),
            Phase::Busy => None,
        }
    }
}

/// Ends a request's busy phase when its service future ends or is dropped.
struct Busy(Arc<Watch>);

impl Drop for Busy {
    fn drop(&mut self) {
        self.0.end();
    }
}

/// A socket that tells its [`Watch`] when bytes arrive.
struct Watched {
    inner: TcpStream,
    watch: Arc<Watch>,
}

impl AsyncRead for Watched {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        let before = buf.filled().len();
        let res = Pin::new(&mut self.inner).poll_read(cx, buf);
        if matches!(res, Poll::Ready(Ok(()))) && buf.filled().len() > before {
            self.watch.read_some();
        }
        res
    }
}

impl AsyncWrite for Watched {
    fn poll_write(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.inner).poll_write(cx, buf)
    }

    fn poll_flush(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.inner).poll_flush(cx)
    }

    fn poll_shutdown(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.inner).poll_shutdown(cx)
    }

    fn poll_write_vectored(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        bufs: &[io::IoSlice<'_>],
    ) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.inner).poll_write_vectored(cx, bufs)
    }

    fn is_write_vectored(&self) -> bool {
        self.inner.is_write_vectored()
    }
}

/// Serves `app` on `listener` within `limits` until `shutdown` resolves,
/// then finishes the requests under way and returns.
///
/// # Errors
/// Never in practice: a failed accept (out of file descriptors, say) is
/// logged and retried after a pause.
pub async fn serve(
    listener: TcpListener,
    app: Router,
    limits: ConnLimits,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> io::Result<()> {
    let max = limits.max_connections.clamp(1, Semaphore::MAX_PERMITS);
    let slots = Arc::new(Semaphore::new(max));
    let (stop_tx, stop_rx) = watch::channel(false);
    tokio::pin!(shutdown);
    loop {
        let (stream, _) = tokio::select! {
            () = &mut shutdown => break,
            accepted = listener.accept() => match accepted {
                Ok(accepted) => accepted,
                Err(e) => {
                    tracing::warn!(error = %e, "accept failed");
                    tokio::time::sleep(Duration::from_millis(50)).await;
                    continue;
                }
            },
        };
        let Ok(slot) = Arc::clone(&slots).try_acquire_owned() else {
            // Full: close this one at once; the open ones go on.
            metrics::counter!(metric_names::CONNECTIONS_REFUSED_TOTAL).increment(1);
            drop(stream);
            continue;
        };
        let (app, mut stop_rx) = (app.clone(), stop_rx.clone());
        tokio::spawn(async move {
            let _slot = slot;
            metrics::gauge!(metric_names::CONNECTIONS_OPEN).increment(1.0);
            serve_connection(stream, app, limits, &mut stop_rx).await;
            metrics::gauge!(metric_names::CONNECTIONS_OPEN).decrement(1.0);
        });
    }
    drop(listener);
    let _ = stop_tx.send(true);
    // Every connection holds a slot until it is done.
    let _all = slots.acquire_many(max as u32).await;
    Ok(())
}

async fn serve_connection(
    stream: TcpStream,
    app: Router,
    limits: ConnLimits,
    stop: &mut watch::Receiver<bool>,
) {
    let _ = stream.set_nodelay(true);
    let watch = Arc::new(Watch::new());
    let io = TokioIo::new(Watched {
        inner: stream,
        watch: Arc::clone(&watch),
    });
    let service_watch = Arc::clone(&watch);
    let service = hyper::service::service_fn(move |req: hyper::Request<Incoming>| {
        service_watch.begin();
        let busy = Busy(Arc::clone(&service_watch));
        let app = app.clone();
        async move {
            let _busy = busy;
            let res = app.oneshot(req.map(Body::new)).await;
            Ok::<_, Infallible>(match res {
                Ok(res) => res,
                Err(never) => match never {},
            })
        }
    });
    let builder = hyper_util::server::conn::auto::Builder::new(TokioExecutor::new());
    let conn = builder.serve_connection_with_upgrades(io, service);
    tokio::pin!(conn);
    let mut stopping = false;
    loop {
        let deadline = watch.deadline(&limits);
        let sleep = async {
            match deadline {
                Some((at, _)) => tokio::time::sleep_until(at).await,
                None => std::future::pending().await,
            }
        };
        tokio::select! {
            _ = conn.as_mut() => return,
            () = watch.changed.notified() => {}
            () = sleep => {
                // Still the same phase past its deadline: close.
                if let (Some((_, why)), Some((at, _))) = (deadline, watch.deadline(&limits))
                    && at <= Instant::now()
                {
                    metrics::counter!(metric_names::CONNECTIONS_CLOSED_TOTAL, "reason" => why).increment(1);
                    return;
                }
            }
            changed = stop.changed(), if !stopping => {
                if changed.is_err() || *stop.borrow() {
                    stopping = true;
                    conn.as_mut().graceful_shutdown();
                }
            }
        }
    }
}
