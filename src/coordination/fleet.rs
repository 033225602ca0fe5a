//! The sensors being coordinated, and the searches every coordination runs
//! for one of them: its values at each step against some other sensors'
//! looks, then the dynamic programme of [`crate::search`].

use std::sync::OnceLock;

use rayon::prelude::*;

use crate::cancel::CancelToken;
use crate::estimator::{Estimator, FirstDetections};
use crate::geometry::{Rect, Region};
use crate::scenario::{Cell, FovSpec, Look, Scenario};
use crate::search::{BestPath, ValueGrid, best_path, best_path_bounded};
use crate::separation::mark_too_close;

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

/// Sensors of given types at given starts, planning `horizon` steps with
/// one estimator: what every search of a plan shares.
pub struct Fleet<'a> {
    /// The scenario planned in.
    pub scenario: &'a Scenario,
    /// The estimator of the values.
    pub est: &'a dyn Estimator,
    /// Where each sensor starts, in request order.
    pub starts: &'a [Cell],
    /// Each sensor's type (an index into the scenario's types).
    pub types: &'a [usize],
    /// The horizon T.
    pub horizon: usize,
    /// Minimum separation kept, cells (0: none).
    pub min_separation: usize,
    /// Checked before every step's values of every search.
    pub cancel: &'a CancelToken,
    /// The intrusion objective, when the plan maximises first detections
    /// instead of detections (see [`Fleet::with_first_detections`]).
    pub first: Option<&'a FirstDetections<'a>>,
    /// Every first-detections search runs in full, so that each sensor's
    /// values are those of the search that chose its path (the plan
    /// reports them: `explain`); see [`Fleet::first_search`].
    pub full_searches: bool,
    /// Each sensor's first-detections search alone, once made.
    alone: Vec<OnceLock<FirstSearch>>,
    /// Each sensor's motion (its speed, the free cells around it), built
    /// once and shared by every search it runs.
    motions: Vec<ValueGrid>,
}

impl<'a> Fleet<'a> {
    /// The fleet of `starts.len()` sensors; builds each one's motion.
    pub fn new(
        scenario: &'a Scenario,
        est: &'a dyn Estimator,
        starts: &'a [Cell],
        types: &'a [usize],
        horizon: usize,
        min_separation: usize,
        cancel: &'a CancelToken,
    ) -> Self {
        let motions = (0..starts.len())
            .into_par_iter()
            .with_min_len(crate::parallel::min_len())
            .map(|i| sensor_motion(scenario, starts[i], types[i], horizon))
            .collect();
        Self {
            scenario,
            est,
            starts,
            types,
            horizon,
            min_separation,
            cancel,
            first: None,
            full_searches: false,
            alone: (0..starts.len()).map(|_| OnceLock::new()).collect(),
            motions,
        }
    }

    /// The same fleet maximising first detections: every search is then
    /// the bounded search of [`Fleet::first_search`], and totals count
    /// each target once over the horizon.
    pub fn with_first_detections(mut self, first: &'a FirstDetections<'a>) -> Self {
        self.first = Some(first);
        self
    }

    /// Number of sensors.
    pub fn len(&self) -> usize {
        self.starts.len()
    }

    /// True for a fleet of no sensor.
    pub fn is_empty(&self) -> bool {
        self.starts.is_empty()
    }

    /// An empty value grid of sensor `i`'s motion.
    pub fn motion(&self, i: usize) -> ValueGrid {
        self.motions[i].clone()
    }

    /// Sensor `i`'s search: its grid filled step by step by `fill`, cells
    /// too close to `avoid`'s paths marked, then the best path. Stops
    /// filling once the token is cancelled (the caller checks it after).
    pub fn plan_one(
        &self,
        i: usize,
        fill: &mut dyn FnMut(usize, &mut ValueGrid),
        avoid: Vec<&[Cell]>,
    ) -> SensorPlan {
        let mut grid = self.motion(i);
        for t in 1..=grid.horizon() {
            if self.cancel.is_cancelled() {
                break;
            }
            fill(t, &mut grid);
        }
        mark_too_close(&mut grid, self.starts[i], self.min_separation, avoid);
        search(grid, self.starts[i])
    }

    /// Sensor `i`'s best path against `looks` (per step 1..=T): the
    /// estimator's values less what those looks detect, ignoring the
    /// separation.
    pub fn best_against(&self, i: usize, looks: &[Vec<Look>]) -> SensorPlan {
        let mut grid = self.motion(i);
        for t in 1..=grid.horizon() {
            if self.cancel.is_cancelled() {
                break;
            }
            self.est
                .fill(i, self.starts[i], t, &looks[t - 1], &mut grid);
        }
        search(grid, self.starts[i])
    }

    /// The looks, at each step, of the `sensors` on `paths` (indexed by
    /// sensor), keeping those that can meet the field of view of a cell
    /// that sensor `i` can reach from its start.
    pub fn looks_by_step(&self, paths: &[&[Cell]], sensors: &[usize], i: usize) -> Vec<Vec<Look>> {
        let s = self.scenario;
        self.near_reach(i, |t| {
            sensors
                .iter()
                .map(|&q| s.look(self.types[q], paths[q][t - 1]))
                .collect()
        })
    }

    /// `looks(t)` for each step 1..=T, keeping those that can meet the
    /// field of view of a cell that sensor `i` can reach by then.
    pub fn near_reach(&self, i: usize, looks: impl Fn(usize) -> Vec<Look>) -> Vec<Vec<Look>> {
        (1..=self.horizon)
            .map(|t| {
                let reach = self.reach_box(i, t);
                let mut near = looks(t);
                near.retain(|l| l.region.may_overlap(&reach));
                near
            })
            .collect()
    }

    /// A region bounding every field of view of sensor `i` at a cell it can
    /// reach in `t` steps.
    pub fn reach_box(&self, i: usize, t: usize) -> Region {
        let s = self.scenario;
        let c = s.centre(self.starts[i]);
        let ty = &s.types[self.types[i]];
        let half = match ty.fov {
            FovSpec::Square { half_width } => half_width,
            FovSpec::Circle { radius } => radius,
        } + (ty.speed * t) as f64 * s.cell_size;
        Region {
            rect: Rect {
                x0: c.x - half,
                y0: c.y - half,
                x1: c.x + half,
                y1: c.y + half,
            },
            disk: None,
        }
    }

    /// The expected detections of `paths` at each step 1..=T, counting the
    /// sensors in `order` (each against the looks of those before it); for
    /// first detections, the targets each step detects for the first time.
    pub fn by_step(&self, paths: &[&[Cell]], order: &[usize]) -> Vec<f64> {
        let s = self.scenario;
        if let Some(first) = self.first {
            return first.by_step_on(paths, order, self.horizon);
        }
        (1..=self.horizon)
            .map(|t| {
                let mut above: Vec<Look> = Vec::with_capacity(order.len());
                let mut total = 0.0;
                for &p in order {
                    total += self.est.value(p, paths[p][t - 1], t, &above);
                    above.push(s.look(self.types[p], paths[p][t - 1]));
                }
                total
            })
            .collect()
    }
}

/// What [`Fleet::first_search`] found for one sensor.
#[derive(Debug, Clone)]
pub struct FirstSearch {
    /// The best path found, its value the exact gain in first detections.
    pub plan: SensorPlan,
    /// No path of the sensor (separation ignored) gains more than this.
    pub upper: f64,
    /// The exact gain and violations of the `current` path asked about.
    pub current: Option<(f64, u32)>,
}

/// Gains a first-detections search evaluates at most past its pairs (see
/// [`crate::search::best_path_bounded`]) up to T = 4: every path of a
/// speed-1 sensor (9 + 9² + 9³ + 9⁴ = 7,380 prefixes) fits, so those
/// searches are exact.
pub const FIRST_SEARCH_BUDGET: usize = 20_000;

/// The same beyond T = 4, where the search is an approximation: the pair
/// programme's path, improved by a short search (its loss is measured in
/// `docs/intrusion.md`).
pub const FIRST_SEARCH_BUDGET_LONG: usize = 1_000;

/// The budget of a first-detections search at horizon `horizon`:
/// `FIRST_SEARCH_BUDGET` up to T = 4 (the search is exact), and
/// `FIRST_SEARCH_BUDGET_LONG` past it.
pub fn first_search_budget(horizon: usize) -> usize {
    if horizon <= 4 {
        FIRST_SEARCH_BUDGET
    } else {
        FIRST_SEARCH_BUDGET_LONG
    }
}

impl Fleet<'_> {
    /// Sensor `i`'s best path for first detections against the looks of
    /// `sensors` on `paths` (at every step: a target another sensor
    /// detects at step 1 is not there to detect at step 3), around
    /// `avoid`'s paths; with `current`, that path's exact gain too.
    ///
    /// The sensor's search alone (no `sensors`, no `avoid`) is kept for
    /// the later ones. When it proved its path optimal, and no look of
    /// `sensors` holds a target that path's looks hold
    /// ([`FirstDetections::apart`]), the path gains against them what it
    /// gains alone, and no path gains more (a gain against more looks is
    /// never more than alone): a later search without `avoid` returns it
    /// unsearched, unless `current` is another path (whose gain it would
    /// need) or [`Fleet::full_searches`] is set (the values returned are
    /// then those alone).
    ///
    /// # Panics
    /// On a fleet without [`Fleet::with_first_detections`].
    pub fn first_search(
        &self,
        i: usize,
        paths: &[&[Cell]],
        sensors: &[usize],
        avoid: Vec<&[Cell]>,
        current: Option<&[Cell]>,
    ) -> FirstSearch {
        let first = self.first.expect("a fleet maximising first detections");
        let plain = avoid.is_empty();
        if let Some(alone) = self.alone[i].get().filter(|_| plain)
            && current.is_none_or(|c| c == alone.plan.path)
        {
            let again = sensors.is_empty();
            let unmoved = !again
                && !self.full_searches
                && alone.upper <= alone.plan.value
                && first.apart(i, &alone.plan.path, paths, sensors);
            if again || unmoved {
                return FirstSearch {
                    plan: alone.plan.clone(),
                    upper: if again { alone.upper } else { alone.plan.value },
                    current: current.map(|_| (alone.plan.value, alone.plan.violations)),
                };
            }
        }
        let mut grid = self.motion(i);
        let cover = first.path_cover_among(i, self.starts[i], paths, sensors, &mut grid);
        mark_too_close(&mut grid, self.starts[i], self.min_separation, avoid);
        let found = best_path_bounded(&grid, &cover, first_search_budget(self.horizon));
        let current = current.and_then(|path| {
            let moves = path_moves(self.starts[i], path);
            let violations = grid.path_violations(&moves)?;
            let offsets: Vec<(i32, i32)> = path
                .iter()
                .map(|c| (c.col - self.starts[i].col, c.row - self.starts[i].row))
                .collect();
            Some((cover.value(&offsets), violations))
        });
        let path = found
            .best
            .offsets()
            .into_iter()
            .map(|(dc, dr)| self.starts[i].offset(dc, dr))
            .collect();
        let found = FirstSearch {
            plan: SensorPlan {
                path,
                value: found.best.value,
                violations: found.best.violations,
                grid,
            },
            upper: found.upper,
            current,
        };
        if sensors.is_empty() && plain {
            let _ = self.alone[i].set(found.clone());
        }
        found
    }
}

impl Fleet<'_> {
    /// What the total of `paths` counted in `order` loses without sensor
    /// `i`'s path, over steps 1..=T (not for first detections). For an
    /// order-independent estimator that is its value against every other
    /// path, one value a step; for the paper estimator the sum of
    /// [`Fleet::rank_change`] (the lower sensors' overlaps change too).
    pub fn marginal(&self, paths: &[&[Cell]], order: &[usize], i: usize) -> f64 {
        let s = self.scenario;
        if self.est.order_independent() {
            let others: Vec<usize> = order.iter().copied().filter(|&q| q != i).collect();
            return (1..=self.horizon)
                .map(|t| {
                    let looks: Vec<Look> = others
                        .iter()
                        .map(|&q| s.look(self.types[q], paths[q][t - 1]))
                        .collect();
                    self.est.value(i, paths[i][t - 1], t, &looks)
                })
                .sum();
        }
        let rank = order.iter().position(|&q| q == i).unwrap_or(0);
        (1..=self.horizon)
            .map(|t| self.rank_change(paths, order, rank, paths[i][t - 1], t))
            .sum()
    }

    /// The change in the total at step `t` of `paths` counted in `order`
    /// when the sensor ranked `rank` stands at `k` instead of being absent:
    /// its own value against the sensors above it, plus the change it
    /// causes in the values of the sensors below it. For an
    /// order-independent estimator that is its value against all the
    /// others; for the paper estimator, whose total depends on rank order,
    /// the lower sensors' overlap reductions change too.
    pub fn rank_change(
        &self,
        paths: &[&[Cell]],
        order: &[usize],
        rank: usize,
        k: Cell,
        t: usize,
    ) -> f64 {
        let (s, types, est) = (self.scenario, self.types, self.est);
        let i = order[rank];
        let fk = s.look(types[i], k);
        let above: Vec<Look> = order[..rank]
            .iter()
            .map(|&q| s.look(types[q], paths[q][t - 1]))
            .collect();
        let mut delta = est.value(i, k, t, &above);
        for (lower_rank, &q) in order.iter().enumerate().skip(rank + 1) {
            let fq = s.fov_region_of(types[q], paths[q][t - 1]);
            if !fq.may_overlap(&fk.region) {
                continue;
            }
            let mut above_q: Vec<Look> = order[..lower_rank]
                .iter()
                .filter(|&&p| p != i)
                .map(|&p| s.look(types[p], paths[p][t - 1]))
                .collect();
            let without = est.value(q, paths[q][t - 1], t, &above_q);
            above_q.push(fk);
            let with = est.value(q, paths[q][t - 1], t, &above_q);
            delta += with - without;
        }
        delta
    }
}

/// An empty value grid of the motion of a sensor of type `ty` starting at
/// `start`: its speed, through the scenario's free cells, over `horizon`
/// steps.
pub fn sensor_motion(scenario: &Scenario, start: Cell, ty: usize, horizon: usize) -> ValueGrid {
    ValueGrid::with_motion(horizon, scenario.types[ty].speed, |dc, dr| {
        scenario.is_free(ty, start.offset(dc, dr))
    })
}

/// The per-step displacements of a path from `start`.
pub fn path_moves(start: Cell, path: &[Cell]) -> Vec<(i32, i32)> {
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
pub fn search(grid: ValueGrid, start: Cell) -> SensorPlan {
    let BestPath {
        moves,
        value,
        violations,
    } = best_path(&grid);
    let mut c = start;
    let path = moves
        .iter()
        .map(|&(dc, dr)| {
            c = c.offset(dc, dr);
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

/// Each plan's path, as a slice.
pub fn path_slices(plans: &[SensorPlan]) -> Vec<&[Cell]> {
    plans.iter().map(|p| p.path.as_slice()).collect()
}
