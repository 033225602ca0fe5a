//! Cost curves of the planner (placeholder, filled in below).
#![allow(missing_docs)]
fn main() {}
