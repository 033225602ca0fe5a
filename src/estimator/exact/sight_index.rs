//! What a ground look at each cell cannot see, worked out once per
//! scenario: its sight, the box of what it misses, and the hidden parts of
//! every ray that crosses that box (see `sighted`).
//!
//! A ground look's value is its square's unseen mass by the windows, less
//! the unseen mass on the parts of the rays it does not see. Those parts
//! depend on the cell and the field of view only (not on the history, the
//! step or the other sensors), so a plan reads them here instead of
//! clipping the rays against the obstacles' shadows at every cell and
//! step. Built on the same rays, by the same code, as a plan would work
//! them out: the values are the same to the bit.

use rayon::prelude::*;

use super::cell_sights::{CellSight, cell_sight};
use super::rays::SourceRays;
use crate::geometry::Region;
use crate::scenario::{Cell, Scenario};

/// The most cells (summed over the ground fields of view) that a scenario
/// indexes: past it, plans work the sights out per cell as they go. At a
/// few kilobytes a cell, this keeps an index under about 100 MB.
pub const MAX_INDEXED_SIGHT_CELLS: usize = 1 << 15;

/// One ray's part inside a field of view, before a building ends the
/// flights along it, and which of the view's hidden parts lie on it.
#[derive(Debug, Clone, Copy)]
pub(super) struct HiddenRay {
    /// The ray's index in its source's grid.
    pub(super) m: u32,
    /// The ray's part `[lo, hi]` inside the field of view, alive.
    pub(super) lo: f64,
    pub(super) hi: f64,
    /// `parts[end of the previous ray..end]` are its hidden parts.
    end: u32,
}

/// What a ground look at one cell cannot see.
#[derive(Debug, Default)]
pub(super) struct CellView {
    /// Its sight and the box of what it misses.
    pub(super) sight: CellSight,
    /// The rays that cross the box and hold hidden parts, by source (the
    /// rays' order) then ray.
    rays: Vec<HiddenRay>,
    /// `rays[by_source[ri]..by_source[ri + 1]]` are source `ri`'s.
    by_source: Vec<u32>,
    /// The hidden parts, sorted and disjoint along each ray.
    parts: Vec<(f64, f64)>,
}

impl CellView {
    /// The view of a ground look at one cell: `sight` is the look's,
    /// `region` its field of view.
    fn new(rays: &[SourceRays], region: &Region, sight: CellSight) -> Self {
        let mut view = CellView {
            by_source: vec![0],
            ..CellView::default()
        };
        if let Some((v, Some(hidden))) = &sight
            && !v.blind()
        {
            let crossed = Region {
                rect: *hidden,
                disk: None,
            };
            let mut buf = Vec::new();
            for sr in rays {
                hidden_parts(sr, region, &crossed, v, &mut buf, |m, lo, hi, parts| {
                    view.parts.extend_from_slice(parts);
                    view.rays.push(HiddenRay {
                        m: m as u32,
                        lo,
                        hi,
                        end: view.parts.len() as u32,
                    });
                });
                view.by_source.push(view.rays.len() as u32);
            }
        }
        view.sight = sight;
        view
    }

    /// Source `ri`'s rays with hidden parts, each with its parts.
    pub(super) fn rays_of(
        &self,
        ri: usize,
    ) -> impl Iterator<Item = (&HiddenRay, &[(f64, f64)])> + '_ {
        let (a, b) = (self.by_source[ri] as usize, self.by_source[ri + 1] as usize);
        let mut from = if a == 0 { 0 } else { self.rays[a - 1].end };
        self.rays[a..b].iter().map(move |ray| {
            let parts = &self.parts[from as usize..ray.end as usize];
            from = ray.end;
            (ray, parts)
        })
    }

    fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.rays.len() * std::mem::size_of::<HiddenRay>()
            + self.by_source.len() * 4
            + self.parts.len() * 16
    }
}

/// Calls `f(m, lo, hi, parts)` for every ray `m` of `sr` that crosses
/// `crossed` (a box holding what the sight `v` hides of `region`) with its
/// alive part `[lo, hi]` inside `region` and the parts of that which `v`
/// does not see, when there are any.
pub(super) fn hidden_parts(
    sr: &SourceRays,
    region: &Region,
    crossed: &Region,
    v: &crate::obstacle::Sight,
    buf: &mut Vec<crate::geometry::Point>,
    mut f: impl FnMut(usize, f64, f64, &[(f64, f64)]),
) {
    let Some((a, b)) = sr.range(crossed, buf) else {
        return;
    };
    let o = sr.source.pos;
    let mut parts = Vec::new();
    for m in a..b {
        let (d, _) = sr.dirs[m];
        let Some((lo, hi)) = sr.alive_in(m, region) else {
            continue;
        };
        parts.clear();
        v.visible(o, d, lo, hi, &mut parts);
        // The gaps between the visible parts, in place.
        let n = parts.len();
        let mut from = lo;
        for i in 0..n {
            let (p, q) = parts[i];
            if p > from {
                parts.push((from, p));
            }
            from = q;
        }
        if hi > from {
            parts.push((from, hi));
        }
        parts.drain(..n);
        if !parts.is_empty() {
            f(m, lo, hi, &parts);
        }
    }
}

/// Every ground field of view's [`CellView`] at every cell of a scenario.
#[derive(Debug, Default)]
pub struct SightIndex {
    /// Per field of view (the scenario's `fovs`), the index of its first
    /// cell's view in `views` (cells in row-major order), if it is
    /// indexed (a ground one).
    first: Vec<Option<usize>>,
    views: Vec<CellView>,
}

impl SightIndex {
    /// The index of `scenario`'s ground fields of view on `rays`, or
    /// `None` without obstacles, without ground sensors, or past
    /// [`MAX_INDEXED_SIGHT_CELLS`].
    pub fn new(scenario: &Scenario, rays: &[SourceRays]) -> Option<Self> {
        if !scenario.has_obstacles() {
            return None;
        }
        // One sensor type of each ground field of view.
        let ground: Vec<Option<usize>> = (0..scenario.fovs.len())
            .map(|slot| {
                scenario
                    .types
                    .iter()
                    .position(|t| t.fov_slot == slot && !scenario.sees_over[slot])
            })
            .collect();
        let cells = scenario.cell_count();
        let indexed = ground.iter().flatten().count();
        if indexed == 0 || indexed * cells > MAX_INDEXED_SIGHT_CELLS {
            return None;
        }
        let mut first = Vec::with_capacity(ground.len());
        let mut views = Vec::with_capacity(indexed * cells);
        for ty in ground {
            let Some(ty) = ty else {
                first.push(None);
                continue;
            };
            first.push(Some(views.len()));
            let slot: Vec<CellView> = (0..cells)
                .into_par_iter()
                .map(|i| {
                    let look = scenario.look(ty, scenario.cell_at(i));
                    CellView::new(rays, &look.region, cell_sight(scenario, &look))
                })
                .collect();
            views.extend(slot);
        }
        Some(SightIndex { first, views })
    }

    /// The view of the ground field of view `slot` at `k`, if indexed
    /// (`scenario` is the one the index was built for).
    pub(super) fn view(&self, scenario: &Scenario, slot: usize, k: Cell) -> Option<&CellView> {
        let first = (*self.first.get(slot)?)?;
        scenario
            .on_lattice(k)
            .then(|| &self.views[first + scenario.index(k)])
    }

    /// Approximate heap memory held, bytes.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.first.len() * 16
            + self.views.iter().map(CellView::memory_bytes).sum::<usize>()
    }
}
