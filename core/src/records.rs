//! The static records of a baked hierarchy, exactly as they lie in a `.clod` file.
//!
//! All records are `#[repr(C)]`, `Pod`, 4-byte aligned and free of implicit padding, so a
//! section of the file is a slice of records cast without copying. The split of the paper's
//! node into [`Node`] (every node: parent and position, 8 bytes) and [`Split`] (only the nodes
//! that can be split, which come first in id order) keeps leaves, about half of all nodes,
//! at 8 bytes each.

use bytemuck::{Pod, Zeroable};

use crate::ids::{NodeId, PolyId, PositionId, SurfaceGroupId, SurfaceId};

/// How a node position may move under a collapse (CAVECLOD §3.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum PositionClass {
    /// Inside one surface group: a node here may be the stationary or the floating child.
    Free = 0,
    /// On one surface-group boundary (or a mesh border): may float only along that boundary.
    Sharp = 1,
    /// Where several boundaries meet: always the stationary child, never floats.
    Rigid = 2,
}

impl PositionClass {
    /// Decodes the stored `u32`; `None` for an unknown value.
    pub const fn from_u32(value: u32) -> Option<Self> {
        match value {
            0 => Some(Self::Free),
            1 => Some(Self::Sharp),
            2 => Some(Self::Rigid),
            _ => None,
        }
    }

    /// The word the papers use.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Free => "FREE",
            Self::Sharp => "SHARP",
            Self::Rigid => "RIGID",
        }
    }
}

/// A node position: a point and its [`PositionClass`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Position {
    /// The point.
    pub xyz: [f32; 3],
    /// A [`PositionClass`] as `u32`.
    pub class: u32,
}

impl Position {
    /// The decoded class (validated at load, so `Free` is never returned for bad data of a
    /// loaded hierarchy).
    pub fn class(&self) -> PositionClass {
        PositionClass::from_u32(self.class).unwrap_or(PositionClass::Free)
    }
}

/// Every node of the hierarchy: its parent and its position.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct Node {
    /// The node this one was collapsed into; `NONE` for a root (a base-mesh node).
    pub parent: NodeId,
    /// Where the node lies. A stationary child shares its parent's position.
    pub position: PositionId,
}

/// The vertex split of an internal node (Hoppe's `SrVsplit`), and the bounds the
/// refinement criteria use. Node `i` owns split record `i`: nodes that can be split come
/// first in id order.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Split {
    /// The child that keeps this node's position (Hoppe's `vt`, the left child).
    pub stationary: NodeId,
    /// The child at a new position (Hoppe's `vu`, the right child).
    pub floating: NodeId,
    /// The polygon left of the new edge, `(stationary, floating, v_l)`.
    pub f_l: PolyId,
    /// The polygon right of the new edge, `(stationary, v_r, floating)`; `NONE` on a border.
    pub f_r: PolyId,
    /// The neighbours the split needs: `[fl_ccw, fl_clw, fr_clw, fr_ccw]`. `fl_clw` always
    /// exists; the others are `NONE` on a border, and `fr_ccw` exists iff `f_r` does.
    pub neighbours: [PolyId; 4],
    /// Centre direction of the cone bounding the normals of the polygons this node
    /// influences (unit length, or zero when the cone is disabled).
    pub cone_normal: [f32; 3],
    /// `sin²` of the cone's half angle plus the normals' spread, as in Hoppe's `sin2alpha`;
    /// `>= 1` disables the backface test.
    pub cone_sin2: f32,
    /// Radius of the sphere, centred on the node's position, bounding everything its
    /// descendants touch.
    pub radius: f32,
    /// Uniform error bound (world units): how far the surface may move by this split.
    pub uni_error: f32,
    /// Directional error bound (world units) along the surface normal.
    pub dir_error: f32,
    /// Reserved, zero.
    pub reserved: u32,
}

/// A polygon of the full-resolution mesh.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct Polygon {
    /// The three full-resolution (leaf) nodes, counter-clockwise. For a polygon a split
    /// creates, corner 0 descends from the split's stationary child, and corner 1 (of `f_l`)
    /// or corner 2 (of `f_r`) from its floating child.
    pub nodes: [NodeId; 3],
    /// The node whose split creates this polygon; `NONE` for a base-mesh polygon.
    pub creator: NodeId,
    /// The surface (material): selects the index list.
    pub surface: SurfaceId,
    /// The surface-group id: selects the vertex-table row.
    pub group: SurfaceGroupId,
}

/// A polygon of the base mesh as the coarsest level shows it. Base polygons are polygons
/// `0..base_polygon_count`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct BaseFace {
    /// The three root nodes, in the order of the polygon's `nodes`.
    pub corners: [NodeId; 3],
    /// `neighbours[j]`: the base polygon across the edge opposite corner `j`, or `NONE`.
    pub neighbours: [PolyId; 3],
}

/// One entry of the sparse vertex table: in row `group`, the vertex at this position.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct VertexKey {
    /// The surface-group id.
    pub group: SurfaceGroupId,
    /// Zero.
    pub reserved: u16,
    /// Index into the vertex buffer.
    pub vertex: u32,
}

/// A vertex of the persistent vertex buffer (the paper's 32-byte D3Dvertex).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Vertex {
    /// Position; equal to the position it is keyed by in the vertex table.
    pub position: [f32; 3],
    /// Unit normal.
    pub normal: [f32; 3],
    /// Texture coordinates.
    pub uv: [f32; 2],
}

/// Counts and bounds of a hierarchy (the `META` section).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Meta {
    /// Nodes (`n`).
    pub node_count: u32,
    /// Nodes with a split record; they are nodes `0..split_count`.
    pub split_count: u32,
    /// Roots (base-mesh nodes).
    pub root_count: u32,
    /// Full-resolution polygons (`p`).
    pub polygon_count: u32,
    /// Base-mesh polygons; they are polygons `0..base_polygon_count`.
    pub base_polygon_count: u32,
    /// Node positions (`e`).
    pub position_count: u32,
    /// Vertices (`d`).
    pub vertex_count: u32,
    /// Entries of the vertex table.
    pub vertex_key_count: u32,
    /// Surfaces (index lists).
    pub surface_count: u32,
    /// Surface-group ids (`s`, rows of the vertex table).
    pub surface_group_count: u32,
    /// Longest root-to-leaf path, in edges.
    pub max_depth: u32,
    /// Reserved, zero.
    pub flags: u32,
    /// Minimum corner of the positions' bounding box.
    pub bounds_min: [f32; 3],
    /// Maximum corner of the positions' bounding box.
    pub bounds_max: [f32; 3],
    /// Reserved, zero.
    pub reserved: [u32; 4],
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn record_sizes_are_the_documented_ones() {
        assert_eq!(core::mem::size_of::<Position>(), 16);
        assert_eq!(core::mem::size_of::<Node>(), 8);
        assert_eq!(core::mem::size_of::<Split>(), 64);
        assert_eq!(core::mem::size_of::<Polygon>(), 20);
        assert_eq!(core::mem::size_of::<BaseFace>(), 24);
        assert_eq!(core::mem::size_of::<VertexKey>(), 8);
        assert_eq!(core::mem::size_of::<Vertex>(), 32);
        assert_eq!(core::mem::size_of::<Meta>(), 88);
    }
}
