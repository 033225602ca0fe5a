//! HTTP integration tests: a real server on an ephemeral port, exercised
//! with reqwest over the socket.

#![allow(clippy::unwrap_used)]

mod bounded;
mod connections;
mod errors;
mod evaluate;
mod fit;
mod fleet;
mod fuzz;
mod helpers;
mod intrusion;
mod jobs;
mod obstacles;
mod openapi;
mod ops;
mod plan;
mod scenarios;
mod separation;
mod sessions;
