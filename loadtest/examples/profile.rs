#![allow(missing_docs, clippy::unwrap_used)]
use std::time::Instant;
use vigil::planner::Planner;
use vigil::scenario::builtins;
use vigil_loadtest::workload::Workload;

fn main() {
    let planner = Planner::new(builtins().remove(0));
    let t0 = Instant::now();
    let reqs = Workload::reference().requests(&planner, 20);
    eprintln!("built in {:?}", t0.elapsed());
    let n: usize = reqs.iter().map(|r| r.targets.len()).sum();
    eprintln!("mean targets {}", n as f64 / reqs.len() as f64);
    let iters: usize = std::env::args()
        .nth(1)
        .map(|a| a.parse().unwrap())
        .unwrap_or(200);
    let mut times = Vec::new();
    for i in 0..iters {
        let t = Instant::now();
        std::hint::black_box(planner.plan_request(&reqs[i % reqs.len()]).unwrap());
        times.push(t.elapsed().as_secs_f64() * 1e6);
    }
    times.sort_by(f64::total_cmp);
    eprintln!(
        "median {:.1} us p90 {:.1}",
        times[times.len() / 2],
        times[times.len() * 9 / 10]
    );
}
