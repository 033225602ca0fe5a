//! A sensor's motion model: the displacements of one step at each speed,
//! in tie-breaking order, and the reachability tables of one (horizon,
//! speed, free cells) that the grids built with them share.

use std::cell::RefCell;
use std::fmt;
use std::sync::Arc;

use crate::limits::{MAX_HORIZON, MAX_SENSOR_SPEED};

/// The nine moves `(dc, dr)` of one step at speed 1, in tie-breaking order
/// (the same as `step_displacements(1)`).
pub const MOVES: [(i32, i32); 9] = [
    (0, 0),
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

/// The `N = (2m+1)²` displacements of speed `m` in tie-breaking order: by
/// Chebyshev ring (stay first), then `dr` ascending, then `dc` ascending.
const fn ring_order<const N: usize>(m: i32) -> [(i32, i32); N] {
    let mut out = [(0, 0); N];
    let mut i = 0;
    let mut k = 0;
    while k <= m {
        let mut dr = -k;
        while dr <= k {
            let mut dc = -k;
            while dc <= k {
                let ring = if dc.abs() > dr.abs() {
                    dc.abs()
                } else {
                    dr.abs()
                };
                if ring == k {
                    out[i] = (dc, dr);
                    i += 1;
                }
                dc += 1;
            }
            dr += 1;
        }
        k += 1;
    }
    assert!(i == N);
    out
}

static STEPS_1: [(i32, i32); 9] = ring_order(1);
static STEPS_2: [(i32, i32); 25] = ring_order(2);
static STEPS_3: [(i32, i32); 49] = ring_order(3);

/// Every displacement `(dc, dr)` with `max(|dc|, |dr|) ≤ speed`, in
/// tie-breaking order: by Chebyshev ring (stay first), then `dr` ascending,
/// then `dc` ascending. For speed 1 this is [`MOVES`].
///
/// # Panics
///
/// If `speed` is not in `1..=MAX_SENSOR_SPEED`.
pub fn step_displacements(speed: usize) -> &'static [(i32, i32)] {
    match speed {
        1 => &STEPS_1,
        2 => &STEPS_2,
        3 => &STEPS_3,
        _ => panic!("speed {speed} is not in 1..={MAX_SENSOR_SPEED}"),
    }
}

// `Motion::build` keeps a row of offsets, shifted by the speed, in 128
// bits: the fastest sensor's longest horizon must fit.
const _: () = assert!(2 * MAX_SENSOR_SPEED * MAX_HORIZON + 1 + MAX_SENSOR_SPEED <= 128);

/// First step of an offset that is never reachable.
const NEVER: u32 = u32::MAX;

/// The reachability tables of one (horizon, speed, free mask), shared by the
/// grids built with them.
#[derive(PartialEq, Eq)]
pub(super) struct Motion {
    pub(super) speed: usize,
    pub(super) horizon: usize,
    pub(super) side: usize,
    /// Every offset free.
    pub(super) open: bool,
    /// Per offset (row-major, `(dr+mT)·side + dc+mT`), the first step at which
    /// it is reachable, [`NEVER`] if none. Reachability is monotone in the
    /// step (staying is legal), so reachable at `t` ⇔ `first ≤ t`.
    pub(super) first: Vec<u32>,
    /// Per offset reachable before step T, its legal one-step displacements
    /// as bits `(dr+m)·(2m+1) + dc+m`; 0 elsewhere.
    pub(super) steps: Vec<u64>,
    /// `succ[succ_start[o]..succ_start[o+1]]`: the offsets one legal step
    /// from `o`, in displacement order (so `o` itself first).
    pub(super) succ_start: Vec<u32>,
    pub(super) succ: Vec<u32>,
}

impl fmt::Debug for Motion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Motion")
            .field("speed", &self.speed)
            .field("horizon", &self.horizon)
            .field("side", &self.side)
            .finish_non_exhaustive()
    }
}

/// The cells of a `(2m+1)²` window, as bits `r·w + c`, dilated by one king
/// move (clipped to the window).
fn dilate(x: u64, w: u32) -> u64 {
    let full = (1u64 << (w * w)) - 1;
    let col0 = (0..w).fold(0u64, |a, r| a | 1 << (r * w));
    let last = col0 << (w - 1);
    let h = x | ((x << 1) & !col0) | ((x >> 1) & !last);
    (h | (h << w) | (h >> w)) & full
}

impl Motion {
    /// Builds the tables from the free mask (row-major over the
    /// `side × side` offsets, the start included and free).
    pub(super) fn build(speed: usize, horizon: usize, free: &[bool]) -> Self {
        let side = 2 * speed * horizon + 1;
        let n = side * side;
        let e = speed * horizon;
        let start = e * side + e;
        let m = speed as i32;
        let w = 2 * speed as u32 + 1;
        let disps = step_displacements(speed);
        let mut first = vec![NEVER; n];
        let mut steps = vec![0u64; n];
        // Each row's free offsets as bits, shifted up by m so that the
        // window of a column c is the row's bits c..c+2m (the widest row
        // fits with the shift: checked at compile time above).
        let rows: Vec<u128> = free
            .chunks(side)
            .map(|row| {
                row.iter()
                    .enumerate()
                    .filter(|&(_, &f)| f)
                    .fold(0u128, |bits, (c, _)| bits | 1 << (c + speed))
            })
            .collect();
        let row_bits = (1u128 << w) - 1;
        first[start] = 0;
        let mut frontier = vec![start];
        for t in 1..=horizon {
            let mut next = Vec::new();
            for &o in &frontier {
                let (r, c) = ((o / side) as i32, (o % side) as i32);
                // The free cells of the window around o.
                let mut win = 0u64;
                for dr in -m..=m {
                    if let Some(row) = rows.get((r + dr) as usize) {
                        let bits = (row >> c) & row_bits;
                        win |= (bits as u64) << ((dr + m) as u32 * w);
                    }
                }
                // Breadth-first search to depth m, as m dilations.
                let mut reach = 1u64 << (speed as u32 * w + speed as u32);
                for _ in 0..speed {
                    reach = dilate(reach, w) & win;
                }
                steps[o] = reach;
                // Every reachable cell, in bit order (the frontier's order
                // does not change what it reaches, nor when).
                let mut bits = reach;
                while bits != 0 {
                    let bit = bits.trailing_zeros();
                    bits &= bits - 1;
                    let (dr, dc) = ((bit / w) as i32 - m, (bit % w) as i32 - m);
                    let o2 = ((r + dr) * side as i32 + c + dc) as usize;
                    if first[o2] == NEVER {
                        first[o2] = t as u32;
                        next.push(o2);
                    }
                }
            }
            frontier = next;
        }
        let mut succ_start = Vec::with_capacity(n + 1);
        let mut succ = Vec::new();
        for (o, &mask) in steps.iter().enumerate() {
            succ_start.push(succ.len() as u32);
            if mask == 0 {
                continue;
            }
            for &(dc, dr) in disps {
                if mask >> ((dr + m) as u32 * w + (dc + m) as u32) & 1 == 1 {
                    succ.push((o as i32 + dr * side as i32 + dc) as u32);
                }
            }
        }
        succ_start.push(succ.len() as u32);
        Self {
            speed,
            horizon,
            side,
            open: free.iter().all(|&f| f),
            first,
            steps,
            succ_start,
            succ,
        }
    }

    /// The tables with every cell free, cached per thread.
    pub(super) fn open(speed: usize, horizon: usize) -> Arc<Self> {
        thread_local! {
            static OPEN: RefCell<Vec<Arc<Motion>>> = const { RefCell::new(Vec::new()) };
        }
        OPEN.with_borrow_mut(|cache| {
            if let Some(m) = cache
                .iter()
                .find(|m| m.speed == speed && m.horizon == horizon)
            {
                return Arc::clone(m);
            }
            let side = 2 * speed * horizon + 1;
            let m = Arc::new(Self::build(speed, horizon, &vec![true; side * side]));
            cache.push(Arc::clone(&m));
            m
        })
    }

    /// `m·T`: the largest `|dc|` or `|dr|` of an offset.
    pub(super) fn extent(&self) -> i32 {
        (self.speed * self.horizon) as i32
    }

    /// The index of offset `(dc, dr)`, if inside the `side × side` square.
    pub(super) fn index(&self, dc: i32, dr: i32) -> Option<usize> {
        let e = self.extent();
        (dc.abs() <= e && dr.abs() <= e).then(|| (dr + e) as usize * self.side + (dc + e) as usize)
    }

    pub(super) fn start(&self) -> usize {
        let e = self.speed * self.horizon;
        e * self.side + e
    }

    pub(super) fn successors(&self, o: usize) -> &[u32] {
        &self.succ[self.succ_start[o] as usize..self.succ_start[o + 1] as usize]
    }

    /// The offset one step `(dc, dr)` from `o` (reachable before step T), if
    /// that step is legal.
    pub(super) fn step(&self, o: usize, (dc, dr): (i32, i32)) -> Option<usize> {
        let m = self.speed as i32;
        if dc.abs() > m || dr.abs() > m {
            return None;
        }
        let w = 2 * m + 1;
        let bit = ((dr + m) * w + dc + m) as u32;
        (self.steps[o] >> bit & 1 == 1).then(|| (o as i32 + dr * self.side as i32 + dc) as usize)
    }
}
