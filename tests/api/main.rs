//! HTTP integration tests: a real server on an ephemeral port, exercised
//! with reqwest over the socket.

#![allow(clippy::unwrap_used)]

mod errors;
mod helpers;
mod plan;
mod scenarios;
