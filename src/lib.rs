//! Vigil: T-step ahead planning of mobile surveillance sensors that maximise
//! the expected number of targets detected, after Krishna, Hexmoor and
//! Sogani, "A T-Step Ahead Optimal Target Detection Algorithm for a Multi
//! Sensor Surveillance System".
//!
//! The algorithm is plain synchronous code, layered as the paper is:
//! - [`obstacle`]: buildings and screens: sight lines they block, flights they end;
//! - [`scenario`]: the model (zone, lattice, sources, field of view), validated once;
//! - [`stats`]: the offline per-cell statistics (`lambda_hat`, `escape_time`, `d_hat`);
//! - [`estimator`]: `n̂(k,t)`, by the paper's equations or exactly;
//! - [`search`]: the best T-step path of one sensor (dynamic programming);
//! - [`coordination`]: priority and iterated coordination of several sensors;
//! - [`separation`]: the minimum separation between sensors, counted and kept;
//! - [`planner`]: a scenario's planner and the request/response types;
//! - [`session`]: the state of a step-by-step client, turned into plan requests;
//! - [`world`]: a simulation of the target process, for checks and simulators.
//!
//! [`cancel`] lets the HTTP layer stop a plan nobody waits for, and [`cost`]
//! predicts what a precomputation or a plan will cost before it starts.
//! A plan's parallel loops split among rayon's workers only when it runs
//! on one (`parallel`).
//! [`http`] is the thin HTTP layer over them, and [`store`] keeps
//! registered scenarios on disk.

mod by_name;
pub mod cancel;
pub mod catalog;
pub mod codec;
pub mod coordination;
pub mod cost;
pub mod estimator;
pub mod evaluate;
pub mod fit;
pub mod geometry;
pub mod http;
mod json_path;
pub mod limits;
pub mod memory;
pub mod metric_names;
pub mod obstacle;
mod parallel;
pub mod planner;
pub mod scenario;
pub mod search;
pub mod separation;
pub mod session;
pub mod stats;
pub mod store;
pub mod world;
