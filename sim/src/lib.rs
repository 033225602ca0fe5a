//! `vigil-sim`: simulates the paper's world and drives a Vigil planner over
//! HTTP one step at a time, as an external simulator would.
//!
//! - [`driver`]: the world, the sensors and the step loop;
//! - [`policy`]: the sensor policies, local baselines and planner clients;
//! - [`metrics`]: per-step counts, per-run averages, confidence intervals;
//! - [`client`]: the HTTP client, and an in-process server for one-command runs;
//! - [`experiment`]: runs over seeds and the paper's experiment grids;
//! - [`learn`]: what a policy that learns the rates learnt;
//! - [`live`]: the live view, one run watched in a browser;
//! - [`rates`]: a world whose sources emit at other rates than the planner
//!   is told;
//! - [`report`]: the paper's table layout and JSON output;
//! - [`svg`]: a picture of one run, like the paper's Figure 3.

pub mod client;
pub mod driver;
pub mod experiment;
pub mod learn;
pub mod live;
pub mod metrics;
pub mod policy;
pub mod rates;
pub mod report;
pub mod svg;
