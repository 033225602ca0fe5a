//! `vigil-loadtest`: an open-loop load generator for the Vigil planner, and
//! the realistic plan requests it (and the cost-curve benches) replay.
//!
//! - [`workload`]: plan requests taken from `vigil-sim` states.

pub mod workload;
