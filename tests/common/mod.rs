//! Helpers shared by the integration tests (each test binary that needs
//! them declares `mod common;`).

use std::collections::HashSet;

use vigil::scenario::{Cell, Scenario};

/// The cells within `speed` king moves of `from` through free cells (on
/// the lattice, not blocked for the type): the legal one-step moves of a
/// sensor of type `ty`, by a breadth-first search of the tests' own.
pub fn one_step(s: &Scenario, from: Cell, ty: usize) -> HashSet<Cell> {
    let speed = s.types[ty].speed;
    let mut frontier = vec![from];
    let mut seen = HashSet::from([from]);
    for _ in 0..speed {
        let mut next = Vec::new();
        for c in &frontier {
            for dr in -1..=1 {
                for dc in -1..=1 {
                    let n = Cell {
                        col: c.col + dc,
                        row: c.row + dr,
                    };
                    if s.is_free(ty, n) && seen.insert(n) {
                        next.push(n);
                    }
                }
            }
        }
        frontier = next;
    }
    seen
}
