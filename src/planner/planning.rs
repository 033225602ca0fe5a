//! The [`Planner`] of one scenario: its statistics, computed once, and
//! [`Planner::plan`], which turns a validated request into coordinated
//! T-step paths.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use super::input::{PlanInput, step_looks};
use super::wire::*;
use crate::cancel::{CancelToken, Cancelled, Progress};
use crate::codec::{CodecError, NextPiece, Reader, Writer, expect_len};
use crate::coordination::{Fleet, Objective, coordinate};
use crate::estimator::{
    Carry, ElementaryGrid, Estimator, ExactEstimator, FirstDetections, PaperEstimator, Precomputed,
    SightIndex, Situation, SourceRays,
};
use crate::scenario::{Cell, Look, Scenario, ValidationError};
use crate::stats::Stats;

/// The version of [`Planner::encode_precomputed`]'s bytes: raise it with
/// any change to what they hold or how, so that a replica never reads
/// another build's bytes as its own.
pub const PRECOMPUTED_FORMAT: u32 = 1;

/// The first bytes of [`Planner::encode_precomputed`]'s.
const PRECOMPUTED_MAGIC: &[u8] = b"vigil-precomputed";

/// A scenario with its precomputed statistics, ready to plan.
#[derive(Debug)]
pub struct Planner {
    /// The scenario.
    pub scenario: Scenario,
    /// Its per-cell statistics, per field of view (the scenario's `fovs`;
    /// `stats[0]` is the type `default`'s).
    pub stats: Vec<Stats>,
    pub(crate) rays: Vec<SourceRays>,
    pub(crate) grid: Option<ElementaryGrid>,
    /// What ground looks cannot see, cell by cell, on `rays` (derived from
    /// the scenario and `rays`, so built again, not stored).
    sights: Option<SightIndex>,
    /// Time the precomputation took, milliseconds.
    pub precompute_ms: f64,
    /// Which planner this is, for the carries it makes ([`Carry`]): no
    /// two planners of one process share it, so a carry made by another
    /// (another scenario, or other learnt rates) starts over.
    identity: u64,
}

/// The next planner's [`Planner::identity`].
fn next_identity() -> u64 {
    static NEXT: AtomicU64 = AtomicU64::new(1);
    NEXT.fetch_add(1, Ordering::Relaxed)
}

impl Planner {
    /// Precomputes the statistics of a scenario.
    pub fn new(scenario: Scenario) -> Self {
        match Self::precompute(scenario, &CancelToken::never(), &Progress::default()) {
            Ok(planner) => planner,
            Err(Cancelled) => unreachable!("work that is never cancelled finishes"),
        }
    }

    /// [`Planner::new`], in blocks of cells (see
    /// [`Stats::for_slot_cancellable`]) that check `cancel` and advance
    /// `progress`; the indexing of rays that follows is one more block.
    /// The planner is the same as [`Planner::new`]'s.
    ///
    /// # Errors
    /// [`Cancelled`] once `cancel` is cancelled.
    pub fn precompute(
        scenario: Scenario,
        cancel: &CancelToken,
        progress: &Progress,
    ) -> Result<Self, Cancelled> {
        let density = SourceRays::density(&scenario);
        Self::precompute_at(scenario, density, cancel, progress)
    }

    /// [`Planner::new`] with `rays_per_pi` rays per π in each source's
    /// angular grid instead of the default ([`SourceRays::density`]): for
    /// accuracy studies, whose reference is a much finer grid.
    pub fn with_rays_per_pi(scenario: Scenario, rays_per_pi: f64) -> Self {
        match Self::precompute_at(
            scenario,
            rays_per_pi,
            &CancelToken::never(),
            &Progress::default(),
        ) {
            Ok(planner) => planner,
            Err(Cancelled) => unreachable!("a token that never cancels"),
        }
    }

    /// This planner with the plain midpoint rule in its windows, as before
    /// the area correction ([`SourceRays::plain_midpoint`]): for accuracy
    /// studies that compare the two on the same states.
    pub fn plain_midpoint(mut self) -> Self {
        self.rays.iter_mut().for_each(SourceRays::plain_midpoint);
        self.identity = next_identity();
        self
    }

    /// [`Planner::precompute`] at `rays_per_pi`.
    fn precompute_at(
        scenario: Scenario,
        rays_per_pi: f64,
        cancel: &CancelToken,
        progress: &Progress,
    ) -> Result<Self, Cancelled> {
        let started = Instant::now();
        progress.add_total(scenario.fovs.len() * Stats::blocks(&scenario) + 1);
        let stats = (0..scenario.fovs.len())
            .map(|slot| Stats::for_slot_cancellable(&scenario, slot, cancel, progress))
            .collect::<Result<Vec<_>, _>>()?;
        cancel.check()?;
        let mut rays = SourceRays::with_density(&scenario, rays_per_pi);
        let grid = if scenario.has_obstacles() {
            ElementaryGrid::with_mass(&scenario, |g| SourceRays::alive_mass(&rays, &scenario, g))
        } else {
            ElementaryGrid::new(&scenario)
        };
        if let Some(grid) = &grid {
            SourceRays::index_crossings(&mut rays, &scenario, grid);
        }
        SourceRays::index_looks(&mut rays, &scenario);
        progress.advance(1);
        let sights = SightIndex::new(&scenario, &rays);
        Ok(Planner {
            scenario,
            stats,
            rays,
            grid,
            sights,
            precompute_ms: started.elapsed().as_secs_f64() * 1e3,
            identity: next_identity(),
        })
    }

    /// What [`Planner::precompute`] computed (its statistics, rays and
    /// indexes), as bytes that [`Planner::from_precomputed`] reads back to
    /// the bit. Headed by [`PRECOMPUTED_FORMAT`] and the scenario's id.
    pub fn encode_precomputed(&self) -> Vec<u8> {
        let mut w = Writer::new();
        w.bytes(PRECOMPUTED_MAGIC);
        w.u64(PRECOMPUTED_FORMAT.into());
        w.bytes(self.scenario.id.as_bytes());
        w.len(self.stats.len());
        self.stats.iter().for_each(|s| s.encode(&mut w));
        w.len(self.rays.len());
        self.rays.iter().for_each(|r| r.encode(&mut w));
        w.bool(self.grid.is_some());
        if let Some(grid) = &self.grid {
            grid.encode(&mut w);
        }
        w.finish()
    }

    /// The planner of `scenario` from [`Planner::encode_precomputed`]'s
    /// bytes, the same as [`Planner::new`] would compute.
    ///
    /// # Errors
    /// A [`CodecError`] when the bytes are of another format or scenario,
    /// or not such bytes at all.
    pub fn from_precomputed(scenario: Scenario, bytes: &[u8]) -> Result<Self, CodecError> {
        Self::read_precomputed(scenario, Reader::new(bytes))
    }

    /// [`Planner::from_precomputed`] of `total` bytes that `next` hands
    /// over piece by piece (see [`Reader::pieces`]), each read as it comes.
    ///
    /// # Errors
    /// As [`Planner::from_precomputed`], and `next`'s.
    pub fn from_precomputed_pieces(
        scenario: Scenario,
        total: usize,
        next: &mut NextPiece<'_>,
    ) -> Result<Self, CodecError> {
        Self::read_precomputed(scenario, Reader::pieces(total, next))
    }

    fn read_precomputed(scenario: Scenario, mut r: Reader<'_>) -> Result<Self, CodecError> {
        let started = Instant::now();
        if r.bytes()? != PRECOMPUTED_MAGIC {
            return Err(CodecError("not a precomputation".into()));
        }
        let format = r.u64()?;
        if format != u64::from(PRECOMPUTED_FORMAT) {
            return Err(CodecError(format!(
                "format {format}, this server reads {PRECOMPUTED_FORMAT}"
            )));
        }
        let id = r.bytes()?;
        if id != scenario.id.as_bytes() {
            return Err(CodecError(format!(
                "the precomputation of {}, not of {}",
                String::from_utf8_lossy(&id),
                scenario.id
            )));
        }
        let n = r.len()?;
        expect_len("statistics", n, scenario.fovs.len())?;
        let cells = scenario.cell_count();
        let stats = (0..n)
            .map(|_| Stats::decode(&mut r, cells))
            .collect::<Result<Vec<_>, _>>()?;
        let n = r.len()?;
        if n > scenario.sources.len() {
            return Err(CodecError(format!("{n} rays for fewer sources")));
        }
        let rays = (0..n)
            .map(|_| SourceRays::decode(&mut r, &scenario))
            .collect::<Result<Vec<_>, _>>()?;
        let grid = if r.bool()? {
            Some(ElementaryGrid::decode(&mut r, &scenario)?)
        } else {
            None
        };
        r.end()?;
        let sights = SightIndex::new(&scenario, &rays);
        Ok(Planner {
            scenario,
            stats,
            rays,
            grid,
            sights,
            precompute_ms: started.elapsed().as_secs_f64() * 1e3,
            identity: next_identity(),
        })
    }

    /// The statistics of the sensor type `ty`'s field of view.
    pub fn stats_of(&self, ty: usize) -> &Stats {
        &self.stats[self.scenario.types[ty].fov_slot]
    }

    /// Approximate heap memory held, bytes (for cache bounds).
    pub fn memory_bytes(&self) -> usize {
        let cells = self.scenario.cell_count();
        let blocked = if self.scenario.has_no_go() { cells } else { 0 };
        let stats = 3 * self.stats.len() * cells * std::mem::size_of::<f64>() + blocked;
        let grid = self.grid.as_ref().map_or(0, ElementaryGrid::memory_bytes);
        let rays: usize = self.rays.iter().map(SourceRays::memory_bytes).sum();
        let sights = self.sights.as_ref().map_or(0, SightIndex::memory_bytes);
        std::mem::size_of::<Self>() + stats + grid + rays + sights
    }

    /// Validates and plans a request.
    pub fn plan_request(&self, req: &PlanRequest) -> Result<PlanResponse, ValidationError> {
        Ok(self.plan(&PlanInput::new(&self.scenario, req)?))
    }

    /// Validates a request and plans it unless `cancel` is cancelled
    /// first (see [`Planner::plan_cancellable`]).
    ///
    /// # Errors
    /// The outer error for an invalid request, the inner one when the work
    /// was cancelled.
    pub fn plan_request_cancellable(
        &self,
        req: &PlanRequest,
        cancel: &CancelToken,
    ) -> Result<Result<PlanResponse, Cancelled>, ValidationError> {
        Ok(self.plan_cancellable(&PlanInput::new(&self.scenario, req)?, cancel))
    }

    /// Plans a validated request.
    ///
    /// Runs on a worker of rayon's global pool (moving there first when
    /// called from outside it), so the plan's parallel parts split among
    /// the workers without handing work back and forth between threads.
    /// With a global pool of one thread (one core) it runs where it is
    /// called instead ([`Planner::plan_here`]): the same answer, without
    /// the two thread switches of the move.
    pub fn plan(&self, input: &PlanInput) -> PlanResponse {
        match self.plan_cancellable(input, &CancelToken::never()) {
            Ok(response) => response,
            Err(Cancelled) => unreachable!("a plan that is never cancelled finishes"),
        }
    }

    /// [`Planner::plan`], checking `cancel` between its stages and within
    /// the search and coordination (see [`coordinate`]), so a cancelled plan
    /// stops within one sensor-step's fill.
    ///
    /// # Errors
    /// [`Cancelled`] once `cancel` is cancelled.
    pub fn plan_cancellable(
        &self,
        input: &PlanInput,
        cancel: &CancelToken,
    ) -> Result<PlanResponse, Cancelled> {
        if rayon::current_thread_index().is_none() && rayon::current_num_threads() > 1 {
            return rayon::scope(|_| self.plan_here(input, cancel));
        }
        self.plan_here(input, cancel)
    }

    /// [`Planner::plan_cancellable`] for a step of a session whose last
    /// step left `carry`: the exact estimator starts from what the carry
    /// kept and keeps what the next step needs (see [`Carry`]). The plan
    /// is the stateless plan of the same input, to rounding (1e-9 in the
    /// tests). A cancelled plan leaves the carry empty.
    ///
    /// # Errors
    /// [`Cancelled`] once `cancel` is cancelled.
    pub fn plan_carried(
        &self,
        input: &PlanInput,
        cancel: &CancelToken,
        carry: &mut Carry,
    ) -> Result<PlanResponse, Cancelled> {
        let res = if rayon::current_thread_index().is_none() && rayon::current_num_threads() > 1 {
            rayon::scope(|_| self.plan_with(input, cancel, Some(&mut *carry)))
        } else {
            self.plan_with(input, cancel, Some(&mut *carry))
        };
        if res.is_err() {
            *carry = Carry::new();
        }
        res
    }

    /// [`Planner::plan_cancellable`] on the calling thread: on a worker of
    /// a rayon pool the plan's parallel parts split among its workers; on
    /// any other thread they run there, one after the other. The answer is
    /// the same to the last bit either way. For a pool of one thread this
    /// saves the two thread switches of the hop to it and back.
    ///
    /// # Errors
    /// [`Cancelled`] once `cancel` is cancelled.
    pub fn plan_here(
        &self,
        input: &PlanInput,
        cancel: &CancelToken,
    ) -> Result<PlanResponse, Cancelled> {
        self.plan_with(input, cancel, None)
    }

    /// [`Planner::plan_here`], from and into `carry` when given.
    fn plan_with(
        &self,
        input: &PlanInput,
        cancel: &CancelToken,
        carry: Option<&mut Carry>,
    ) -> Result<PlanResponse, Cancelled> {
        cancel.check()?;
        let started = Instant::now();
        let s = &self.scenario;
        let est = self.estimator(input, cancel, carry)?;
        cancel.check()?;
        let result = est.with_fleet(s, input, cancel, |fleet| {
            coordinate(
                fleet,
                input.coordination,
                input.joint,
                input.certify,
                started,
            )
        })?;
        let cell_out = |c: Cell| {
            let p = s.centre(c);
            CellOut {
                col: c.col,
                row: c.row,
                x: p.x,
                y: p.y,
            }
        };
        let mut rank = vec![0; input.starts.len()];
        for (r, &i) in result.order.iter().enumerate() {
            rank[i] = r + 1;
        }
        let plans = result
            .plans
            .iter()
            .enumerate()
            .map(|(i, p)| PlanOut {
                sensor: input.ids[i].clone(),
                priority: rank[i],
                start: cell_out(input.starts[i]),
                path: p.path.iter().map(|&c| cell_out(c)).collect(),
                expected_detections: p.value,
                separation_violations: result.violations.per_sensor[i],
                explain: input.explain.then(|| Explain {
                    values: p.grid.to_nested(),
                }),
            })
            .collect();
        Ok(PlanResponse {
            scenario: s.id.clone(),
            horizon: input.horizon,
            estimator: input.estimator,
            coordination: input.coordination,
            objective: input.objective,
            min_separation: input.min_separation,
            separation_violations: result.violations.pairs,
            plans,
            expected_detections: result.by_step.iter().sum(),
            expected_by_step: result.by_step,
            bound: result.bound,
            joint: result.joint,
            compute_micros: started.elapsed().as_micros() as u64,
        })
    }

    /// The estimator `input` asks for, prepared for its sensors, targets
    /// and looks.
    ///
    /// # Errors
    /// [`Cancelled`] once `cancel` is cancelled.
    pub(crate) fn estimator(
        &self,
        input: &PlanInput,
        cancel: &CancelToken,
        carry: Option<&mut Carry>,
    ) -> Result<Chosen<'_>, Cancelled> {
        let s = &self.scenario;
        // Nothing to carry for the paper's estimator, which keeps no seen
        // sets. First detections plan statelessly too: their searches,
        // not the estimator's preparation, are their work, and a carried
        // step's sums (the same terms in another order) broke exact ties
        // between paths otherwise than the stateless plan does, which
        // their coverage makes common.
        let carry = match carry {
            Some(carry)
                if input.estimator == EstimatorKind::Paper
                    || input.objective == Objective::FirstDetections =>
            {
                *carry = Carry::new();
                None
            }
            carry => carry,
        };
        Ok(match input.estimator {
            EstimatorKind::Paper => Chosen::Paper({
                PaperEstimator::new(
                    s,
                    &self.stats,
                    &input.starts,
                    &input.types,
                    &input.targets,
                    input.horizon,
                )
            }),
            EstimatorKind::Exact => match carry {
                Some(carry) => {
                    let observed = self.observed_looks(input);
                    let est = ExactEstimator::carried(
                        self.precomputed(None),
                        self.situation(input, &observed),
                        self.identity,
                        carry,
                    );
                    cancel.check()?;
                    est.prepare_carried(carry);
                    Chosen::Exact(Box::new(est))
                }
                None => {
                    let est = self.exact_estimator(input, None);
                    cancel.check()?;
                    est.prepare();
                    Chosen::Exact(Box::new(est))
                }
            },
        })
    }

    /// The exact estimator of `input` (whichever estimator it asks for), its
    /// windows built on first use, on `rays` instead of the planner's own
    /// when given: an accuracy study compares its values with those of a
    /// finer angular grid ([`SourceRays::with_density`]).
    pub fn exact_estimator<'a>(
        &'a self,
        input: &PlanInput,
        rays: Option<&'a [SourceRays]>,
    ) -> ExactEstimator<'a> {
        let observed = self.observed_looks(input);
        ExactEstimator::new(self.precomputed(rays), self.situation(input, &observed))
    }

    /// What the exact estimator reads of this planner, on `rays` instead
    /// of its own when given.
    fn precomputed<'a>(&'a self, rays: Option<&'a [SourceRays]>) -> Precomputed<'a> {
        Precomputed {
            scenario: &self.scenario,
            stats: &self.stats,
            rays: rays.unwrap_or(&self.rays),
            grid: self.grid.as_ref(),
            // Indexed on the planner's own rays only.
            sights: self.sights.as_ref().filter(|_| rays.is_none()),
        }
    }

    /// `input`'s sensors, targets and `observed` looks.
    fn situation<'a>(&self, input: &'a PlanInput, observed: &'a [Vec<Look>]) -> Situation<'a> {
        Situation {
            observed,
            targets: &input.targets,
            starts: &input.starts,
            types: &input.types,
            horizon: input.horizon,
        }
    }

    /// `O_s` for s = 0, 1, …: the looks taken now and in the history (the
    /// whole zone, certain, now when the caller reports every target in it).
    fn observed_looks(&self, input: &PlanInput) -> Vec<Vec<Look>> {
        let s = &self.scenario;
        let now = match input.observed {
            Observed::Zone => vec![Look::certain(s.zone_region())],
            Observed::Sensors => step_looks(
                s,
                input
                    .starts
                    .iter()
                    .copied()
                    .zip(input.types.iter().copied()),
            ),
        };
        std::iter::once(now)
            .chain(
                input
                    .history
                    .iter()
                    .map(|step| step_looks(s, step.iter().copied())),
            )
            .collect()
    }
}

/// The estimator a plan asked for.
pub(crate) enum Chosen<'p> {
    Paper(PaperEstimator<'p>),
    /// Boxed: an exact estimator holds several plan-long caches.
    Exact(Box<ExactEstimator<'p>>),
}

impl Chosen<'_> {
    /// As an [`Estimator`].
    pub(crate) fn as_dyn(&self) -> &dyn Estimator {
        match self {
            Chosen::Paper(est) => est,
            Chosen::Exact(est) => &**est,
        }
    }

    /// Runs `f` on the fleet of `input`'s sensors on `scenario`, with
    /// this estimator, maximising `input`'s objective (first detections
    /// over the exact estimator; a validated input never asks them of the
    /// paper's).
    pub(crate) fn with_fleet<R>(
        &self,
        scenario: &Scenario,
        input: &PlanInput,
        cancel: &CancelToken,
        f: impl FnOnce(&Fleet) -> R,
    ) -> R {
        let first = match (input.objective, self) {
            (Objective::FirstDetections, Chosen::Exact(est)) => Some(FirstDetections::new(est)),
            _ => None,
        };
        let mut fleet = Fleet::new(
            scenario,
            self.as_dyn(),
            &input.starts,
            &input.types,
            input.horizon,
            input.min_separation,
            cancel,
        );
        if let Some(first) = &first {
            fleet = fleet.with_first_detections(first);
        }
        fleet.full_searches = input.explain;
        f(&fleet)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coordination::MAX_REPAIR_SEARCHES_PER_SENSOR;
    use crate::scenario::paper_spec;

    /// A crowded fleet (64 sensors on neighbouring cells, 4 cells apart
    /// asked) makes the separation's repair search about n² times a round;
    /// its searches stop at their budget, which the cost model counts.
    #[test]
    fn the_separation_repair_searches_within_its_budget() {
        let planner = Planner::new(Scenario::new(paper_spec(10.0)).expect("valid"));
        let sensors: Vec<SensorIn> = (0..64)
            .map(|i| SensorIn {
                id: Id::Number((i as u64).into()),
                x: 5.0 + 10.0 * f64::from(i % 8),
                y: 5.0 + 10.0 * f64::from(i / 8),
                sensor_type: None,
            })
            .collect();
        let req = PlanRequest {
            sensors,
            horizon: Some(3.into()),
            min_separation: Some(4.into()),
            certify: Some(false),
            ..Default::default()
        };
        let input = PlanInput::new(&planner.scenario, &req).expect("valid");
        let cancel = CancelToken::new();
        let est = planner
            .estimator(&input, &cancel, None)
            .expect("not cancelled");
        let result = est
            .with_fleet(&planner.scenario, &input, &cancel, |fleet| {
                coordinate(
                    fleet,
                    input.coordination,
                    input.joint,
                    false,
                    Instant::now(),
                )
            })
            .expect("not cancelled");
        let n = input.starts.len();
        assert!(result.repairs > 0 && result.violations.pairs > 0);
        // A trial under way finishes: at most one more search per sensor.
        assert!(
            result.repair_searches <= (MAX_REPAIR_SEARCHES_PER_SENSOR + 1) * n,
            "{} searches",
            result.repair_searches
        );
    }

    /// Ids are equal as JSON values: a number however written, never a
    /// number and a string; `key` agrees with equality.
    #[test]
    fn ids_are_equal_as_json_values() {
        let id = |text: &str| -> Id { serde_json::from_str(text).expect(text) };
        let same = [
            ("7", "7.0"),
            ("7", "7e0"),
            ("-3", "-3.0"),
            ("0", "-0.0"),
            ("1.5", "15e-1"),
            ("18446744073709551615", "18446744073709551615"),
            (r#""a""#, r#""a""#),
        ];
        for (a, b) in same {
            assert_eq!(id(a), id(b), "{a} {b}");
            assert_eq!(id(a).key(), id(b).key(), "{a} {b}");
        }
        let differ = [
            ("7", r#""7""#),
            ("7", "7.5"),
            ("9007199254740993", "9007199254740992"),
            (r#""7.0""#, r#""7""#),
        ];
        for (a, b) in differ {
            assert_ne!(id(a), id(b), "{a} {b}");
            assert_ne!(id(a).key(), id(b).key(), "{a} {b}");
        }
    }

    #[test]
    fn ids_are_strings_or_numbers_echoed_as_given() {
        for text in [
            r#""a""#,
            r#""7""#,
            "7",
            "-3",
            "1.5",
            "18446744073709551615",
            "1e3",
        ] {
            let id: Id = serde_json::from_str(text).expect(text);
            let back = serde_json::to_string(&id).expect("serializes");
            let again: Id = serde_json::from_str(&back).expect("parses back");
            assert_eq!(again, id, "{text}");
            // Parsed the way `serde_json` reads the same token.
            assert_eq!(
                serde_json::to_value(&id).expect("value"),
                serde_json::from_str::<serde_json::Value>(text).expect("value"),
                "{text}"
            );
        }
        assert!(matches!(
            serde_json::from_str::<Id>(r#""7""#),
            Ok(Id::Text(_))
        ));
        assert!(matches!(serde_json::from_str::<Id>("7"), Ok(Id::Number(_))));
        for bad in ["true", "null", "[1]", r#"{"a":1}"#] {
            let err = serde_json::from_str::<Id>(bad).expect_err(bad);
            assert!(err.to_string().contains("a string or a number"), "{err}");
        }
    }
}
