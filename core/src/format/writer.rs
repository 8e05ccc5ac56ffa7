//! Serialising owned arrays into `.clod` bytes without allocating, through the file's
//! [`FilePlan`].

use bytemuck::Pod;

use super::parts::{ExtraSection, HierarchyParts};
use super::plan::{FilePlan, SectionList, SectionSpec, SectionWriter, Sink, StreamError};
use super::{tags, validate, FileHeader, Tag, WriteError};
use crate::format::Meta;

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

/// Sections a hierarchy always has, in their file order.
pub const KNOWN_SECTIONS: [Tag; 11] = [
    tags::META,
    tags::POSITIONS,
    tags::NODES,
    tags::SPLITS,
    tags::BOUNDS,
    tags::POLYGONS,
    tags::ROOTS,
    tags::BASE,
    tags::VERTEX_TABLE_OFFSETS,
    tags::VERTEX_TABLE,
    tags::VERTICES,
];

const KNOWN: usize = KNOWN_SECTIONS.len();

fn known_sections<'a>(parts: &HierarchyParts<'a>, meta: &'a Meta) -> [Planned<'a>; KNOWN] {
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

/// The hierarchy's sections then the extra ones: the file's sections in order.
struct Listed<'a> {
    known: [Planned<'a>; KNOWN],
    extra: &'a [ExtraSection<'a>],
}

impl Listed<'_> {
    fn bytes(&self, i: usize) -> &[u8] {
        match self.known.get(i) {
            Some(k) => k.bytes,
            None => self.extra[i - KNOWN].bytes,
        }
    }
}

impl SectionList for Listed<'_> {
    fn count(&self) -> usize {
        KNOWN + self.extra.len()
    }
    fn spec(&self, i: usize) -> SectionSpec {
        let (tag, record_size, len) = match self.known.get(i) {
            Some(k) => (k.tag, k.record_size, k.bytes.len()),
            None => {
                let e = &self.extra[i - KNOWN];
                (e.tag, e.record_size, e.bytes.len())
            }
        };
        SectionSpec {
            tag,
            record_size,
            byte_len: len as u64,
        }
    }
}

/// Bytes [`write_into`] will write for these parts and extra sections (0 if they cannot be
/// planned: [`FilePlan::new`]).
pub fn serialized_len(parts: &HierarchyParts<'_>, extra: &[ExtraSection<'_>]) -> usize {
    let meta = Meta::default();
    let listed = Listed {
        known: known_sections(parts, &meta),
        extra,
    };
    FilePlan::new(&listed).map_or(0, |p| p.file_len() as usize)
}

/// Validates `parts` and the appearance sections among `extra` (materials and vertex
/// colours, [`materials`](crate::format::materials)) exactly as a reader would, and checks
/// that no extra section uses a tag of [`KNOWN_SECTIONS`] and each holds whole records.
/// Returns the `META` record the file carries. [`write_into`] calls it; a caller writing
/// the sections itself ([`SectionWriter`](super::SectionWriter)) calls it first.
pub fn validate_parts(
    parts: &HierarchyParts<'_>,
    extra: &[ExtraSection<'_>],
) -> Result<Meta, WriteError> {
    let meta = validate::validate(parts, None, &validate::OnePiece)?;
    for e in extra {
        let reserved = KNOWN_SECTIONS.contains(&e.tag);
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
    Ok(meta)
}

/// A [`Sink`] over a buffer.
struct SliceSink<'b> {
    out: &'b mut [u8],
    at: usize,
}

impl Sink for SliceSink<'_> {
    type Error = WriteError;
    fn put(&mut self, bytes: &[u8]) -> Result<(), WriteError> {
        let end = self.at + bytes.len();
        let Some(dst) = self.out.get_mut(self.at..end) else {
            return Err(WriteError::BufferTooSmall {
                needed: end,
                given: self.out.len(),
            });
        };
        dst.copy_from_slice(bytes);
        self.at = end;
        Ok(())
    }
}

fn flatten(e: StreamError<WriteError>) -> WriteError {
    match e {
        StreamError::Sink(e) | StreamError::Plan(e) => e,
    }
}

/// Validates `parts` and `extra` ([`validate_parts`]), then writes the file into `out`
/// through its [`FilePlan`]. Returns the number of bytes written, [`serialized_len`].
pub fn write_into(
    parts: &HierarchyParts<'_>,
    extra: &[ExtraSection<'_>],
    out: &mut [u8],
) -> Result<usize, WriteError> {
    let meta = validate_parts(parts, extra)?;
    let listed = Listed {
        known: known_sections(parts, &meta),
        extra,
    };
    let plan = FilePlan::new(&listed)?;
    let needed = plan.file_len() as usize;
    if out.len() < needed {
        return Err(WriteError::BufferTooSmall {
            needed,
            given: out.len(),
        });
    }
    let out = &mut out[..needed];
    let mut w = SectionWriter::new(plan, SliceSink { out, at: 0 }).map_err(flatten)?;
    for i in 0..listed.count() {
        w.put(listed.bytes(i)).map_err(flatten)?;
    }
    let (header, sink) = w.finish().map_err(flatten)?;
    sink.out[..core::mem::size_of::<FileHeader>()].copy_from_slice(bytemuck::bytes_of(&header));
    Ok(needed)
}
