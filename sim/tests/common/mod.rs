//! What the tests that run the `vigil-sim` binary share: a temporary
//! directory for its reports, and running it.

// Each test binary uses the part it needs.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

use serde_json::Value;

/// The binary under test.
pub const BIN: &str = env!("CARGO_BIN_EXE_vigil-sim");

/// A temporary directory of one test, removed at the end.
pub struct TempDir(PathBuf);

impl TempDir {
    /// `vigil-sim-NAME-PID` in the system's temporary directory.
    pub fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("vigil-sim-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        TempDir(dir)
    }

    /// The path of the report `NAME.json` in it.
    pub fn json(&self, name: &str) -> PathBuf {
        self.0.join(format!("{name}.json"))
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Starts `vigil-sim ARGS` (its output captured).
pub fn start(args: &[&str]) -> Child {
    Command::new(BIN)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("vigil-sim starts")
}

/// Runs the commands (each `vigil-sim ARGS`, with its own in-process
/// server) at once; their outputs in order.
pub fn run_all(commands: &[Vec<String>]) -> Vec<Output> {
    let children: Vec<Child> = commands
        .iter()
        .map(|args| start(&args.iter().map(String::as_str).collect::<Vec<_>>()))
        .collect();
    children
        .into_iter()
        .map(|c| c.wait_with_output().expect("vigil-sim ends"))
        .collect()
}

/// `words` and `--json JSON`.
pub fn args(words: &[&str], json: &Path) -> Vec<String> {
    let mut v: Vec<String> = words.iter().map(|&w| w.to_owned()).collect();
    v.push("--json".into());
    v.push(json.display().to_string());
    v
}

/// The rows of a successful run's JSON report at `json`.
pub fn rows(out: &Output, json: &Path) -> Vec<Value> {
    assert!(
        out.status.success(),
        "vigil-sim failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(json).expect("report")).expect("JSON");
    report["runs"].as_array().expect("runs").clone()
}
