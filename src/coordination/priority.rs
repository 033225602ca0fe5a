//! The paper's priority pass, and with a minimum separation the repair
//! rounds after it (see the module docs of [`crate::coordination`]).

use super::fleet::{Fleet, SensorPlan, path_slices, search};
use crate::cancel::Cancelled;
use crate::scenario::Cell;
use crate::search::ValueGrid;
use crate::separation::{self, mark_too_close};

/// Largest number of repair rounds of the separation.
pub const MAX_REPAIRS: usize = 8;

/// The repair rounds' searches, at most this many per sensor in all (a
/// trial under way finishes, at most one more per sensor): a crowded fleet
/// can otherwise search about n² times a round. The cost model counts
/// them (`crate::cost`), so the plan's admission stays right.
pub const MAX_REPAIR_SEARCHES_PER_SENSOR: usize = 8;

/// The sensors in rank order, and what each searches from.
pub(super) struct Ranking<'f, 'a> {
    /// The sensors being planned.
    pub fleet: &'f Fleet<'a>,
    /// Sensor indices from highest to lowest priority.
    pub order: Vec<usize>,
    /// Each sensor's lone values. Without coordination but apart a sensor
    /// keeps them, and at a step where no higher-ranked look comes near its
    /// reach its values against them are these (the same fill, of no looks).
    pub alone: &'f [ValueGrid],
    /// Without coordination: each sensor keeps its lone values and only
    /// steers clear of the others' positions.
    pub independent: bool,
}

impl Ranking<'_, '_> {
    /// The paths of `sensors`, when there is a separation to keep.
    fn paths(&self, plans: &[SensorPlan], sensors: impl Iterator<Item = usize>) -> Vec<Vec<Cell>> {
        if self.fleet.min_separation == 0 {
            return Vec::new();
        }
        sensors.map(|q| plans[q].path.clone()).collect()
    }

    /// The search of the sensor ranked `rank`: its values against the
    /// sensors ranked above it (its lone values without coordination),
    /// around the paths of those sensors, or of every other sensor when
    /// `around_all`.
    pub fn ranked(&self, plans: &[SensorPlan], rank: usize, around_all: bool) -> SensorPlan {
        let Fleet {
            est,
            starts,
            min_separation: d,
            ..
        } = *self.fleet;
        let n = starts.len();
        let i = self.order[rank];
        let above = &self.order[..rank];
        let avoid = if around_all {
            self.paths(plans, (0..n).filter(|&j| j != i))
        } else {
            self.paths(plans, above.iter().copied())
        };
        let avoid = avoid.iter().map(Vec::as_slice).collect();
        if self.fleet.first.is_some() {
            let against = if self.independent { &[][..] } else { above };
            return self
                .fleet
                .first_search(i, &path_slices(plans), against, avoid, None)
                .plan;
        }
        if self.independent {
            let mut grid = self.alone[i].clone();
            mark_too_close(&mut grid, starts[i], d, avoid);
            search(grid, starts[i])
        } else {
            let looks = self.fleet.looks_by_step(&path_slices(plans), above, i);
            self.fleet.plan_one(
                i,
                &mut |t, g| match &looks[t - 1][..] {
                    [] => g.copy_step(t, &self.alone[i]),
                    near => est.fill(i, starts[i], t, near, g),
                },
                avoid,
            )
        }
    }

    /// Priority: each sensor after the first searches again against the
    /// ones above it, in rank order.
    ///
    /// # Errors
    /// [`Cancelled`] once the fleet's token is cancelled.
    pub fn priority_pass(&self, plans: &mut [SensorPlan]) -> Result<(), Cancelled> {
        for rank in 1..self.order.len() {
            plans[self.order[rank]] = self.ranked(plans, rank, false);
            self.fleet.cancel.check()?;
        }
        Ok(())
    }

    /// Repair: a higher-ranked sensor may have cornered a lower one, which
    /// the priority pass never revisits. The highest-ranked sensor too
    /// close to another that can have fewer violations against every other
    /// path takes that path, the ranks below it plan again in order, and
    /// the change stays if fewer pairs are too close. Returns the rounds
    /// run (at most [`MAX_REPAIRS`]) and the searches they made; they stop
    /// early too once they have searched [`MAX_REPAIR_SEARCHES_PER_SENSOR`]
    /// times per sensor.
    ///
    /// # Errors
    /// [`Cancelled`] once the fleet's token is cancelled.
    pub fn repair(&self, plans: &mut Vec<SensorPlan>) -> Result<(usize, usize), Cancelled> {
        let d = self.fleet.min_separation;
        let n = self.order.len();
        let mut repairs = 0;
        let budget = MAX_REPAIR_SEARCHES_PER_SENSOR * n;
        let mut searches = 0;
        let mut total = separation::count(&path_slices(plans), d);
        while total.pairs > 0 && repairs < MAX_REPAIRS && searches < budget {
            repairs += 1;
            let mut improved = false;
            for rank in 0..n {
                let i = self.order[rank];
                if total.per_sensor[i] == 0 {
                    continue;
                }
                if searches >= budget {
                    break;
                }
                let candidate = self.ranked(plans, rank, true);
                searches += 1;
                self.fleet.cancel.check()?;
                if candidate.violations >= total.per_sensor[i] {
                    continue;
                }
                let mut trial = plans.clone();
                trial[i] = candidate;
                for below in rank + 1..n {
                    trial[self.order[below]] = self.ranked(&trial, below, false);
                    searches += 1;
                    self.fleet.cancel.check()?;
                }
                let after = separation::count(&path_slices(&trial), d);
                if after.pairs < total.pairs {
                    (*plans, total) = (trial, after);
                    improved = true;
                    break;
                }
            }
            if !improved {
                break;
            }
        }
        Ok((repairs, searches))
    }
}
