//! The layout of a `.clod` file planned from its sections' sizes alone, and writing it one
//! section at a time.
//!
//! A [`FilePlan`] places every section from its tag, record size and byte length: where it
//! starts, the section table, the file's length. A [`SectionWriter`] then takes the sections'
//! bytes in file order, in as many pieces as the caller likes, passes them to a [`Sink`]
//! (a buffer, a file) with the section table and the zero padding between them, and keeps
//! the checksum as it goes; at the end it gives the header, which belongs at offset 0. So a
//! file can be written while only one section's bytes, or a part of one, exist at a time.
//! [`write_into`](super::write_into) writes through the same plan, so the two layouts are
//! one.
//!
//! The writer checks the bytes only against the plan (no section longer or shorter than
//! planned); what they mean is checked by [`validate_parts`](super::validate_parts) before
//! writing, or by reading the written file back.

use super::{
    align_up, FileHeader, SectionEntry, Tag, WriteError, MAGIC, MAX_SECTIONS, SECTION_ALIGN,
    VERSION_MAJOR, VERSION_MINOR,
};
use crate::checksum::Checksum64;

const HEADER_LEN: u64 = core::mem::size_of::<FileHeader>() as u64;
const ENTRY_LEN: u64 = core::mem::size_of::<SectionEntry>() as u64;
const ZEROS: [u8; SECTION_ALIGN] = [0; SECTION_ALIGN];

/// One section of a planned file: what it holds and how many bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SectionSpec {
    /// Its tag.
    pub tag: Tag,
    /// Size of one record; non-zero.
    pub record_size: u32,
    /// Its length in bytes; a multiple of `record_size`.
    pub byte_len: u64,
}

/// The sections of a file in file order, however the caller keeps them (a slice of
/// [`SectionSpec`]s, or records of its own), without allocating.
pub trait SectionList {
    /// How many sections.
    fn count(&self) -> usize;
    /// Section `i` (`i < count()`).
    fn spec(&self, i: usize) -> SectionSpec;
}

impl SectionList for [SectionSpec] {
    fn count(&self) -> usize {
        self.len()
    }
    fn spec(&self, i: usize) -> SectionSpec {
        self[i]
    }
}

/// Where the sections of a file go.
pub struct FilePlan<'s, L: SectionList + ?Sized = [SectionSpec]> {
    sections: &'s L,
    file_len: u64,
}

impl<L: SectionList + ?Sized> Clone for FilePlan<'_, L> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<L: SectionList + ?Sized> Copy for FilePlan<'_, L> {}

impl<L: SectionList + ?Sized> core::fmt::Debug for FilePlan<'_, L> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("FilePlan")
            .field("sections", &self.sections.count())
            .field("file_len", &self.file_len)
            .finish()
    }
}

fn aligned(n: u64) -> Option<u64> {
    let a = SECTION_ALIGN as u64;
    Some(n.checked_add(a - 1)? & !(a - 1))
}

impl<'s, L: SectionList + ?Sized> FilePlan<'s, L> {
    /// Plans the file. Fails if there are more than [`MAX_SECTIONS`] sections, if a section's
    /// record size is zero or its length not a whole number of records, or if the file's
    /// length does not fit 64 bits.
    pub fn new(sections: &'s L) -> Result<Self, WriteError> {
        let count = sections.count();
        if count > MAX_SECTIONS as usize {
            return Err(WriteError::TooManySections { count });
        }
        let mut at = Self::data_start_for(count);
        for i in 0..count {
            let s = sections.spec(i);
            if s.record_size == 0 || s.byte_len % u64::from(s.record_size) != 0 {
                return Err(WriteError::BadExtraSection { tag: s.tag });
            }
            at = at
                .checked_add(s.byte_len)
                .and_then(aligned)
                .ok_or(WriteError::TooLarge)?;
        }
        Ok(Self {
            sections,
            file_len: at,
        })
    }

    fn data_start_for(count: usize) -> u64 {
        // At most MAX_SECTIONS entries: no overflow.
        align_up((HEADER_LEN + count as u64 * ENTRY_LEN) as usize) as u64
    }

    /// The sections planned.
    pub fn sections(&self) -> &'s L {
        self.sections
    }

    /// The whole file's length in bytes.
    pub fn file_len(&self) -> u64 {
        self.file_len
    }

    /// Where the first section starts: after the header, the section table and padding.
    pub fn data_start(&self) -> u64 {
        Self::data_start_for(self.sections.count())
    }

    /// The section table's entries in order, each with its section's offset.
    pub fn entries(&self) -> impl Iterator<Item = SectionEntry> + '_ {
        let mut at = self.data_start();
        (0..self.sections.count()).map(move |i| {
            let s = self.sections.spec(i);
            let entry = SectionEntry {
                tag: s.tag,
                record_size: s.record_size,
                offset: at,
                record_count: s.byte_len / u64::from(s.record_size),
            };
            // `new` checked that every offset fits.
            at = at
                .checked_add(s.byte_len)
                .and_then(aligned)
                .unwrap_or(u64::MAX);
            entry
        })
    }

    /// The header of the file with this checksum of every byte after the header.
    pub fn header(&self, checksum: u64) -> FileHeader {
        FileHeader {
            magic: MAGIC,
            version_major: VERSION_MAJOR,
            version_minor: VERSION_MINOR,
            header_len: HEADER_LEN as u32,
            file_len: self.file_len,
            section_count: self.sections.count() as u32,
            flags: 0,
            checksum,
            reserved: [0; 6],
        }
    }
}

/// Where a [`SectionWriter`] puts the file's bytes, in file order.
pub trait Sink {
    /// Why putting failed.
    type Error;
    /// Appends `bytes`.
    fn put(&mut self, bytes: &[u8]) -> Result<(), Self::Error>;
}

/// Why writing through a [`SectionWriter`] failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StreamError<E> {
    /// The sink refused.
    Sink(E),
    /// The bytes given do not match the plan.
    Plan(WriteError),
}

impl<E: core::fmt::Display> core::fmt::Display for StreamError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Sink(e) => e.fmt(f),
            Self::Plan(e) => e.fmt(f),
        }
    }
}

impl<E: core::fmt::Debug + core::fmt::Display> core::error::Error for StreamError<E> {}

/// Writes a planned file section by section: the header's place (zeros), the section table,
/// then each section's bytes as they are given, with the padding between sections; the
/// checksum is kept as the bytes pass. [`finish`](Self::finish) gives the header to write
/// over the first [`size_of::<FileHeader>()`](FileHeader) bytes.
pub struct SectionWriter<'s, S: Sink, L: SectionList + ?Sized = [SectionSpec]> {
    plan: FilePlan<'s, L>,
    sink: S,
    checksum: Checksum64,
    /// The section the next bytes belong to (`count()` when all are written).
    section: usize,
    /// Bytes of it written so far.
    written: u64,
}

impl<'s, S: Sink, L: SectionList + ?Sized> SectionWriter<'s, S, L> {
    /// Writes the header's place and the section table into `sink`.
    pub fn new(plan: FilePlan<'s, L>, sink: S) -> Result<Self, StreamError<S::Error>> {
        let mut w = Self {
            plan,
            sink,
            checksum: Checksum64::new(),
            section: 0,
            written: 0,
        };
        w.sink
            .put(&ZEROS[..HEADER_LEN as usize])
            .map_err(StreamError::Sink)?;
        for e in plan.entries() {
            w.emit(bytemuck::bytes_of(&e))?;
        }
        let table_end = HEADER_LEN + plan.sections.count() as u64 * ENTRY_LEN;
        w.pad((plan.data_start() - table_end) as usize)?;
        w.skip_empty();
        Ok(w)
    }

    /// The section the next bytes go into, and how many of its bytes are still to come;
    /// `None` once every section is written.
    pub fn current(&self) -> Option<(SectionSpec, u64)> {
        (self.section < self.plan.sections.count()).then(|| {
            let s = self.plan.sections.spec(self.section);
            (s, s.byte_len - self.written)
        })
    }

    /// The next bytes of the current section; a section is complete when its planned length
    /// has been given, and the next one starts. Bytes beyond the current section's end are
    /// refused (nothing of them is written).
    pub fn put(&mut self, bytes: &[u8]) -> Result<(), StreamError<S::Error>> {
        if bytes.is_empty() {
            return Ok(());
        }
        let Some((spec, left)) = self.current() else {
            return Err(StreamError::Plan(WriteError::NotAsPlanned {
                tag: None,
                planned: 0,
                given: bytes.len() as u64,
            }));
        };
        if bytes.len() as u64 > left {
            return Err(StreamError::Plan(WriteError::NotAsPlanned {
                tag: Some(spec.tag),
                planned: spec.byte_len,
                given: self.written + bytes.len() as u64,
            }));
        }
        self.emit(bytes)?;
        self.written += bytes.len() as u64;
        if self.written == spec.byte_len {
            let end = (self.written % SECTION_ALIGN as u64) as usize;
            if end != 0 {
                self.pad(SECTION_ALIGN - end)?;
            }
            self.section += 1;
            self.written = 0;
            self.skip_empty();
        }
        Ok(())
    }

    /// Every section written: the file's header (to go at offset 0) and the sink. Fails if a
    /// section is still short of its planned length.
    pub fn finish(self) -> Result<(FileHeader, S), StreamError<S::Error>> {
        if let Some((spec, _)) = self.current() {
            return Err(StreamError::Plan(WriteError::NotAsPlanned {
                tag: Some(spec.tag),
                planned: spec.byte_len,
                given: self.written,
            }));
        }
        Ok((self.plan.header(self.checksum.finish()), self.sink))
    }

    fn skip_empty(&mut self) {
        while self.section < self.plan.sections.count()
            && self.plan.sections.spec(self.section).byte_len == 0
        {
            self.section += 1;
        }
    }

    fn pad(&mut self, n: usize) -> Result<(), StreamError<S::Error>> {
        self.emit(&ZEROS[..n])
    }

    fn emit(&mut self, bytes: &[u8]) -> Result<(), StreamError<S::Error>> {
        self.checksum.update(bytes);
        self.sink.put(bytes).map_err(StreamError::Sink)
    }
}
