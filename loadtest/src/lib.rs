//! `vigil-loadtest`: an open-loop load generator for the Vigil planner, and
//! the realistic plan requests it (and the cost-curve benches) replay.
//!
//! - [`workload`]: plan requests taken from `vigil-sim` states.
//! - [`requests`]: generating, reading and writing files of request bodies.
//! - [`schedule`]: intended send times (constant or Poisson arrivals).
//! - [`generator`]: the open-loop engine (latency from the intended send
//!   time, no coordinated omission, HdrHistogram).
//! - [`sweep`]: climbing the rate until p99 passes an SLO (the knee).
//! - [`inproc`]: the in-process plan time of the same requests, and the
//!   HTTP efficiency.
//! - [`session`]: session mode: a session's steps replayed in process
//!   ([`session::session_step`]), timed beside the stateless plans.
//! - [`certify`]: the certified gap and plan time of each coordination.
//! - [`accuracy`]: the exact estimator's error against a fine angular grid.
//! - [`report`]: the summary of a whole `run.sh` session.
//!
//! The method and the figures are in the crate's `README.md`.

pub mod accuracy;
pub mod certify;
pub mod generator;
pub mod inproc;
pub mod report;
pub mod requests;
pub mod schedule;
pub mod session;
pub mod sweep;
pub mod workload;
