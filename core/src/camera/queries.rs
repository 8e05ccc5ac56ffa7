//! Questions about a camera's front: which nodes and polygons are active, where a polygon
//! sits, the counts and the bytes, answered in O(1) from the map from split to pair.

use super::records::{FREE, NONE};
use super::state::{CameraState, Front};
use crate::hierarchy::HierarchyRecords;
use crate::ids::{NodeId, PolyId, PolyKey};

impl CameraState<'_> {
    /// `true` if this camera was made for `h`.
    pub fn is_for(&self, h: &impl HierarchyRecords) -> bool {
        self.front.hierarchy == h.checksum()
    }

    /// Number of active nodes.
    pub fn active_node_count(&self) -> u32 {
        self.front.active_nodes
    }

    /// Number of active polygons.
    pub fn active_polygon_count(&self) -> u32 {
        self.front.active_polygons
    }

    /// Number of splits currently applied.
    pub fn split_count(&self) -> u32 {
        self.front.pairs
    }

    /// Most splits this camera can hold at once.
    pub fn max_pairs(&self) -> u32 {
        self.front.owner.len() as u32
    }

    /// Active polygons per surface: index list `s` needs `3 * surface_polygons()[s]` indices.
    pub fn surface_polygons(&self) -> &[u32] {
        self.front.surface_polygons
    }

    /// Bytes this camera occupies: its words plus the struct itself.
    pub fn bytes(&self) -> usize {
        let f = &self.front;
        f.pair_of.bytes()
            + 4 * (f.owner.len() + f.surface_polygons.len() + f.refused.len() + self.stack.len())
            + core::mem::size_of_val(&*f.active)
            + core::mem::size_of_val(&*f.slots)
            + core::mem::size_of_val(&*f.triangles)
            + core::mem::size_of_val(&*f.morphs.vertices)
            + core::mem::size_of_val(&*f.morphs.states)
            + f.morphs.map.bytes()
            + core::mem::size_of_val(&*f.morphs.coarsening)
            + core::mem::size_of_val(&*f.morphs.free)
            + core::mem::size_of::<Self>()
    }

    /// Bytes of this camera's morph memory (part of [`bytes`](Self::bytes)): 0 without
    /// morphs ([`CameraConfig::max_morphs`](crate::CameraConfig::max_morphs)).
    pub fn morph_bytes(&self) -> usize {
        let m = &self.front.morphs;
        core::mem::size_of_val(&*m.vertices)
            + core::mem::size_of_val(&*m.states)
            + m.map.bytes()
            + core::mem::size_of_val(&*m.coarsening)
            + core::mem::size_of_val(&*m.free)
    }

    /// `true` if `node` is on this camera's active front (O(1)).
    pub fn is_node_active(&self, h: &impl HierarchyRecords, node: NodeId) -> bool {
        self.front.is_node_active(h, node)
    }

    /// `true` if `node`'s split is applied in this camera (O(1)).
    pub fn is_split(&self, node: NodeId) -> bool {
        self.front.is_split(node)
    }

    /// `true` if `poly` is active in this camera (O(1)).
    pub fn is_polygon_active(&self, h: &impl HierarchyRecords, poly: PolyId) -> bool {
        self.front.slot_of(h, poly).is_some()
    }

    /// The active nodes, in active-list order.
    pub fn active_nodes(&self) -> impl Iterator<Item = NodeId> + '_ {
        self.front.active[..self.front.active_len as usize]
            .iter()
            .filter(|a| a.node & FREE == 0)
            .map(|a| NodeId(a.node))
    }

    /// The active polygons, in slot (emission) order.
    pub fn active_polygons<'s>(
        &'s self,
        h: &'s impl HierarchyRecords,
    ) -> impl Iterator<Item = PolyId> + 's {
        let f = &self.front;
        (0..f.base + 2 * f.pairs).filter_map(move |s| f.poly_at(h, s))
    }

    /// The current corners of an active polygon, in the polygon's order; `None` if inactive.
    pub fn polygon_corners(&self, h: &impl HierarchyRecords, poly: PolyId) -> Option<[NodeId; 3]> {
        let f = &self.front;
        let s = f.slots.get(f.slot_of(h, poly)? as usize)?;
        let mut out = [NodeId::NONE; 3];
        for k in 0..3 {
            out[k] = f.node_of(s.corners[k])?;
        }
        Some(out)
    }

    /// The current neighbours of an active polygon (`neighbours[j]` across the edge opposite
    /// corner `j`, `NONE` on a border); `None` if inactive.
    pub fn polygon_neighbours(
        &self,
        h: &impl HierarchyRecords,
        poly: PolyId,
    ) -> Option<[PolyId; 3]> {
        let f = &self.front;
        let s = f.slots.get(f.slot_of(h, poly)? as usize)?;
        let mut out = [PolyId::NONE; 3];
        for k in 0..3 {
            if s.neighbours[k] != NONE {
                out[k] = f.poly_at(h, s.neighbours[k])?;
            }
        }
        Some(out)
    }
}

impl Front<'_> {
    #[inline]
    pub fn is_split(&self, node: NodeId) -> bool {
        self.pair_of.get(node.index()).is_some_and(|p| p != NONE)
    }

    #[inline]
    pub fn is_created(&self, h: &impl HierarchyRecords, node: NodeId) -> bool {
        match h.node(node) {
            Some(n) => n.parent.is_none() || self.is_split(n.parent),
            None => false,
        }
    }

    #[inline]
    pub fn is_node_active(&self, h: &impl HierarchyRecords, node: NodeId) -> bool {
        self.is_created(h, node) && !self.is_split(node)
    }

    /// The slot of an active polygon: base polygons sit in the first slots, others in their
    /// creator's pair (two reads: the polygon's creator and the camera's `pair_of`).
    #[inline]
    pub fn slot_of(&self, h: &impl HierarchyRecords, poly: PolyId) -> Option<u32> {
        self.slot_of_key(h.key_of(poly)?)
    }

    /// The slot of an active polygon named by its [`PolyKey`]: a base polygon's key is its
    /// slot; any other's says its creator and side, so one read of the camera's `pair_of`
    /// answers.
    #[inline]
    pub fn slot_of_key(&self, key: PolyKey) -> Option<u32> {
        let Some((node, right)) = key.creator(self.base) else {
            // A base polygon's key is its slot (`NONE` is no base polygon's).
            return (key.0 < self.base).then_some(key.0);
        };
        let pair = self.pair_of.get(node.index())?;
        if pair == NONE {
            return None;
        }
        Some(self.base + 2 * pair + right as u32)
    }

    /// The polygon in a slot, if the slot is live.
    #[inline]
    pub fn poly_at(&self, h: &impl HierarchyRecords, slot: u32) -> Option<PolyId> {
        if slot < self.base {
            return Some(PolyId(slot));
        }
        let rel = slot - self.base;
        let (pair, side) = (rel / 2, rel % 2);
        if pair >= self.pairs {
            return None;
        }
        let s = h.split(*self.owner.get(pair as usize)?)?;
        let p = if side == 0 { s.f_l } else { s.f_r };
        p.get()
    }

    /// The node an active-vertex record holds.
    #[inline]
    pub fn node_of(&self, record: u32) -> Option<NodeId> {
        let a = self.active.get(record as usize)?.node;
        (a & FREE == 0).then_some(NodeId(a))
    }
}
