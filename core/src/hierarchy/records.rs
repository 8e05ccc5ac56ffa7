//! [`HierarchyRecords`]: the records a camera reads, wherever they lie.
//!
//! A camera reads a hierarchy through this trait alone, so the same refinement runs over a
//! whole file ([`Hierarchy`](crate::Hierarchy), whose records are arrays indexed by id) and over a paged file
//! streamed into a pool ([`StreamedHierarchy`](crate::stream::StreamedHierarchy), whose
//! records are found by their page). The camera's code is generic over it: the whole-file
//! form compiles to the same array reads it always did.
//!
//! A record another form may not hold right now is an `Option`; the camera asks
//! [`split_ready`](HierarchyRecords::split_ready) before it splits a node, and a split whose
//! records are absent is deferred (see the streaming module), so refinement never reads an
//! absent record.

use crate::format::{
    BaseFace, Meta, Node, Polygon, Position, Split, SplitBounds, Vertex, VertexKey,
};
use crate::ids::{NodeId, PageKey, PolyId, PolyKey, PositionId, SurfaceGroupId};

/// What a split needs that is not at hand: the page to want, whose absence defers it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Absent {
    /// The page holding the missing records.
    pub page: PageKey,
    /// The node whose split waits for it.
    pub node: NodeId,
}

/// Read access to a validated hierarchy's records (see the module docs).
pub trait HierarchyRecords {
    /// The hierarchy's identity: cameras record it to refuse a hierarchy they were not made
    /// for.
    fn checksum(&self) -> u64;

    /// Counts and bounds.
    fn meta(&self) -> &Meta;

    /// The roots, ascending.
    fn roots(&self) -> &[NodeId];

    /// The base mesh: polygon `i` of it is polygon `PolyId(i)`.
    fn base(&self) -> &[BaseFace];

    /// Number of surfaces (index lists).
    fn surface_count(&self) -> usize;

    /// Every node that can be split has an id below this.
    fn split_id_bound(&self) -> usize;

    /// Every vertex has an index below this.
    fn vertex_id_bound(&self) -> usize;

    /// Where vertex `vertex` lies in the device's vertex buffer, the index an index list
    /// holds for it: the vertex itself over a whole file, whose persistent vertex buffer
    /// holds every vertex by id; its place in the device vertex pool over a streamed file
    /// (see [`VertexPoolLayout`](crate::stream::VertexPoolLayout)). `None` if it has no
    /// place there now (its page is not resident).
    #[inline(always)]
    fn device_vertex(&self, vertex: u32) -> Option<u32> {
        Some(vertex)
    }

    /// Vertices in the device's vertex buffer: morphing corners are numbered past them
    /// ([`CameraState::emit_indices_morphed`](crate::CameraState::emit_indices_morphed)).
    #[inline]
    fn device_vertex_bound(&self) -> usize {
        self.vertex_id_bound()
    }

    /// Whether ids are dense (`0..count`): then per-id arrays in a camera cost what the
    /// hierarchy holds; otherwise a camera keeps only maps sized by its own capacity.
    fn dense_ids(&self) -> bool;

    /// The node record; `None` for an id out of range or a record not at hand.
    fn node(&self, node: NodeId) -> Option<&Node>;

    /// The split record of `node`; `None` for a leaf, an id out of range, or a record not at
    /// hand.
    fn split(&self, node: NodeId) -> Option<&Split>;

    /// The refinement bounds of `node`; `None` as for [`split`](Self::split).
    fn split_bounds(&self, node: NodeId) -> Option<&SplitBounds>;

    /// The polygon record.
    fn polygon(&self, poly: PolyId) -> Option<&Polygon>;

    /// The position record.
    fn position(&self, position: PositionId) -> Option<&Position>;

    /// The vertex-table entries of a position: one per surface group with a vertex there.
    fn vertex_keys(&self, position: PositionId) -> &[VertexKey];

    /// The vertex record.
    fn vertex(&self, vertex: u32) -> Option<&Vertex>;

    /// Whether every record a split of `node` reads and creates is at hand (its children,
    /// their positions and vertices, the polygons it creates); `Err` names the page to want.
    #[inline(always)]
    fn split_ready(&self, node: NodeId) -> Result<(), Absent> {
        let _ = node;
        Ok(())
    }

    /// A split waits for `absent` (see [`split_ready`](Self::split_ready)); its projected
    /// error exceeds the tolerance by `excess_px` pixels, which orders the loads.
    #[inline(always)]
    fn want(&self, absent: Absent, excess_px: f32) {
        let _ = (absent, excess_px);
    }

    /// `node` joined a camera's front (a split made it, or a reset): its records are in
    /// use. With [`node_left_front`](Self::node_left_front), what keeps a streamed page
    /// from eviction while a front stands on it.
    #[inline(always)]
    fn node_entered_front(&self, node: NodeId) {
        let _ = node;
    }

    /// `node` left a camera's front (split, collapsed into its parent, or reset away).
    #[inline(always)]
    fn node_left_front(&self, node: NodeId) {
        let _ = node;
    }

    /// Asks for the cache line of `position`'s vertex-table row, ahead of a lookup.
    #[inline(always)]
    fn prefetch_vertex_keys(&self, position: PositionId) {
        let _ = position;
    }

    /// Number of base polygons.
    #[inline]
    fn base_polygon_count(&self) -> usize {
        self.base().len()
    }

    /// The point of a node.
    #[inline]
    fn node_point(&self, node: NodeId) -> Option<[f32; 3]> {
        self.position(self.node(node)?.position).map(|p| p.xyz)
    }

    /// The vertex index of surface group `group` at `position`. O(log k) in the k groups
    /// meeting at the position (k = 1 inside a group).
    #[inline]
    fn vertex_index(&self, group: SurfaceGroupId, position: PositionId) -> Option<u32> {
        let keys = self.vertex_keys(position);
        if let [only] = keys {
            return (only.group == group).then_some(only.vertex);
        }
        keys.binary_search_by_key(&group, |k| k.group)
            .ok()
            .map(|i| keys[i].vertex)
    }

    /// The polygon a [`PolyKey`] names; `None` for `NONE` or a key no polygon has.
    #[inline]
    fn polygon_of(&self, key: PolyKey) -> Option<PolyId> {
        let base = self.base_polygon_count() as u32;
        match key.creator(base) {
            Some((node, right)) => {
                let s = self.split(node)?;
                (if right { s.f_r } else { s.f_l }).get()
            }
            None => (key.is_some() && key.0 < base).then_some(PolyId(key.0)),
        }
    }

    /// The [`PolyKey`] of `poly`; `None` for an id out of range.
    #[inline]
    fn key_of(&self, poly: PolyId) -> Option<PolyKey> {
        let p = self.polygon(poly)?;
        Some(p.creator.key(self.base_polygon_count() as u32, poly))
    }
}
