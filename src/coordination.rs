//! Coordination of several sensors' searches (the paper's steps 5–7, and ours).
//!
//! - [`Coordination::None`]: each sensor searches alone.
//! - [`Coordination::Priority`]: each sensor searches alone; sensors are
//!   ranked by the value of their path, highest first (ties: request order);
//!   each next sensor searches again with its values reduced for the fields
//!   of view of all higher-ranked sensors at the same step.
//! - [`Coordination::Iterated`]: starts from `Priority`, then in rounds every
//!   sensor, in rank order, searches again against all the others' current
//!   paths, taking the new path only if it raises the total; it stops when a
//!   round changes nothing, or after 10 rounds.
//!
//! The total is `Σ_t Σ_p value(p, cell_p(t), t, looks of the sensors ranked
//! above p at t)`: for the exact estimator the expected number of
//! (target, step) pairs detected by at least one sensor, whatever the order
//! (with detection probabilities, `Σ 1 − Π (1 − p)` over the sensors whose
//! field of view holds the target). In `Iterated` a sensor's value for a
//! cell is the change in that total when it stands there (its marginal
//! against all the others for the exact estimator; for the paper estimator
//! also the change in the lower-ranked sensors' overlap reductions), so each
//! accepted change raises the total and it never ends below `Priority`.
//!
//! With a minimum separation `d > 0` ([`crate::separation`]) every mode
//! keeps the sensors apart: paths are fixed in rank order, and each sensor
//! after the first searches with the fixed paths' cells marked as
//! violations, minimising (violations, −value) lexicographically. `None`
//! still ignores the others' values, but not their positions.
//!
//! That pass never revisits a higher-ranked sensor, which may corner a
//! lower one (push it against the zone's edge, say) although it could
//! have stood back. So while some pair is too close, a repair round (at
//! most [`MAX_REPAIRS`]) takes the highest-ranked sensor in a violation
//! whose search around *every* other path has fewer violations than its
//! own, gives it that path, lets the ranks below it plan again in order,
//! and keeps the result if fewer pairs are too close in all. The last
//! sensor still plans last, around the others' final paths.
//!
//! In `Iterated` a sensor's search counts violations against every other
//! sensor's current path, and a new path is taken when it has fewer
//! violations, or as many and more value, so each change lowers the
//! number of pairs too close or keeps it and raises the total.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use crate::cancel::{CancelToken, Cancelled};
use crate::estimator::Estimator;
use crate::geometry::Region;
use crate::scenario::{Cell, FovSpec, Look, Scenario};
use crate::search::{BestPath, ValueGrid, best_path};
use crate::separation::{self, Violations, mark_too_close};

/// How sensors' searches are coordinated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "lowercase")]
pub enum Coordination {
    /// Every sensor plans alone (the paper's 'b' rows).
    None,
    /// The paper's priority scheme (the 'a' rows).
    #[default]
    Priority,
    /// Priority, then best-response rounds against all others.
    Iterated,
}

/// Largest number of best-response rounds in `Iterated`.
pub const MAX_ROUNDS: usize = 10;

/// Largest number of repair rounds of the separation.
pub const MAX_REPAIRS: usize = 8;

/// One sensor's plan.
#[derive(Debug, Clone)]
pub struct SensorPlan {
    /// Cells at steps 1..=T.
    pub path: Vec<Cell>,
    /// The value its final search maximised.
    pub value: f64,
    /// The violations of the separation rule that search counted against
    /// the paths it planned around.
    pub violations: u32,
    /// The values that search used.
    pub grid: ValueGrid,
}

/// Plans of every sensor, in request order, with their ranks.
#[derive(Debug, Clone)]
pub struct Coordinated {
    /// Per sensor, in request order.
    pub plans: Vec<SensorPlan>,
    /// Sensor indices from highest to lowest priority.
    pub order: Vec<usize>,
    /// Estimated distinct detections at steps 1..=T.
    pub by_step: Vec<f64>,
    /// Best-response rounds run (iterated only).
    pub rounds: usize,
    /// Repair rounds of the separation run (see the module docs).
    pub repairs: usize,
    /// Breaches of the minimum separation among the final paths.
    pub violations: Violations,
}

/// Plans `starts.len()` sensors of types `types` over `horizon` steps; each
/// moves at its type's speed through the scenario's free cells, and keeps
/// the minimum separation `min_separation` (cells; 0 for none) from the
/// others wherever it can (see the module docs).
///
/// # Errors
/// [`Cancelled`] once `cancel` is cancelled: it is checked before every
/// step's values of every search and between sensors and rounds, so the
/// work stops within one sensor-step's fill.
#[allow(clippy::too_many_arguments)]
pub fn coordinate(
    s: &Scenario,
    est: &dyn Estimator,
    starts: &[Cell],
    types: &[usize],
    horizon: usize,
    mode: Coordination,
    min_separation: usize,
    cancel: &CancelToken,
) -> Result<Coordinated, Cancelled> {
    let n = starts.len();
    // Each sensor's motion (its speed, the free cells around it), built
    // once and shared by every search it runs.
    let motions: Vec<ValueGrid> = (0..n)
        .into_par_iter()
        .with_min_len(crate::parallel::min_len())
        .map(|i| {
            let start = starts[i];
            ValueGrid::with_motion(horizon, s.types[types[i]].speed, |dc, dr| {
                s.is_free(Cell {
                    col: start.col + dc,
                    row: start.row + dr,
                })
            })
        })
        .collect();
    let d = min_separation;
    let plan_one = |i: usize, fill: &mut dyn FnMut(usize, &mut ValueGrid), avoid: Vec<&[Cell]>| {
        let mut grid = motions[i].clone();
        for t in 1..=grid.horizon() {
            // The caller checks the token after the search.
            if cancel.is_cancelled() {
                break;
            }
            fill(t, &mut grid);
        }
        mark_too_close(&mut grid, starts[i], d, avoid);
        search(grid, starts[i])
    };
    // The paths of `sensors`, when there is a separation to keep.
    let paths =
        |plans: &[SensorPlan], sensors: &mut dyn Iterator<Item = usize>| -> Vec<Vec<Cell>> {
            if d == 0 {
                return Vec::new();
            }
            sensors.map(|q| plans[q].path.clone()).collect()
        };
    // Every sensor alone.
    let mut plans: Vec<SensorPlan> = (0..n)
        .into_par_iter()
        .with_min_len(crate::parallel::min_len())
        .map(|i| plan_one(i, &mut |t, g| est.fill(i, starts[i], t, &[], g), Vec::new()))
        .collect();
    cancel.check()?;
    let mut order: Vec<usize> = (0..n).collect();
    // Stable sort: ties keep request order.
    order.sort_by(|&a, &b| plans[b].value.total_cmp(&plans[a].value));
    // Each sensor's lone values: without coordination but apart it keeps
    // them, and at a step where no higher-ranked look comes near its reach
    // its values against them are these (the same fill, of no looks).
    let alone: Vec<ValueGrid> = if mode != Coordination::None || d > 0 {
        plans.iter().map(|p| p.grid.clone()).collect()
    } else {
        Vec::new()
    };
    // The priority pass's search of the sensor ranked `rank`: its values
    // against the sensors ranked above it (its lone values without
    // coordination), around the paths of those sensors, or of every other
    // sensor when `around_all`.
    let ranked = |plans: &[SensorPlan], rank: usize, around_all: bool| -> SensorPlan {
        let i = order[rank];
        let above = &order[..rank];
        let avoid = if around_all {
            paths(plans, &mut (0..n).filter(|&j| j != i))
        } else {
            paths(plans, &mut above.iter().copied())
        };
        let avoid = avoid.iter().map(Vec::as_slice).collect();
        if mode == Coordination::None {
            let mut grid = alone[i].clone();
            mark_too_close(&mut grid, starts[i], d, avoid);
            search(grid, starts[i])
        } else {
            let looks = looks_by_step(s, plans, types, above, horizon, i, starts[i]);
            plan_one(
                i,
                &mut |t, g| match &looks[t - 1][..] {
                    [] => g.copy_step(t, &alone[i]),
                    near => est.fill(i, starts[i], t, near, g),
                },
                avoid,
            )
        }
    };
    let mut rounds = 0;
    let mut repairs = 0;
    if mode != Coordination::None || d > 0 {
        // Priority: each sensor against the ones above it, in rank order.
        for rank in 1..n {
            plans[order[rank]] = ranked(&plans, rank, false);
            cancel.check()?;
        }
    }
    if d > 0 {
        // Repair: a higher-ranked sensor may have cornered a lower one,
        // which the pass above never revisits. The highest-ranked sensor
        // too close to another that can have fewer violations against every
        // other path takes that path, the ranks below it plan again in
        // order, and the change stays if fewer pairs are too close.
        let mut total = separation::count(&all_paths(&plans), d);
        while total.pairs > 0 && repairs < MAX_REPAIRS {
            repairs += 1;
            let mut improved = false;
            for rank in 0..n {
                let i = order[rank];
                if total.per_sensor[i] == 0 {
                    continue;
                }
                let candidate = ranked(&plans, rank, true);
                cancel.check()?;
                if candidate.violations >= total.per_sensor[i] {
                    continue;
                }
                let mut trial = plans.clone();
                trial[i] = candidate;
                for below in rank + 1..n {
                    trial[order[below]] = ranked(&trial, below, false);
                    cancel.check()?;
                }
                let after = separation::count(&all_paths(&trial), d);
                if after.pairs < total.pairs {
                    (plans, total) = (trial, after);
                    improved = true;
                    break;
                }
            }
            if !improved {
                break;
            }
        }
    }
    if mode == Coordination::Iterated {
        let mut changed = true;
        while changed && rounds < MAX_ROUNDS {
            changed = false;
            rounds += 1;
            for rank in 0..order.len() {
                let i = order[rank];
                let avoid = paths(&plans, &mut (0..n).filter(|&j| j != i));
                let avoid = avoid.iter().map(Vec::as_slice).collect();
                let grid_plan = if est.order_independent() {
                    let others: Vec<usize> = order.iter().copied().filter(|&j| j != i).collect();
                    let looks = looks_by_step(s, &plans, types, &others, horizon, i, starts[i]);
                    plan_one(
                        i,
                        &mut |t, g| est.fill(i, starts[i], t, &looks[t - 1], g),
                        avoid,
                    )
                } else {
                    plan_one(
                        i,
                        &mut |t, g| {
                            g.fill_step(t, |dc, dr| {
                                let k = Cell {
                                    col: starts[i].col + dc,
                                    row: starts[i].row + dr,
                                };
                                Some(total_change(s, est, &plans, types, &order, rank, k, t))
                            });
                        },
                        avoid,
                    )
                };
                cancel.check()?;
                let current = path_moves(starts[i], &plans[i].path);
                let (current_value, current_violations) = grid_plan
                    .grid
                    .path_score(&current)
                    .unwrap_or((f64::NEG_INFINITY, u32::MAX));
                let tol = 1e-9 * current_value.abs().max(1.0);
                if grid_plan.violations < current_violations
                    || (grid_plan.violations == current_violations
                        && grid_plan.value > current_value + tol)
                {
                    plans[i] = grid_plan;
                    changed = true;
                } else {
                    plans[i] = SensorPlan {
                        value: current_value,
                        violations: current_violations,
                        path: std::mem::take(&mut plans[i].path),
                        grid: grid_plan.grid,
                    };
                }
            }
        }
    }
    let mut by_step = Vec::with_capacity(horizon);
    for t in 1..=horizon {
        let mut total = 0.0;
        for (rank, &p) in order.iter().enumerate() {
            cancel.check()?;
            let above: Vec<Look> = order[..rank]
                .iter()
                .map(|&q| s.look(types[q], plans[q].path[t - 1]))
                .collect();
            total += est.value(p, plans[p].path[t - 1], t, &above);
        }
        by_step.push(total);
    }
    let violations = separation::count(&all_paths(&plans), d);
    Ok(Coordinated {
        plans,
        order,
        by_step,
        rounds,
        repairs,
        violations,
    })
}

fn all_paths(plans: &[SensorPlan]) -> Vec<Vec<Cell>> {
    plans.iter().map(|p| p.path.clone()).collect()
}

/// For the paper estimator, whose total depends on rank order: the change
/// in the total at step `t` when the sensor ranked `rank` stands at `k`
/// instead of being absent. Its own value against the sensors above it,
/// plus the change it causes in the reductions of the sensors below it.
#[allow(clippy::too_many_arguments)]
fn total_change(
    s: &Scenario,
    est: &dyn Estimator,
    plans: &[SensorPlan],
    types: &[usize],
    order: &[usize],
    rank: usize,
    k: Cell,
    t: usize,
) -> f64 {
    let i = order[rank];
    let fk = s.look(types[i], k);
    let above: Vec<Look> = order[..rank]
        .iter()
        .map(|&q| s.look(types[q], plans[q].path[t - 1]))
        .collect();
    let mut delta = est.value(i, k, t, &above);
    for (lower_rank, &q) in order.iter().enumerate().skip(rank + 1) {
        let fq = s.fov_region_of(types[q], plans[q].path[t - 1]);
        if !fq.may_overlap(&fk.region) {
            continue;
        }
        let mut above_q: Vec<Look> = order[..lower_rank]
            .iter()
            .filter(|&&p| p != i)
            .map(|&p| s.look(types[p], plans[p].path[t - 1]))
            .collect();
        let without = est.value(q, plans[q].path[t - 1], t, &above_q);
        above_q.push(fk);
        let with = est.value(q, plans[q].path[t - 1], t, &above_q);
        delta += with - without;
    }
    delta
}

/// The looks, at each step, of the `sensors` on their current paths,
/// keeping those that can meet the field of view of a cell that sensor `i`
/// can reach from `start`.
fn looks_by_step(
    s: &Scenario,
    plans: &[SensorPlan],
    types: &[usize],
    sensors: &[usize],
    horizon: usize,
    i: usize,
    start: Cell,
) -> Vec<Vec<Look>> {
    (1..=horizon)
        .map(|t| {
            let reach = reach_box(s, types[i], start, t);
            sensors
                .iter()
                .map(|&q| s.look(types[q], plans[q].path[t - 1]))
                .filter(|l| l.region.may_overlap(&reach))
                .collect()
        })
        .collect()
}

/// A region bounding every field of view of a sensor of type `ty` at a
/// cell it can reach in `t` steps.
fn reach_box(s: &Scenario, ty: usize, start: Cell, t: usize) -> Region {
    let c = s.centre(start);
    let ty = &s.types[ty];
    let half = match ty.fov {
        FovSpec::Square { half_width } => half_width,
        FovSpec::Circle { radius } => radius,
    } + (ty.speed * t) as f64 * s.cell_size;
    Region {
        rect: crate::geometry::Rect {
            x0: c.x - half,
            y0: c.y - half,
            x1: c.x + half,
            y1: c.y + half,
        },
        disk: None,
    }
}

fn path_moves(start: Cell, path: &[Cell]) -> Vec<(i32, i32)> {
    let mut prev = start;
    path.iter()
        .map(|&c| {
            let m = (c.col - prev.col, c.row - prev.row);
            prev = c;
            m
        })
        .collect()
}

/// Searches a filled value grid of a sensor starting at `start`.
fn search(grid: ValueGrid, start: Cell) -> SensorPlan {
    let BestPath {
        moves,
        value,
        violations,
    } = best_path(&grid);
    let mut c = start;
    let path = moves
        .iter()
        .map(|&(dc, dr)| {
            c = Cell {
                col: c.col + dc,
                row: c.row + dr,
            };
            c
        })
        .collect();
    SensorPlan {
        path,
        value,
        violations,
        grid,
    }
}
