//! Seen sets along rays: for each ray of a source, what the sensors' looks
//! covered now and in the history, each interval pushed by the distance a
//! target has flown since.
//!
//! With looks that detect with certainty (the paper's sensors) a seen set
//! is a union of intervals. With detection probabilities below 1 it is, per
//! piece of the ray, the probability `1 − Π (1 − p)` over the looks that
//! held the piece that a target there was detected: a target that stayed
//! unreported is still in the zone with the rest of that probability.

use super::rays::{LookKey, SourceRays, max, min, slab};
use crate::geometry::OpenIntervals;
use crate::obstacle::Sight;
use crate::scenario::{Look, all_certain};

/// A look's interval on a ray, not yet pushed: its ray, the step `s` of
/// the look (pushed by `v·s`), the start of the look's whole interval on
/// the ray (which decides whether it starts past the ray's exit), the
/// interval and the look's `p_detect`.
#[derive(Clone, Copy)]
struct RayPiece {
    m: u32,
    s: u32,
    gate: f64,
    from: f64,
    to: f64,
    p_detect: f64,
}

thread_local! {
    /// [`RayHits::weighted`]'s pieces and their sorted copy, kept across
    /// calls: buffers this large come fresh from the kernel, which zeroes
    /// their pages, and that cost more than filling them (docs/obstacles.md).
    static WEIGHTED_SCRATCH: std::cell::RefCell<(Vec<RayPiece>, Vec<RayPiece>)> =
        std::cell::RefCell::default();
}

/// The most pieces [`WEIGHTED_SCRATCH`] keeps room for between calls
/// (32 MB each for its two buffers).
const MAX_KEPT_PIECES: usize = 1 << 20;

/// What the rays of one source saw: per ray, the union of the intervals
/// seen `s` steps ago, each pushed by `v·s` (the distance a target has flown
/// since), merged into sorted disjoint intervals. At step `t` the seen set is
/// the same union pushed a further `v·t`. Stored compactly, ray by ray; with
/// uncertain looks each interval also carries the probability that a target
/// in it was detected.
///
/// A union leaves out the intervals that start past the ray's exit from the
/// zone (`SourceRays::beyond`): about a quarter of a 16-step history's on
/// the reference workload. Every use clips the seen set to a part of the
/// zone, and pushing moves it further out, so no value changes, to the bit:
/// an interval left out covers nothing in the zone, and one it would have
/// merged with already reaches past the exit. An indexed look whose every
/// interval starts past the exit is skipped whole
/// ([`LookCrossings::past_exit`](super::rays::LookCrossings::past_exit)).
#[derive(Clone, Default)]
pub(super) struct RayHits {
    /// `hits[offsets[m]..offsets[m+1]]` are ray `m`'s intervals.
    pub(super) offsets: Vec<u32>,
    pub(super) hits: Vec<(f64, f64)>,
    /// Aligned with `hits`: the detection probability of each interval.
    /// Empty when every look is certain (every interval's is 1).
    detected: Vec<f64>,
    /// Aligned with `hits`, once [`RayHits::with_prefix`] built them:
    /// each interval's end, apart so that a search reads only them.
    ends: Vec<f64>,
    /// The same: each interval's start, the detected length of the ray's
    /// earlier intervals and its detection probability, together so that
    /// a search's answer is one read.
    prefix: Vec<Prefix>,
    /// Per ray, the end of every full block of [`BLOCK`] of its intervals
    /// (`tops[top_offsets[m]..top_offsets[m+1]]`): a search counts the
    /// blocks that end before its point, then the ends in the next block,
    /// two short scans instead of a binary search's chain of dependent
    /// reads.
    tops: Vec<f64>,
    top_offsets: Vec<u32>,
}

/// Intervals per block of [`RayHits::detected_upto`]'s search: sixteen ends,
/// two cache lines.
const BLOCK: usize = 16;

/// One interval of a seen set as [`RayHits::detected_upto`] reads it.
#[derive(Clone, Copy, Default)]
struct Prefix {
    start: f64,
    before: f64,
    detected: f64,
}

impl RayHits {
    /// The seen sets of the rays `sr` for a class of speed `speed`.
    /// `keys[s][i]` is the key of `observed[s][i]`'s field of view in the
    /// rays' [`LookCrossings`](super::rays::LookCrossings) (see
    /// [`look_key`](super::rays::look_key)), or `None`. `sights[s][i]` is
    /// what `observed[s][i]` cannot see, when obstacles hide part of it
    /// (`sights` is empty in a scenario without obstacles): its seen set
    /// holds only the visible parts of its intervals.
    pub(super) fn new(
        sr: &SourceRays,
        observed: &[Vec<Look>],
        keys: &[Vec<Option<LookKey>>],
        sights: &[Vec<Option<Sight>>],
        speed: f64,
    ) -> Self {
        let mut one = Self::for_classes(sr, observed, keys, sights, &[speed]);
        one.pop().unwrap_or_default()
    }

    /// [`RayHits::new`] for each of the classes of `speeds` on the rays
    /// `sr`: with uncertain looks or obstacles, the looks' intervals on the
    /// rays are found once for all of them.
    pub(super) fn for_classes(
        sr: &SourceRays,
        observed: &[Vec<Look>],
        keys: &[Vec<Option<LookKey>>],
        sights: &[Vec<Option<Sight>>],
        speeds: &[f64],
    ) -> Vec<Self> {
        if sights.is_empty() && observed.iter().all(|step| all_certain(step)) {
            speeds
                .iter()
                .map(|&speed| Self::union(sr, observed, keys, speed))
                .collect()
        } else {
            Self::weighted(sr, observed, keys, sights, speeds)
        }
    }

    /// Seen sets of uncertain looks: every look's interval on every ray it
    /// crosses (read from the index when the look is indexed), then per
    /// ray a sweep that cuts them into disjoint pieces with their detection
    /// probability. As in a union, the intervals that start past the ray's
    /// exit are left out: no use of a seen set looks there. The intervals
    /// are found and sorted by ray once; each class of `speeds` pushes
    /// them by its own distances.
    fn weighted(
        sr: &SourceRays,
        observed: &[Vec<Look>],
        keys: &[Vec<Option<LookKey>>],
        sights: &[Vec<Option<Sight>>],
        speeds: &[f64],
    ) -> Vec<Self> {
        WEIGHTED_SCRATCH.with_borrow_mut(|(pieces, sorted)| {
            pieces.clear();
            Self::weighted_pieces(sr, observed, keys, sights, speeds, pieces);
            Self::by_ray(sr.dirs.len(), pieces, sorted);
            // With obstacles the seen sets are read by prefix sums.
            let prefix = !sights.is_empty();
            let hits = speeds
                .iter()
                .map(|&speed| Self::weighted_sweep(sr, sorted, speed, prefix))
                .collect();
            // A scratch grown past the cap is not kept.
            if pieces.capacity() > MAX_KEPT_PIECES {
                *pieces = Vec::new();
                *sorted = Vec::new();
            }
            hits
        })
    }

    /// Pushes onto `pieces` every look's intervals on the rays `sr`, not
    /// yet pushed by the targets' flight (see [`RayPiece`]).
    fn weighted_pieces(
        sr: &SourceRays,
        observed: &[Vec<Look>],
        keys: &[Vec<Option<LookKey>>],
        sights: &[Vec<Option<Sight>>],
        speeds: &[f64],
        pieces: &mut Vec<RayPiece>,
    ) {
        let mut buf = Vec::new();
        let mut visible = Vec::new();
        let o = sr.source.pos;
        let slowest = speeds.iter().copied().fold(f64::INFINITY, f64::min);
        for (s, looks) in observed.iter().enumerate() {
            // Every class's pieces start past the exit when the slowest's do.
            let least_shift = slowest * s as f64;
            let step = s as u32;
            for (i, look) in looks.iter().enumerate() {
                let key = keys.get(s).and_then(|k| k.get(i).copied().flatten());
                if let (Some(key), Some(table)) = (key, &sr.looks) {
                    if table.past_exit(key, least_shift) {
                        continue;
                    }
                    let (a, stored) = table.of(key);
                    for (m, &(p, q)) in (a..).zip(stored) {
                        if p <= q {
                            pieces.push(RayPiece {
                                m: m as u32,
                                s: step,
                                gate: p,
                                from: p,
                                to: q,
                                p_detect: look.p_detect,
                            });
                        }
                    }
                    continue;
                }
                let Some((a, b)) = sr.range(&look.region, &mut buf) else {
                    continue;
                };
                let sight = sights
                    .get(s)
                    .and_then(|v| v.get(i))
                    .and_then(Option::as_ref);
                for m in a..b {
                    let (d, inv) = sr.dirs[m];
                    let Some((p, q)) = look.region.ray(o, d, inv) else {
                        continue;
                    };
                    if p + least_shift > sr.beyond[m] {
                        continue;
                    }
                    let piece = |from: f64, to: f64| RayPiece {
                        m: m as u32,
                        s: step,
                        gate: p,
                        from,
                        to,
                        p_detect: look.p_detect,
                    };
                    let Some(sight) = sight else {
                        pieces.push(piece(p, q));
                        continue;
                    };
                    visible.clear();
                    sight.visible(o, d, p, q, &mut visible);
                    pieces.extend(visible.iter().map(|&(p, q)| piece(p, q)));
                }
            }
        }
    }

    /// Copies `pieces` into `sorted` by ray, a counting sort (the pieces
    /// of one ray keep their order), of `n` rays.
    fn by_ray(n: usize, pieces: &[RayPiece], sorted: &mut Vec<RayPiece>) {
        let mut counts = vec![0usize; n + 1];
        for piece in pieces {
            counts[piece.m as usize + 1] += 1;
        }
        for m in 0..n {
            counts[m + 1] += counts[m];
        }
        sorted.clear();
        sorted.extend_from_slice(pieces);
        for &piece in pieces {
            let slot = &mut counts[piece.m as usize];
            sorted[*slot] = piece;
            *slot += 1;
        }
    }

    /// The seen sets of a class of speed `speed` from the pieces of every
    /// look, sorted by ray: each pushed by `speed·s`, left out when its
    /// look's interval then starts past the ray's exit. With `prefix`, the
    /// prefix sums of [`RayHits::with_prefix`] too, ray by ray while its
    /// intervals are at hand.
    fn weighted_sweep(sr: &SourceRays, pieces: &[RayPiece], speed: f64, prefix: bool) -> Self {
        let n = sr.dirs.len();
        let mut offsets = vec![0u32; n + 1];
        // A ray's sweep makes fewer than twice as many intervals as it has
        // pieces.
        let mut hits: Vec<(f64, f64)> = Vec::with_capacity(2 * pieces.len());
        let mut detected: Vec<f64> = Vec::with_capacity(2 * pieces.len());
        let mut out = RayHits::default();
        if prefix {
            out.ends.reserve(2 * pieces.len());
            out.prefix.reserve(2 * pieces.len());
        }
        let mut sweep = Sweep::default();
        let mut i = 0;
        for m in 0..n {
            let start = i;
            while i < pieces.len() && pieces[i].m as usize == m {
                i += 1;
            }
            let first = hits.len();
            let far = sr.beyond.get(m).copied().unwrap_or(f64::INFINITY);
            let pushed = pieces[start..i].iter().filter_map(|x| {
                let shift = speed * f64::from(x.s);
                (x.gate + shift <= far).then_some((x.from + shift, x.to + shift, x.p_detect))
            });
            sweep.run(pushed, |a, b, seen| {
                // A piece that continues the last one of this ray at the
                // same probability extends it.
                match (hits[first..].last_mut(), detected.last()) {
                    (Some(last), Some(&d)) if last.1 == a && d == seen => last.1 = b,
                    _ => {
                        hits.push((a, b));
                        detected.push(seen);
                    }
                }
            });
            if prefix {
                out.push_prefix(&hits[first..], &detected[first..]);
            }
            offsets[m + 1] = hits.len() as u32;
        }
        out.offsets = offsets;
        out.hits = hits;
        out.detected = detected;
        out
    }

    /// Seen sets of certain looks: unions of intervals.
    fn union(
        sr: &SourceRays,
        observed: &[Vec<Look>],
        keys: &[Vec<Option<LookKey>>],
        speed: f64,
    ) -> Self {
        let mut buf = Vec::new();
        let n = sr.dirs.len();
        let o = sr.source.pos;
        // Regions go track by track (the i-th region of every step: one
        // sensor's fields of view, newest first). Consecutive ones overlap on
        // most rays, so each ray's intervals from one track are merged as
        // they come, in a buffer over the track's rays; what is left (about
        // one interval per ray and track) is sorted by ray afterwards.
        let tracks = observed.iter().map(Vec::len).max().unwrap_or(0);
        // About one piece per ray and track: reserved at once, not grown.
        let mut pieces: Vec<(u32, f64, f64)> = Vec::with_capacity((n * tracks).min(1 << 16));
        let mut open: Vec<(f64, f64)> = Vec::new();
        let mut spans = Vec::with_capacity(observed.len());
        for i in 0..tracks {
            spans.clear();
            let (mut lo, mut hi) = (n, 0);
            for (s, regions) in observed.iter().enumerate() {
                let Some(region) = regions.get(i).map(|l| &l.region) else {
                    continue;
                };
                let shift = speed * s as f64;
                let key = keys.get(s).and_then(|k| k.get(i).copied().flatten());
                if let (Some(key), Some(table)) = (key, &sr.looks) {
                    if table.past_exit(key, shift) {
                        continue;
                    }
                    // Indexed: the same range and intervals, read.
                    let (a, stored) = table.of(key);
                    if !stored.is_empty() {
                        let b = a + stored.len();
                        spans.push((a, b, shift, region, Some(stored)));
                        (lo, hi) = (lo.min(a), hi.max(b));
                    }
                } else if let Some((a, b)) = sr.range(region, &mut buf) {
                    spans.push((a, b, shift, region, None));
                    (lo, hi) = (lo.min(a), hi.max(b));
                }
            }
            if spans.is_empty() {
                continue;
            }
            open.clear();
            open.resize(hi - lo, EMPTY);
            for &(a, b, shift, region, stored) in &spans {
                let open = &mut open[a - lo..b - lo];
                if let Some(stored) = stored {
                    merge_stored(stored, &sr.beyond[a..b], open, a as u32, shift, &mut pieces);
                } else if region.disk.is_none() {
                    // Slab test, branch-free (no direction component is 0).
                    let rays = sr.dirs[a..b].iter().zip(&sr.beyond[a..b]);
                    for (j, ((&(_, inv), &far), cur)) in rays.zip(open).enumerate() {
                        let (p, q) = slab(&region.rect, o, inv);
                        if p <= q && p + shift <= far {
                            extend(cur, (a + j) as u32, p + shift, q + shift, &mut pieces);
                        }
                    }
                } else {
                    for (j, cur) in open.iter_mut().enumerate() {
                        let (d, inv) = sr.dirs[a + j];
                        if let Some((p, q)) = region.ray(o, d, inv)
                            && p + shift <= sr.beyond[a + j]
                        {
                            extend(cur, (a + j) as u32, p + shift, q + shift, &mut pieces);
                        }
                    }
                }
            }
            for (j, &(p, q)) in open.iter().enumerate() {
                if p <= q {
                    pieces.push(((lo + j) as u32, p, q));
                }
            }
        }
        // By ray (a counting sort), then each ray's few pieces by start,
        // merged into sorted disjoint intervals.
        let mut offsets = vec![0u32; n + 1];
        for &(m, ..) in &pieces {
            offsets[m as usize + 1] += 1;
        }
        for m in 0..n {
            offsets[m + 1] += offsets[m];
        }
        let mut next = offsets.clone();
        let mut sorted = vec![(0.0, 0.0); pieces.len()];
        for &(m, p, q) in &pieces {
            sorted[next[m as usize] as usize] = (p, q);
            next[m as usize] += 1;
        }
        let mut hits: Vec<(f64, f64)> = Vec::with_capacity(sorted.len());
        let mut start = 0;
        for m in 0..n {
            let list = &mut sorted[start..offsets[m + 1] as usize];
            start = offsets[m + 1] as usize;
            list.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
            let first = hits.len();
            for &(p, q) in list.iter() {
                match hits[first..].last_mut() {
                    Some(last) if p <= last.1 => last.1 = last.1.max(q),
                    _ => hits.push((p, q)),
                }
            }
            offsets[m + 1] = hits.len() as u32;
        }
        RayHits {
            offsets,
            hits,
            detected: Vec::new(),
            ends: Vec::new(),
            prefix: Vec::new(),
            tops: Vec::new(),
            top_offsets: Vec::new(),
        }
    }

    /// No intervals on `rays` rays.
    pub(super) fn empty_of(rays: usize) -> Self {
        RayHits {
            offsets: vec![0; rays + 1],
            ..Self::default()
        }
    }

    /// Heap bytes held.
    pub(super) fn memory_bytes(&self) -> usize {
        self.offsets.capacity() * 4
            + self.hits.capacity() * 16
            + self.detected.capacity() * 8
            + self.ends.capacity() * 8
            + self.prefix.capacity() * std::mem::size_of::<Prefix>()
            + self.tops.capacity() * 8
            + self.top_offsets.capacity() * 4
    }

    /// The union of two unions of certain looks on the same rays, `a`'s
    /// intervals pushed by `shift_a` and `b`'s by `shift_b`: per ray a merge
    /// of two sorted lists, intervals that touch joined as
    /// [`RayHits::new`] joins them.
    pub(super) fn merged(a: &RayHits, shift_a: f64, b: &RayHits, shift_b: f64) -> Self {
        let n = a.offsets.len() - 1;
        debug_assert_eq!(n + 1, b.offsets.len());
        debug_assert!(a.certain() && b.certain());
        let mut offsets = Vec::with_capacity(n + 1);
        offsets.push(0u32);
        let mut hits: Vec<(f64, f64)> = Vec::with_capacity(a.hits.len() + b.hits.len());
        for m in 0..n {
            let (xa, xb) = (a.of(m), b.of(m));
            let (mut i, mut j) = (0, 0);
            let first = hits.len();
            while i < xa.len() || j < xb.len() {
                let take_a =
                    j == xb.len() || (i < xa.len() && xa[i].0 + shift_a <= xb[j].0 + shift_b);
                let (p, q) = if take_a {
                    i += 1;
                    (xa[i - 1].0 + shift_a, xa[i - 1].1 + shift_a)
                } else {
                    j += 1;
                    (xb[j - 1].0 + shift_b, xb[j - 1].1 + shift_b)
                };
                match hits[first..].last_mut() {
                    Some(last) if p <= last.1 => last.1 = last.1.max(q),
                    _ => hits.push((p, q)),
                }
            }
            offsets.push(hits.len() as u32);
        }
        RayHits {
            offsets,
            hits,
            ..Self::default()
        }
    }

    /// These intervals pushed by `shift`.
    pub(super) fn lifted(mut self, shift: f64) -> Self {
        if shift != 0.0 {
            for h in &mut self.hits {
                *h = (h.0 + shift, h.1 + shift);
            }
        }
        self
    }

    /// These intervals without those that start past `beyond[m]` on ray
    /// `m`: as [`RayHits::new`] leaves them out.
    pub(super) fn within(mut self, beyond: &[f64]) -> Self {
        let mut kept = 0;
        let mut start = 0;
        for (m, &far) in beyond.iter().enumerate() {
            let end = self.offsets[m + 1] as usize;
            for i in start..end {
                if self.hits[i].0 <= far {
                    self.hits[kept] = self.hits[i];
                    kept += 1;
                }
            }
            start = end;
            self.offsets[m + 1] = kept as u32;
        }
        self.hits.truncate(kept);
        self
    }

    /// What changed from `old` (pushed by `shift_old`) to `new`, two unions
    /// of certain looks on the same rays: per ray the pieces of their
    /// symmetric difference, sorted, each "detected" +1 where only `new`
    /// holds it and −1 where only `old` does, so that a seen mass
    /// accumulated over it is `new`'s less `old`'s.
    pub(super) fn change(new: &RayHits, old: &RayHits, shift_old: f64) -> Self {
        let n = new.offsets.len() - 1;
        debug_assert_eq!(n + 1, old.offsets.len());
        let mut offsets = Vec::with_capacity(n + 1);
        offsets.push(0u32);
        let mut hits: Vec<(f64, f64)> = Vec::new();
        let mut detected: Vec<f64> = Vec::new();
        for m in 0..n {
            let (a, b) = (new.of(m), old.of(m));
            // Each union's boundaries in order (its intervals are disjoint
            // and do not touch), merged: bit 0 of an event says which set
            // (1 = old), bit 1 an end; at one distance starts first, so a
            // point interval opens, then closes.
            let bound = |xs: &[(f64, f64)], i: usize, shift: f64, set: u8| {
                let (p, q) = xs[i / 2];
                if i.is_multiple_of(2) {
                    (p + shift, set)
                } else {
                    (q + shift, set | 2)
                }
            };
            let (na, nb) = (2 * a.len(), 2 * b.len());
            let (mut i, mut j) = (0, 0);
            let events = std::iter::from_fn(|| {
                let ea = (i < na).then(|| bound(a, i, 0.0, 0));
                let eb = (j < nb).then(|| bound(b, j, shift_old, 1));
                let take_a = match (ea, eb) {
                    (Some(x), Some(y)) => x.0 < y.0 || (x.0 == y.0 && x.1 <= y.1),
                    (Some(_), None) => true,
                    (None, Some(_)) => false,
                    (None, None) => return None,
                };
                if take_a {
                    i += 1;
                    ea
                } else {
                    j += 1;
                    eb
                }
            });
            let (mut in_new, mut in_old) = (false, false);
            let mut prev = 0.0;
            let first = hits.len();
            for (x, e) in events {
                if x > prev && in_new != in_old {
                    let sign = if in_new { 1.0 } else { -1.0 };
                    match (hits[first..].last_mut(), detected.last()) {
                        (Some(last), Some(&d)) if last.1 == prev && d == sign => last.1 = x,
                        _ => {
                            hits.push((prev, x));
                            detected.push(sign);
                        }
                    }
                }
                prev = x;
                let opens = e & 2 == 0;
                if e & 1 == 0 {
                    in_new = opens;
                } else {
                    in_old = opens;
                }
            }
            offsets.push(hits.len() as u32);
        }
        RayHits {
            offsets,
            hits,
            detected,
            ends: Vec::new(),
            prefix: Vec::new(),
            tops: Vec::new(),
            top_offsets: Vec::new(),
        }
    }

    /// Ray `m`'s seen intervals (sorted, disjoint) as of step 0.
    #[inline]
    pub(super) fn of(&self, m: usize) -> &[(f64, f64)] {
        &self.hits[self.offsets[m] as usize..self.offsets[m + 1] as usize]
    }

    /// The detection probabilities of ray `m`'s intervals, aligned with
    /// [`RayHits::of`]; empty when every look was certain.
    #[inline]
    pub(super) fn detected(&self, m: usize) -> &[f64] {
        if self.detected.is_empty() {
            &[]
        } else {
            &self.detected[self.offsets[m] as usize..self.offsets[m + 1] as usize]
        }
    }

    /// True when every look was certain.
    #[inline]
    pub(super) fn certain(&self) -> bool {
        self.detected.is_empty()
    }

    /// The same seen sets with the prefix sums that
    /// [`RayHits::detected_upto`] reads.
    pub(super) fn with_prefix(mut self) -> Self {
        if self.top_offsets.len() == self.offsets.len() {
            return self;
        }
        let ones = vec![1.0; if self.certain() { self.hits.len() } else { 0 }];
        let detected = if self.certain() {
            &ones
        } else {
            &self.detected
        };
        let mut out = Self::default();
        out.prefix.reserve(self.hits.len());
        out.ends.reserve(self.hits.len());
        for m in 0..self.offsets.len().saturating_sub(1) {
            let ray = self.offsets[m] as usize..self.offsets[m + 1] as usize;
            out.push_prefix(&self.hits[ray.clone()], &detected[ray]);
        }
        self.ends = out.ends;
        self.prefix = out.prefix;
        self.tops = out.tops;
        self.top_offsets = out.top_offsets;
        self
    }

    /// Appends one ray's prefix sums: its intervals `hits`, each with its
    /// detection probability.
    fn push_prefix(&mut self, hits: &[(f64, f64)], detected: &[f64]) {
        if self.top_offsets.is_empty() {
            self.top_offsets.push(0);
        }
        self.tops
            .extend(hits.iter().skip(BLOCK - 1).step_by(BLOCK).map(|&(_, b)| b));
        self.top_offsets.push(self.tops.len() as u32);
        let mut acc = 0.0;
        for (&(a, b), &detected) in hits.iter().zip(detected) {
            self.prefix.push(Prefix {
                start: a,
                before: acc,
                detected,
            });
            self.ends.push(b);
            acc += (b - a) * detected;
        }
    }

    /// Seen sets from their parts: per ray `m`, the sorted disjoint
    /// intervals `hits[offsets[m]..offsets[m+1]]`, each with its detection
    /// probability.
    #[cfg(test)]
    pub(super) fn from_parts(offsets: Vec<u32>, hits: Vec<(f64, f64)>, detected: Vec<f64>) -> Self {
        Self {
            offsets,
            hits,
            detected,
            ..Self::default()
        }
    }

    /// `∫_{−∞}^{x} detected` along ray `m` as of step 0 (needs
    /// [`RayHits::with_prefix`]): a search of the ray's ends, so that a
    /// part of a ray is measured without walking or sorting its pieces (a
    /// seen set of a long history has dozens on a ray).
    #[inline]
    pub(super) fn detected_upto(&self, m: usize, x: f64) -> f64 {
        let (lo, hi) = (self.offsets[m] as usize, self.offsets[m + 1] as usize);
        let ends = &self.ends[lo..hi];
        // The first piece that ends after x: the ends are sorted, so the
        // number of them at most x, counted block by block.
        let tops = &self.tops[self.top_offsets[m] as usize..self.top_offsets[m + 1] as usize];
        let full = if tops.len() <= 4 * BLOCK {
            tops.iter().filter(|&&e| e <= x).count()
        } else {
            tops.partition_point(|&e| e <= x)
        };
        let block = &ends[BLOCK * full..ends.len().min(BLOCK * (full + 1))];
        let j = BLOCK * full + block.iter().filter(|&&e| e <= x).count();
        match self.prefix[lo..hi].get(j) {
            Some(p) if x > p.start => p.before + (x - p.start) * p.detected,
            Some(p) => p.before,
            None if j == 0 => 0.0,
            None => {
                let p = self.prefix[hi - 1];
                p.before + (ends[j - 1] - p.start) * p.detected
            }
        }
    }
}

/// The sweep that cuts one ray's weighted intervals into pieces of one
/// detection probability each, as [`crate::geometry::detection_pieces`]
/// does: starts and ends are sorted apart, by the bits of their distance
/// (never negative, so the bits sort as the numbers do), which is about
/// twice as fast as sorting both together by a float comparison; at one
/// distance the ends come first. Its buffers are kept from ray to ray.
#[derive(Default)]
pub(super) struct Sweep {
    starts: Vec<(u64, f64)>,
    ends: Vec<(u64, f64)>,
}

impl Sweep {
    /// Calls `piece(a, b, detected)` for each piece of the union of
    /// `intervals` (`(a, b, p)`, `0 ≤ a`), in order, `detected` being
    /// `1 − Π (1 − p)` over the intervals that hold it.
    pub(super) fn run(
        &mut self,
        intervals: impl Iterator<Item = (f64, f64, f64)>,
        mut piece: impl FnMut(f64, f64, f64),
    ) {
        let key = |x: f64| (x + 0.0).to_bits();
        self.starts.clear();
        self.ends.clear();
        for (a, b, p) in intervals {
            if b > a {
                self.starts.push((key(a), 1.0 - p));
                self.ends.push((key(b), 1.0 - p));
            }
        }
        self.starts.sort_unstable_by_key(|e| e.0);
        self.ends.sort_unstable_by_key(|e| e.0);
        let mut held = OpenIntervals::default();
        let mut prev = 0.0;
        let (mut i, mut j) = (0, 0);
        while j < self.ends.len() {
            let opens = i < self.starts.len() && self.starts[i].0 < self.ends[j].0;
            let (x, q) = if opens {
                i += 1;
                self.starts[i - 1]
            } else {
                j += 1;
                self.ends[j - 1]
            };
            let x = f64::from_bits(x);
            if held.any() && x > prev {
                piece(prev, x, held.detected());
            }
            prev = x;
            held.toggle(opens, q);
        }
    }
}

/// [`extend`] over the stored intervals of consecutive rays from `first`,
/// shifted by `shift`, skipping those that start `beyond`. Kept apart (and
/// [`extend`]'s move to `pieces` out of line) so that the loop's values
/// stay in registers.
#[inline(never)]
fn merge_stored(
    stored: &[(f64, f64)],
    beyond: &[f64],
    open: &mut [(f64, f64)],
    first: u32,
    shift: f64,
    pieces: &mut Vec<(u32, f64, f64)>,
) {
    for (m, ((&(p, q), &far), cur)) in (first..).zip(stored.iter().zip(beyond).zip(open)) {
        if p <= q && p + shift <= far {
            extend(cur, m, p + shift, q + shift, pieces);
        }
    }
}

/// Moves `cur`, ray `m`'s merged interval, to `pieces` unless it is empty.
#[cold]
#[inline(never)]
fn flush(cur: &(f64, f64), m: u32, pieces: &mut Vec<(u32, f64, f64)>) {
    if cur.0 <= cur.1 {
        pieces.push((m, cur.0, cur.1));
    }
}

/// No interval yet (`p > q`).
const EMPTY: (f64, f64) = (f64::INFINITY, f64::NEG_INFINITY);

/// Extends `cur`, ray `m`'s interval being merged, by `[p, q]` when they
/// overlap; otherwise moves `cur` to `pieces` and starts again from `[p, q]`.
#[inline(always)]
fn extend(cur: &mut (f64, f64), m: u32, p: f64, q: f64, pieces: &mut Vec<(u32, f64, f64)>) {
    if p <= cur.1 && q >= cur.0 {
        *cur = (min(cur.0, p), max(cur.1, q));
    } else {
        flush(cur, m, pieces);
        *cur = (p, q);
    }
}
