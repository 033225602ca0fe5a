//! Best-response rounds: every sensor in rank order searches again against
//! all the others' current paths, and takes the new path when it has fewer
//! separation violations, or as many and more value (see the module docs
//! of [`crate::coordination`]).

use std::time::Instant;

use super::fleet::{Fleet, SensorPlan, path_moves, path_slices};
use crate::cancel::Cancelled;
use crate::scenario::Cell;

/// Largest number of best-response rounds in `Iterated` (and in each of
/// `Joint`'s restarts).
pub const MAX_ROUNDS: usize = 10;

/// What [`best_responses`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rounds {
    /// Rounds run.
    pub rounds: usize,
    /// Whether the last round changed nothing (a best-response
    /// equilibrium), rather than the rounds or the time running out.
    pub settled: bool,
}

/// Runs rounds over `plans` (request order) with sensors in `order` until
/// one changes nothing, `max_rounds` have run, or `deadline` (checked
/// between sensors) has passed. A sensor's value for a cell is the change
/// in the total when it stands there: its marginal against all the others
/// for an order-independent estimator, and for the paper estimator also
/// the change in the lower-ranked sensors' overlap reductions. So each
/// accepted change raises the total (or lowers the violations).
///
/// # Errors
/// [`Cancelled`] once the fleet's token is cancelled.
pub fn best_responses(
    fleet: &Fleet,
    plans: &mut [SensorPlan],
    order: &[usize],
    max_rounds: usize,
    deadline: Option<Instant>,
) -> Result<Rounds, Cancelled> {
    let (est, starts, d) = (fleet.est, fleet.starts, fleet.min_separation);
    let n = plans.len();
    let mut rounds = 0;
    let mut changed = true;
    // How many paths had been taken when each sensor last searched (its
    // own included), and the count so far: a search depends only on the
    // others' paths, so a sensor none of whose others took a path since
    // its last search would find what it found then, and keep its path.
    let mut searched_at: Vec<Option<usize>> = vec![None; n];
    let mut taken = 0;
    while changed && rounds < max_rounds {
        changed = false;
        rounds += 1;
        for rank in 0..order.len() {
            if deadline.is_some_and(|d| Instant::now() >= d) {
                return Ok(Rounds {
                    rounds,
                    settled: false,
                });
            }
            let i = order[rank];
            if searched_at[i] == Some(taken) {
                continue;
            }
            let avoid: Vec<&[Cell]> = if d == 0 {
                Vec::new()
            } else {
                (0..n)
                    .filter(|&j| j != i)
                    .map(|j| plans[j].path.as_slice())
                    .collect()
            };
            let (grid_plan, current) = if fleet.first.is_some() {
                let others: Vec<usize> = order.iter().copied().filter(|&j| j != i).collect();
                let found = fleet.first_search(
                    i,
                    &path_slices(plans),
                    &others,
                    avoid,
                    Some(&plans[i].path),
                );
                (found.plan, found.current)
            } else {
                let grid_plan = if est.order_independent() {
                    let others: Vec<usize> = order.iter().copied().filter(|&j| j != i).collect();
                    let looks = fleet.looks_by_step(&path_slices(plans), &others, i);
                    fleet.plan_one(
                        i,
                        &mut |t, g| est.fill(i, starts[i], t, &looks[t - 1], g),
                        avoid,
                    )
                } else {
                    let current = path_slices(plans);
                    fleet.plan_one(
                        i,
                        &mut |t, g| {
                            g.fill_step(t, |dc, dr| {
                                let k = starts[i].offset(dc, dr);
                                Some(fleet.rank_change(&current, order, rank, k, t))
                            });
                        },
                        avoid,
                    )
                };
                let current = grid_plan
                    .grid
                    .path_score(&path_moves(starts[i], &plans[i].path));
                (grid_plan, current)
            };
            fleet.cancel.check()?;
            let (current_value, current_violations) =
                current.unwrap_or((f64::NEG_INFINITY, u32::MAX));
            let tol = 1e-9 * current_value.abs().max(1.0);
            if grid_plan.violations < current_violations
                || (grid_plan.violations == current_violations
                    && grid_plan.value > current_value + tol)
            {
                plans[i] = grid_plan;
                changed = true;
                taken += 1;
            } else {
                plans[i] = SensorPlan {
                    value: current_value,
                    violations: current_violations,
                    path: std::mem::take(&mut plans[i].path),
                    grid: grid_plan.grid,
                };
            }
            searched_at[i] = Some(taken);
        }
    }
    Ok(Rounds {
        rounds,
        settled: !changed,
    })
}
