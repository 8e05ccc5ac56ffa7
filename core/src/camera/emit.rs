//! Index emission: each active polygon's three vertex indices, found through the vertex
//! table, appended to the index list of its surface, in slot order (deterministic for a
//! given history of operations). Output goes into caller-provided slices; too little room
//! is an error naming the surface, never a panic.
//!
//! Each polygon's indices are the end of a chain of reads at unrelated addresses: the slot's
//! polygon (for a split's pair, the split record), the polygon record (surface and group),
//! per corner the active-vertex record (the node), the node record (the position), and the
//! vertex table's row for the position and its entry for the group. Followed polygon by
//! polygon, each read waits for the one before it, and once the hierarchy and the cameras
//! outgrow the caches every link is a miss. Emission therefore takes [`BATCH`] slots at a
//! time and follows one link for all of them before the next, so the misses of a link are
//! independent and the core overlaps them; the indices, their order and the errors are
//! those of the polygon-by-polygon walk (the first missing vertex in slot and corner order).
//! `emit/packed` (a 1M-polygon terrain, 36k polygons emitted) went from 683 µs to 571-583 µs
//! (0.84-0.85x, the two builds benchmarked one after the other), and the demo's cameras (10k
//! polygons each, mostly in cache) emit in 0.121-0.127 ms where they took 0.133-0.153 ms (5
//! alternating runs). The last two links run in the loop that hands out the triangles: a
//! separate pass for them was slower in cache (0.134-0.150 ms in the demo). 32 slots per
//! batch keep the batch's arrays under 1 KB of stack; on the bench (with the separate pass) 16
//! measured as 32, and 64 was 4% faster, not worth twice the stack on a small target.

use super::{CameraState, NONE};
use crate::hierarchy::Hierarchy;
use crate::ids::{PolyId, PositionId};
use crate::outputs::{check_lists, Shortfall};
use crate::records::Polygon;

/// Why indices could not be emitted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmitError {
    /// The camera was made for another hierarchy.
    WrongHierarchy,
    /// Fewer output lists (or offsets) than the hierarchy has surfaces (plus one).
    TooFewOutputs {
        /// Needed.
        needed: usize,
        /// Given.
        given: usize,
    },
    /// An output list is too short.
    OutputTooSmall {
        /// The surface.
        surface: u16,
        /// Indices needed.
        needed: usize,
        /// Room given.
        given: usize,
    },
    /// A corner has no vertex in its surface group: connectivity contradicts the hierarchy
    /// (corrupt data that validation cannot see).
    MissingVertex {
        /// The polygon.
        poly: PolyId,
        /// Its corner.
        corner: u8,
    },
    /// A surface received a different number of indices than the camera counted: the camera
    /// was used on after an [`OpError::Inconsistent`](crate::OpError::Inconsistent) without
    /// a [`reset`](CameraState::reset). The output is not usable.
    CountMismatch {
        /// The surface.
        surface: u16,
        /// Indices counted.
        expected: usize,
        /// Indices found.
        found: usize,
    },
}

impl core::fmt::Display for EmitError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::WrongHierarchy => write!(f, "camera state belongs to another hierarchy"),
            Self::TooFewOutputs { needed, given } => {
                write!(f, "{given} index outputs given, {needed} needed")
            }
            Self::OutputTooSmall {
                surface,
                needed,
                given,
            } => {
                write!(
                    f,
                    "index list of surface {surface}: room for {given}, {needed} needed"
                )
            }
            Self::MissingVertex { poly, corner } => {
                write!(
                    f,
                    "polygon {} corner {corner}: no vertex for its surface group",
                    poly.0
                )
            }
            Self::CountMismatch {
                surface,
                expected,
                found,
            } => write!(
                f,
                "surface {surface}: {found} indices emitted, {expected} counted (reset the camera)"
            ),
        }
    }
}

impl core::error::Error for EmitError {}

/// Slots per batch: enough independent reads per link to keep the core's miss queue busy,
/// few enough that a batch's gathered links stay in the first-level cache (768 bytes).
const BATCH: usize = 32;

impl CameraState<'_> {
    /// Indices each surface's list needs: `3 ×` its active polygons.
    pub fn index_count(&self, surface: usize) -> usize {
        self.front
            .surface_polygons
            .get(surface)
            .map_or(0, |&n| 3 * n as usize)
    }

    /// Calls `sink(surface, [i0, i1, i2])` for every active polygon in emission order.
    ///
    /// Slots are taken [`BATCH`] at a time, and each batch goes through the chain of reads
    /// one link at a time for all its polygons (see the module docs), so the reads of one
    /// link are independent and their misses overlap.
    #[inline]
    fn for_each_triangle(
        &self,
        h: &Hierarchy<'_>,
        mut sink: impl FnMut(usize, [u32; 3]),
    ) -> Result<(), EmitError> {
        let f = &self.front;
        let polys = h.polygons();
        let nodes = h.nodes();
        let live = ((f.base + 2 * f.pairs) as usize).min(f.slots.len());
        // Per slot of the batch: its polygon, then that polygon's record; per corner: its
        // node, then the node's position (`NONE` where a link is missing).
        let mut ids = [PolyId::NONE; BATCH];
        let mut records: [Option<&Polygon>; BATCH] = [None; BATCH];
        let mut corners = [[NONE; 3]; BATCH];
        let mut start = 0;
        while start < live {
            let batch = &f.slots[start..live.min(start + BATCH)];
            // Link 1: the polygon each slot holds (a base polygon, or one side of the split
            // that owns the pair: the split record) and the node each corner's record holds.
            for (k, ps) in batch.iter().enumerate() {
                ids[k] = f.poly_at(h, (start + k) as u32).unwrap_or(PolyId::NONE);
                for (c, &r) in corners[k].iter_mut().zip(&ps.corners) {
                    *c = f.node_of(r).map_or(NONE, |n| n.0);
                }
            }
            // Link 2: the polygon records, and each corner's position.
            for k in 0..batch.len() {
                records[k] = polys.get(ids[k].index());
                for c in &mut corners[k] {
                    *c = nodes.get(*c as usize).map_or(NONE, |n| n.position.0);
                }
            }
            // Links 3 and 4: the vertex table's row of each position and the group's entry,
            // then the triangle. A slot without a polygon holds nothing to draw (none is live
            // in a consistent camera).
            for k in 0..batch.len() {
                let Some(poly) = records[k] else {
                    continue;
                };
                let mut tri = [0u32; 3];
                for (c, &pos) in corners[k].iter().enumerate() {
                    tri[c] = h.vertex_index(poly.group, PositionId(pos)).ok_or(
                        EmitError::MissingVertex {
                            poly: ids[k],
                            corner: c as u8,
                        },
                    )?;
                }
                sink(poly.surface.index(), tri);
            }
            start += batch.len();
        }
        Ok(())
    }

    /// Writes each surface's indices to the start of `out[surface]` and its index count to
    /// `written[surface]`. Returns the total number of indices.
    pub fn emit_indices(
        &self,
        h: &Hierarchy<'_>,
        out: &mut [&mut [u32]],
        written: &mut [u32],
    ) -> Result<usize, EmitError> {
        if !self.is_for(h) {
            return Err(EmitError::WrongHierarchy);
        }
        let ns = h.surface_count();
        check_lists(out, written, ns, |s| self.index_count(s)).map_err(|e| match e {
            Shortfall::TooFewOutputs { needed, given } => {
                EmitError::TooFewOutputs { needed, given }
            }
            Shortfall::TooSmall {
                surface,
                needed,
                given,
            } => EmitError::OutputTooSmall {
                surface: surface as u16,
                needed,
                given,
            },
        })?;
        written[..ns].fill(0);
        let mut total = 0;
        self.for_each_triangle(h, |s, tri| {
            let at = written[s] as usize;
            if let Some(dst) = out[s].get_mut(at..at + 3) {
                dst.copy_from_slice(&tri);
                written[s] += 3;
                total += 3;
            }
        })?;
        for s in 0..ns {
            let expected = self.index_count(s);
            if written[s] as usize != expected {
                return Err(EmitError::CountMismatch {
                    surface: s as u16,
                    expected,
                    found: written[s] as usize,
                });
            }
        }
        Ok(total)
    }

    /// Writes every surface's indices back to back into `out`; `offsets` (surfaces + 1
    /// entries) receives the ranges: surface `s` is `out[offsets[s]..offsets[s + 1]]`.
    /// Returns the total number of indices.
    pub fn emit_indices_packed(
        &self,
        h: &Hierarchy<'_>,
        out: &mut [u32],
        offsets: &mut [u32],
    ) -> Result<usize, EmitError> {
        if !self.is_for(h) {
            return Err(EmitError::WrongHierarchy);
        }
        let ns = h.surface_count();
        if offsets.len() < ns + 1 {
            return Err(EmitError::TooFewOutputs {
                needed: ns + 1,
                given: offsets.len(),
            });
        }
        let total: usize = (0..ns).map(|s| self.index_count(s)).sum();
        if out.len() < total {
            return Err(EmitError::OutputTooSmall {
                surface: u16::MAX,
                needed: total,
                given: out.len(),
            });
        }
        // offsets[s + 1] is surface s's cursor during the pass and its end afterwards.
        offsets[0] = 0;
        let mut start = 0u32;
        for s in 0..ns {
            offsets[s + 1] = start;
            start += self.index_count(s) as u32;
        }
        self.for_each_triangle(h, |s, tri| {
            let at = offsets[s + 1] as usize;
            if let Some(dst) = out.get_mut(at..at + 3) {
                dst.copy_from_slice(&tri);
                offsets[s + 1] += 3;
            }
        })?;
        // Each cursor must have reached exactly the start of the next surface.
        let mut end = 0usize;
        for s in 0..ns {
            let expected = self.index_count(s);
            end += expected;
            if offsets[s + 1] as usize != end {
                return Err(EmitError::CountMismatch {
                    surface: s as u16,
                    expected,
                    found: (offsets[s + 1] as usize).saturating_sub(end - expected),
                });
            }
        }
        Ok(total)
    }
}
