//! The header, the section table and the look-up of the known sections.

use bytemuck::Pod;

use super::materials::AppearanceSections;
use crate::checksum::checksum64;
use crate::format::materials::material_tags;
use crate::format::{
    tags, ExtraSection, FileHeader, FormatError, HierarchyParts, Meta, SectionEntry, Tag,
    FLAG_PAGED, MAGIC, MAX_SECTIONS, SECTION_ALIGN, VERSION_MAJOR,
};

/// The sections of a parsed file, before validation.
pub(crate) struct Parsed<'a> {
    pub parts: HierarchyParts<'a>,
    pub meta: Meta,
    pub checksum: u64,
    pub appearance: AppearanceSections<'a>,
}

/// The section table of `bytes` after its header checks, with the checksum of every byte
/// after the header verified or not (a file a [`Hierarchy`](crate::Hierarchy) was made from
/// was verified once already: looking a section up again must not read the whole file
/// again); entry `i` is valid if the function returned `Ok`.
pub(crate) fn section_table_checked(
    bytes: &[u8],
    verify_checksum: bool,
) -> Result<(SectionTable<'_>, u64), FormatError> {
    section_table_flagged(bytes, verify_checksum, 0)
}

/// [`section_table_checked`] for a file whose header may carry `allowed_flags` (a paged
/// file's root: [`FLAG_PAGED`]).
pub(crate) fn section_table_flagged(
    bytes: &[u8],
    verify_checksum: bool,
    allowed_flags: u32,
) -> Result<(SectionTable<'_>, u64), FormatError> {
    let header = header(bytes, allowed_flags)?;
    let header_len = core::mem::size_of::<FileHeader>();
    let table_len = header.section_count as usize * core::mem::size_of::<SectionEntry>();
    if bytes.len() < header_len + table_len {
        return Err(FormatError::Truncated {
            needed: (header_len + table_len) as u64,
            len: bytes.len() as u64,
        });
    }
    let computed = if verify_checksum {
        checksum64(&bytes[header_len..])
    } else {
        header.checksum
    };
    if computed != header.checksum {
        return Err(FormatError::ChecksumMismatch {
            stored: header.checksum,
            computed,
        });
    }
    let table = SectionTable {
        bytes: &bytes[header_len..header_len + table_len],
    };
    entries(table, (header_len + table_len) as u64, bytes.len() as u64)?;
    Ok((table, header.checksum))
}

/// The header's fields: magic, version, lengths, zero flags and reserved words, and a
/// section count within [`MAX_SECTIONS`].
fn header(bytes: &[u8], allowed_flags: u32) -> Result<FileHeader, FormatError> {
    let header_len = core::mem::size_of::<FileHeader>();
    if bytes.len() < header_len {
        return Err(FormatError::Truncated {
            needed: header_len as u64,
            len: bytes.len() as u64,
        });
    }
    let header: FileHeader = bytemuck::pod_read_unaligned(&bytes[..header_len]);
    if header.magic != MAGIC {
        return Err(FormatError::BadMagic);
    }
    if header.version_major != VERSION_MAJOR {
        return Err(FormatError::UnsupportedVersion {
            major: header.version_major,
            minor: header.version_minor,
        });
    }
    if header.header_len as usize != header_len {
        return Err(FormatError::BadHeader {
            field: "header_len",
            value: header.header_len.into(),
        });
    }
    if header.flags == FLAG_PAGED && allowed_flags & FLAG_PAGED == 0 {
        return Err(FormatError::Paged);
    }
    let len = bytes.len() as u64;
    if header.file_len > len {
        return Err(FormatError::LengthMismatch {
            header: header.file_len,
            actual: len,
        });
    }
    if header.file_len < len {
        return Err(FormatError::TrailingBytes {
            expected: header.file_len,
            len,
        });
    }
    if header.flags & !allowed_flags != 0 {
        return Err(FormatError::BadHeader {
            field: "flags",
            value: header.flags.into(),
        });
    }
    if let Some(&r) = header.reserved.iter().find(|&&r| r != 0) {
        return Err(FormatError::BadHeader {
            field: "reserved",
            value: r.into(),
        });
    }
    if header.section_count > MAX_SECTIONS {
        return Err(FormatError::BadHeader {
            field: "section_count",
            value: header.section_count.into(),
        });
    }
    Ok(header)
}

/// Each entry: a non-zero record size, an aligned offset after the table and the previous
/// section, and an end within the file (`file_len`).
fn entries(table: SectionTable<'_>, table_end: u64, file_len: u64) -> Result<(), FormatError> {
    let mut end_of_previous = table_end;
    for (i, e) in table.iter().enumerate() {
        let problem = |problem| FormatError::SectionTable {
            index: i as u32,
            tag: e.tag,
            problem,
        };
        if e.record_size == 0 {
            return Err(problem("record size is zero"));
        }
        if e.offset % SECTION_ALIGN as u64 != 0 {
            return Err(problem("offset is not a multiple of 64"));
        }
        if e.offset < end_of_previous {
            return Err(problem("overlaps the table or the previous section"));
        }
        let len = (e.record_size as u64)
            .checked_mul(e.record_count)
            .ok_or(problem("length overflows"))?;
        let end = e
            .offset
            .checked_add(len)
            .ok_or(problem("length overflows"))?;
        if end > file_len {
            return Err(problem("extends past the end of the file"));
        }
        end_of_previous = end;
    }
    Ok(())
}

/// The section table, read entry by entry (its `u64` fields need no alignment from the
/// caller's buffer: only the sections' own records, at most 4-byte aligned, are cast in
/// place).
#[derive(Clone, Copy)]
pub(crate) struct SectionTable<'a> {
    bytes: &'a [u8],
}

impl SectionTable<'_> {
    pub(crate) fn iter(&self) -> impl Iterator<Item = SectionEntry> + '_ {
        self.bytes
            .chunks_exact(core::mem::size_of::<SectionEntry>())
            .map(bytemuck::pod_read_unaligned)
    }
}

/// The entry of `tag`, if the table has one; an error if it has two.
pub(crate) fn find(table: SectionTable<'_>, tag: Tag) -> Result<Option<SectionEntry>, FormatError> {
    let mut found: Option<SectionEntry> = None;
    for e in table.iter() {
        if e.tag == tag {
            if found.is_some() {
                return Err(FormatError::DuplicateSection { tag });
            }
            found = Some(e);
        }
    }
    Ok(found)
}

/// The records of `tag`, if present: of this version's record size and castable in place.
pub(crate) fn optional_section<'a, T: Pod>(
    bytes: &'a [u8],
    table: SectionTable<'_>,
    tag: Tag,
) -> Result<Option<&'a [T]>, FormatError> {
    let Some(e) = find(table, tag)? else {
        return Ok(None);
    };
    let expected = core::mem::size_of::<T>() as u32;
    if e.record_size != expected {
        return Err(FormatError::RecordSize {
            tag,
            expected,
            found: e.record_size,
        });
    }
    // In range: checked by `section_table_checked`.
    let start = e.offset as usize;
    let end = start + e.record_size as usize * e.record_count as usize;
    bytemuck::try_cast_slice(&bytes[start..end])
        .map(Some)
        .map_err(|_| FormatError::Misaligned { tag })
}

pub(crate) fn section<'a, T: Pod>(
    bytes: &'a [u8],
    table: SectionTable<'_>,
    tag: Tag,
) -> Result<&'a [T], FormatError> {
    optional_section(bytes, table, tag)?.ok_or(FormatError::MissingSection { tag })
}

/// The appearance sections of a file (found and cast, not validated).
fn appearance_sections<'a>(
    bytes: &'a [u8],
    table: SectionTable<'_>,
) -> Result<AppearanceSections<'a>, FormatError> {
    Ok(AppearanceSections {
        materials: optional_section(bytes, table, material_tags::MATERIALS)?,
        blob: optional_section(bytes, table, material_tags::BLOB)?,
        vertex_colours: optional_section(bytes, table, material_tags::VERTEX_COLOURS)?,
    })
}

/// The appearance sections among a writer's extra sections, found and cast as a reader
/// would find them in the written file.
pub(crate) fn appearance_extras<'a>(
    extra: &[ExtraSection<'a>],
) -> Result<AppearanceSections<'a>, FormatError> {
    fn one<'a, T: Pod>(
        extra: &[ExtraSection<'a>],
        tag: Tag,
    ) -> Result<Option<&'a [T]>, FormatError> {
        let mut found = extra.iter().filter(|e| e.tag == tag);
        let Some(e) = found.next() else {
            return Ok(None);
        };
        if found.next().is_some() {
            return Err(FormatError::DuplicateSection { tag });
        }
        let expected = core::mem::size_of::<T>() as u32;
        if e.record_size != expected {
            return Err(FormatError::RecordSize {
                tag,
                expected,
                found: e.record_size,
            });
        }
        bytemuck::try_cast_slice(e.bytes)
            .map(Some)
            .map_err(|_| FormatError::Misaligned { tag })
    }
    Ok(AppearanceSections {
        materials: one(extra, material_tags::MATERIALS)?,
        blob: one(extra, material_tags::BLOB)?,
        vertex_colours: one(extra, material_tags::VERTEX_COLOURS)?,
    })
}

/// Finds the known sections of `bytes` (header, table and checksum checked), without
/// validating their contents.
pub(crate) fn parse(bytes: &[u8]) -> Result<Parsed<'_>, FormatError> {
    parse_checked(bytes, true)
}

/// [`parse`], with the checksum verified or not (see [`section_table_checked`]).
pub(crate) fn parse_checked(
    bytes: &[u8],
    verify_checksum: bool,
) -> Result<Parsed<'_>, FormatError> {
    let (table, checksum) = section_table_checked(bytes, verify_checksum)?;
    let meta_records: &[Meta] = section(bytes, table, tags::META)?;
    let meta = match meta_records {
        [m] => *m,
        _ => {
            return Err(FormatError::Count {
                tag: tags::META,
                expected: 1,
                found: meta_records.len() as u64,
            })
        }
    };
    let parts = HierarchyParts {
        positions: section(bytes, table, tags::POSITIONS)?,
        nodes: section(bytes, table, tags::NODES)?,
        splits: section(bytes, table, tags::SPLITS)?,
        bounds: section(bytes, table, tags::BOUNDS)?,
        polygons: section(bytes, table, tags::POLYGONS)?,
        roots: section(bytes, table, tags::ROOTS)?,
        base: section(bytes, table, tags::BASE)?,
        vertex_table_offsets: section(bytes, table, tags::VERTEX_TABLE_OFFSETS)?,
        vertex_table: section(bytes, table, tags::VERTEX_TABLE)?,
        vertices: section(bytes, table, tags::VERTICES)?,
        surface_count: meta.surface_count,
        surface_group_count: meta.surface_group_count,
    };
    Ok(Parsed {
        parts,
        meta,
        checksum,
        appearance: appearance_sections(bytes, table)?,
    })
}
