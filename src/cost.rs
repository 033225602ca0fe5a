//! Predicted costs of the work a request asks for, so the service can
//! decide before starting it: a scenario's precomputation (run as a job
//! past the synchronous budget) and a plan (refused past `--max-plan-ms`).
//!
//! The models are linear, `Σ c_k·x_k`: each term `x_k` counts the work of
//! one stage of the code, read off the scenario or the request without any
//! estimator work ([`precompute_terms`], [`plan_terms`], [`first_terms`]);
//! each coefficient `c_k` is CPU milliseconds per unit on one core
//! ([`PRECOMPUTE_MODEL`], [`PLAN_MODEL`] and, for plans that maximise
//! first detections, [`FIRST_MODEL`] hold them; the tables below list the
//! same values).
//!
//! The coefficients are fitted from timed runs by
//! `cargo run --release -p vigil-loadtest --example cost_model`, which
//! prints them in the form of the tables below; how, on what data, and
//! how well the models predict is in `docs/performance.md` (*The cost
//! model*). A prediction must stay cheap next to the work it predicts:
//! O(sources + fields of view) for a precomputation, O(sensors² + targets +
//! history) for a plan.
//!
//! Precompute ([`precompute_ms`]; `C` cells, per field of view):
//!
//! | term | c (ms) | counts |
//! |---|---:|---|
//! | pairs: square, half-plane sources | 1.661e-4 | `C × sources`: angular span and the closed-form `∫1/r` ([`crate::stats`]) |
//! | pairs: square, cone sources | 3.549e-4 | the same, a wedge integral |
//! | pairs: circle, in cones | 2.592e-3 | `C × Σ` each source's share of the angles towards the zone: 16-point quadrature between breakpoints |
//! | pairs: circle, outside cones | 9.038e-4 | the other pairs: the span alone |
//! | grid: rects × half-plane sources | 3.627e-5 | the elementary grid's prefix table (squares only) |
//! | grid: rects × cone sources | 2.328e-4 | the same, wedge integrals |
//! | crossings: rays × (nx + ny) | 6.406e-6 | the index of the rays' crossings of the grid |
//!
//! With obstacles the statistics cast rays instead of the closed forms,
//! and [`precompute_ms`] adds them ([`obstacle_rays`], with three
//! coefficients of their own). A plan with obstacles takes the windows
//! for every look that sees its whole square, and the rays for what a
//! ground look near an obstacle does not see (`sighted` below).
//!
//! Plan ([`plan_ms`]); `n` sensors, horizon `T`; per sensor and step `t`
//! its reachable cells `(2vt+1)²` clipped to the lattice and their block of
//! elementary rectangles; `E`: the sensors whose looks can meet that reach
//! by step `t` (from the starts); `ov`: the other sensors' looks expected
//! to meet one look's field of view at step `t`, each placed uniformly
//! over its reach (from the starts, so a crowded fleet counts every
//! neighbour); each search runs per pass:
//! alone, in priority order (excluding half the nearby sensors) and, for
//! `iterated`, `1 + min(4, Ē/10)` rounds excluding all of them (`Ē` the
//! mean `E` at step `T`; `1 + min(7, Ē/4)` with the paper estimator;
//! measured: 1–6 and 1–9 rounds):
//!
//! | term | c (ms) | counts |
//! |---|---:|---|
//! | 1 | 1.331e-2 | fixed |
//! | seen: look-rays, certain | 5.495e-7 | rays × looks now and in the history, per class (exact) |
//! | seen: look-rays, uncertain | 3.668e-5 | the same when `p_detect < 1` |
//! | seen: sorting pieces | 2.280e-5 | `P·log₂(2 + P/rays)`, `P` = rays × sensors |
//! | windows: T × look-rays (whole grid) | 0.000e0 | seen intervals walked over a grid of ≤ 65 536 rectangles |
//! | windows: T × rects (whole grid) | 5.320e-6 | its unseen mass per step |
//! | windows: blocks | 8.287e-6 | larger grids: rays × the blocks' size in fields of view |
//! | fill: cells | 1.115e-5 | reachable cells × passes (values and search) |
//! | fill: rects × (1 + E in rows) | 0.000e0 | prefix sums, masked by the excluded looks |
//! | fill: targets × looks checked | 1.155e-7 | targets in the zone × the excluded looks tried on each |
//! | fill: cells × clear targets | 4.718e-6 | cells × the targets near the reach, tested cell by cell; past `BLOCKS_FROM` cells × targets, cells + targets × a view's width in cells (each target's block, then prefix sums) |
//! | general: cells × classes | 0.000e0 | circles: a ray range per cell and class |
//! | general: cells × rays × (1 + ov) | 1.964e-5 | its rays, with the overlapping looks |
//! | general: cells × targets | 1.165e-6 | every reported target per cell |
//! | sighted: cells × rays near obstacles | 1.123e-5 | a ground look's hidden part by its rays: cells × rays × the share of its reach whose squares meet an obstacle |
//! | paper: setup | 1.149e-5 | per sensor: `(2vT+1)²` overlaps, targets, 512 escape samples per source and class |
//! | paper: cells × (seen + E) | 6.805e-7 | per cell: the sensor's targets and the excluded looks |
//! | paper: cells × ov² | 5.801e-6 | the excluded area's cover |
//! | paper iterated: cells × n × (1 + ov) | 7.732e-6 | every lower-ranked sensor's change (× `geometry::CURVED_SLAB_NODES` for circles: their cover's quadrature nodes) |
//! | general uncertain: cells × rays × (looks per ray + ov) | 3.415e-6 | with `p_detect < 1` the seen pieces are kept apart (not one union) and swept with the overlapping looks |
//! | sighted: cells × rays near obstacles × ov × (1 + obstacles per view) | 2.219e-6 | the same rays cut by the overlapping looks' own shadows (each excluded look an obstacle cuts) |
//! | fill: partly seen targets × view cells | 2.227e-6 | past `BLOCKS_FROM` cells × targets, each target an excluded uncertain look holds, added over the block of cells whose views hold it |
//! | paper: cells × ov², circles | 4.803e-5 | the cover of circles: `geometry::CURVED_SLAB_NODES` quadrature nodes a slab |
//! | fill: rects × E in rows, uncertain | 6.515e-6 | the same masks when the looks are uncertain: a rectangle's product of misses never stops at 0, so it tries every look across its row |
//!
//! The `sighted` coefficient was first fitted alone on `site-campus`'s
//! fleets (`--only campus`; `docs/obstacles.md`); it is now fitted with
//! the others.
//!
//! First detections ([`plan_ms`] with `"objective": "first_detections"`,
//! whose searches replace the fill and programme above); per sensor `k`
//! searches: alone, ranked, the certificate's, and `iterated`'s rounds
//! (`1 + min(7, Ē/4)`):
//!
//! | term | c (ms) | counts |
//! |---|---:|---|
//! | estimator | 1 (held) | the first seven terms above: seen sets and windows |
//! | searches: backgrounds | 8.983e-6 | `k × (n − 1) × T × rays per look`: the other sensors' pieces each search merges |
//! | searches: pair gains × t | 1.991e-6 | `k × Σ_t cells(t − 1) × (2v+1)² × t × rays per look`: a pair into step `t` meets `t` stops' pieces |
//! | searches: paths within the budget | 1.661e-7 | `k × min((2v+1)^T, budget) × T × rays per look`: the branch and bound past the pairs |
//! | searches: cells near obstacles | 3.575e-5 | `k × Σ_t cells(t) × rays per look × the share of the reach near an obstacle` (ground sensors) |

mod first;
mod reach;

pub use first::{FIRST_MODEL, FirstTerms, first_terms};
use reach::{
    half, iterated_rounds, near_by_step, obstacles_per_view, overlaps_by_step, rays_per_look,
    repair_passes, sensor_reach, source_rays,
};

use crate::coordination::{Coordination, Objective};
use crate::estimator::{
    BLOCKS_FROM, INDEX_CROSSINGS_PER_CELL, MAX_SMALL_GRID, MIN_INDEX_CROSSINGS,
    ONE_WINDOW_RECTANGLES,
};
use crate::geometry::{CURVED_SLAB_NODES, Point};
use crate::limits::OBSTACLE_STATS_RAYS_PER_PI;
use crate::planner::{EstimatorKind, Observed, PlanInput, Planner};
use crate::scenario::{FovSpec, Scenario, Source};
use crate::stats::{ESCAPE_SAMPLES, angular_span};

/// The precompute model: each term's name and coefficient, milliseconds
/// per unit, in the order of [`precompute_terms`].
pub const PRECOMPUTE_MODEL: [(&str, f64); 7] = [
    ("pairs: square, half-plane sources", 1.661e-4),
    ("pairs: square, cone sources", 3.549e-4),
    ("pairs: circle, in cones", 2.592e-3),
    ("pairs: circle, outside cones", 9.038e-4),
    ("grid: rects × half-plane sources", 3.627e-5),
    ("grid: rects × cone sources", 2.328e-4),
    ("crossings: rays × (nx + ny)", 6.406e-6),
];

/// The plan model: each term's name and coefficient, milliseconds per unit,
/// in the order of [`plan_terms`].
pub const PLAN_MODEL: [(&str, f64); 24] = [
    ("1", 1.331e-2),
    ("seen: look-rays, certain", 5.495e-7),
    ("seen: look-rays, uncertain", 3.668e-5),
    ("seen: sorting pieces", 2.280e-5),
    ("windows: T × look-rays (whole grid)", 0.000e0),
    ("windows: T × rects (whole grid)", 5.320e-6),
    ("windows: blocks", 8.287e-6),
    ("fill: cells", 1.115e-5),
    ("fill: rects × (1 + E in rows)", 0.000e0),
    ("fill: targets × looks checked", 1.155e-7),
    ("fill: cells × clear targets", 4.718e-6),
    ("general: cells × classes", 0.000e0),
    ("general: cells × rays × (1 + ov)", 1.964e-5),
    ("general: cells × targets", 1.165e-6),
    ("sighted: cells × rays near obstacles", 1.123e-5),
    ("paper: setup", 1.149e-5),
    ("paper: cells × (seen + E)", 6.805e-7),
    ("paper: cells × ov²", 5.801e-6),
    ("paper iterated: cells × n × (1 + ov)", 7.732e-6),
    (
        "general uncertain: cells × rays × (looks per ray + ov)",
        3.415e-6,
    ),
    (
        "sighted: cells × rays near obstacles × ov × (1 + obstacles per view)",
        2.219e-6,
    ),
    ("fill: partly seen targets × view cells", 2.227e-6),
    ("paper: cells × ov², circles", 4.803e-5),
    ("fill: rects × E in rows, uncertain", 6.515e-6),
];

/// The units of work of one precomputation, one per term of [`PRECOMPUTE_MODEL`] (same order).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PrecomputeTerms {
    /// pairs: square, half-plane sources (`PRECOMPUTE_MODEL[0]`).
    pub square_half_plane: f64,
    /// pairs: square, cone sources (`PRECOMPUTE_MODEL[1]`).
    pub square_cones: f64,
    /// pairs: circle, in cones (`PRECOMPUTE_MODEL[2]`).
    pub circle_in_cones: f64,
    /// pairs: circle, outside cones (`PRECOMPUTE_MODEL[3]`).
    pub circle_outside_cones: f64,
    /// grid: rects × half-plane sources (`PRECOMPUTE_MODEL[4]`).
    pub grid_half_plane: f64,
    /// grid: rects × cone sources (`PRECOMPUTE_MODEL[5]`).
    pub grid_cones: f64,
    /// crossings: rays × (nx + ny) (`PRECOMPUTE_MODEL[6]`).
    pub crossings: f64,
}

impl PrecomputeTerms {
    /// The terms in the order of [`PRECOMPUTE_MODEL`].
    pub fn to_array(&self) -> [f64; 7] {
        [
            self.square_half_plane,
            self.square_cones,
            self.circle_in_cones,
            self.circle_outside_cones,
            self.grid_half_plane,
            self.grid_cones,
            self.crossings,
        ]
    }
}

/// The units of work of one plan, one per term of [`PLAN_MODEL`] (same order).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PlanTerms {
    /// 1 (`PLAN_MODEL[0]`).
    pub constant: f64,
    /// seen: look-rays, certain (`PLAN_MODEL[1]`).
    pub seen_certain: f64,
    /// seen: look-rays, uncertain (`PLAN_MODEL[2]`).
    pub seen_uncertain: f64,
    /// seen: sorting pieces (`PLAN_MODEL[3]`).
    pub seen_sorting: f64,
    /// windows: T × look-rays (whole grid) (`PLAN_MODEL[4]`).
    pub windows_look_rays: f64,
    /// windows: T × rects (whole grid) (`PLAN_MODEL[5]`).
    pub windows_rects: f64,
    /// windows: blocks (`PLAN_MODEL[6]`).
    pub windows_blocks: f64,
    /// fill: cells (`PLAN_MODEL[7]`).
    pub fill_cells: f64,
    /// fill: rects × (1 + E in rows) (`PLAN_MODEL[8]`).
    pub fill_rects: f64,
    /// fill: targets × looks checked (`PLAN_MODEL[9]`).
    pub fill_targets: f64,
    /// fill: cells × clear targets (`PLAN_MODEL[10]`).
    pub fill_clear_targets: f64,
    /// general: cells × classes (`PLAN_MODEL[11]`).
    pub general_classes: f64,
    /// general: cells × rays × (1 + ov) (`PLAN_MODEL[12]`).
    pub general_rays: f64,
    /// general: cells × targets (`PLAN_MODEL[13]`).
    pub general_targets: f64,
    /// sighted: cells × rays near obstacles (`PLAN_MODEL[14]`).
    pub sighted_rays: f64,
    /// paper: setup (`PLAN_MODEL[15]`).
    pub paper_setup: f64,
    /// paper: cells × (seen + E) (`PLAN_MODEL[16]`).
    pub paper_cells: f64,
    /// paper: cells × ov² (`PLAN_MODEL[17]`).
    pub paper_overlaps: f64,
    /// paper iterated: cells × n × (1 + ov) (`PLAN_MODEL[18]`).
    pub paper_iterated: f64,
    /// general uncertain: cells × rays × (looks per ray + ov)
    /// (`PLAN_MODEL[19]`).
    pub general_uncertain: f64,
    /// sighted: cells × rays near obstacles × ov × (1 + obstacles per
    /// view) (`PLAN_MODEL[20]`).
    pub sighted_cut: f64,
    /// fill: partly seen targets × view cells (`PLAN_MODEL[21]`).
    pub fill_partial_targets: f64,
    /// paper: cells × ov², circles (`PLAN_MODEL[22]`).
    pub paper_overlaps_circles: f64,
    /// fill: rects × E in rows, uncertain (`PLAN_MODEL[23]`).
    pub fill_rects_uncertain: f64,
}

impl PlanTerms {
    /// The terms in the order of [`PLAN_MODEL`].
    pub fn to_array(&self) -> [f64; 24] {
        [
            self.constant,
            self.seen_certain,
            self.seen_uncertain,
            self.seen_sorting,
            self.windows_look_rays,
            self.windows_rects,
            self.windows_blocks,
            self.fill_cells,
            self.fill_rects,
            self.fill_targets,
            self.fill_clear_targets,
            self.general_classes,
            self.general_rays,
            self.general_targets,
            self.sighted_rays,
            self.paper_setup,
            self.paper_cells,
            self.paper_overlaps,
            self.paper_iterated,
            self.general_uncertain,
            self.sighted_cut,
            self.fill_partial_targets,
            self.paper_overlaps_circles,
            self.fill_rects_uncertain,
        ]
    }
}

/// Predicted CPU time of [`Planner::new`] on `s`, milliseconds on one
/// core: positive and finite for every valid scenario; O(sources + fields
/// of view) to compute.
pub fn precompute_ms(s: &Scenario) -> f64 {
    let work = dot(&PRECOMPUTE_MODEL, &precompute_terms(s).to_array()).max(FLOOR_MS);
    let list = s.obstacles.list();
    let vertices: usize = list.iter().map(|o| o.polygon.vertices().len()).sum();
    work + obstacle_rays(s)
        * (OBSTACLE_MS_PER_RAY
            + OBSTACLE_MS_PER_RAY_AND_OBSTACLE * list.len() as f64
            + OBSTACLE_MS_PER_RAY_AND_VERTEX * vertices as f64)
}

/// Milliseconds per ray of the statistics of a scenario with obstacles
/// ([`obstacle_rays`]), per ray and obstacle, and per ray and vertex:
/// each ray is clipped by every building (where a target stops) and by the
/// shadows that hide parts of the field of view, edge by edge. Fitted on
/// `site-campus` (with its twelve obstacles, with four, with 5 m cells)
/// and on yards of 4 to 64 obstacles of 4 to 32 vertices (the
/// `cost_model` example's `obstacles` cases; figures in
/// `docs/obstacles.md`). Those statistics integrate every cell's visible
/// field of view along rays ([`crate::stats`]), where the closed forms
/// the model's other terms count no longer apply.
const OBSTACLE_MS_PER_RAY: f64 = 1.37e-5;
/// See [`OBSTACLE_MS_PER_RAY`].
const OBSTACLE_MS_PER_RAY_AND_OBSTACLE: f64 = 1.26e-6;
/// See [`OBSTACLE_MS_PER_RAY`].
const OBSTACLE_MS_PER_RAY_AND_VERTEX: f64 = 3.97e-7;

/// Points per side of the grid over the zone on which [`obstacle_rays`]
/// averages the angles a field of view spans.
const RAY_SAMPLES_PER_SIDE: usize = 32;

/// The rays the statistics of a scenario with obstacles cast: per view,
/// cell and source, the angle the field of view spans seen from the
/// source, at [`OBSTACLE_STATS_RAYS_PER_PI`] rays per π; the angle
/// averaged over a grid of [`RAY_SAMPLES_PER_SIDE`]² points of the zone
/// (a view near a source spans a wide angle). Zero without obstacles.
pub fn obstacle_rays(s: &Scenario) -> f64 {
    if !s.has_obstacles() {
        return 0.0;
    }
    let k = RAY_SAMPLES_PER_SIDE;
    let mut spans = 0.0;
    for &fov in &s.fovs {
        let h = half(fov);
        for src in s.sources.iter().filter(|src| src.rate > 0.0) {
            let mut sum = 0.0;
            for i in 0..k {
                for j in 0..k {
                    let x = s.width * (i as f64 + 0.5) / k as f64;
                    let y = s.height * (j as f64 + 0.5) / k as f64;
                    let r = (src.pos.x - x).hypot(src.pos.y - y);
                    sum += 2.0 * (h / r.max(s.cell_size / 2.0)).atan();
                }
            }
            spans += sum / (k * k) as f64 / std::f64::consts::PI;
        }
    }
    s.cell_count() as f64 * spans * OBSTACLE_STATS_RAYS_PER_PI as f64
}

/// Predicted CPU time of planning `input` on `planner`
/// ([`Planner::plan`]), milliseconds on one core: positive and finite;
/// O(sensors² + targets + history) to compute (microseconds).
pub fn plan_ms(planner: &Planner, input: &PlanInput) -> f64 {
    let terms = plan_terms(planner, input).to_array();
    if input.objective == Objective::FirstDetections {
        // Its searches, not the model's fill and programme, are the work
        // (and `joint` runs as `iterated`).
        let estimator = dot(&PLAN_MODEL[..ESTIMATOR_TERMS], &terms[..ESTIMATOR_TERMS]);
        let first = first_terms(planner, input, estimator).to_array();
        return dot(&FIRST_MODEL, &first).max(FLOOR_MS);
    }
    let work = dot(&PLAN_MODEL, &terms).max(FLOOR_MS);
    // `joint` may use all of its budget on top of `iterated`'s work.
    match (input.coordination, input.estimator) {
        (Coordination::Joint, EstimatorKind::Exact) => {
            work + input.joint.budget.as_secs_f64() * 1e3
        }
        _ => work,
    }
}

/// Milliseconds per unit of the paper estimator's marginals in an
/// evaluate: `m²·(1 + m)·nodes` per sensor and step, `m` the other looks
/// that meet its view (a marginal re-scores each lower sensor it
/// overlaps, each value a cover of about `m²`), `nodes` 12 for a circle's
/// quadrature and 1 for a square. Measured in `docs/performance.md` (*The
/// cost model*).
const EVALUATE_PAPER_MS_PER_COVER: f64 = 6.0e-7;

/// Predicted CPU time of scoring `paths` (one per sensor of `input`, its
/// cells at steps 1..=T) on `planner`, milliseconds on one core: the
/// estimator's preparation and one value per sensor and step are less
/// than a plan without coordination ([`plan_ms`] of it); with the paper
/// estimator, whose marginals re-score the sensors below each one, the
/// covers they take on top. O(sensors² × T).
pub fn evaluate_ms(
    planner: &Planner,
    input: &PlanInput,
    paths: &[Vec<crate::scenario::Cell>],
) -> f64 {
    let mut uncoordinated = input.clone();
    uncoordinated.coordination = Coordination::None;
    let base = plan_ms(planner, &uncoordinated);
    if input.estimator != EstimatorKind::Paper {
        return base;
    }
    let s = &planner.scenario;
    let mut covers = 0.0;
    for t in 0..input.horizon {
        let views: Vec<_> = (paths.iter().zip(&input.types))
            .filter_map(|(path, &ty)| Some((s.fov_region_of(ty, *path.get(t)?).rect, ty)))
            .collect();
        for (i, (a, ty)) in views.iter().enumerate() {
            let m = (views.iter().enumerate())
                .filter(|&(q, (b, _))| q != i && !a.intersect(b).is_empty())
                .count() as f64;
            let nodes = match s.types[*ty].fov {
                FovSpec::Circle { .. } => CURVED_SLAB_NODES as f64,
                FovSpec::Square { .. } => 1.0,
            };
            covers += m * m * (1.0 + m) * nodes;
        }
    }
    base + EVALUATE_PAPER_MS_PER_COVER * covers
}

/// The first [`PLAN_MODEL`] terms, up to `fill: cells`: the estimator a
/// plan builds before its searches (its seen sets and windows).
pub const ESTIMATOR_TERMS: usize = 7;

/// Milliseconds per crossing of a fit's exposure (a look, a ray of the
/// scenario's grid that may cross it, a class:
/// [`crate::fit::WindowLooks::work`]) on a scenario without obstacles, and
/// with them (a ground look's visible parts of each ray): measured in
/// `docs/learning.md` (*Cost*), rounded up.
const FIT_MS_PER_CROSSING: f64 = 6.0e-5;
/// See [`FIT_MS_PER_CROSSING`].
const FIT_MS_PER_CROSSING_WITH_OBSTACLES: f64 = 1.7e-4;

/// Predicted CPU time of a fit of scenario `s` whose exposure walks
/// `crossings` crossings, milliseconds on one core.
pub fn fit_ms(s: &Scenario, crossings: usize) -> f64 {
    let per = if s.has_obstacles() {
        FIT_MS_PER_CROSSING_WITH_OBSTACLES
    } else {
        FIT_MS_PER_CROSSING
    };
    (crossings as f64 * per).max(FLOOR_MS)
}

/// The least either model predicts: every term can be 0 (sources that
/// emit nothing), the work never is.
const FLOOR_MS: f64 = 0.01;

fn dot(model: &[(&str, f64)], terms: &[f64]) -> f64 {
    model.iter().zip(terms).map(|((_, c), t)| c * t).sum()
}

/// The terms of [`PRECOMPUTE_MODEL`] for `s` (for fitting and checks).
pub fn precompute_terms(s: &Scenario) -> PrecomputeTerms {
    let cells = s.cell_count() as f64;
    let mut buf = Vec::new();
    let (mut cover, mut cone, mut inside) = (0.0, 0.0, 0.0);
    for src in s.sources.iter().filter(|src| src.rate > 0.0) {
        inside += in_cone(s, src, &mut buf);
        if src.covers_zone {
            cover += 1.0;
        } else {
            cone += 1.0;
        }
    }
    let mut t = PrecomputeTerms::default();
    let mut halves = Vec::new();
    for &fov in &s.fovs {
        match fov {
            FovSpec::Square { half_width } => {
                t.square_half_plane += cells * cover;
                t.square_cones += cells * cone;
                halves.push(half_width);
            }
            FovSpec::Circle { .. } => {
                t.circle_in_cones += cells * inside;
                t.circle_outside_cones += cells * (cover + cone - inside);
            }
        }
    }
    if s.all_square() {
        let nx = intervals(s.cols, s.cell_size, &halves);
        let ny = intervals(s.rows, s.cell_size, &halves);
        // As `ElementaryGrid::new` and `SourceRays::index_crossings`
        // decide: no grid past what one size of square gives, no index past
        // ~100 bytes a cell.
        let one = (2.0 * s.cols as f64 + 1.0) * (2.0 * s.rows as f64 + 1.0);
        if nx * ny <= one.max(MAX_SMALL_GRID as f64) {
            t.grid_half_plane = nx * ny * cover;
            t.grid_cones = nx * ny * cone;
            let rays: f64 = source_rays(s).iter().map(|r| r.1).sum();
            if rays * (nx + ny)
                <= (INDEX_CROSSINGS_PER_CELL as f64 * cells).max(MIN_INDEX_CROSSINGS as f64)
            {
                t.crossings = rays * (nx + ny);
            }
        }
    }
    t
}

/// The share of the angles towards the zone that a source's cone holds
/// (1 for a half-plane source).
fn in_cone(s: &Scenario, src: &Source, buf: &mut Vec<Point>) -> f64 {
    if src.covers_zone {
        return 1.0;
    }
    let z = s.zone();
    let angles = [(z.x0, z.y0), (z.x1, z.y0), (z.x1, z.y1), (z.x0, z.y1)]
        .map(|(x, y)| src.angle_to(Point::new(x, y)));
    let lo = angles.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = angles.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    match angular_span(src, &s.zone_region(), buf) {
        Some((a, b)) if hi > lo => ((b - a) / (hi - lo)).min(1.0),
        _ => 0.0,
    }
}

/// Elementary intervals along an axis of `n` cells: the squares' edges
/// fall on one family of about `n` points per distinct offset modulo the
/// cell (one when `2·half_width` is a whole number of cells).
fn intervals(n: i32, cell: f64, halves: &[f64]) -> f64 {
    let mut offsets: Vec<f64> = halves
        .iter()
        .flat_map(|&h| [0.5 * cell - h, 0.5 * cell + h])
        .map(|o| o.rem_euclid(cell))
        .map(|o| if cell - o < 1e-9 * cell { 0.0 } else { o })
        .collect();
    offsets.sort_by(f64::total_cmp);
    offsets.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * cell);
    offsets.len() as f64 * n as f64 + 1.0
}

/// The terms of [`PLAN_MODEL`] for `input` on `planner` (for fitting and
/// checks).
pub fn plan_terms(planner: &Planner, input: &PlanInput) -> PlanTerms {
    let s = &planner.scenario;
    let (n, big_t, cs) = (input.starts.len(), input.horizon, s.cell_size);
    let exact = input.estimator == EstimatorKind::Exact;
    let grid = planner.grid.as_ref().filter(|_| exact && s.all_square());
    let rays = source_rays(s);
    let classes = s.classes.len() as f64;
    let per_look = rays_per_look(s, input, &rays);
    let all_rays: f64 = rays.iter().map(|r| r.1 * r.2).sum();
    let history: usize = input.history.iter().map(Vec::len).sum();
    let now = match input.observed {
        Observed::Zone => all_rays,
        Observed::Sensors => n as f64 * per_look,
    };
    let look_rays = now + history as f64 * per_look;
    let stride = big_t + 1;
    let near = near_by_step(s, input);
    let me = sensor_reach(s, input);
    // Reported targets still in the zone at step t (the estimators drop the
    // others): each leaves at its first crossing of the zone's edge.
    let mut in_zone = vec![0.0; big_t + 2];
    for tg in input.targets.iter().filter(|tg| s.in_zone(tg.pos)) {
        let exit = |x: f64, v: f64, w: f64| match v {
            v if v > 0.0 => (w - x) / v,
            v if v < 0.0 => x / -v,
            _ => f64::INFINITY,
        };
        let out = exit(tg.pos.x, tg.vel.x, s.width).min(exit(tg.pos.y, tg.vel.y, s.height));
        in_zone[0] += 1.0;
        // `out ≥ 0`: the cast floors.
        in_zone[(out as usize).saturating_add(1).min(big_t + 1)] -= 1.0;
    }
    for step in 1..=big_t {
        in_zone[step] += in_zone[step - 1];
    }
    let known = in_zone[0];

    let mut t = PlanTerms {
        constant: 1.0,
        ..PlanTerms::default()
    };
    let certain = s.types.iter().all(|ty| ty.p_detect == 1.0);
    // Looks (now and in the history) that cross one ray, on average.
    let looks_per_ray = look_rays / all_rays.max(1.0);
    if exact {
        if certain {
            t.seen_certain = look_rays;
        } else {
            t.seen_uncertain = look_rays;
        }
        let pieces = n as f64 * per_look;
        t.seen_sorting = pieces * (2.0 + pieces / all_rays.max(1.0)).log2();
    }
    let whole = grid.is_some_and(|g| g.dims().0 * g.dims().1 <= ONE_WINDOW_RECTANGLES);
    if let (Some(g), true) = (grid, whole) {
        t.windows_look_rays = big_t as f64 * look_rays;
        t.windows_rects = (big_t * g.dims().0 * g.dims().1) as f64;
    }
    let rounds = iterated_rounds(&near, n, exact);
    // (runs, share of the nearby sensors excluded) per pass.
    // An exact plan's certificate takes one more search per sensor, with
    // no exclusion; `joint` is `iterated`'s work (its budget is added in
    // `plan_ms`).
    // Without the certificate an exact plan skips its search (`joint`
    // always certifies).
    let certified = exact && (input.certify || input.coordination == Coordination::Joint);
    let passes: &[(f64, f64)] = match (input.coordination, certified) {
        (Coordination::None, false) => &[(1.0, 0.0)],
        (Coordination::None, true) => &[(1.0, 0.0), (1.0, 0.0)],
        (Coordination::Priority, false) => &[(1.0, 0.0), (1.0, 0.5)],
        (Coordination::Priority, true) => &[(1.0, 0.0), (1.0, 0.5), (1.0, 0.0)],
        (Coordination::Iterated | Coordination::Joint, false) => {
            &[(1.0, 0.0), (1.0, 0.5), (rounds, 1.0)]
        }
        (Coordination::Iterated | Coordination::Joint, true) => {
            &[(1.0, 0.0), (1.0, 0.5), (rounds, 1.0), (1.0, 0.0)]
        }
    };
    let mut passes = passes.to_vec();
    // The separation's repair, as ranked searches.
    let repairs = repair_passes(s, input);
    if repairs > 0.0 {
        passes.push((repairs, 0.5));
    }
    let zone_area = s.width * s.height;
    // The looks that meet one look's field of view, for the paths that
    // test each cell against them (the grid's prefix sums do not, but the
    // rays of a look an obstacle cuts do).
    let overlaps = if grid.is_none() || s.has_obstacles() {
        overlaps_by_step(s, input)
    } else {
        Vec::new()
    };
    // Per step, for the windows: the reach blocks' bounding box, their
    // total size, and their size in fields of view.
    let mut bbox = vec![(usize::MAX, 0, usize::MAX, 0); stride];
    let (mut total, mut blocks) = (vec![0.0; stride], vec![0.0; stride]);
    let mut fov_rects = 0.0;
    for (i, &(start, _, _)) in me.iter().enumerate() {
        let ty = &s.types[input.types[i]];
        let side = 2.0 * half(ty.fov);
        let circle = matches!(ty.fov, FovSpec::Circle { .. });
        let a = (side.min(s.width) * side.min(s.height)) / zone_area;
        let (own, own_rows) = grid.map_or((1.0, 1.0), |g| {
            let (a0, a1, b0, b1) = g.span(ty.fov_slot, start);
            (
                ((a1 - a0) * (b1 - b0)).max(1) as f64,
                (b1 - b0).max(1) as f64,
            )
        });
        fov_rects += own;
        // (1 − a)^excluded per pass, the share of the targets no excluded
        // look holds (looks placed independently), kept as a product.
        let base: Vec<f64> = passes
            .iter()
            .map(|&(_, share)| (1.0 - a).max(0.0).powf(share))
            .collect();
        let mut miss = vec![1.0; passes.len()];
        let mut e = 0.0;
        for step in 1..=big_t {
            let fresh = near[i * stride + step];
            e += fresh as f64;
            for (m, b) in miss.iter_mut().zip(&base) {
                *m *= b.powi(fresh as i32);
            }
            let r = (ty.speed * step) as i32;
            let (lo, hi) = s.reach_corners(start, r);
            let cells = ((hi.col - lo.col + 1) * (hi.row - lo.row + 1)) as f64;
            let (rects, rows) = grid.map_or((0.0, 1.0), |g| {
                let ((a0, _, b0, _), (_, a1, _, b1)) =
                    (g.span(ty.fov_slot, lo), g.span(ty.fov_slot, hi));
                let b = &mut bbox[step];
                *b = (b.0.min(a0), b.1.max(a1), b.2.min(b0), b.3.max(b1));
                (((a1 - a0) * (b1 - b0)) as f64, (b1 - b0).max(1) as f64)
            });
            total[step] += rects;
            blocks[step] += rects / own;
            let per_view = if grid.is_some() && !ty.elevated {
                obstacles_per_view(s, lo, hi, half(ty.fov))
            } else {
                0.0
            };
            let near_obstacles = per_view.min(1.0);
            // The reported targets a fill reads (those in the reach grown by
            // a view), and whether it tests each cell against each of them
            // or counts them per view block (`BLOCKS_FROM`; a ground look
            // among obstacles always tests).
            let reach_area = ((f64::from(hi.col - lo.col + 1) * cs + side).min(s.width))
                * ((f64::from(hi.row - lo.row + 1) * cs + side).min(s.height));
            let near_targets = in_zone[step] * (reach_area / zone_area).min(1.0);
            let per_cell =
                near_targets * cells <= BLOCKS_FROM as f64 || (s.has_obstacles() && !ty.elevated);
            let span = (side / cs).ceil() + 1.0;
            let view_cells = (span * span).min(cells);
            for (&(w, share), &miss) in passes.iter().zip(&miss) {
                let ex = e * share;
                t.fill_cells += w * cells;
                if grid.is_some() {
                    let in_rows = ex * (own_rows / rows).min(1.0);
                    t.fill_rects += w * rects * (1.0 + in_rows);
                    // Uncertain looks never stop a rectangle's product
                    // early: it tries every look across its row.
                    if !certain {
                        t.fill_rects_uncertain += w * rects * in_rows;
                    }
                    // A target's check stops at the first look that
                    // holds it: about 1/a looks when they cover a lot.
                    let checks = if a > 0.0 { (1.0 - miss) / a } else { ex };
                    t.fill_targets += w * (known + in_zone[step] * checks);
                    if per_cell {
                        t.fill_clear_targets += w * cells * near_targets;
                    } else {
                        // Counted per view block: each target's block
                        // found along both axes, clear ones added by prefix
                        // sums, partly seen ones over their block.
                        t.fill_clear_targets += w * (cells + near_targets * span);
                        if !certain {
                            t.fill_partial_targets += w * near_targets * (1.0 - miss) * view_cells;
                        }
                    }
                    t.sighted_rays += w * cells * per_look * near_obstacles;
                    let ov = overlaps.get(i * stride + step).copied().unwrap_or(0.0);
                    t.sighted_cut +=
                        w * cells * per_look * near_obstacles * ov * share * (1.0 + per_view);
                } else if exact {
                    let ov = overlaps[i * stride + step];
                    t.general_classes += w * cells * classes;
                    t.general_rays += w * cells * per_look * (1.0 + ov * share);
                    t.general_targets += w * cells * known;
                    if !certain {
                        t.general_uncertain += w * cells * per_look * (looks_per_ray + ov * share);
                    }
                } else {
                    let ov = overlaps[i * stride + step];
                    t.paper_cells += w * cells * (known * a + ex);
                    // A circle's cover takes `CURVED_SLAB_NODES` a slab.
                    if circle {
                        t.paper_overlaps_circles += w * cells * (ov * share).powi(2);
                    } else {
                        t.paper_overlaps += w * cells * (ov * share).powi(2);
                    }
                    if share == 1.0 {
                        let nodes = if circle {
                            CURVED_SLAB_NODES as f64
                        } else {
                            1.0
                        };
                        t.paper_iterated += w * cells * n as f64 * (1.0 + ov) * nodes;
                    }
                }
            }
        }
        if !exact {
            let reach = (2 * ty.speed * big_t + 1) as f64;
            t.paper_setup +=
                reach * reach + known + ESCAPE_SAMPLES as f64 * (rays.len() as f64 + classes);
        }
    }
    if grid.is_some() && !whole {
        // One window over the reaches' bounding box when it is not much
        // larger than they are, else one per sensor (as the estimator
        // chooses); each walks the rays that cross it.
        for step in 1..=big_t {
            let b = bbox[step];
            let size = ((b.1 - b.0) * (b.3 - b.2)) as f64;
            t.windows_blocks += per_look
                * if size <= (ONE_WINDOW_RECTANGLES as f64).max(2.0 * total[step]) {
                    size * n as f64 / fov_rects
                } else {
                    blocks[step]
                };
        }
    }
    t
}

#[cfg(test)]
mod tests;
