#![allow(missing_docs, clippy::unwrap_used)]
//! The exact estimator's error against 4,096 rays per π, for every
//! built-in with the fleets it was made for, at its default grid (with
//! the plain midpoint rule, then the area correction) and at the
//! densities given as arguments (rays per π, e.g. `96 192`):
//!
//! ```text
//! cargo run --release -p vigil-loadtest --example accuracy [-- DENSITY…]
//! ```
use vigil::estimator::SourceRays;
use vigil::planner::Planner;
use vigil_loadtest::accuracy::{REFERENCE_RAYS_PER_PI, errors};
use vigil_loadtest::requests::planner_for;
use vigil_loadtest::workload::Workload;
use vigil_sim::driver::{fleet_size, fleet_types};

/// Requests per case: consecutive states of one run.
const STATES: usize = 6;

fn main() {
    let densities: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("a density in rays per π"))
        .collect();
    println!(
        "| scenario | fleet | rays per π | values | mean value | max abs | mean abs | max rel | mean rel |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for (id, fleet) in [
        ("paper-v10", None),
        ("paper-v15", None),
        ("site-gates", None),
        ("site-fleet", None),
        ("site-fleet", Some("drone:4,robot:6")),
    ] {
        let planner = planner_for(id).unwrap();
        let n = fleet.map_or(10, |f| fleet_size(f).unwrap());
        let types = fleet_types(&planner.scenario, fleet, n).unwrap();
        let reqs = Workload::reference().requests_of_fleet(&planner, STATES, types);
        let fine = SourceRays::with_density(&planner.scenario, REFERENCE_RAYS_PER_PI);
        let default = SourceRays::density(&planner.scenario);
        let plain = Planner::with_rays_per_pi(planner.scenario.clone(), default).plain_midpoint();
        let mut rows = vec![
            (format!("{default} plain"), errors(&plain, &reqs, &fine)),
            (format!("{default}"), errors(&planner, &reqs, &fine)),
        ];
        for &d in &densities {
            let coarse = Planner::with_rays_per_pi(planner.scenario.clone(), d);
            rows.push((format!("{d}"), errors(&coarse, &reqs, &fine)));
        }
        for (d, e) in rows {
            println!(
                "| {id} | {} | {d} | {} | {:.3} | {:.2e} | {:.2e} | {:.2e} | {:.2e} |",
                fleet.unwrap_or("10 default"),
                e.values,
                e.mean_value,
                e.max_abs,
                e.mean_abs,
                e.max_rel,
                e.mean_rel
            );
        }
    }
}
