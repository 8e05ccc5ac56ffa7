//! What a hierarchy is made of, borrowed: its arrays ([`HierarchyParts`]) and the sections
//! this version does not define ([`ExtraSection`]). The writer serialises them and the
//! validation checks them.

use super::records::{BaseFace, Node, Polygon, Position, Split, SplitBounds, Vertex, VertexKey};
use super::Tag;
use crate::ids::NodeId;

/// The arrays of a hierarchy, borrowed: what a builder produces and what
/// [`Hierarchy`](crate::Hierarchy) views.
#[derive(Clone, Copy, Debug, Default)]
pub struct HierarchyParts<'a> {
    /// One per node position.
    pub positions: &'a [Position],
    /// One per node; nodes `0..splits.len()` can be split, parents before children.
    pub nodes: &'a [Node],
    /// One per node that can be split.
    pub splits: &'a [Split],
    /// One per node that can be split.
    pub bounds: &'a [SplitBounds],
    /// One per full-resolution polygon; base polygons first.
    pub polygons: &'a [Polygon],
    /// The roots (nodes without parent), ascending.
    pub roots: &'a [NodeId],
    /// One per base polygon.
    pub base: &'a [BaseFace],
    /// `positions.len() + 1` offsets into `vertex_table`.
    pub vertex_table_offsets: &'a [u32],
    /// The vertex table's entries, grouped by position, ascending group within a position.
    pub vertex_table: &'a [VertexKey],
    /// The vertex buffer.
    pub vertices: &'a [Vertex],
    /// Number of surfaces (index lists); every polygon's surface is below it.
    pub surface_count: u32,
    /// Number of surface-group ids; every group id is below it.
    pub surface_group_count: u32,
}

/// A section this version does not define, carried along (g-mesh levels, octrees, ...).
#[derive(Clone, Copy, Debug)]
pub struct ExtraSection<'a> {
    /// Its tag; must not be one of [`tags`](crate::format::tags).
    pub tag: Tag,
    /// Size of one record; `bytes.len()` must be a multiple of it.
    pub record_size: u32,
    /// The records.
    pub bytes: &'a [u8],
}
