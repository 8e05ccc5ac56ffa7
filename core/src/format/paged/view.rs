//! A page's arrays, cast in place from its bytes.

use bytemuck::Pod;

use super::layout::PageLayout;
use crate::format::records::{Node, Polygon, Position, Split, SplitBounds, Vertex, VertexKey};
use crate::format::{tags, FormatError, Tag};

/// The arrays of one page (or root page), borrowed from its bytes.
#[derive(Clone, Copy, Debug, Default)]
pub struct PageView<'a> {
    /// The page's nodes; the first `splits.len()` can be split.
    pub nodes: &'a [Node],
    /// Split record per node that can be split.
    pub splits: &'a [Split],
    /// Refinement bounds per node that can be split.
    pub bounds: &'a [SplitBounds],
    /// The polygons this page's splits create (and, in a root page, base polygons).
    pub polygons: &'a [Polygon],
    /// The node positions this page's nodes bring.
    pub positions: &'a [Position],
    /// Per position plus one: where its vertex-table entries start in `vertex_table`.
    pub vertex_table_offsets: &'a [u32],
    /// The vertex table's entries of this page's positions.
    pub vertex_table: &'a [VertexKey],
    /// The vertices at this page's positions.
    pub vertices: &'a [Vertex],
    /// RGBA8 per vertex, or empty.
    pub colours: &'a [[u8; 4]],
}

impl<'a> PageView<'a> {
    /// The arrays of `bytes` (a page laid out as `layout` says, on a 4-byte boundary).
    pub fn cast(bytes: &'a [u8], layout: &PageLayout) -> Result<Self, FormatError> {
        if bytes.len() < layout.len {
            return Err(FormatError::Truncated {
                needed: layout.len as u64,
                len: bytes.len() as u64,
            });
        }
        Ok(Self {
            nodes: array(bytes, &layout.nodes, tags::NODES)?,
            splits: array(bytes, &layout.splits, tags::SPLITS)?,
            bounds: array(bytes, &layout.bounds, tags::BOUNDS)?,
            polygons: array(bytes, &layout.polygons, tags::POLYGONS)?,
            positions: array(bytes, &layout.positions, tags::POSITIONS)?,
            vertex_table_offsets: array(
                bytes,
                &layout.vertex_table_offsets,
                tags::VERTEX_TABLE_OFFSETS,
            )?,
            vertex_table: array(bytes, &layout.vertex_table, tags::VERTEX_TABLE)?,
            vertices: array(bytes, &layout.vertices, tags::VERTICES)?,
            colours: array(bytes, &layout.colours, tags::VERTICES)?,
        })
    }

    /// The vertex-table entries of position `index` of this page (empty when out of range).
    #[inline]
    pub fn vertex_keys(&self, index: usize) -> &'a [VertexKey] {
        let o = self.vertex_table_offsets;
        match (o.get(index), index.checked_add(1).and_then(|i| o.get(i))) {
            (Some(&a), Some(&b)) => self.vertex_table.get(a as usize..b as usize).unwrap_or(&[]),
            _ => &[],
        }
    }
}

fn array<'a, T: Pod>(
    bytes: &'a [u8],
    range: &core::ops::Range<usize>,
    tag: Tag,
) -> Result<&'a [T], FormatError> {
    let b = bytes.get(range.clone()).ok_or(FormatError::Truncated {
        needed: range.end as u64,
        len: bytes.len() as u64,
    })?;
    bytemuck::try_cast_slice(b).map_err(|_| FormatError::Misaligned { tag })
}
