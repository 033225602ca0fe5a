//! The intrusion objective: the expected number of targets not yet
//! detected that a plan detects at least once ("first detections").
//!
//! A target that no sensor has detected (unseen in the history, as the
//! exact estimator's unseen part defines it) flies along a ray from its
//! source. Put it by its distance `r` from the source at step 0 (negative
//! for a target not yet emitted): at step `t` it is at `r + v·t`. A look at
//! step `t` that holds the interval `[a, b]` of the ray therefore holds the
//! targets with `r ∈ [a − v·t, b − v·t]`: its *piece*, pulled back to step 0.
//! Along each (class, ray) the targets are spread with the constant density
//! `λ_c/(spread·v_c)` per unit of `r` (the class's ray weight), each still
//! undetected with probability `u(r) = Π (1 − p)` over the history's looks
//! that held it (see `seen`). A plan detects it at least once with
//! probability `1 − Π (1 − p)` over the plan's pieces that hold `r`, so the
//! objective is, per (class, ray), `∫ u(r) (1 − Π_plan (1 − p)) dr`, summed
//! with the ray weights (the midpoint rule in angle, as everywhere in the
//! exact estimator). Writing `D(X) = ∫ 1 − Π_X (1 − p)`, it is
//! `D(history ∪ plan) − D(history)` over the plan's pieces: interval
//! arithmetic, exact along each ray.
//!
//! The objective is a weighted coverage: monotone in the looks and
//! submodular, so a look adds at most what it adds alone (the upper bound
//! that [`crate::search::best_path_bounded`] prunes with), and the
//! certificate's marginal bound holds for it.

use super::ExactEstimator;
use super::rays::{SourceRays, look_key};
use std::borrow::Cow;
use std::cell::RefCell;
use std::sync::{Arc, Mutex, OnceLock};

use crate::geometry::{Point, detection_pieces, detection_within};
use crate::limits::MAX_HORIZON;
use crate::scenario::{Cell, Look};
use crate::search::{PathGain, Stop, ValueGrid};

/// A look's interval on one (class, ray), pulled back to step 0.
#[derive(Debug, Clone, Copy)]
struct Piece {
    /// The (class, ray) pair: `key_start[class] + ray`.
    key: u32,
    a: f64,
    b: f64,
    /// The look's detection probability.
    p: f64,
    /// The class's ray weight: targets per unit of `r`.
    w: f64,
}

/// Per key, sorted disjoint pieces `(x0, x1, detected)` of a ray, and the
/// detected length before each within its key: what is already detected
/// (or, for a search, detected or counted by another sensor).
#[derive(Debug, Default)]
pub(super) struct Profile {
    /// `ends[start[i]..start[i + 1]]` belong to the `i`-th key listed.
    start: Vec<u32>,
    /// Each piece's end `x1`, apart so that [`first_ending_after`]'s search
    /// reads only them.
    ends: Vec<f64>,
    /// Aligned with `ends`: the rest of each piece, together so that the
    /// search's answer is one read.
    known: Vec<Known>,
}

/// A piece of a [`Profile`] but its end: its start, its detection
/// probability, and `Σ (x1 − x0)·detected` of its key's earlier pieces.
#[derive(Debug, Clone, Copy)]
struct Known {
    x0: f64,
    detected: f64,
    before: f64,
}

/// Pieces of a key up to which [`first_ending_after`] counts the ends before
/// its point instead of bisecting them: a count is a scan without
/// branches, a bisection a chain of dependent loads and mispredictions.
const SCAN_PIECES: usize = 32;

impl Profile {
    /// Appends one key's sorted disjoint pieces.
    pub(super) fn push_key(&mut self, pieces: impl IntoIterator<Item = (f64, f64, f64)>) {
        if self.start.is_empty() {
            self.start.push(0);
        }
        let mut acc = 0.0;
        for (x0, x1, d) in pieces {
            self.ends.push(x1);
            self.known.push(Known {
                x0,
                detected: d,
                before: acc,
            });
            acc += (x1 - x0) * d;
        }
        self.start.push(self.ends.len() as u32);
    }

    /// Room for `n` more pieces.
    fn reserve(&mut self, n: usize) {
        self.ends.reserve(n);
        self.known.reserve(n);
    }

    /// The `i`-th key's pieces, `(x0, x1, detected)`.
    fn of(&self, i: usize) -> impl Iterator<Item = (f64, f64, f64)> + '_ {
        let (lo, hi) = (self.start[i] as usize, self.start[i + 1] as usize);
        (self.known[lo..hi].iter().zip(&self.ends[lo..hi])).map(|(k, &x1)| (k.x0, x1, k.detected))
    }

    /// The `i`-th key's piece ends and the rest of its pieces.
    fn key(&self, i: usize) -> (&[f64], &[Known]) {
        let (lo, hi) = (self.start[i] as usize, self.start[i + 1] as usize);
        (&self.ends[lo..hi], &self.known[lo..hi])
    }

    /// `∫_{−∞}^a` and `∫_{−∞}^b` of what the `i`-th key's pieces detect,
    /// for `a ≤ b`: `b`'s piece is looked for only past `a`'s.
    pub(super) fn upto_pair(&self, i: usize, a: f64, b: f64) -> (f64, f64) {
        let (ends, known) = self.key(i);
        upto_pair_from(ends, known, first_ending_after(ends, a), a, b)
    }

    /// `∫_{−∞}^a` and `∫_{−∞}^b` of what the `i`-th key's pieces detect,
    /// unless they detect every point of `[a, b]` for certain (pieces
    /// detected with probability 1 meet end to end from `a` to `b`): then
    /// `None`.
    pub(super) fn ends_unless_detected(&self, i: usize, a: f64, b: f64) -> Option<(f64, f64)> {
        let (ends, known) = self.key(i);
        let j = first_ending_after(ends, a);
        let mut reached = a;
        for (k, &end) in known[j..].iter().zip(&ends[j..]) {
            if k.x0 > reached || k.detected != 1.0 {
                break;
            }
            reached = end;
            if reached >= b {
                return None;
            }
        }
        Some(upto_pair_from(ends, known, j, a, b))
    }
}

/// `∫_{−∞}^a` and `∫_{−∞}^b` over a key's pieces, `j` the first that ends
/// after `a ≤ b`: `b`'s piece is looked for only from it on.
fn upto_pair_from(ends: &[f64], known: &[Known], j: usize, a: f64, b: f64) -> (f64, f64) {
    let k = j + first_ending_after(&ends[j..], b);
    (upto_from(ends, known, j, a), upto_from(ends, known, k, b))
}

/// The first of a key's pieces that ends after `x` (their ends are
/// sorted, so it follows the ends at or before `x`).
fn first_ending_after(ends: &[f64], x: f64) -> usize {
    if ends.len() <= SCAN_PIECES {
        ends.iter().filter(|&&e| e <= x).count()
    } else {
        ends.partition_point(|&e| e <= x)
    }
}

/// `∫_{−∞}^x detected` over a key's pieces, `j` the first that ends
/// after `x`.
fn upto_from(ends: &[f64], known: &[Known], j: usize, x: f64) -> f64 {
    match known.get(j) {
        Some(k) if x > k.x0 => k.before + (x - k.x0) * k.detected,
        Some(k) => k.before,
        None => known.last().map_or(0.0, |k| {
            k.before + (ends[ends.len() - 1] - k.x0) * k.detected
        }),
    }
}

/// Scratch space of [`FirstDetections::pieces`], kept across the looks of
/// one call site: growing fresh vectors per look cost more than the
/// pieces.
#[derive(Debug, Default)]
struct PieceScratch {
    buf: Vec<Point>,
    /// What one look holds of the rays (see [`FirstDetections::held`]).
    held: Vec<(u32, u32, f64, f64)>,
    visible: Vec<(f64, f64)>,
}

/// What the extra looks of a search detect over the history, for the keys
/// they meet: per key, the merged profile of both.
#[derive(Debug)]
struct Background {
    /// Sorted keys with extra pieces, and their merged profiles.
    keys: Vec<u32>,
    merged: Profile,
}

/// The first-detections objective of one exact estimator's situation (see
/// the module docs): plans' values, and each sensor's path gains for the
/// search.
pub struct FirstDetections<'e> {
    est: &'e ExactEstimator<'e>,
    /// Per class, its first key (and one past the last class's keys).
    key_start: Vec<u32>,
    /// Per source's rays (the estimator's `rays`), its classes.
    classes_of_rays: Vec<std::ops::Range<usize>>,
    /// The history's seen sets, one key each.
    history: Profile,
    /// Per sensor, its stops (see [`FirstDetections::stops`]).
    stops: Vec<OnceLock<Stops>>,
    /// The last background built from sensors' paths, with those paths
    /// and sensors: the certificate searches every sensor against the
    /// same paths of all of them.
    last_among: Mutex<Option<Among>>,
}

/// A background of some sensors' paths (see
/// [`FirstDetections::path_cover_among`]), and what it was built from.
struct Among {
    sensors: Vec<usize>,
    paths: Vec<Vec<Cell>>,
    horizon: usize,
    background: Arc<Background>,
}

impl<'e> FirstDetections<'e> {
    /// The objective over `est`'s history: what its seen sets hold is
    /// detected already.
    pub fn new(est: &'e ExactEstimator<'e>) -> Self {
        let mut key_start = Vec::with_capacity(est.classes.len() + 1);
        let mut next = 0u32;
        for c in &est.classes {
            key_start.push(next);
            next += est.rays[c.rays].dirs.len() as u32;
        }
        key_start.push(next);
        let classes_of_rays = (0..est.rays.len())
            .map(|ri| {
                let first = est.classes.iter().position(|c| c.rays == ri);
                let count = est.classes.iter().filter(|c| c.rays == ri).count();
                first.map_or(0..0, |f| f..f + count)
            })
            .collect();
        let mut history = Profile::default();
        for (c, hits) in est.classes.iter().zip(&est.seen) {
            for m in 0..est.rays[c.rays].dirs.len() {
                let (iv, det) = (hits.of(m), hits.detected(m));
                history.push_key(
                    iv.iter()
                        .enumerate()
                        .map(|(i, &(a, b))| (a, b, if det.is_empty() { 1.0 } else { det[i] })),
                );
            }
        }
        if history.start.is_empty() {
            history.start.push(0);
        }
        Self {
            est,
            key_start,
            classes_of_rays,
            history,
            stops: (0..est.types.len()).map(|_| OnceLock::new()).collect(),
            last_among: Mutex::new(None),
        }
    }

    /// Appends the pieces of `look` taken at step `t`, sorted by key.
    fn pieces(&self, look: &Look, t: usize, out: &mut Vec<Piece>, scratch: &mut PieceScratch) {
        let mut held = std::mem::take(&mut scratch.held);
        held.clear();
        self.held(look, &mut held, scratch);
        self.pieces_at(&held, look.p_detect, t, out);
        scratch.held = held;
    }

    /// Appends what `look` holds of each ray, `(source's rays, ray, lo,
    /// hi)` by source's rays then ray: the part of the ray in its field
    /// of view, before a building ends the flights along it, and with
    /// obstacles only what the look sees of it (see `sighted`). The same
    /// at every step.
    fn held(&self, look: &Look, out: &mut Vec<(u32, u32, f64, f64)>, scratch: &mut PieceScratch) {
        let PieceScratch { buf, visible, .. } = scratch;
        let sight = self.est.scenario.sight(look);
        let key = look_key(self.est.scenario, &look.region);
        let mut hold = |ri: u32, sr: &SourceRays, m: usize, lo: f64, hi: f64| {
            let hi = hi.min(sr.stop(m));
            match &sight {
                None if hi > lo => out.push((ri, m as u32, lo, hi)),
                None => {}
                Some(v) => {
                    visible.clear();
                    v.visible(sr.source.pos, sr.dirs[m].0, lo, hi.max(lo), visible);
                    out.extend(
                        visible
                            .iter()
                            .filter(|(p, q)| q > p)
                            .map(|&(p, q)| (ri, m as u32, p, q)),
                    );
                }
            }
        };
        for (ri, sr) in self.est.rays.iter().enumerate() {
            if self.classes_of_rays[ri].is_empty() {
                continue;
            }
            // An indexed look's intervals are read, to the same bits (as
            // the seen sets read them); a ray that misses has `lo > hi`.
            if let (Some(key), Some(table)) = (key, &sr.looks) {
                let (a, stored) = table.of(key);
                for (m, &(lo, hi)) in (a..).zip(stored) {
                    if lo <= hi {
                        hold(ri as u32, sr, m, lo, hi);
                    }
                }
                continue;
            }
            let Some((a, b)) = sr.range(&look.region, buf) else {
                continue;
            };
            for m in a..b {
                let (d, inv) = sr.dirs[m];
                if let Some((lo, hi)) = look.region.ray(sr.source.pos, d, inv) {
                    hold(ri as u32, sr, m, lo, hi);
                }
            }
        }
    }

    /// Appends the pieces at step `t` of a look of detection probability
    /// `p` that holds `held` (see [`FirstDetections::held`]), sorted by
    /// key: each part pulled back by each class's flight.
    fn pieces_at(&self, held: &[(u32, u32, f64, f64)], p: f64, t: usize, out: &mut Vec<Piece>) {
        for same in held.chunk_by(|x, y| x.0 == y.0) {
            for c in self.classes_of_rays[same[0].0 as usize].clone() {
                let class = &self.est.classes[c];
                let shift = class.speed * t as f64;
                out.extend(same.iter().map(|&(_, m, lo, hi)| Piece {
                    key: self.key_start[c] + m,
                    a: lo - shift,
                    b: hi - shift,
                    p,
                    w: class.weight,
                }));
            }
        }
    }

    /// Expected first detections of `looks` (`looks[t − 1]`: every look
    /// taken at step `t`), per step: the targets not yet detected that some
    /// look of step `t` detects and no look of an earlier step did.
    pub fn by_step(&self, looks: &[Vec<Look>]) -> Vec<f64> {
        let mut buf = PieceScratch::default();
        let mut all: Vec<(usize, Piece)> = Vec::new();
        let mut one = Vec::new();
        for (t, step) in looks.iter().enumerate() {
            for look in step {
                one.clear();
                self.pieces(look, t + 1, &mut one, &mut buf);
                all.extend(one.iter().map(|&p| (t + 1, p)));
            }
        }
        self.first_by_step(all, looks.len())
    }

    /// [`FirstDetections::by_step`] of the looks of `sensors` on `paths`
    /// (`paths[q][t − 1]` at step `t`, for `t` in 1..=`horizon`), read
    /// from the sensors' stops where their searches built them: a piece
    /// they leave out, which the history detected for certain, detects no
    /// target first (the values agree to rounding).
    pub fn by_step_on(&self, paths: &[&[Cell]], sensors: &[usize], horizon: usize) -> Vec<f64> {
        let (pieces, step_ends) = self.pieces_by_step(paths, sensors, horizon);
        let mut all: Vec<(usize, Piece)> = Vec::with_capacity(pieces.len());
        let mut from = 0;
        for (t, &end) in (1..).zip(&step_ends) {
            all.extend(pieces[from..end].iter().map(|&p| (t, p)));
            from = end;
        }
        self.first_by_step(all, horizon)
    }

    /// The first detections per step of `all`, (step, piece) pairs over
    /// `horizon` steps.
    fn first_by_step(&self, mut all: Vec<(usize, Piece)>, horizon: usize) -> Vec<f64> {
        // Sorted by key then step.
        all.sort_by(|x, y| x.1.key.cmp(&y.1.key).then(x.0.cmp(&y.0)));
        let mut by_step = vec![0.0; horizon];
        let mut intervals: Vec<(f64, f64, f64)> = Vec::new();
        let mut events = Vec::new();
        for group in all.chunk_by(|x, y| x.1.key == y.1.key) {
            let key = group[0].1.key as usize;
            let w = group[0].1.w;
            let lo = group.iter().map(|x| x.1.a).fold(f64::INFINITY, f64::min);
            let hi = group
                .iter()
                .map(|x| x.1.b)
                .fold(f64::NEG_INFINITY, f64::max);
            intervals.clear();
            intervals.extend(
                self.history
                    .of(key)
                    .filter(|&(x0, x1, _)| x1 > lo && x0 < hi),
            );
            let mut prev = detection_within(&intervals, lo, hi, &mut events);
            let mut taken = 0;
            for t in 1..=horizon {
                let upto = group[taken..].iter().take_while(|x| x.0 <= t).count();
                if upto == 0 {
                    continue;
                }
                intervals.extend(
                    group[taken..taken + upto]
                        .iter()
                        .map(|x| (x.1.a, x.1.b, x.1.p)),
                );
                taken += upto;
                let now = detection_within(&intervals, lo, hi, &mut events);
                by_step[t - 1] += w * (now - prev);
                prev = now;
            }
        }
        by_step
    }

    /// The pieces of `extra`'s looks (`extra[t − 1]` taken at step `t`),
    /// step by step.
    fn pieces_of(&self, extra: &[Vec<Look>]) -> Vec<Piece> {
        let mut buf = PieceScratch::default();
        let mut pieces = Vec::new();
        for (t, step) in extra.iter().enumerate() {
            for look in step {
                self.pieces(look, t + 1, &mut pieces, &mut buf);
            }
        }
        pieces
    }

    /// The pieces of the looks of `sensors` on `paths` (`paths[q][t − 1]`
    /// at step `t`), step by step in the order of `sensors`: the same as
    /// [`FirstDetections::pieces_of`] their looks, read from each sensor's
    /// stops where its search built them (which leave out the pieces the
    /// history detected for certain: a background detects them already).
    fn pieces_on(&self, paths: &[&[Cell]], sensors: &[usize], horizon: usize) -> Vec<Piece> {
        self.pieces_by_step(paths, sensors, horizon).0
    }

    /// [`FirstDetections::pieces_on`], and where each step's pieces end.
    fn pieces_by_step(
        &self,
        paths: &[&[Cell]],
        sensors: &[usize],
        horizon: usize,
    ) -> (Vec<Piece>, Vec<usize>) {
        let s = self.est.scenario;
        let mut buf = PieceScratch::default();
        let mut pieces = Vec::new();
        let mut step_ends = Vec::with_capacity(horizon);
        for t in 1..=horizon {
            for &q in sensors {
                let cell = paths[q][t - 1];
                match self.stop_pieces(q, t, cell) {
                    Some(own) => pieces.extend_from_slice(own),
                    None => self.pieces(&s.look(self.est.types[q], cell), t, &mut pieces, &mut buf),
                }
            }
            step_ends.push(pieces.len());
        }
        (pieces, step_ends)
    }

    /// The pieces of sensor `q`'s look at `cell` at step `t` that the
    /// history did not detect for certain, if its search built them.
    fn stop_pieces(&self, q: usize, t: usize, cell: Cell) -> Option<&[Piece]> {
        let stops = self.stops[q].get()?;
        let offset = (cell.col - stops.start.col, cell.row - stops.start.row);
        stops.try_stop(t, offset).map(|r| &stops.pieces[r])
    }

    /// True when no look of `sensors` on `paths` (`paths[q][t − 1]` at
    /// step `t`) holds a target that a look of sensor `sensor` on `path`
    /// holds: no piece of theirs meets the span of its pieces on any key.
    /// `path`'s first detections against those looks are then its first
    /// detections alone, and no other path of the sensor gains more
    /// against them than it gains alone. False when `sensor`'s stops are
    /// not built yet or `path` leaves them.
    pub fn apart(
        &self,
        sensor: usize,
        path: &[Cell],
        paths: &[&[Cell]],
        sensors: &[usize],
    ) -> bool {
        let keys = *self.key_start.last().unwrap_or(&0) as usize;
        let mut span = vec![(f64::INFINITY, f64::NEG_INFINITY); keys];
        for (t, &cell) in (1..).zip(path) {
            let Some(mine) = self.stop_pieces(sensor, t, cell) else {
                return false;
            };
            for x in mine {
                let s = &mut span[x.key as usize];
                *s = (s.0.min(x.a), s.1.max(x.b));
            }
        }
        let clear = |pieces: &[Piece]| {
            pieces.iter().all(|e| {
                let (a, b) = span[e.key as usize];
                e.b <= a || e.a >= b
            })
        };
        let (s, mut buf, mut made) = (self.est.scenario, PieceScratch::default(), Vec::new());
        (1..=path.len()).all(|t| {
            sensors.iter().all(|&q| {
                let cell = paths[q][t - 1];
                match self.stop_pieces(q, t, cell) {
                    Some(theirs) => clear(theirs),
                    None => {
                        made.clear();
                        self.pieces(&s.look(self.est.types[q], cell), t, &mut made, &mut buf);
                        clear(&made)
                    }
                }
            })
        })
    }

    /// The background of a search: the history, and over it the `pieces`
    /// of other looks, in the order their looks were taken.
    fn background(&self, mut pieces: Vec<Piece>) -> Background {
        pieces.sort_by_key(|p| p.key);
        let mut keys = Vec::new();
        let mut merged = Profile::default();
        merged.start.push(0);
        // About as many pieces as the extra looks' and the history's on
        // their keys: reserved at once, not grown.
        merged.reserve(2 * pieces.len());
        let mut intervals: Vec<(f64, f64, f64)> = Vec::new();
        let mut events = Vec::new();
        let mut out = Vec::new();
        for group in pieces.chunk_by(|x, y| x.key == y.key) {
            let key = group[0].key;
            intervals.clear();
            intervals.extend(self.history.of(key as usize));
            intervals.extend(group.iter().map(|p| (p.a, p.b, p.p)));
            let lo = intervals.iter().map(|x| x.0).fold(f64::INFINITY, f64::min);
            let hi = intervals
                .iter()
                .map(|x| x.1)
                .fold(f64::NEG_INFINITY, f64::max);
            out.clear();
            detection_pieces(&intervals, lo, hi, &mut events, |a, b, d| {
                out.push((a, b, d))
            });
            keys.push(key);
            merged.push_key(out.iter().copied());
        }
        Background { keys, merged }
    }

    /// Sensor `sensor`'s stops on the cells of `grid`'s motion around
    /// `start`: built on the first search of the sensor, and shared by the
    /// later ones (a sensor's start, type and motion are the same in every
    /// search of a plan).
    fn stops(&self, sensor: usize, start: Cell, grid: &ValueGrid) -> &Stops {
        self.stops[sensor].get_or_init(|| {
            let s = self.est.scenario;
            let ty = self.est.types[sensor];
            let horizon = grid.horizon();
            let extent = (grid.speed() * horizon) as i32;
            let side = grid.side();
            let mut stops = Stops {
                start,
                extent,
                side,
                slots: vec![u32::MAX; horizon * side * side],
                start_of: vec![0],
                pieces: Vec::new(),
                history_ends: Vec::new(),
                alone: Vec::new(),
                per_key: 1,
            };
            let mut buf = PieceScratch::default();
            // Offsets reachable by the last step: every offset's look once.
            let mut offsets = 0;
            grid.for_each_reachable(horizon, |_, _| offsets += 1);
            // What the look at each offset holds of the rays, found at the
            // first step that reaches it (`held[at[offset]]`), and how many
            // pieces it makes at each step: all of them first, so that the
            // stops' pieces take their room at once rather than by growing.
            let mut held = Vec::new();
            let mut at: Vec<Option<(std::ops::Range<usize>, usize)>> = vec![None; side * side];
            let mut total = 0;
            for t in 1..=horizon {
                grid.for_each_reachable(t, |dc, dr| {
                    let Some(k) = s.lattice_cell(start, dc, dr) else {
                        return;
                    };
                    let offset = (dr + extent) as usize * side + (dc + extent) as usize;
                    let (_, pieces) = at[offset].get_or_insert_with(|| {
                        let from = held.len();
                        self.held(&s.look(ty, k), &mut held, &mut buf);
                        if from == 0 {
                            held.reserve(held.len() * offsets);
                        }
                        let pieces = held[from..]
                            .iter()
                            .map(|h| self.classes_of_rays[h.0 as usize].len())
                            .sum();
                        (from..held.len(), pieces)
                    });
                    total += *pieces;
                });
            }
            stops.pieces.reserve_exact(total);
            stops.history_ends.reserve_exact(total);
            let p_detect = s.types[ty].p_detect;
            for t in 1..=horizon {
                grid.for_each_reachable(t, |dc, dr| {
                    if s.lattice_cell(start, dc, dr).is_none() {
                        return;
                    }
                    let first = stops.pieces.len();
                    let offset = (dr + extent) as usize * side + (dc + extent) as usize;
                    let Some((range, _)) = &at[offset] else {
                        return;
                    };
                    self.pieces_at(&held[range.clone()], p_detect, t, &mut stops.pieces);
                    // A piece whose targets the history detected for
                    // certain adds nothing, alone or on top of others, and
                    // takes nothing from the pieces it overlaps (the
                    // background detects every point of it): left out.
                    let mut kept = first;
                    for k in first..stops.pieces.len() {
                        let p = stops.pieces[k];
                        let Some(ends) =
                            self.history.ends_unless_detected(p.key as usize, p.a, p.b)
                        else {
                            continue;
                        };
                        stops.pieces[kept] = p;
                        kept += 1;
                        stops.history_ends.push(ends);
                    }
                    stops.pieces.truncate(kept);
                    for same in stops.pieces[first..].chunk_by(|p, q| p.key == q.key) {
                        stops.per_key = stops.per_key.max(same.len());
                    }
                    let index = stops.index(t, (dc, dr));
                    stops.slots[index] = (stops.start_of.len() - 1) as u32;
                    stops.start_of.push(stops.pieces.len() as u32);
                });
            }
            stops.alone = gains_alone(&stops.pieces, &stops.history_ends);
            stops
        })
    }

    /// The gains of sensor `sensor`'s stops (see [`PathCover`]) on the
    /// cells of `grid`'s motion around `start`, against the history and
    /// `extra`'s looks (`extra[t − 1]` at step `t`); `grid`'s values become
    /// each stop's gain alone.
    pub fn path_cover(
        &self,
        sensor: usize,
        start: Cell,
        extra: &[Vec<Look>],
        grid: &mut ValueGrid,
    ) -> PathCover<'_> {
        let stops = self.stops(sensor, start, grid);
        self.cover(stops, &self.background(self.pieces_of(extra)), grid)
    }

    /// [`FirstDetections::path_cover`] against the looks of `sensors` on
    /// `paths` (`paths[q][t − 1]` at step `t`, for every step of `grid`).
    pub fn path_cover_among(
        &self,
        sensor: usize,
        start: Cell,
        paths: &[&[Cell]],
        sensors: &[usize],
        grid: &mut ValueGrid,
    ) -> PathCover<'_> {
        let stops = self.stops(sensor, start, grid);
        let background = self.background_among(paths, sensors, grid.horizon());
        self.cover(stops, &background, grid)
    }

    /// The background of the looks of `sensors` on `paths` over `horizon`
    /// steps: the last one built, when it was built from the same paths of
    /// the same sensors (the certificate asks for one per sensor), or a
    /// new one, kept in its place.
    fn background_among(
        &self,
        paths: &[&[Cell]],
        sensors: &[usize],
        horizon: usize,
    ) -> Arc<Background> {
        let same = |among: &Among| {
            among.horizon == horizon
                && among.sensors == sensors
                && sensors
                    .iter()
                    .zip(&among.paths)
                    .all(|(&q, path)| paths[q][..horizon] == path[..])
        };
        let lock = || self.last_among.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(among) = lock().as_ref().filter(|among| same(among)) {
            return Arc::clone(&among.background);
        }
        // Built outside the lock: parallel searches against other sensors
        // (best-response rounds) build their own at the same time.
        let pieces = self.pieces_on(paths, sensors, horizon);
        let background = Arc::new(self.background(pieces));
        *lock() = Some(Among {
            sensors: sensors.to_vec(),
            paths: sensors
                .iter()
                .map(|&q| paths[q][..horizon].to_vec())
                .collect(),
            horizon,
            background: Arc::clone(&background),
        });
        background
    }

    /// The gains of `stops` over `background`; `grid`'s values become each
    /// stop's gain alone.
    fn cover<'s>(
        &'s self,
        stops: &'s Stops,
        background: &Background,
        grid: &mut ValueGrid,
    ) -> PathCover<'s> {
        let (ends, alone) = if background.keys.is_empty() {
            // The history alone (a sensor's search by itself): the stops
            // hold its ends and gains already.
            (
                Cow::Borrowed(&stops.history_ends[..]),
                Cow::Borrowed(&stops.alone[..]),
            )
        } else {
            // Which keys the extra looks touch: their ends move; the
            // others' are the history's.
            let mut overlay = vec![u32::MAX; self.history.start.len().saturating_sub(1)];
            for (i, &key) in background.keys.iter().enumerate() {
                overlay[key as usize] = i as u32;
            }
            let ends: Vec<(f64, f64)> = stops
                .pieces
                .iter()
                .zip(&stops.history_ends)
                .map(|(p, &history)| match overlay[p.key as usize] {
                    u32::MAX => history,
                    i => background.merged.upto_pair(i as usize, p.a, p.b),
                })
                .collect();
            let alone = gains_alone(&stops.pieces, &ends);
            (Cow::Owned(ends), Cow::Owned(alone))
        };
        for t in 1..=grid.horizon() {
            grid.fill_step(t, |dc, dr| {
                let i = stops.slots[stops.index(t, (dc, dr))];
                (i != u32::MAX).then(|| alone[stops.pieces_of(i as usize)].iter().sum())
            });
        }
        PathCover {
            stops,
            ends,
            alone,
            scratch: RefCell::default(),
        }
    }
}

/// Each piece's gain alone, `ends` being what the others detected up to
/// its ends.
fn gains_alone(pieces: &[Piece], ends: &[(f64, f64)]) -> Vec<f64> {
    pieces
        .iter()
        .zip(ends)
        .map(|(p, &(ga, gb))| p.w * p.p * ((p.b - p.a) - (gb - ga)))
        .collect()
}

/// One sensor's stops: every (step, cell) of its reach with the pieces of
/// its look there that the history did not detect for certain, and what
/// the history detected up to their ends.
#[derive(Debug)]
struct Stops {
    /// The sensor's start, which offsets are from.
    start: Cell,
    extent: i32,
    side: usize,
    /// Per (step, offset) of the grid, its stop's index, `u32::MAX` where
    /// none.
    slots: Vec<u32>,
    /// `pieces[start_of[i]..start_of[i + 1]]`: the `i`-th stop's pieces,
    /// sorted by key.
    start_of: Vec<u32>,
    pieces: Vec<Piece>,
    /// Aligned with `pieces`: `∫_{−∞}^a` and `∫_{−∞}^b` of what the history
    /// detected.
    history_ends: Vec<(f64, f64)>,
    /// Aligned with `pieces`: each one's gain over the history alone.
    alone: Vec<f64>,
    /// The most pieces one stop has on one key: 1 unless obstacles cut a
    /// look's view of a ray.
    per_key: usize,
}

impl Stops {
    /// The slot of step `t` (1-based) at offset `(dc, dr)`.
    fn index(&self, t: usize, (dc, dr): (i32, i32)) -> usize {
        (t - 1) * self.side * self.side
            + (dr + self.extent) as usize * self.side
            + (dc + self.extent) as usize
    }

    /// The pieces' indices of the stop of step `t` at offset `(dc, dr)`,
    /// if the sensor may stand there then.
    fn try_stop(&self, t: usize, (dc, dr): (i32, i32)) -> Option<std::ops::Range<usize>> {
        if t == 0 || t * self.side * self.side > self.slots.len() {
            return None;
        }
        if dc.abs() > self.extent || dr.abs() > self.extent {
            return None;
        }
        let i = self.slots[self.index(t, (dc, dr))];
        (i != u32::MAX).then(|| self.pieces_of(i as usize))
    }

    /// The `i`-th stop's pieces' indices.
    fn pieces_of(&self, i: usize) -> std::ops::Range<usize> {
        self.start_of[i] as usize..self.start_of[i + 1] as usize
    }

    /// The pieces' indices of the stop of step `t` at offset `(dc, dr)`.
    fn stop(&self, t: usize, offset: (i32, i32)) -> std::ops::Range<usize> {
        self.pieces_of(self.slots[self.index(t, offset)] as usize)
    }
}

/// One sensor's path gains for [`crate::search::best_path_bounded`]: what
/// each stop of a path adds to the first detections of the history and the
/// other sensors' looks, on top of the path's earlier stops.
pub struct PathCover<'s> {
    stops: &'s Stops,
    /// Aligned with the stops' pieces: what the background detected up to
    /// each one's ends (`∫_{−∞}^a` and `∫_{−∞}^b`), so that every integral
    /// over parts of pieces, whose ends are pieces' ends, is a difference.
    ends: Cow<'s, [(f64, f64)]>,
    /// Aligned with the stops' pieces: each one's gain alone.
    alone: Cow<'s, [f64]>,
    /// Scratch space of the gains.
    scratch: RefCell<Sweep>,
}

/// Scratch space of one gain: the earlier pieces over one of the stop's,
/// the pieces' ends with what the background detected up to each, and the
/// sweep's events.
#[derive(Debug, Default)]
struct Sweep {
    over: Vec<(f64, f64, f64)>,
    known: Vec<(f64, f64)>,
    events: Vec<(f64, f64, bool)>,
}

impl PathCover<'_> {
    /// The exact value of a whole path (offsets of steps 1, 2, …).
    pub fn value(&self, path: &[(i32, i32)]) -> f64 {
        let stops: Vec<Stop> = path.iter().enumerate().map(|(i, &o)| (i + 1, o)).collect();
        (0..stops.len())
            .map(|i| self.gain(i + 1, path[i], &stops[..i]))
            .sum()
    }
}

impl PathCover<'_> {
    /// [`PathGain::gain`] with room in `over` for every earlier piece that
    /// may meet one of the stop's, and twice that in `known`, plus two.
    #[inline(always)]
    fn gain_in(
        &self,
        mine: std::ops::Range<usize>,
        earlier: &mut [(usize, usize)],
        over: &mut [(f64, f64, f64)],
        known: &mut [(f64, f64)],
        events: &mut Vec<(f64, f64, bool)>,
    ) -> f64 {
        let pieces = &self.stops.pieces;
        let mut total = 0.0;
        for i in mine {
            let x = pieces[i];
            let mut n = 0;
            // The pieces are sorted by key, so one cursor per stop walks
            // them once. A look holds one piece per key, or several where
            // obstacles cut its view of the ray: every one that meets `x`.
            for (c, end) in earlier.iter_mut() {
                while *c < *end && pieces[*c].key < x.key {
                    *c += 1;
                }
                let same = pieces[*c..*end].iter().zip(&self.ends[*c..*end]);
                for (&q, &(ga, gb)) in same.take_while(|(q, _)| q.key == x.key) {
                    if q.b > x.a && q.a < x.b {
                        over[n] = (q.a, q.b, q.p);
                        // Pieces' ends and what the background detected
                        // up to each.
                        known[2 * n] = (q.a, ga);
                        known[2 * n + 1] = (q.b, gb);
                        n += 1;
                    }
                }
            }
            if n == 0 {
                total += self.alone[i];
                continue;
            }
            let (ga, gb) = self.ends[i];
            if n == 1 {
                // One earlier piece (the common case): no sweep.
                total += gain_over_one(&x, (ga, gb), over[0], (known[0].1, known[1].1));
                continue;
            }
            known[2 * n] = (x.a, ga);
            known[2 * n + 1] = (x.b, gb);
            let known = &known[..2 * n + 2];
            // Every end of a part below is one of these.
            let g = |v: f64| known.iter().find(|k| k.0 == v).map_or(0.0, |k| k.1);
            // ∫ u·(1 − det_earlier) over the piece: its length less what is
            // detected already, less what the earlier stops detect of the rest.
            let mut left = (x.b - x.a) - (gb - ga);
            detection_pieces(&over[..n], x.a, x.b, events, |a, b, d| {
                left -= d * ((b - a) - (g(b) - g(a)));
            });
            total += x.w * x.p * left;
        }
        total
    }

    /// [`PathGain::gain`] on top of one earlier stop (`earlier`, its
    /// pieces' indices) when a look holds one piece per key: the pair gains
    /// of the search. The same operations as [`PathCover::gain_in`] with
    /// one earlier piece, in the same order, without its buffers.
    fn pair_gain(&self, mine: std::ops::Range<usize>, earlier: std::ops::Range<usize>) -> f64 {
        let pieces = &self.stops.pieces;
        let mut c = earlier.start;
        let mut total = 0.0;
        for i in mine {
            let x = pieces[i];
            while c < earlier.end && pieces[c].key < x.key {
                c += 1;
            }
            total += match pieces.get(c) {
                Some(q) if c < earlier.end && q.key == x.key && q.b > x.a && q.a < x.b => {
                    gain_over_one(&x, self.ends[i], (q.a, q.b, q.p), self.ends[c])
                }
                _ => self.alone[i],
            };
        }
        total
    }
}

/// What piece `x` adds on top of the one earlier piece `(a, b, p)` that
/// meets it, with what the background detected up to each one's ends
/// (`x_ends`, `q_ends`): `∫ u·(1 − det_earlier)` over `x`, times its
/// weight and probability. The overlap's ends are ends of the two pieces.
#[inline(always)]
fn gain_over_one(x: &Piece, x_ends: (f64, f64), q: (f64, f64, f64), q_ends: (f64, f64)) -> f64 {
    let ((a, b, d), (ga, gb)) = (q, x_ends);
    let known = [(a, q_ends.0), (b, q_ends.1), (x.a, ga), (x.b, gb)];
    let g = |v: f64| known.iter().find(|k| k.0 == v).map_or(0.0, |k| k.1);
    let mut left = (x.b - x.a) - (gb - ga);
    let (lo, hi) = (a.max(x.a), b.min(x.b));
    left -= d * ((hi - lo) - (g(hi) - g(lo)));
    x.w * x.p * left
}

impl PathGain for PathCover<'_> {
    fn gain(&self, t: usize, at: (i32, i32), before: &[Stop]) -> f64 {
        let mine = self.stops.stop(t, at);
        if let [(u, off)] = *before
            && self.stops.per_key == 1
        {
            return self.pair_gain(mine, self.stops.stop(u, off));
        }
        // The earlier stops' pieces, and a cursor in each.
        let mut earlier = [(0usize, 0usize); MAX_HORIZON];
        for (e, &(u, off)) in earlier.iter_mut().zip(before) {
            let r = self.stops.stop(u, off);
            *e = (r.start, r.end);
        }
        let earlier = &mut earlier[..before.len()];
        let mut scratch = self.scratch.borrow_mut();
        let Sweep {
            over,
            known,
            events,
        } = &mut *scratch;
        if self.stops.per_key == 1 {
            let mut over = [(0.0, 0.0, 0.0); MAX_HORIZON];
            let mut known = [(0.0, 0.0); 2 * MAX_HORIZON + 2];
            return self.gain_in(mine, earlier, &mut over, &mut known, events);
        }
        let room = self.stops.per_key * before.len();
        over.resize(room, (0.0, 0.0, 0.0));
        known.resize(2 * room + 2, (0.0, 0.0));
        self.gain_in(mine, earlier, over, known, events)
    }
}
