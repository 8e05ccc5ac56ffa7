//! The octree's records, its sections and their validation.
//!
//! Sections (tags `OC..`, carried as extra sections of a `.clod` file, all little-endian):
//!
//! | tag    | record                        | per                         |
//! |--------|-------------------------------|-----------------------------|
//! | `OCMT` | [`OctreeMeta`] (32 bytes)     | one record                  |
//! | `OCND` | [`OctreeNode`] (48 bytes)     | node, breadth first         |
//! | `OCRG` | [`OctreeRange`] (12 bytes)    | node and surface with triangles |
//! | `OCVX` | [`Vertex`] (32 bytes)         | vertex, all levels          |
//! | `OCIX` | `u32`                         | triangle corner             |
//!
//! Everything is validated once in [`Octree::new`]; selection and emission then index with
//! the stored ids without re-checking.

use bytemuck::{Pod, Zeroable};

use crate::format::Vertex;
use crate::format::{ExtraSection, Tag};
use crate::Hierarchy;

use super::error::{OctreeFormatError, MAX_OCTREE_LEVELS};

/// Section tags of the multiresolution octree.
pub mod octree_tags {
    use crate::format::Tag;
    /// [`OctreeMeta`](super::OctreeMeta): counts (one record).
    pub const META: Tag = Tag(*b"OCMT");
    /// [`OctreeNode`](super::OctreeNode) per node, breadth first.
    pub const NODES: Tag = Tag(*b"OCND");
    /// [`OctreeRange`](super::OctreeRange) per node and surface with triangles.
    pub const RANGES: Tag = Tag(*b"OCRG");
    /// [`Vertex`](crate::format::Vertex) per octree vertex, all levels.
    pub const VERTICES: Tag = Tag(*b"OCVX");
    /// `u32` per triangle corner: indices into `OCVX`.
    pub const INDICES: Tag = Tag(*b"OCIX");
    /// All of them, in file order.
    pub const ALL: [Tag; 5] = [META, NODES, RANGES, VERTICES, INDICES];
}

/// Counts of an octree (the `OCMT` section, one record).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct OctreeMeta {
    /// Records of `OCND`.
    pub node_count: u32,
    /// Levels; the root's level is `level_count - 1`.
    pub level_count: u32,
    /// Records of `OCVX`.
    pub vertex_count: u32,
    /// Entries of `OCIX`.
    pub index_count: u32,
    /// Records of `OCRG`.
    pub range_count: u32,
    /// Surfaces (index lists); equal to the hierarchy's.
    pub surface_count: u32,
    /// Zero.
    pub reserved: [u32; 2],
}

/// One node of the octree: a block of one level (the `OCND` section).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct OctreeNode {
    /// Box of the node's triangles at its level (for a node without triangles, of its
    /// children); contains its children's boxes.
    pub min: [f32; 3],
    /// See `min`.
    pub max: [f32; 3],
    /// Object-space bound of the geometric error of drawing this node instead of the
    /// full-resolution input: finite, `>= 0`, and no smaller than any child's.
    pub error: f32,
    /// Level, 0 = finest; a child's level is its parent's minus one.
    pub level: u32,
    /// First child; children are consecutive.
    pub first_child: u32,
    /// Children; zero exactly at level 0.
    pub child_count: u32,
    /// First of the node's ranges in `OCRG`.
    pub first_range: u32,
    /// The node's ranges, one per surface it has triangles of, surfaces ascending.
    pub range_count: u32,
}

impl OctreeNode {
    /// The node's children, as a range of node ids.
    pub fn children(&self) -> core::ops::Range<u32> {
        self.first_child..self.first_child.saturating_add(self.child_count)
    }
}

/// One surface's triangles of one node (the `OCRG` section).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct OctreeRange {
    /// The surface (index list) the triangles belong to.
    pub surface: u32,
    /// First entry in `OCIX`.
    pub first_index: u32,
    /// Entries, a positive multiple of 3.
    pub index_count: u32,
}

/// The arrays of an octree, borrowed (see the module docs for their meaning).
#[derive(Clone, Copy, Debug)]
pub struct OctreeParts<'a> {
    /// Counts.
    pub meta: OctreeMeta,
    /// Nodes, breadth first; node 0 is the root.
    pub nodes: &'a [OctreeNode],
    /// Per-node, per-surface ranges of `indices`.
    pub ranges: &'a [OctreeRange],
    /// One vertex buffer for every level.
    pub vertices: &'a [Vertex],
    /// Triangle lists, indices into `vertices`.
    pub indices: &'a [u32],
}

impl<'a> OctreeParts<'a> {
    /// The five sections to write beside a hierarchy, in [`octree_tags::ALL`] order. The
    /// meta record is borrowed from `self`.
    pub fn sections(&self) -> [ExtraSection<'_>; 5] {
        fn s<T: Pod>(tag: Tag, records: &[T]) -> ExtraSection<'_> {
            ExtraSection {
                tag,
                record_size: core::mem::size_of::<T>() as u32,
                bytes: bytemuck::cast_slice(records),
            }
        }
        use octree_tags as t;
        [
            s(t::META, core::slice::from_ref(&self.meta)),
            s(t::NODES, self.nodes),
            s(t::RANGES, self.ranges),
            s(t::VERTICES, self.vertices),
            s(t::INDICES, self.indices),
        ]
    }
}

/// A validated multiresolution octree. Read-only and `Copy`: any number of
/// [`OctreeCut`](super::OctreeCut)s, on any threads, select over one octree.
#[derive(Clone, Copy, Debug)]
pub struct Octree<'a> {
    parts: OctreeParts<'a>,
    identity: u64,
}

fn cast<T: Pod>(tag: Tag, bytes: &[u8]) -> Result<&[T], OctreeFormatError> {
    bytemuck::try_cast_slice(bytes).map_err(|_| OctreeFormatError::BadSection(tag))
}

fn count(tag: Tag, expected: u32, got: usize) -> Result<(), OctreeFormatError> {
    if got as u64 == u64::from(expected) {
        Ok(())
    } else {
        Err(OctreeFormatError::CountMismatch {
            tag,
            expected: expected.into(),
            got: got as u64,
        })
    }
}

fn finite(v: &[f32]) -> bool {
    v.iter().all(|x| x.is_finite())
}

impl<'a> Octree<'a> {
    /// The octree sections of a hierarchy loaded from bytes: `Ok(None)` when it has none.
    /// The octree must describe the hierarchy's surfaces.
    pub fn from_hierarchy(h: &Hierarchy<'a>) -> Result<Option<Self>, OctreeFormatError> {
        use octree_tags as t;
        // One look-up per tag: each costs a pass over the file (its checksum).
        let found = t::ALL.map(|tag| h.section(tag));
        if found.iter().all(Option::is_none) {
            return Ok(None);
        }
        let get = |i: usize| found[i].ok_or(OctreeFormatError::MissingSection(t::ALL[i]));
        let metas: &[OctreeMeta] = cast(t::META, get(0)?)?;
        let [meta] = metas else {
            return Err(OctreeFormatError::CountMismatch {
                tag: t::META,
                expected: 1,
                got: metas.len() as u64,
            });
        };
        let parts = OctreeParts {
            meta: *meta,
            nodes: cast(t::NODES, get(1)?)?,
            ranges: cast(t::RANGES, get(2)?)?,
            vertices: cast(t::VERTICES, get(3)?)?,
            indices: cast(t::INDICES, get(4)?)?,
        };
        let hierarchy = h.surface_count() as u32;
        if meta.surface_count != hierarchy {
            return Err(OctreeFormatError::SurfaceCount {
                octree: meta.surface_count,
                hierarchy,
            });
        }
        let mut o = Self::new(parts)?;
        // The file's checksum covers the octree sections: cuts made for another file are
        // refused even when the counts agree.
        o.identity ^= h.checksum();
        Ok(Some(o))
    }

    /// Validates `parts`: counts against the arrays, the tree (one root, breadth-first order,
    /// consecutive children, levels, errors and boxes nesting), the ranges and the indices.
    /// Linear in the size of the arrays.
    pub fn new(parts: OctreeParts<'a>) -> Result<Self, OctreeFormatError> {
        use octree_tags as t;
        let m = &parts.meta;
        count(t::NODES, m.node_count, parts.nodes.len())?;
        count(t::RANGES, m.range_count, parts.ranges.len())?;
        count(t::VERTICES, m.vertex_count, parts.vertices.len())?;
        count(t::INDICES, m.index_count, parts.indices.len())?;
        if m.surface_count > u32::from(u16::MAX) {
            return Err(OctreeFormatError::TooManySurfaces {
                surfaces: m.surface_count,
            });
        }
        if parts.nodes.is_empty() {
            return Err(OctreeFormatError::Empty);
        }
        if m.level_count == 0 || m.level_count > MAX_OCTREE_LEVELS {
            return Err(OctreeFormatError::LevelCount {
                levels: m.level_count,
            });
        }
        validate_nodes(&parts)?;
        validate_ranges(&parts)?;
        let vertex_count = parts.vertices.len() as u64;
        if let Some(index) = parts
            .indices
            .iter()
            .position(|&v| u64::from(v) >= vertex_count)
        {
            return Err(OctreeFormatError::VertexOutOfRange {
                index: index as u32,
                vertex: parts.indices[index],
            });
        }
        if let Some(vertex) = parts
            .vertices
            .iter()
            .position(|v| !(finite(&v.position) && finite(&v.normal) && finite(&v.uv)))
        {
            return Err(OctreeFormatError::VertexNotFinite {
                vertex: vertex as u32,
            });
        }
        Ok(Self {
            parts,
            identity: crate::checksum::checksum64(bytemuck::bytes_of(&parts.meta)),
        })
    }

    /// The arrays.
    pub fn parts(&self) -> &OctreeParts<'a> {
        &self.parts
    }

    /// Counts.
    pub fn meta(&self) -> &OctreeMeta {
        &self.parts.meta
    }

    /// What cuts record to refuse an octree they were not made for: a hash of the counts,
    /// mixed with the file's checksum for [`from_hierarchy`](Self::from_hierarchy).
    pub fn identity(&self) -> u64 {
        self.identity
    }

    /// Nodes, breadth first; node 0 is the root.
    pub fn nodes(&self) -> &'a [OctreeNode] {
        self.parts.nodes
    }

    /// All ranges.
    pub fn ranges(&self) -> &'a [OctreeRange] {
        self.parts.ranges
    }

    /// The vertex buffer of every level.
    pub fn vertices(&self) -> &'a [Vertex] {
        self.parts.vertices
    }

    /// All indices.
    pub fn indices(&self) -> &'a [u32] {
        self.parts.indices
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.parts.nodes.len()
    }

    /// Number of levels.
    pub fn level_count(&self) -> u32 {
        self.parts.meta.level_count
    }

    /// Number of surfaces.
    pub fn surface_count(&self) -> usize {
        self.parts.meta.surface_count as usize
    }

    /// One node (`None` past the last).
    pub fn node(&self, node: u32) -> Option<&'a OctreeNode> {
        self.parts.nodes.get(node as usize)
    }

    /// A node's ranges, surfaces ascending (empty past the last node).
    pub fn node_ranges(&self, node: u32) -> &'a [OctreeRange] {
        self.node(node).map_or(&[], |n| self.ranges_of(n))
    }

    /// The indices of a range of this octree (empty for a range out of bounds).
    pub fn range_indices(&self, range: &OctreeRange) -> &'a [u32] {
        let start = range.first_index as usize;
        self.parts
            .indices
            .get(start..start + range.index_count as usize)
            .unwrap_or(&[])
    }

    /// A node's ranges; the node's range bounds were validated.
    #[inline]
    pub(super) fn ranges_of(&self, n: &OctreeNode) -> &'a [OctreeRange] {
        let start = n.first_range as usize;
        self.parts
            .ranges
            .get(start..start + n.range_count as usize)
            .unwrap_or(&[])
    }
}

/// Tree invariants: breadth-first order with consecutive children ranges covering
/// `1..node_count` (one parent per node but the root), levels, errors, boxes.
fn validate_nodes(parts: &OctreeParts<'_>) -> Result<(), OctreeFormatError> {
    let nodes = parts.nodes;
    let n = nodes.len() as u64;
    for (i, node) in nodes.iter().enumerate() {
        let node_id = i as u32;
        if !finite(&node.min) || !finite(&node.max) || !node.error.is_finite() {
            return Err(OctreeFormatError::NotFinite { node: node_id });
        }
        if (0..3).any(|a| node.min[a] > node.max[a]) {
            return Err(OctreeFormatError::EmptyBox { node: node_id });
        }
        if node.error < 0.0 {
            return Err(OctreeFormatError::NegativeError { node: node_id });
        }
        if (node.level == 0) != (node.child_count == 0) {
            return Err(OctreeFormatError::BadLevel { node: node_id });
        }
    }
    if u64::from(nodes[0].level) + 1 != u64::from(parts.meta.level_count) {
        return Err(OctreeFormatError::BadLevel { node: 0 });
    }
    // `next`: the first node without a parent yet. Children ranges must follow each other
    // exactly, so every node gets one parent and the order is breadth first.
    let mut next = 1u64;
    for (i, node) in nodes.iter().enumerate() {
        let node_id = i as u32;
        if i as u64 >= next && i > 0 {
            return Err(OctreeFormatError::Orphan { node: node_id });
        }
        if node.child_count == 0 {
            continue;
        }
        let first = u64::from(node.first_child);
        let end = first + u64::from(node.child_count);
        if end > n {
            return Err(OctreeFormatError::ChildOutOfRange { node: node_id });
        }
        if first < next {
            return Err(OctreeFormatError::SharedChild { node: node_id });
        }
        if first > next {
            return Err(OctreeFormatError::Orphan { node: next as u32 });
        }
        for c in first..end {
            let child = &nodes[c as usize];
            let c = c as u32;
            if node.level.checked_sub(1) != Some(child.level) {
                return Err(OctreeFormatError::BadLevel { node: c });
            }
            if child.error > node.error {
                return Err(OctreeFormatError::ErrorAboveParent { node: c });
            }
            if (0..3).any(|a| child.min[a] < node.min[a] || child.max[a] > node.max[a]) {
                return Err(OctreeFormatError::ChildOutsideParent { node: c });
            }
        }
        next = end;
    }
    // Every node was below `next` when visited, so `next == n`: the ranges cover
    // `1..node_count` exactly.
    Ok(())
}

/// Ranges: within `OCRG`, surfaces ascending per node and below the surface count, index
/// counts positive multiples of 3 within `OCIX`, and a total that fits a `u32` (so no cut's
/// counts can overflow).
fn validate_ranges(parts: &OctreeParts<'_>) -> Result<(), OctreeFormatError> {
    let (ranges, surfaces) = (parts.ranges, parts.meta.surface_count);
    let index_len = parts.indices.len() as u64;
    for (r, range) in ranges.iter().enumerate() {
        let range_id = r as u32;
        if range.surface >= surfaces {
            return Err(OctreeFormatError::SurfaceOutOfRange { range: range_id });
        }
        if range.index_count == 0 || range.index_count % 3 != 0 {
            return Err(OctreeFormatError::BadIndexCount { range: range_id });
        }
        if u64::from(range.first_index) + u64::from(range.index_count) > index_len {
            return Err(OctreeFormatError::IndicesOutOfRange { range: range_id });
        }
    }
    let mut total = 0u64;
    for (i, node) in parts.nodes.iter().enumerate() {
        let node_id = i as u32;
        let start = u64::from(node.first_range);
        if start + u64::from(node.range_count) > ranges.len() as u64 {
            return Err(OctreeFormatError::RangesOutOfRange { node: node_id });
        }
        let own = &ranges[start as usize..(start + u64::from(node.range_count)) as usize];
        if own.windows(2).any(|w| w[0].surface >= w[1].surface) {
            return Err(OctreeFormatError::SurfacesNotAscending { node: node_id });
        }
        total += own.iter().map(|r| u64::from(r.index_count)).sum::<u64>();
        if total > u64::from(u32::MAX) {
            return Err(OctreeFormatError::TooManyIndices);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_have_the_contract_sizes() {
        assert_eq!(core::mem::size_of::<OctreeMeta>(), 32);
        assert_eq!(core::mem::size_of::<OctreeNode>(), 48);
        assert_eq!(core::mem::size_of::<OctreeRange>(), 12);
    }
}
