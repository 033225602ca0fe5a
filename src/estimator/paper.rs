//! The paper's estimator, equations (1) and (2).

use super::{Estimator, Target};
use crate::geometry::Region;
use crate::scenario::{Cell, MAX_HORIZON, Scenario};
use crate::stats::{Stats, paper_statistical_part};

/// Equations (1) and (2) of the paper, read as follows for the sensor at
/// cell `Pi` (its current cell) estimating cell `Pk` at step `t`:
///
/// - `n_Pi − k` (deterministic part): the reported targets inside `F_Pi` now
///   whose straight-line position at step `t` is inside `F_Pk`. At `Pk = Pi`
///   this is eq. (1)'s "seen now, minus the k that will have left".
/// - statistical part at `Pi`: `λ̂_Pi·t − Σ_j λ̂_Pi,j Σ_{u=1..t} P(te_Pi,j < t−u)`
///   (see [`paper_statistical_part`]). With speed mixtures and cones the
///   sum over sources `j` runs over target classes (source × speed): each
///   class enters at its own rate `λ_j·w·θ_Pi,j/spread_j` and escapes after
///   its own chord over its own speed.
/// - eq. (2): `κ = |F_Pi ∩ F_Pk| / |F_Pk|` weighs that statistical part and
///   `(1−κ)` weighs `d̂_Pk`, the stationary count (over every class and
///   cone), for the part of `F_Pk` the sensor cannot see; `κ = 1` at `Pi`
///   gives eq. (1).
///
/// Coordination (step 6) multiplies by `1 − f`, `f` the fraction of `F_Pk`'s
/// area covered by the excluded fields of view.
pub struct PaperEstimator<'a> {
    scenario: &'a Scenario,
    stats: &'a Stats,
    horizon: usize,
    sensors: Vec<PaperSensor>,
}

struct PaperSensor {
    cell: Cell,
    own: Region,
    statistical: [f64; MAX_HORIZON + 1],
    seen: Vec<Target>,
    /// `κ` and `|F_k|` by offset from `cell`, `(2T+1)²`, row-major.
    overlap: Vec<(f64, f64)>,
}

impl<'a> PaperEstimator<'a> {
    /// Prepares the estimator for sensors at `cells` reporting `targets`,
    /// for paths of up to `horizon` steps.
    pub fn new(
        scenario: &'a Scenario,
        stats: &'a Stats,
        cells: &[Cell],
        targets: &[Target],
        horizon: usize,
    ) -> Self {
        let h = horizon as i32;
        let sensors = cells
            .iter()
            .map(|&cell| {
                let own = scenario.fov_region(cell);
                let mut overlap = Vec::with_capacity(((2 * h + 1) * (2 * h + 1)) as usize);
                for dr in -h..=h {
                    for dc in -h..=h {
                        let fk = scenario.fov_region(Cell {
                            col: cell.col + dc,
                            row: cell.row + dr,
                        });
                        let area = fk.area();
                        let kappa = if (dc, dr) == (0, 0) || area <= 0.0 {
                            1.0
                        } else {
                            (fk.covered_area(std::slice::from_ref(&own)) / area).clamp(0.0, 1.0)
                        };
                        overlap.push((kappa, area));
                    }
                }
                PaperSensor {
                    cell,
                    own,
                    statistical: paper_statistical_part(scenario, &own),
                    seen: targets
                        .iter()
                        .copied()
                        .filter(|tg| own.contains(tg.pos))
                        .collect(),
                    overlap,
                }
            })
            .collect();
        Self {
            scenario,
            stats,
            horizon,
            sensors,
        }
    }
}

impl Estimator for PaperEstimator<'_> {
    fn scenario(&self) -> &Scenario {
        self.scenario
    }

    fn value(&self, sensor: usize, k: Cell, t: usize, excluded: &[Region]) -> f64 {
        let me = &self.sensors[sensor];
        let fk = self.scenario.fov_region(k);
        let (dc, dr) = (k.col - me.cell.col, k.row - me.cell.row);
        let h = self.horizon as i32;
        let (kappa, area) = if dc.abs() <= h && dr.abs() <= h {
            me.overlap[((dr + h) * (2 * h + 1) + dc + h) as usize]
        } else {
            let area = fk.area();
            let kappa = if area > 0.0 {
                (fk.covered_area(std::slice::from_ref(&me.own)) / area).clamp(0.0, 1.0)
            } else {
                1.0
            };
            (kappa, area)
        };
        let deterministic = me.seen.iter().filter(|tg| fk.contains(tg.at(t))).count() as f64;
        let d_hat = self.stats.d_hat[self.scenario.index(k)];
        let n = deterministic + kappa * me.statistical[t] + (1.0 - kappa) * d_hat;
        if excluded.is_empty() || area <= 0.0 {
            return n;
        }
        let f = (fk.covered_area(excluded) / area).clamp(0.0, 1.0);
        n * (1.0 - f)
    }

    fn order_independent(&self) -> bool {
        false
    }
}
