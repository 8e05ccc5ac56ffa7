//! Serialising owned arrays into `.clod` bytes without allocating.

use bytemuck::Pod;

use super::{
    align_up, tags, validate, FileHeader, SectionEntry, Tag, WriteError, MAGIC, VERSION_MAJOR,
    VERSION_MINOR,
};
use crate::checksum::checksum64;
use crate::format::{
    BaseFace, Meta, Node, Polygon, Position, Split, SplitBounds, Vertex, VertexKey,
};
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
    /// Its tag; must not be one of [`tags`].
    pub tag: Tag,
    /// Size of one record; `bytes.len()` must be a multiple of it.
    pub record_size: u32,
    /// The records.
    pub bytes: &'a [u8],
}

struct Planned<'a> {
    tag: Tag,
    record_size: u32,
    bytes: &'a [u8],
}

fn known<'a, T: Pod>(tag: Tag, records: &'a [T]) -> Planned<'a> {
    Planned {
        tag,
        record_size: core::mem::size_of::<T>() as u32,
        bytes: bytemuck::cast_slice(records),
    }
}

const KNOWN: usize = 11;

fn plan<'a>(parts: &HierarchyParts<'a>, meta: &'a Meta) -> [Planned<'a>; KNOWN] {
    [
        known(tags::META, core::slice::from_ref(meta)),
        known(tags::POSITIONS, parts.positions),
        known(tags::NODES, parts.nodes),
        known(tags::SPLITS, parts.splits),
        known(tags::BOUNDS, parts.bounds),
        known(tags::POLYGONS, parts.polygons),
        known(tags::ROOTS, parts.roots),
        known(tags::BASE, parts.base),
        known(tags::VERTEX_TABLE_OFFSETS, parts.vertex_table_offsets),
        known(tags::VERTEX_TABLE, parts.vertex_table),
        known(tags::VERTICES, parts.vertices),
    ]
}

fn layout_len<'a>(sections: impl Iterator<Item = (u32, &'a [u8])>, count: usize) -> usize {
    let mut at =
        align_up(core::mem::size_of::<FileHeader>() + count * core::mem::size_of::<SectionEntry>());
    for (_, bytes) in sections {
        at = align_up(at + bytes.len());
    }
    at
}

/// Bytes [`write_into`] will write for these parts and extra sections.
pub fn serialized_len(parts: &HierarchyParts<'_>, extra: &[ExtraSection<'_>]) -> usize {
    let meta = Meta::default();
    let known = plan(parts, &meta);
    layout_len(
        known
            .iter()
            .map(|s| (s.record_size, s.bytes))
            .chain(extra.iter().map(|s| (s.record_size, s.bytes))),
        KNOWN + extra.len(),
    )
}

/// Validates `parts` and the appearance sections among `extra` (materials and vertex
/// colours, [`materials`](crate::format::materials)) exactly as a reader would, then writes
/// the file into `out`. Returns the number of bytes written, [`serialized_len`].
pub fn write_into(
    parts: &HierarchyParts<'_>,
    extra: &[ExtraSection<'_>],
    out: &mut [u8],
) -> Result<usize, WriteError> {
    let meta = validate::validate(parts, None)?;
    for e in extra {
        let reserved = plan(parts, &meta).iter().any(|k| k.tag == e.tag);
        if reserved || e.record_size == 0 || e.bytes.len() % e.record_size as usize != 0 {
            return Err(WriteError::BadExtraSection { tag: e.tag });
        }
    }
    let appearance = validate::appearance_extras(extra)?;
    validate::appearance(
        &appearance,
        parts.surface_count as usize,
        parts.vertices.len(),
    )?;
    let needed = serialized_len(parts, extra);
    if out.len() < needed {
        return Err(WriteError::BufferTooSmall {
            needed,
            given: out.len(),
        });
    }
    let out = &mut out[..needed];
    out.fill(0);
    let known = plan(parts, &meta);
    let all = known
        .iter()
        .map(|s| (s.tag, s.record_size, s.bytes))
        .chain(extra.iter().map(|s| (s.tag, s.record_size, s.bytes)));
    let count = KNOWN + extra.len();
    let table_at = core::mem::size_of::<FileHeader>();
    let mut at = align_up(table_at + count * core::mem::size_of::<SectionEntry>());
    for (i, (tag, record_size, bytes)) in all.enumerate() {
        let entry = SectionEntry {
            tag,
            record_size,
            offset: at as u64,
            record_count: (bytes.len() / record_size as usize) as u64,
        };
        let e_at = table_at + i * core::mem::size_of::<SectionEntry>();
        out[e_at..e_at + core::mem::size_of::<SectionEntry>()]
            .copy_from_slice(bytemuck::bytes_of(&entry));
        out[at..at + bytes.len()].copy_from_slice(bytes);
        at = align_up(at + bytes.len());
    }
    let checksum = checksum64(&out[table_at..]);
    let header = FileHeader {
        magic: MAGIC,
        version_major: VERSION_MAJOR,
        version_minor: VERSION_MINOR,
        header_len: core::mem::size_of::<FileHeader>() as u32,
        file_len: needed as u64,
        section_count: count as u32,
        flags: 0,
        checksum,
        reserved: [0; 6],
    };
    out[..table_at].copy_from_slice(bytemuck::bytes_of(&header));
    Ok(needed)
}
