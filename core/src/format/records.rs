//! The static records of a baked hierarchy, exactly as they lie in a `.clod` file.
//!
//! All records are `#[repr(C)]`, `Pod`, 4-byte aligned and free of implicit padding, so a
//! section of the file is a slice of records cast without copying. The split of the paper's
//! node into [`Node`] (every node: parent and position, 8 bytes) and [`Split`] (only the nodes
//! that can be split, which come first in id order) keeps leaves, about half of all nodes,
//! at 8 bytes each.

use bytemuck::{Pod, Zeroable};

use crate::ids::{NodeId, PolyId, PolyKey, PositionId, SurfaceGroupId, SurfaceId};

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

/// The vertex split of an internal node (Hoppe's `SrVsplit`): its topology. Node `i` owns
/// split record `i`: nodes that can be split come first in id order. What refinement reads
/// every frame lives apart, in [`SplitBounds`], so a refinement pass touches 32 bytes per node
/// and the operations touch these 32.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct Split {
    /// The child that keeps this node's position (Hoppe's `vt`, the left child).
    pub stationary: NodeId,
    /// The child at a new position (Hoppe's `vu`, the right child).
    pub floating: NodeId,
    /// The polygon left of the new edge, `(stationary, floating, v_l)`.
    pub f_l: PolyId,
    /// The polygon right of the new edge, `(stationary, v_r, floating)`; `NONE` on a border.
    pub f_r: PolyId,
    /// The neighbours the split needs: `[fl_ccw, fl_clw, fr_clw, fr_ccw]`, by [`PolyKey`]
    /// (so a camera finds their slots without reading their polygon records;
    /// [`Hierarchy::polygon_of`](crate::Hierarchy::polygon_of) gives their [`PolyId`]s).
    /// `fl_clw` always exists; the others are `NONE` on a border, and `fr_ccw` exists iff
    /// `f_r` does.
    pub neighbours: [PolyKey; 4],
}

/// What the refinement criteria of a splittable node read: its point, bounding sphere,
/// normal cone and error bounds, 32 bytes (two per cache line).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct SplitBounds {
    /// The node's point (equal to its position's; kept here so one record answers).
    pub point: [f32; 3],
    /// Radius of the sphere, centred on `point`, bounding everything the node's
    /// descendants touch.
    pub radius: f32,
    /// Centre direction of the cone bounding the normals below the node, octahedral-encoded
    /// as two signed-normalised 16-bit numbers ([`SplitBounds::cone_normal`]).
    pub cone_axis: [i16; 2],
    /// `sin²` of the cone's half angle, as in Hoppe's `sin2alpha`; `>= 1` disables the
    /// backface test.
    pub cone_sin2: f32,
    /// Uniform error bound (world units): how far the surface may move by this split.
    pub uni_error: f32,
    /// Directional error bound (world units) along the surface normal.
    pub dir_error: f32,
}

impl SplitBounds {
    /// Bounds with the cone axis encoded from a unit vector (zero for a disabled cone).
    pub fn new(
        point: [f32; 3],
        radius: f32,
        cone_normal: [f32; 3],
        cone_sin2: f32,
        uni_error: f32,
        dir_error: f32,
    ) -> Self {
        Self {
            point,
            radius,
            cone_axis: octahedral_encode(cone_normal),
            cone_sin2,
            uni_error,
            dir_error,
        }
    }

    /// The decoded cone axis (unit length, or zero when encoded from zero).
    #[inline]
    pub fn cone_normal(&self) -> [f32; 3] {
        octahedral_decode(self.cone_axis)
    }
}

fn snorm16(x: f32) -> i16 {
    let v = x.clamp(-1.0, 1.0) * 32767.0;
    (if v >= 0.0 { v + 0.5 } else { v - 0.5 }) as i16
}

/// Octahedral encoding of a unit vector (Meyer et al. 2010) in two snorm16 numbers; the zero
/// vector encodes as `[0, 0]`... which decodes to +z, so a disabled cone is marked by
/// `cone_sin2 >= 1` instead.
pub fn octahedral_encode(n: [f32; 3]) -> [i16; 2] {
    let l1 = n[0].abs() + n[1].abs() + n[2].abs();
    if l1.is_nan() || l1 <= 0.0 {
        return [0, 0];
    }
    let (x, y, z) = (n[0] / l1, n[1] / l1, n[2] / l1);
    let (u, v) = if z >= 0.0 {
        (x, y)
    } else {
        (
            (1.0 - y.abs()) * if x >= 0.0 { 1.0 } else { -1.0 },
            (1.0 - x.abs()) * if y >= 0.0 { 1.0 } else { -1.0 },
        )
    };
    [snorm16(u), snorm16(v)]
}

/// Decodes [`octahedral_encode`].
pub fn octahedral_decode(e: [i16; 2]) -> [f32; 3] {
    let (u, v) = (e[0] as f32 * (1.0 / 32767.0), e[1] as f32 * (1.0 / 32767.0));
    let z = 1.0 - u.abs() - v.abs();
    let (x, y) = if z >= 0.0 {
        (u, v)
    } else {
        (
            (1.0 - v.abs()) * if u >= 0.0 { 1.0 } else { -1.0 },
            (1.0 - u.abs()) * if v >= 0.0 { 1.0 } else { -1.0 },
        )
    };
    let l = libm::sqrtf(x * x + y * y + z * z);
    if l > 0.0 {
        let r = 1.0 / l;
        [x * r, y * r, z * r]
    } else {
        [0.0, 0.0, 1.0]
    }
}

/// Which split creates a polygon, and on which side: `2 · node + side` (side 1 for `f_r`), or
/// [`Creator::BASE`] for a base-mesh polygon. Finding a polygon's slot in a camera then reads
/// no split record.
#[repr(transparent)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct Creator(pub u32);

impl Creator {
    /// A base-mesh polygon.
    pub const BASE: Self = Self(u32::MAX);

    /// Created by `node`'s split, as `f_r` if `right`, else `f_l`.
    pub const fn new(node: NodeId, right: bool) -> Self {
        Self((node.0 << 1) | right as u32)
    }

    /// The node whose split creates the polygon; `None` for a base polygon.
    #[inline]
    pub const fn node(self) -> Option<NodeId> {
        if self.0 == u32::MAX {
            None
        } else {
            Some(NodeId(self.0 >> 1))
        }
    }

    /// `true` for the right polygon (`f_r`).
    #[inline]
    pub const fn is_right(self) -> bool {
        self.0 & 1 == 1
    }

    /// The [`PolyKey`] of polygon `poly`, whose creator this is, in a hierarchy of
    /// `base_polygons` base polygons.
    #[inline]
    pub const fn key(self, base_polygons: u32, poly: PolyId) -> PolyKey {
        match self.node() {
            Some(node) => PolyKey::created(base_polygons, node, self.is_right()),
            None => PolyKey::base(poly),
        }
    }
}

/// A polygon of the full-resolution mesh.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct Polygon {
    /// The three full-resolution (leaf) nodes, counter-clockwise. For a polygon a split
    /// creates, corner 0 descends from the split's stationary child, and corner 1 (of `f_l`)
    /// or corner 2 (of `f_r`) from its floating child.
    pub nodes: [NodeId; 3],
    /// The split that creates this polygon and its side; [`Creator::BASE`] for a base-mesh
    /// polygon.
    pub creator: Creator,
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
        assert_eq!(core::mem::size_of::<Split>(), 32);
        assert_eq!(core::mem::size_of::<SplitBounds>(), 32);
        assert_eq!(core::mem::size_of::<Polygon>(), 20);
        assert_eq!(core::mem::size_of::<BaseFace>(), 24);
        assert_eq!(core::mem::size_of::<VertexKey>(), 8);
        assert_eq!(core::mem::size_of::<Vertex>(), 32);
        assert_eq!(core::mem::size_of::<Meta>(), 88);
    }
}

#[cfg(test)]
mod octahedral_tests {
    use super::*;

    #[test]
    fn octahedral_round_trip_within_a_tenth_of_a_degree() {
        let mut worst = 1.0f32;
        for i in 0..40 {
            for j in 0..80 {
                let (t, p) = (
                    i as f32 / 39.0 * core::f32::consts::PI,
                    j as f32 / 80.0 * core::f32::consts::TAU,
                );
                let n = [
                    libm::sinf(t) * libm::cosf(p),
                    libm::sinf(t) * libm::sinf(p),
                    libm::cosf(t),
                ];
                let d = octahedral_decode(octahedral_encode(n));
                worst = worst.min(n[0] * d[0] + n[1] * d[1] + n[2] * d[2]);
            }
        }
        // cos(0.1°) = 1 - 1.5e-6; f32 dot products resolve about 1e-7.
        assert!(worst > 1.0 - 1.5e-6, "{worst}");
    }

    #[test]
    fn creator_packs_node_and_side() {
        let c = Creator::new(NodeId(12345), true);
        assert_eq!((c.node(), c.is_right()), (Some(NodeId(12345)), true));
        assert_eq!(Creator::new(NodeId(7), false).node(), Some(NodeId(7)));
        assert_eq!(Creator::BASE.node(), None);
        assert_ne!(Creator::new(NodeId((1 << 31) - 2), true), Creator::BASE);
    }
}
