//! The shared, static hierarchy: a read-only view of a baked file's sections.
//!
//! A [`Hierarchy`] borrows its arrays (from the file bytes, or from a builder's vectors) and
//! never changes them, so it is `Sync`: any number of cameras, on any threads, refine over one
//! hierarchy at once. Everything a camera changes lives in its own
//! [`CameraState`](crate::CameraState).

use crate::format::materials::Materials;
use crate::format::{self, FormatError, HierarchyParts, OnePiece, Pieces, Tag};
use crate::format::{
    BaseFace, Meta, Node, Polygon, Position, Split, SplitBounds, Vertex, VertexKey,
};
use crate::ids::{NodeId, PolyId, PolyKey, PositionId, SurfaceGroupId};

mod records;
pub use records::{Absent, HierarchyRecords};

/// A validated view-dependent hierarchy of vertex splits over a full-resolution mesh.
#[derive(Clone, Copy, Debug)]
pub struct Hierarchy<'a> {
    parts: HierarchyParts<'a>,
    meta: Meta,
    checksum: u64,
    file: &'a [u8],
    appearance: format::validate::Appearance<'a>,
}

impl<'a> Hierarchy<'a> {
    /// Views the sections of a `.clod` file in place and validates every index, count and
    /// invariant. `bytes` must be 4-byte aligned (any `Vec<u32>`-backed or allocator-provided
    /// buffer is); a misaligned buffer is an error, never a copy. Aligning it to 64 bytes is
    /// worth it: sections start on multiples of 64, so then no 32-byte record a refinement
    /// pass reads straddles two cache lines (`HierarchyBuf`, with the `alloc` feature, keeps its bytes
    /// so aligned). The optional materials and vertex colours are validated too.
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self, FormatError> {
        Self::from_bytes_in(bytes, &OnePiece)
    }

    /// [`from_bytes`](Self::from_bytes) with each validation pass run in the `pieces` of its
    /// records (on a caller's threads): the same checks and the same first error, whatever
    /// the pieces.
    pub fn from_bytes_in(bytes: &'a [u8], pieces: &impl Pieces) -> Result<Self, FormatError> {
        let parsed = format::validate::parse(bytes)?;
        let meta = format::validate::validate(&parsed.parts, Some(&parsed.meta), pieces)?;
        let appearance = format::validate::appearance(
            &parsed.appearance,
            parsed.parts.surface_count as usize,
            parsed.parts.vertices.len(),
        )?;
        Ok(Self {
            parts: parsed.parts,
            meta,
            checksum: parsed.checksum,
            file: bytes,
            appearance,
        })
    }

    /// The hierarchy of `bytes` that [`from_bytes`](Self::from_bytes) validated before, with
    /// the meta and checksum it found: the sections are found again (the header and the
    /// section table checked), but neither the checksum nor the hierarchy's invariants are
    /// computed again (the materials' few references are: their view is made by the check).
    /// Only for bytes that cannot have changed since.
    #[cfg(feature = "alloc")]
    pub(crate) fn from_validated(
        bytes: &'a [u8],
        meta: Meta,
        checksum: u64,
    ) -> Result<Self, FormatError> {
        let parsed = format::validate::parse_checked(bytes, false)?;
        let appearance = format::validate::appearance(
            &parsed.appearance,
            parsed.parts.surface_count as usize,
            parsed.parts.vertices.len(),
        )?;
        Ok(Self {
            parts: parsed.parts,
            meta,
            checksum,
            file: bytes,
            appearance,
        })
    }

    /// Validates arrays held in memory (for example a builder's) exactly as
    /// [`from_bytes`](Self::from_bytes) validates a file. Such a hierarchy has no materials
    /// and no vertex colours.
    pub fn from_parts(parts: HierarchyParts<'a>) -> Result<Self, FormatError> {
        Self::from_parts_in(parts, &OnePiece)
    }

    /// [`from_parts`](Self::from_parts) with each validation pass run in the `pieces` of its
    /// records (on a caller's threads): the same checks and the same first error, whatever
    /// the pieces.
    pub fn from_parts_in(
        parts: HierarchyParts<'a>,
        pieces: &impl Pieces,
    ) -> Result<Self, FormatError> {
        let meta = format::validate::validate(&parts, None, pieces)?;
        // An in-memory hierarchy is identified by its counts: mix them into a checksum so a
        // camera made for one hierarchy is refused by another.
        let checksum = crate::checksum::checksum64(bytemuck::bytes_of(&meta));
        Ok(Self {
            parts,
            meta,
            checksum,
            file: &[],
            appearance: format::validate::Appearance::default(),
        })
    }

    /// The arrays.
    pub fn parts(&self) -> &HierarchyParts<'a> {
        &self.parts
    }

    /// Counts and bounds.
    pub fn meta(&self) -> &Meta {
        &self.meta
    }

    /// The file's checksum (or, for [`from_parts`](Self::from_parts), a hash of the counts):
    /// cameras record it to refuse a hierarchy they were not made for.
    pub fn checksum(&self) -> u64 {
        self.checksum
    }

    /// The bytes of a section this version does not define (or any section), by tag.
    /// `None` for hierarchies made with [`from_parts`](Self::from_parts).
    pub fn section(&self, tag: Tag) -> Option<&'a [u8]> {
        // The file was validated, checksum included, when the hierarchy was made from it.
        let (table, _) = format::validate::section_table_checked(self.file, false).ok()?;
        let e = table.iter().find(|e| e.tag == tag)?;
        let e = &e;
        let start = e.offset as usize;
        self.file
            .get(start..start + e.record_size as usize * e.record_count as usize)
    }

    /// The surfaces' materials, one per surface, when the file has them (see
    /// [`materials`](crate::format::materials)).
    #[inline]
    pub fn materials(&self) -> Option<Materials<'a>> {
        self.appearance.materials
    }

    /// One colour per vertex of [`vertices`](Self::vertices), when the file has them: RGBA8,
    /// red, green and blue sRGB-encoded, alpha linear
    /// ([`vertex_colour_linear`](crate::format::materials::vertex_colour_linear) decodes one).
    #[inline]
    pub fn vertex_colours(&self) -> Option<&'a [[u8; 4]]> {
        self.appearance.vertex_colours
    }

    /// All node positions.
    #[inline]
    pub fn positions(&self) -> &'a [Position] {
        self.parts.positions
    }

    /// All nodes.
    #[inline]
    pub fn nodes(&self) -> &'a [Node] {
        self.parts.nodes
    }

    /// The split records; record `i` belongs to node `i`.
    #[inline]
    pub fn splits(&self) -> &'a [Split] {
        self.parts.splits
    }

    /// The refinement bounds; record `i` belongs to node `i`.
    #[inline]
    pub fn bounds(&self) -> &'a [SplitBounds] {
        self.parts.bounds
    }

    /// All full-resolution polygons, base polygons first.
    #[inline]
    pub fn polygons(&self) -> &'a [Polygon] {
        self.parts.polygons
    }

    /// The roots, ascending.
    #[inline]
    pub fn roots(&self) -> &'a [NodeId] {
        self.parts.roots
    }

    /// The base mesh: polygon `i` of it is polygon `PolyId(i)`.
    #[inline]
    pub fn base(&self) -> &'a [BaseFace] {
        self.parts.base
    }

    /// The persistent vertex buffer's contents.
    #[inline]
    pub fn vertices(&self) -> &'a [Vertex] {
        self.parts.vertices
    }

    /// Number of nodes (`n`).
    #[inline]
    pub fn node_count(&self) -> usize {
        self.parts.nodes.len()
    }

    /// Number of full-resolution polygons (`p`).
    #[inline]
    pub fn polygon_count(&self) -> usize {
        self.parts.polygons.len()
    }

    /// Number of base polygons.
    #[inline]
    pub fn base_polygon_count(&self) -> usize {
        self.parts.base.len()
    }

    /// Number of surfaces (index lists).
    #[inline]
    pub fn surface_count(&self) -> usize {
        self.parts.surface_count as usize
    }

    /// The split record of `node`, or `None` for a leaf or an id out of range.
    #[inline]
    pub fn split(&self, node: NodeId) -> Option<&'a Split> {
        self.parts.splits.get(node.index())
    }

    /// The refinement bounds of `node`, or `None` for a leaf or an id out of range.
    #[inline]
    pub fn split_bounds(&self, node: NodeId) -> Option<&'a SplitBounds> {
        self.parts.bounds.get(node.index())
    }

    /// The node record, or `None` for an id out of range.
    #[inline]
    pub fn node(&self, node: NodeId) -> Option<&'a Node> {
        self.parts.nodes.get(node.index())
    }

    /// The point of a node.
    #[inline]
    pub fn node_point(&self, node: NodeId) -> Option<[f32; 3]> {
        let n = self.node(node)?;
        self.parts.positions.get(n.position.index()).map(|p| p.xyz)
    }

    /// Asks for the cache line of `position`'s entry in the vertex table's offsets, ahead
    /// of a [`vertex_index`](Self::vertex_index) at that position.
    #[inline]
    pub(crate) fn prefetch_vertex_keys(&self, position: PositionId) {
        if let Some(o) = self.parts.vertex_table_offsets.get(position.index()) {
            crate::prefetch::line(o);
        }
    }

    /// The vertex-table entries of a position: one per surface group with a vertex there.
    #[inline]
    pub fn vertex_keys(&self, position: PositionId) -> &'a [VertexKey] {
        let o = self.parts.vertex_table_offsets;
        // `checked_add`: an absent id (`NONE`) is `usize::MAX` on a 32-bit target.
        let next = position.index().checked_add(1).and_then(|i| o.get(i));
        match (o.get(position.index()), next) {
            (Some(&a), Some(&b)) => self
                .parts
                .vertex_table
                .get(a as usize..b as usize)
                .unwrap_or(&[]),
            _ => &[],
        }
    }

    /// The vertex table: the vertex-buffer index of surface group `group` at `position`.
    /// O(log k) in the k groups meeting at the position (k = 1 inside a group).
    #[inline]
    pub fn vertex_index(&self, group: SurfaceGroupId, position: PositionId) -> Option<u32> {
        HierarchyRecords::vertex_index(self, group, position)
    }

    /// The number of (group, position) pairs the table could hold and how many it holds:
    /// the paper's "21-26% populated".
    pub fn vertex_table_fill(&self) -> (u64, u64) {
        (
            self.parts.surface_group_count as u64 * self.parts.positions.len() as u64,
            self.parts.vertex_table.len() as u64,
        )
    }

    /// The polygon a [`PolyKey`] names; `None` for `NONE` or a key no polygon has.
    #[inline]
    pub fn polygon_of(&self, key: PolyKey) -> Option<PolyId> {
        HierarchyRecords::polygon_of(self, key)
    }

    /// The [`PolyKey`] of `poly`; `None` for an id out of range.
    #[inline]
    pub fn key_of(&self, poly: PolyId) -> Option<PolyKey> {
        HierarchyRecords::key_of(self, poly)
    }

    /// Bytes of static data: every section's records.
    pub fn static_bytes(&self) -> usize {
        let p = &self.parts;
        core::mem::size_of::<Meta>()
            + core::mem::size_of_val(p.positions)
            + core::mem::size_of_val(p.nodes)
            + core::mem::size_of_val(p.splits)
            + core::mem::size_of_val(p.bounds)
            + core::mem::size_of_val(p.polygons)
            + core::mem::size_of_val(p.roots)
            + core::mem::size_of_val(p.base)
            + core::mem::size_of_val(p.vertex_table_offsets)
            + core::mem::size_of_val(p.vertex_table)
            + core::mem::size_of_val(p.vertices)
    }
}

impl HierarchyRecords for Hierarchy<'_> {
    #[inline]
    fn checksum(&self) -> u64 {
        Hierarchy::checksum(self)
    }

    #[inline]
    fn meta(&self) -> &Meta {
        Hierarchy::meta(self)
    }

    #[inline]
    fn roots(&self) -> &[NodeId] {
        Hierarchy::roots(self)
    }

    #[inline]
    fn base(&self) -> &[BaseFace] {
        Hierarchy::base(self)
    }

    #[inline]
    fn surface_count(&self) -> usize {
        Hierarchy::surface_count(self)
    }

    #[inline]
    fn split_id_bound(&self) -> usize {
        self.splits().len()
    }

    #[inline]
    fn vertex_id_bound(&self) -> usize {
        self.vertices().len()
    }

    #[inline]
    fn dense_ids(&self) -> bool {
        true
    }

    #[inline(always)]
    fn node(&self, node: NodeId) -> Option<&Node> {
        Hierarchy::node(self, node)
    }

    #[inline(always)]
    fn split(&self, node: NodeId) -> Option<&Split> {
        Hierarchy::split(self, node)
    }

    #[inline(always)]
    fn split_bounds(&self, node: NodeId) -> Option<&SplitBounds> {
        Hierarchy::split_bounds(self, node)
    }

    #[inline(always)]
    fn polygon(&self, poly: PolyId) -> Option<&Polygon> {
        self.polygons().get(poly.index())
    }

    #[inline(always)]
    fn position(&self, position: PositionId) -> Option<&Position> {
        self.positions().get(position.index())
    }

    #[inline(always)]
    fn vertex_keys(&self, position: PositionId) -> &[VertexKey] {
        Hierarchy::vertex_keys(self, position)
    }

    #[inline(always)]
    fn vertex(&self, vertex: u32) -> Option<&Vertex> {
        self.vertices().get(vertex as usize)
    }

    #[inline(always)]
    fn prefetch_vertex_keys(&self, position: PositionId) {
        Hierarchy::prefetch_vertex_keys(self, position);
    }

    #[inline]
    fn base_polygon_count(&self) -> usize {
        Hierarchy::base_polygon_count(self)
    }
}
