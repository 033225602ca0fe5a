//! The rays of each source and their indexes, written and read back to the
//! bit ([`crate::codec`]), so that a replica can load what another
//! precomputed instead of building it again.

use super::rays::{Crossings, LookCrossings, SourceRays};
use crate::codec::{CodecError, Reader, Writer, expect_len};
use crate::geometry::Point;
use crate::scenario::Scenario;

impl SourceRays {
    /// Writes these rays and their indexes.
    pub fn encode(&self, w: &mut Writer) {
        w.len(self.source_index);
        w.f64(self.lo);
        w.f64(self.step);
        let dirs: Vec<f64> = self
            .dirs
            .iter()
            .flat_map(|(d, inv)| [d.x, d.y, inv.x, inv.y])
            .collect();
        w.f64s(&dirs);
        w.f64s(&self.beyond);
        w.f64s(&self.stops);
        w.bool(self.crossings.is_some());
        if let Some(c) = &self.crossings {
            w.u32s(&c.offsets);
            w.f64s(&c.r);
            let cells: Vec<u32> = c.cells.iter().flatten().copied().collect();
            w.u32s(&cells);
            w.u32s(&c.lin);
            w.f64s(&c.kappa);
        }
        w.bool(self.looks.is_some());
        if let Some(l) = &self.looks {
            w.u32s(&l.first);
            w.u32s(&l.start);
            let pq: Vec<f64> = l.pq.iter().flat_map(|&(p, q)| [p, q]).collect();
            w.f64s(&pq);
            w.f64s(&l.past);
        }
    }

    /// Reads rays [`SourceRays::encode`] wrote for scenario `s` (its
    /// source is taken from `s`).
    ///
    /// # Errors
    /// A [`CodecError`] for bytes that are not such rays.
    pub fn decode(r: &mut Reader, s: &Scenario) -> Result<Self, CodecError> {
        let source_index = r.len()?;
        let source = *s
            .sources
            .get(source_index)
            .ok_or_else(|| CodecError(format!("no source {source_index}")))?;
        let lo = r.f64()?;
        let step = r.f64()?;
        let flat = r.f64s()?;
        if flat.len() % 4 != 0 {
            return Err(CodecError("ray directions come in fours".into()));
        }
        let dirs: Vec<(Point, Point)> = flat
            .chunks_exact(4)
            .map(|c| (Point::new(c[0], c[1]), Point::new(c[2], c[3])))
            .collect();
        let n = dirs.len();
        let beyond = r.f64s()?;
        expect_len("beyond", beyond.len(), n)?;
        let stops = r.f64s()?;
        if !stops.is_empty() {
            expect_len("stops", stops.len(), n)?;
        }
        let crossings = if r.bool()? {
            let c = Crossings {
                offsets: r.u32s()?,
                r: r.f64s()?,
                cells: {
                    let flat = r.u32s()?;
                    if flat.len() % 2 != 0 {
                        return Err(CodecError("crossed cells come in pairs".into()));
                    }
                    flat.chunks_exact(2).map(|c| [c[0], c[1]]).collect()
                },
                lin: r.u32s()?,
                kappa: r.f64s()?,
            };
            expect_len("crossing offsets", c.offsets.len(), n + 1)?;
            let total = c.cells.len();
            if c.offsets.windows(2).any(|w| w[0] > w[1])
                || c.offsets.first() != Some(&0)
                || c.offsets.last().map(|&o| o as usize) != Some(total)
            {
                return Err(CodecError("crossing offsets out of order".into()));
            }
            expect_len("crossing distances", c.r.len(), total + n)?;
            expect_len("crossing indices", c.lin.len(), total)?;
            expect_len("crossing corrections", c.kappa.len(), total)?;
            Some(c)
        } else {
            None
        };
        let looks = if r.bool()? {
            let l = LookCrossings {
                first: r.u32s()?,
                start: r.u32s()?,
                pq: {
                    let flat = r.f64s()?;
                    if flat.len() % 2 != 0 {
                        return Err(CodecError("look intervals come in pairs".into()));
                    }
                    flat.chunks_exact(2).map(|c| (c[0], c[1])).collect()
                },
                past: r.f64s()?,
            };
            let keys = l.first.len();
            expect_len("look starts", l.start.len(), keys + 1)?;
            expect_len("look exits", l.past.len(), keys)?;
            if l.start.windows(2).any(|w| w[0] > w[1])
                || l.start.last().map(|&o| o as usize) != Some(l.pq.len())
            {
                return Err(CodecError("look starts out of order".into()));
            }
            Some(l)
        } else {
            None
        };
        Ok(SourceRays {
            source,
            lo,
            step,
            dirs,
            beyond,
            stops,
            source_index,
            crossings,
            looks,
        })
    }
}
