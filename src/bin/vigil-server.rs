//! `vigil-server`: serves the Vigil planning API over HTTP.
//!
//! ```text
//! vigil-server [--bind ADDR]     (env VIGIL_BIND, default 127.0.0.1:8080)
//! ```
//!
//! Logs go to stderr, filtered by `RUST_LOG` (default `info`). The server
//! stops gracefully on SIGINT or SIGTERM, finishing in-flight requests, and
//! exits with status 0.

use std::io::IsTerminal;
use std::net::SocketAddr;
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use tokio::net::TcpListener;
use tracing_subscriber::EnvFilter;
use vigil::http::{AppState, router};

/// Command-line configuration.
#[derive(Debug, Parser)]
#[command(version, about = "Serves the Vigil planning API over HTTP")]
struct Args {
    /// Address to listen on.
    #[arg(long, env = "VIGIL_BIND", default_value = "127.0.0.1:8080")]
    bind: SocketAddr,
}

#[tokio::main]
async fn main() -> ExitCode {
    let args = Args::parse();
    tracing_subscriber::fmt()
        .with_env_filter(
            EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new("info")),
        )
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .init();

    let started = Instant::now();
    let state = match tokio::task::spawn_blocking(AppState::new).await {
        Ok(state) => state,
        Err(e) => {
            tracing::error!(error = %e, "failed to precompute the built-in scenarios");
            return ExitCode::FAILURE;
        }
    };
    tracing::info!(
        elapsed_ms = started.elapsed().as_secs_f64() * 1e3,
        "precomputed the built-in scenarios"
    );

    let listener = match TcpListener::bind(args.bind).await {
        Ok(listener) => listener,
        Err(e) => {
            tracing::error!(bind = %args.bind, error = %e, "failed to bind");
            return ExitCode::FAILURE;
        }
    };
    let addr = listener.local_addr().unwrap_or(args.bind);
    tracing::info!("listening on {addr}");

    if let Err(e) = axum::serve(listener, router(state))
        .with_graceful_shutdown(shutdown_signal())
        .await
    {
        tracing::error!(error = %e, "server error");
        return ExitCode::FAILURE;
    }
    tracing::info!("shut down");
    ExitCode::SUCCESS
}

/// Resolves on SIGINT (Ctrl+C) or, on Unix, SIGTERM. If a handler cannot be
/// installed, that signal is logged and ignored.
async fn shutdown_signal() {
    let ctrl_c = async {
        if let Err(e) = tokio::signal::ctrl_c().await {
            tracing::error!(error = %e, "cannot listen for SIGINT");
            std::future::pending::<()>().await;
        }
    };

    #[cfg(unix)]
    let terminate = async {
        use tokio::signal::unix::{SignalKind, signal};
        match signal(SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(e) => {
                tracing::error!(error = %e, "cannot listen for SIGTERM");
                std::future::pending::<()>().await;
            }
        }
    };

    #[cfg(not(unix))]
    let terminate = std::future::pending::<()>();

    tokio::select! {
        () = ctrl_c => {},
        () = terminate => {},
    }
    tracing::info!("shutdown signal received, finishing in-flight requests");
}
