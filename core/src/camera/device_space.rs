//! Where a camera's index lists and morph slots point in the device's vertex buffer.
//!
//! Inside the camera a corner is a vertex id, and a morph slot names its vertices by id
//! (see `morph`). On the device a vertex is where the hierarchy puts it
//! ([`HierarchyRecords::device_vertex`]): the id itself over a whole file, a slot's place in
//! the device vertex pool over a streamed one; and a morphing corner is the morph slot past
//! every one of those ([`HierarchyRecords::device_vertex_bound`]). Emission, the index edits
//! and [`CameraState::device_morph_vertices`] convert here, once, as they write.

use super::emit::EmitError;
use super::morph_map::MorphMap;
use super::morph_pool::Morphs;
use super::state::CameraState;
use crate::gpu::MorphVertex;
use crate::hierarchy::HierarchyRecords;

/// Morphed emission's view of the map: `base + slot` for a corner whose vertex morphs.
pub(crate) struct MorphRemap<'a, 'm> {
    map: &'a MorphMap<'m>,
    base: u32,
}

impl<'a, 'm> MorphRemap<'a, 'm> {
    /// The remap of a camera's morphing vertices to `base + slot`; `None` when nothing
    /// morphs (emission is then the plain one).
    pub fn of(morphs: &'a Morphs<'m>, base: u32) -> Option<Self> {
        (morphs.scalars.live > 0).then_some(Self {
            map: &morphs.map,
            base,
        })
    }

    /// A triangle's indices in the device's vertex buffer, each morphing vertex at
    /// `base + slot`: a triangle without one (nearly all) costs the reads of its three bits
    /// and one branch (see `morph_map`). `Err` names a vertex without a place there.
    #[inline(always)]
    pub fn triangle(&self, h: &impl HierarchyRecords, tri: [u32; 3]) -> Result<[u32; 3], u32> {
        let [a, b, c] = tri.map(|v| self.map.bit(v));
        if a | b | c == 0 {
            return on_device(h, tri);
        }
        let [a, b, c] = tri.map(|v| self.index(h, v));
        Ok([a?, b?, c?])
    }

    /// `base + slot` for a morphing vertex, else the vertex's place on the device.
    #[inline]
    fn index(&self, h: &impl HierarchyRecords, vertex: u32) -> Result<u32, u32> {
        let slot = match self.map.bit(vertex) {
            0 => None,
            _ => self.map.get(vertex),
        };
        match slot {
            Some(slot) => Ok(self.base.saturating_add(slot)),
            None => h.device_vertex(vertex).ok_or(vertex),
        }
    }
}

/// A triangle's corners in the device's vertex buffer
/// ([`HierarchyRecords::device_vertex`]); `Err` names a vertex without a place there. Over
/// a whole file, the triangle itself.
#[inline(always)]
pub(crate) fn on_device(h: &impl HierarchyRecords, tri: [u32; 3]) -> Result<[u32; 3], u32> {
    let [a, b, c] = tri;
    match (h.device_vertex(a), h.device_vertex(b), h.device_vertex(c)) {
        (Some(a), Some(b), Some(c)) => Ok([a, b, c]),
        (None, _, _) => Err(a),
        (_, None, _) => Err(b),
        _ => Err(c),
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
