//! The shared PostgreSQL catalogue (`--database-url`), end to end: real
//! `vigil-server` processes on a real PostgreSQL server, which this harness
//! starts in a temporary directory and removes at the end (see
//! [`cluster`]). Each test gets a database of its own; they run one after
//! the other, the one that stops the server last.
//!
//! A custom harness (`harness = false`): set-up and tear-down around every
//! test. Arguments that are not flags filter the tests by name.

#![allow(clippy::unwrap_used)]

mod cluster;
mod precomputed;
mod server;
mod sessions;
mod tests;

use std::future::Future;
use std::pin::Pin;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

use cluster::Cluster;

/// A test: an async function of the shared server.
type Test = fn(Arc<Cluster>) -> Pin<Box<dyn Future<Output = ()> + Send>>;

fn main() -> ExitCode {
    let filters: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let selected: Vec<(&str, Test)> = tests::ALL
        .iter()
        .copied()
        .filter(|(name, _)| filters.is_empty() || filters.iter().any(|f| name.contains(f.as_str())))
        .collect();
    if std::env::args().any(|a| a == "--list") {
        for (name, _) in &selected {
            println!("{name}: test");
        }
        return ExitCode::SUCCESS;
    }
    println!("\nrunning {} database tests", selected.len());
    if selected.is_empty() {
        return ExitCode::SUCCESS;
    }
    let started = Instant::now();
    let cluster = match std::panic::catch_unwind(Cluster::start) {
        Ok(c) => Arc::new(c),
        Err(_) => {
            eprintln!("error: no PostgreSQL server for the database tests (see above)");
            return ExitCode::FAILURE;
        }
    };
    println!(
        "PostgreSQL at {} ({:.1} s)",
        cluster.base_url,
        started.elapsed().as_secs_f64()
    );
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .expect("a runtime");
    let mut failed = Vec::new();
    for (name, test) in selected.iter().copied() {
        let t = Instant::now();
        let result = runtime.block_on(runtime.spawn(test(cluster.clone())));
        let secs = t.elapsed().as_secs_f64();
        match result {
            Ok(()) => println!("test {name} ... ok ({secs:.1} s)"),
            Err(_) => {
                println!("test {name} ... FAILED ({secs:.1} s)");
                failed.push(name);
            }
        }
    }
    drop(runtime);
    drop(cluster);
    // The servers' logs are kept when a test failed.
    if failed.is_empty() {
        let _ = std::fs::remove_dir_all(server::log_dir());
    } else {
        println!("servers' logs: {}", server::log_dir().display());
    }
    println!(
        "\ndatabase tests: {} passed, {} failed, {:.1} s",
        selected.len() - failed.len(),
        failed.len(),
        started.elapsed().as_secs_f64()
    );
    if failed.is_empty() {
        ExitCode::SUCCESS
    } else {
        println!("failed: {failed:?}");
        ExitCode::FAILURE
    }
}
