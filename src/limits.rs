//! Every limit and default of the API, in one place.
//!
//! The code that checks a value, the cost model, the command line and the
//! OpenAPI document (its bounds are written from these constants, see
//! `http::doc::bounds`) all read them from here, so one edit changes the limit
//! everywhere. This module imports nothing: any module may use it.

// The model (a scenario).

/// Largest planning horizon `T` accepted.
pub const MAX_HORIZON: usize = 12;
/// Horizon used when a spec does not give one.
pub const DEFAULT_HORIZON: usize = 3;
/// Largest number of cells in a lattice.
pub const MAX_CELLS: usize = 4_000_000;
/// Largest number of sources in a scenario.
pub const MAX_SOURCES: usize = 64;
/// Most speed classes of one source.
pub const MAX_SPEED_CLASSES: usize = 8;
/// Largest bound on the zone's population accepted: `Σ rate·diagonal/speed`
/// over the target classes (the most targets the zone could hold at once if
/// every one crossed its full diagonal). Keeps every statistic finite.
pub const MAX_POPULATION: f64 = 1e9;
/// Most per-cell statistics of a scenario whose sensor types have several
/// fields of view: cells × distinct fields of view (each field of view has
/// its own statistics of every cell).
pub const MAX_CELL_STATS: usize = 8_000_000;
/// Longest scenario name, characters.
pub const MAX_NAME_CHARS: usize = 200;
/// Rays per π of the exact estimator's angular grid when a spec gives none
/// and every field of view is a square (the fast path): the error and cost
/// of each density are in `docs/performance.md` (*Accuracy*).
pub const DEFAULT_RAYS_PER_PI_SQUARE: usize = 128;
/// The same when a field of view is a circle: the general path integrates
/// excluded areas by the same rule, whose error next to a source is
/// several times larger.
pub const DEFAULT_RAYS_PER_PI_CIRCLE: usize = 384;
/// Fewest rays per π a spec may ask for.
pub const MIN_RAYS_PER_PI: usize = 32;
/// Most rays per π a spec may ask for (a plan's cost is about linear in
/// them).
pub const MAX_RAYS_PER_PI: usize = 1024;

// A fleet.

/// Most named sensor types of a scenario (besides `default`).
pub const MAX_SENSOR_TYPES: usize = 8;
/// Fastest sensor, cells (king moves) per step. The search's motion tables
/// are built for every speed up to it.
pub const MAX_SENSOR_SPEED: usize = 3;
/// Longest sensor type name, characters (of `[A-Za-z0-9_-]`).
pub const MAX_TYPE_NAME_CHARS: usize = 32;
/// Most no-go rectangles of a scenario.
pub const MAX_NO_GO: usize = 256;
/// Most obstacles (buildings and screens) of a scenario.
pub const MAX_OBSTACLES: usize = 64;
/// Fewest vertices of an obstacle's polygon.
pub const MIN_OBSTACLE_VERTICES: usize = 3;
/// Largest magnitude of a source's coordinates: a source may lie far from
/// the zone, but not where the statistics' distances overflow (a source at
/// 1.7e308 gave every plan NaN values).
pub const MAX_SOURCE_COORDINATE: f64 = 1e12;
/// Most vertices of an obstacle's polygon.
pub const MAX_OBSTACLE_VERTICES: usize = 32;
/// Largest magnitude of an obstacle vertex's coordinates: a polygon may
/// reach far past the zone, but not so far that the rounding of its
/// edges' lines (about 1e-16 of it) matters at the zone's scale.
pub const MAX_OBSTACLE_COORDINATE: f64 = 1e9;
/// Rays per π over which the statistics of a scenario with obstacles
/// integrate each cell's visible field of view (its closed forms no longer
/// apply), and its check that every source's cone reaches the zone.
pub const OBSTACLE_STATS_RAYS_PER_PI: usize = 2048;
/// Largest minimum separation accepted, cells.
pub const MAX_MIN_SEPARATION: usize = 16;

// A plan request.

/// Most sensors in one request.
pub const MAX_SENSORS: usize = 256;
/// Most targets in one request.
pub const MAX_TARGETS: usize = 20_000;
/// Most steps of history.
pub const MAX_HISTORY_STEPS: usize = 128;

/// Most characters of a session step's `Idempotency-Key` header.
pub const MAX_IDEMPOTENCY_KEY_CHARS: usize = 128;
/// Most positions in one history step.
pub const MAX_HISTORY_POSITIONS: usize = 256;
/// Steps of history a session keeps by default.
pub const DEFAULT_HISTORY_STEPS: usize = 16;
/// The certified gap `joint` coordination stops at by default.
pub const DEFAULT_GAP_TARGET: f64 = 0.001;
/// The time `joint` coordination may take by default, milliseconds.
pub const DEFAULT_BUDGET_MS: u64 = 20;
/// The most time `joint` coordination may be given, milliseconds.
pub const MAX_BUDGET_MS: u64 = 1000;
/// Largest request body accepted, bytes. Large enough for a plan request
/// with the most targets allowed ([`MAX_TARGETS`]) written at full
/// precision.
pub const MAX_BODY_BYTES: usize = 4 * 1024 * 1024;

// Fitting source rates (`POST /v1/scenarios/{id}/fit`, sessions that learn).

/// Most steps in one fit window.
pub const MAX_FIT_STEPS: usize = 500;
/// Most detections in one step of a fit window.
pub const MAX_FIT_DETECTIONS: usize = 20_000;
/// Largest fit request body accepted, bytes: a window of [`MAX_FIT_STEPS`]
/// steps with 64 sensors and 64 detections a step, written at full
/// precision, fits with room to spare.
pub const MAX_FIT_BODY_BYTES: usize = 32 * 1024 * 1024;
/// Shape of the Gamma prior that `"prior": "scenario"` puts on each
/// source's rate, centred on the spec's rate: worth one target's detection.
pub const RATE_PRIOR_SHAPE: f64 = 1.0;
/// Default traceback and look tolerances, as a fraction of the zone's
/// larger side: wide enough for exact data written at full precision.
pub const DEFAULT_FIT_DISTANCE_TOLERANCE: f64 = 1e-6;
/// Default speed tolerance of a traceback, relative to a class's speed.
pub const DEFAULT_FIT_SPEED_TOLERANCE: f64 = 1e-6;
/// Most distinct tracks a learning session remembers (each counts once
/// for the session's life); past it the oldest are forgotten.
pub const MAX_SESSION_TRACKS: usize = 1_000_000;
/// Most steps of looks a learning session keeps to count its exposure: a
/// target seen now can have been seen before only while it was in the
/// zone, so a session keeps the steps its slowest target needs to cross
/// the zone's diagonal, up to this many.
pub const MAX_LEARN_MEMORY_STEPS: usize = 1000;
/// A learning session plans with a scenario at its learnt rates, rebuilt
/// (its statistics precomputed again) when a source's posterior mean moves
/// from the rate planned with by more than this share of that rate (or of
/// the sources' mean rate, when larger).
pub const LEARN_REPLAN_DRIFT: f64 = 0.05;
