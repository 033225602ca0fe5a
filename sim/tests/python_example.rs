//! The external simulator in Python (`examples/python/drive.py`, standard
//! library only) against a Vigil server started in-process on a loopback
//! port: it registers its scenario, plans 50 steps and prints its
//! detections. Without `python3` this test installs Debian's (see
//! `vigil_testenv::python3`), and FAILS when it cannot.

use std::path::Path;
use std::process::Command;
use std::time::Duration;

use vigil_sim::client::spawn_local_server;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn python_example_drives_the_planner() {
    let python3 = vigil_testenv::python3();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/python/drive.py");
    let base = spawn_local_server().await.expect("in-process planner");
    let run = tokio::task::spawn_blocking(move || {
        Command::new(&python3).arg(&script).arg(&base).output()
    });
    let out = tokio::time::timeout(Duration::from_secs(120), run)
        .await
        .expect("drive.py finishes within 2 minutes")
        .expect("joined")
        .expect("python3 runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "drive.py failed: {stderr}\n{stdout}");
    assert!(stdout.starts_with("scenario s-"), "{stdout}");
    let steps = stdout.lines().filter(|l| l.starts_with("step ")).count();
    assert_eq!(steps, 50, "{stdout}");
    let done = stdout
        .lines()
        .find(|l| l.starts_with("done: 50 steps, "))
        .unwrap_or_else(|| panic!("no summary line: {stdout}"));
    let detections: usize = done
        .trim_start_matches("done: 50 steps, ")
        .split(' ')
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("bad summary line: {done}"));
    // The planned sensors see a few targets per step (about 5 of 13).
    assert!(detections > 50, "{done}");
}
