//! `vigil-server`: serves the Vigil planning API over HTTP.
//!
//! ```text
//! vigil-server --help            every option, each with an environment variable
//! vigil-server --database-url postgres://… --import-dir DIR
//!                                loads a data directory into the database, then exits
//! ```
//!
//! Logs go to stderr, filtered by `RUST_LOG` (default `info`). The server
//! stops gracefully on SIGINT or SIGTERM, finishing in-flight requests, and
//! exits with status 0.

use std::io::IsTerminal;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::Parser;
use tokio::net::TcpListener;
use tracing_subscriber::EnvFilter;
use vigil::http::config::{Config, LogFormat};
use vigil::http::serve::serve;
use vigil::http::{AppState, router};
use vigil::store::{PgStore, Store};

/// A request's JSON, its handling and its plan make some hundreds of small
/// allocations, which mimalloc serves faster than glibc's allocator: one
/// saturated core serves more plans (measured in `loadtest/README.md`).
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// How long a start waits for an unreachable database before giving up.
const DATABASE_WAIT: Duration = Duration::from_secs(30);

#[tokio::main]
async fn main() -> ExitCode {
    let config = Config::parse();
    // Before the work allocates: memory touched earlier keeps its pages.
    let pages = if config.huge_pages {
        Ok(())
    } else {
        vigil::memory::disable_huge_pages()
    };
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new("info"));
    let logs = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr);
    match config.log_format {
        LogFormat::Json => logs.json().init(),
        LogFormat::Human => logs.with_ansi(std::io::stderr().is_terminal()).init(),
    }

    if let Err(e) = pages {
        tracing::warn!(error = %e, "cannot turn transparent huge pages off; running with the system's pages");
    }

    let started = Instant::now();
    let database = match config.database() {
        Some(url) => match PgStore::connect(url, config.database_timeout(), DATABASE_WAIT).await {
            Ok(store) => Some(store),
            Err(e) => {
                tracing::error!(error = %e, "cannot use the database");
                return ExitCode::FAILURE;
            }
        },
        None => None,
    };
    if let Some(dir) = &config.import_dir {
        let Some(store) = database else {
            tracing::error!("--import-dir needs --database-url");
            return ExitCode::FAILURE;
        };
        return import(&store, dir).await;
    }
    let state = if let Some(store) = database {
        AppState::from_database(&config, store)
    } else {
        let owned = config.clone();
        match tokio::task::spawn_blocking(move || AppState::from_config(&owned)).await {
            Ok(Ok(state)) => state,
            Ok(Err(e)) => {
                tracing::error!(data_dir = %config.data_dir.display(), error = %e, "cannot open the scenario store");
                return ExitCode::FAILURE;
            }
            Err(e) => {
                tracing::error!(error = %e, "failed to load the scenarios");
                return ExitCode::FAILURE;
            }
        }
    };
    if config.database().is_some() {
        tracing::info!(
            elapsed_ms = started.elapsed().as_secs_f64() * 1e3,
            "scenarios kept in the database; each is precomputed here on first use"
        );
    } else {
        tracing::info!(
            elapsed_ms = started.elapsed().as_secs_f64() * 1e3,
            scenarios = state.registry.list().len(),
            data_dir = %config.data_dir.display(),
            "scenarios ready"
        );
    }

    let listener = match TcpListener::bind(config.bind).await {
        Ok(listener) => listener,
        Err(e) => {
            tracing::error!(bind = %config.bind, error = %e, "failed to bind");
            return ExitCode::FAILURE;
        }
    };
    let addr = listener.local_addr().unwrap_or(config.bind);
    tracing::info!("listening on {addr}");

    if let Err(e) = serve(
        listener,
        router(state),
        config.conn_limits(),
        shutdown_signal(),
    )
    .await
    {
        tracing::error!(error = %e, "server error");
        return ExitCode::FAILURE;
    }
    tracing::info!("shut down");
    ExitCode::SUCCESS
}

/// `--import-dir`: loads the valid scenarios of a data directory into the
/// database (corrupt files are logged and skipped, as on a start).
async fn import(store: &PgStore, dir: &std::path::Path) -> ExitCode {
    if !dir.is_dir() {
        tracing::error!(dir = %dir.display(), "no such data directory");
        return ExitCode::FAILURE;
    }
    let owned = dir.to_path_buf();
    let scenarios = match tokio::task::spawn_blocking(move || Store::open(&owned)).await {
        Ok(Ok((_, scenarios))) => scenarios,
        Ok(Err(e)) => {
            tracing::error!(dir = %dir.display(), error = %e, "cannot read the data directory");
            return ExitCode::FAILURE;
        }
        Err(e) => {
            tracing::error!(error = %e, "failed to read the data directory");
            return ExitCode::FAILURE;
        }
    };
    match store.import(&scenarios).await {
        Ok(added) => {
            tracing::info!(
                dir = %dir.display(),
                found = scenarios.len(),
                added,
                already_there = scenarios.len() - added,
                "import done"
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            tracing::error!(error = %e, "import failed; running it again resumes it");
            ExitCode::FAILURE
        }
    }
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
