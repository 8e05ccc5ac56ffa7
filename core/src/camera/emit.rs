//! Index emission: each active polygon's three vertex indices, appended to the index list
//! of its surface, in slot order (deterministic for a given history of operations). Output
//! goes into caller-provided slices; too little room is an error naming the surface, never a
//! panic.
//!
//! With the index cache (the default; see `index_cache`) emission copies each slot's entry;
//! without it, it follows the chain of reads through the hierarchy, [`BATCH`] slots at a
//! time. Either way the indices, their order and the errors are the same: the first corner
//! without a vertex, in slot and corner order, is [`EmitError::MissingVertex`].
//!
//! Morphed emission ([`CameraState::emit_indices_morphed`]) writes the same triangles in the
//! same order, but a corner whose vertex morphs gets `vertex_count + slot`, its morph slot
//! past the persistent vertices (see `morph`); with nothing morphing it is the plain
//! emission.

use super::device_space::{on_device, MorphRemap};
use super::index_cache::BATCH;
use super::records::{SlotTriangle, NONE, NO_POLYGON};
use super::state::CameraState;
use crate::gpu::MorphVertex;
use crate::hierarchy::HierarchyRecords;
use crate::ids::{PolyId, SurfaceId};
use crate::outputs::{check_lists, start_packed};

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
        /// The surface; `None` for the packed output of all surfaces.
        surface: Option<SurfaceId>,
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
    /// A corner's vertex has no place in the device's vertex buffer
    /// ([`HierarchyRecords::device_vertex`]): over a streamed file, its page is not
    /// resident, which a consistent camera never draws.
    NoDeviceVertex {
        /// The vertex.
        vertex: u32,
    },
    /// [`index_edits`](CameraState::index_edits) on a camera made without
    /// [`CameraConfig::edit_list`](crate::CameraConfig::edit_list).
    NoIndexEdits,
    /// A surface received a different number of indices than the camera counted: the camera
    /// was used on after an [`OpError::Inconsistent`](crate::OpError::Inconsistent) without
    /// a [`reset`](CameraState::reset). The output is not usable.
    CountMismatch {
        /// The surface.
        surface: SurfaceId,
        /// Indices counted.
        expected: usize,
        /// Indices found.
        found: usize,
    },
}

crate::outputs::from_shortfall!(EmitError);

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
            } => crate::outputs::write_too_small(f, *surface, *needed, *given),
            Self::NoIndexEdits => write!(f, "the camera keeps no index edits"),
            Self::NoDeviceVertex { vertex } => {
                write!(f, "vertex {vertex} has no place in the device vertex pool")
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
                "surface {}: {found} indices emitted, {expected} counted (reset the camera)",
                surface.0
            ),
        }
    }
}

impl core::error::Error for EmitError {}

impl CameraState<'_> {
    /// Indices all surfaces' lists need together: the sum of [`index_count`](Self::index_count)
    /// over the surfaces, the length [`emit_indices_packed`](Self::emit_indices_packed)
    /// needs.
    pub fn total_index_count(&self) -> usize {
        self.front
            .surface_polygons
            .iter()
            .map(|&n| 3 * n as usize)
            .sum()
    }

    /// Indices each surface's list needs: `3 ×` its active polygons.
    pub fn index_count(&self, surface: usize) -> usize {
        self.front
            .surface_polygons
            .get(surface)
            .map_or(0, |&n| 3 * n as usize)
    }

    /// Calls `sink(surface, [i0, i1, i2])` for every active polygon in emission order:
    /// from the index cache, or looked up [`BATCH`] slots at a time without one.
    #[inline]
    fn for_each_triangle(
        &self,
        h: &impl HierarchyRecords,
        mut sink: impl FnMut(usize, [u32; 3]),
    ) -> Result<(), EmitError> {
        let f = &self.front;
        let live = ((f.base + 2 * f.pairs) as usize).min(f.slots.len());
        let mut hand_out = |slot: usize, t: &SlotTriangle| {
            // A slot without a polygon holds nothing to draw (none is live in a consistent
            // camera).
            if t.surface == NO_POLYGON {
                return Ok(());
            }
            if let Some(corner) = t.indices.iter().position(|&i| i == NONE) {
                return Err(EmitError::MissingVertex {
                    poly: f.poly_at(h, slot as u32).unwrap_or(PolyId::NONE),
                    corner: corner as u8,
                });
            }
            sink(usize::from(t.surface), t.indices);
            Ok(())
        };
        if let Some(cached) = f.triangles.get(..live).filter(|_| f.caches_indices()) {
            for (slot, t) in cached.iter().enumerate() {
                hand_out(slot, t)?;
            }
            return Ok(());
        }
        let mut start = 0;
        while start < live {
            let n = (live - start).min(BATCH);
            let g = f.gather(h, start as u32, n);
            for k in 0..n {
                hand_out(start + k, &g.entry(h, k))?;
            }
            start += n;
        }
        Ok(())
    }

    /// Writes each surface's indices to the start of `out[surface]` and its index count to
    /// `written[surface]`. Returns the total number of indices.
    pub fn emit_indices(
        &self,
        h: &impl HierarchyRecords,
        out: &mut [&mut [u32]],
        written: &mut [u32],
    ) -> Result<usize, EmitError> {
        self.emit_lists(h, out, written, |tri| on_device(h, tri))
    }

    /// [`emit_indices`](Self::emit_indices) with every corner whose vertex morphs pointing
    /// at its morph slot: `h.vertex_id_bound() + slot`, where the GPU writes the blended
    /// vertex of [`morph_vertices`](Self::morph_vertices)`()[slot]`. With nothing morphing
    /// it writes what `emit_indices` writes.
    pub fn emit_indices_morphed(
        &self,
        h: &impl HierarchyRecords,
        out: &mut [&mut [u32]],
        written: &mut [u32],
    ) -> Result<usize, EmitError> {
        match MorphRemap::of(&self.front.morphs, h.device_vertex_bound() as u32) {
            Some(m) => self.emit_lists(h, out, written, |tri| m.triangle(h, tri)),
            None => self.emit_lists(h, out, written, |tri| on_device(h, tri)),
        }
    }

    /// The lists of [`emit_indices`](Self::emit_indices), each triangle through `remap`.
    #[inline]
    fn emit_lists(
        &self,
        h: &impl HierarchyRecords,
        out: &mut [&mut [u32]],
        written: &mut [u32],
        remap: impl Fn([u32; 3]) -> Result<[u32; 3], u32>,
    ) -> Result<usize, EmitError> {
        if !self.is_for(h) {
            return Err(EmitError::WrongHierarchy);
        }
        let ns = h.surface_count();
        check_lists(out, written, ns, |s| self.index_count(s))?;
        written[..ns].fill(0);
        let mut total = 0;
        let mut placeless = None;
        self.for_each_triangle(h, |s, tri| {
            let at = written[s] as usize;
            let tri = remap(tri).unwrap_or_else(|v| [*placeless.get_or_insert(v); 3]);
            if let Some(dst) = out[s].get_mut(at..at + 3) {
                dst.copy_from_slice(&tri);
                written[s] += 3;
                total += 3;
            }
        })?;
        if let Some(vertex) = placeless {
            return Err(EmitError::NoDeviceVertex { vertex });
        }
        for s in 0..ns {
            let expected = self.index_count(s);
            if written[s] as usize != expected {
                return Err(EmitError::CountMismatch {
                    surface: SurfaceId(s as u16),
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
        h: &impl HierarchyRecords,
        out: &mut [u32],
        offsets: &mut [u32],
    ) -> Result<usize, EmitError> {
        self.emit_packed(h, out, offsets, |tri| on_device(h, tri))
    }

    /// [`emit_indices_packed`](Self::emit_indices_packed) with morphing corners pointing at
    /// their morph slots, as [`emit_indices_morphed`](Self::emit_indices_morphed) writes them.
    pub fn emit_indices_packed_morphed(
        &self,
        h: &impl HierarchyRecords,
        out: &mut [u32],
        offsets: &mut [u32],
    ) -> Result<usize, EmitError> {
        match MorphRemap::of(&self.front.morphs, h.device_vertex_bound() as u32) {
            Some(m) => self.emit_packed(h, out, offsets, |tri| m.triangle(h, tri)),
            None => self.emit_packed(h, out, offsets, |tri| on_device(h, tri)),
        }
    }

    /// The packed output of [`emit_indices_packed`](Self::emit_indices_packed), each
    /// triangle through `remap`.
    #[inline]
    fn emit_packed(
        &self,
        h: &impl HierarchyRecords,
        out: &mut [u32],
        offsets: &mut [u32],
        remap: impl Fn([u32; 3]) -> Result<[u32; 3], u32>,
    ) -> Result<usize, EmitError> {
        if !self.is_for(h) {
            return Err(EmitError::WrongHierarchy);
        }
        let ns = h.surface_count();
        let total = start_packed(out.len(), offsets, ns, |s| self.index_count(s))?;
        let mut placeless = None;
        self.for_each_triangle(h, |s, tri| {
            let at = offsets[s + 1] as usize;
            let tri = remap(tri).unwrap_or_else(|v| [*placeless.get_or_insert(v); 3]);
            if let Some(dst) = out.get_mut(at..at + 3) {
                dst.copy_from_slice(&tri);
                offsets[s + 1] += 3;
            }
        })?;
        if let Some(vertex) = placeless {
            return Err(EmitError::NoDeviceVertex { vertex });
        }
        // Each cursor must have reached exactly the start of the next surface.
        let mut end = 0usize;
        for s in 0..ns {
            let expected = self.index_count(s);
            end += expected;
            if offsets[s + 1] as usize != end {
                return Err(EmitError::CountMismatch {
                    surface: SurfaceId(s as u16),
                    expected,
                    found: (offsets[s + 1] as usize).saturating_sub(end - expected),
                });
            }
        }
        Ok(total)
    }
}

impl CameraState<'_> {
    /// [`morph_vertices`](Self::morph_vertices) as the device reads them: every vertex at
    /// its place in the device's vertex buffer, and a chained `from` at its slot past
    /// [`device_vertex_bound`](HierarchyRecords::device_vertex_bound). Over a whole file
    /// it writes what `morph_vertices` holds. Writes `out[..n]` and returns `n`;
    /// [`EmitError::OutputTooSmall`] if `out` is shorter than `morph_vertices()`.
    pub fn device_morph_vertices(
        &self,
        h: &impl HierarchyRecords,
        out: &mut [MorphVertex],
    ) -> Result<usize, EmitError> {
        if !self.is_for(h) {
            return Err(EmitError::WrongHierarchy);
        }
        let live = self.morph_vertices();
        let Some(out) = out.get_mut(..live.len()) else {
            return Err(EmitError::OutputTooSmall {
                surface: None,
                needed: live.len(),
                given: out.len(),
            });
        };
        let (ids, device) = (h.vertex_id_bound() as u32, h.device_vertex_bound() as u32);
        let place = |v: u32| {
            h.device_vertex(v)
                .ok_or(EmitError::NoDeviceVertex { vertex: v })
        };
        for (o, m) in out.iter_mut().zip(live) {
            *o = match m.is_idle() {
                true => MorphVertex::IDLE,
                false => MorphVertex {
                    from: match m.from.checked_sub(ids) {
                        Some(slot) => device.saturating_add(slot),
                        None => place(m.from)?,
                    },
                    to: place(m.to)?,
                    t: m.t,
                    coarse: place(m.coarse)?,
                },
            };
        }
        Ok(live.len())
    }
}
