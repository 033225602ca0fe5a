//! The paper's estimator, equations (1) and (2).

use super::{Estimator, Target};
use crate::geometry::Region;
use crate::limits::MAX_HORIZON;
use crate::scenario::{Cell, Look, Scenario, all_certain};
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
///
/// Sensor types: every term is read with the sensor's own type. `F_Pi`,
/// `F_Pk`, `κ` and the statistics (`λ̂`, the escape times, `d̂`) are those of
/// its field of view, and the count is multiplied by its `p_detect`: the
/// targets it detects are that fraction of those inside. With uncertain
/// excluded looks, `f` becomes the expected fraction of `F_Pk` they detect,
/// `∫ 1 − Π (1 − p) / |F_Pk|` (the covered fraction when every `p` is 1).
pub struct PaperEstimator<'a> {
    scenario: &'a Scenario,
    /// Per field of view (the scenario's `fovs`).
    stats: &'a [Stats],
    sensors: Vec<PaperSensor>,
}

struct PaperSensor {
    cell: Cell,
    ty: usize,
    /// Offsets of `overlap` reach `±reach` (speed × horizon).
    reach: i32,
    own: Region,
    statistical: [f64; MAX_HORIZON + 1],
    seen: Vec<Target>,
    /// `κ` and `|F_k|` by offset from `cell`, `(2·reach+1)²`, row-major.
    overlap: Vec<(f64, f64)>,
}

impl<'a> PaperEstimator<'a> {
    /// Prepares the estimator for sensors of types `types` at `cells`
    /// reporting `targets`, for paths of up to `horizon` steps; `stats` per
    /// field of view (the scenario's `fovs`).
    pub fn new(
        scenario: &'a Scenario,
        stats: &'a [Stats],
        cells: &[Cell],
        types: &[usize],
        targets: &[Target],
        horizon: usize,
    ) -> Self {
        let sensors = cells
            .iter()
            .zip(types)
            .map(|(&cell, &ty)| {
                let h = (scenario.types[ty].speed * horizon) as i32;
                let own = scenario.fov_region_of(ty, cell);
                let mut overlap = Vec::with_capacity(((2 * h + 1) * (2 * h + 1)) as usize);
                for dr in -h..=h {
                    for dc in -h..=h {
                        let fk = scenario.fov_region_of(ty, cell.offset(dc, dr));
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
                    ty,
                    reach: h,
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
            sensors,
        }
    }
}

impl Estimator for PaperEstimator<'_> {
    fn scenario(&self) -> &Scenario {
        self.scenario
    }

    fn value(&self, sensor: usize, k: Cell, t: usize, excluded: &[Look]) -> f64 {
        let me = &self.sensors[sensor];
        let ty = &self.scenario.types[me.ty];
        let fk = self.scenario.fov_region_of(me.ty, k);
        let (dc, dr) = (k.col - me.cell.col, k.row - me.cell.row);
        let h = me.reach;
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
        let d_hat = self.stats[ty.fov_slot].d_hat[self.scenario.index(k)];
        let n = ty.p_detect * (deterministic + kappa * me.statistical[t] + (1.0 - kappa) * d_hat);
        if excluded.is_empty() || area <= 0.0 {
            return n;
        }
        let covered = if all_certain(excluded) {
            let regions: Vec<Region> = excluded.iter().map(|x| x.region).collect();
            fk.covered_area(&regions)
        } else {
            let looks: Vec<(Region, f64)> =
                excluded.iter().map(|x| (x.region, x.p_detect)).collect();
            fk.detected_area(&looks)
        };
        let f = (covered / area).clamp(0.0, 1.0);
        n * (1.0 - f)
    }

    fn order_independent(&self) -> bool {
        false
    }
}
