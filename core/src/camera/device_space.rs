//! Where a camera's index lists and morph slots point in the device's vertex buffer.
//!
//! Inside the camera a corner is a vertex id, and a morph slot names its vertices by id
//! (see `morph`). On the device a vertex is where the hierarchy puts it
//! ([`HierarchyRecords::device_vertex`]): the id itself over a whole file, a slot's place in
//! the device vertex pool over a streamed one; and a morphing corner is the morph slot past
//! every one of those ([`HierarchyRecords::device_vertex_bound`]). Emission and the index
//! edits convert here, once, as they write; the morph slots in
//! [`CameraState::device_morph_vertices`](crate::CameraState::device_morph_vertices).

use super::morph_map::MorphMap;
use super::morph_pool::Morphs;
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
