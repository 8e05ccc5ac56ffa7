//! Errors of reading and writing `.clod` data. Each names what is wrong and where: the
//! section, the record index and the field.

use super::Tag;

/// Why bytes are not a valid hierarchy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FormatError {
    /// Fewer bytes than the header or the section table needs.
    Truncated {
        /// Bytes needed.
        needed: u64,
        /// Bytes given.
        len: u64,
    },
    /// The first eight bytes are not `CAVECLOD`.
    BadMagic,
    /// A major version this reader does not know.
    UnsupportedVersion {
        /// Major version in the file.
        major: u16,
        /// Minor version in the file.
        minor: u16,
    },
    /// A header field has a value this version does not allow.
    BadHeader {
        /// The field.
        field: &'static str,
        /// Its value.
        value: u64,
    },
    /// Fewer bytes were given than the header's file length records: a truncated file.
    LengthMismatch {
        /// Length the header records.
        header: u64,
        /// Bytes given.
        actual: u64,
    },
    /// More bytes were given than the header's file length records: bytes after the file's
    /// end (a file appended to, or a buffer passed whole instead of its file's bytes).
    TrailingBytes {
        /// Length the header records.
        expected: u64,
        /// Bytes given.
        len: u64,
    },
    /// The file is paged: its root is read on its own, and its pages as they are wanted
    /// ([`format::paged`](crate::format::paged)).
    Paged,
    /// The checksum does not match: the file is corrupt.
    ChecksumMismatch {
        /// Checksum the header records.
        stored: u64,
        /// Checksum of the bytes.
        computed: u64,
    },
    /// The bytes of a section cannot be cast to its records in place: the buffer given to
    /// `from_bytes` is not 4-byte aligned.
    Misaligned {
        /// The section.
        tag: Tag,
    },
    /// An entry of the section table is unusable.
    SectionTable {
        /// Index of the entry.
        index: u32,
        /// Its tag.
        tag: Tag,
        /// What is wrong.
        problem: &'static str,
    },
    /// A required section is absent.
    MissingSection {
        /// The section.
        tag: Tag,
    },
    /// A known section appears twice.
    DuplicateSection {
        /// The section.
        tag: Tag,
    },
    /// A known section's record size differs from this version's.
    RecordSize {
        /// The section.
        tag: Tag,
        /// Size this version defines.
        expected: u32,
        /// Size in the file.
        found: u32,
    },
    /// A section's record count disagrees with the counts in `META`.
    Count {
        /// The section.
        tag: Tag,
        /// Records the counts imply.
        expected: u64,
        /// Records present.
        found: u64,
    },
    /// A record breaks an invariant of the hierarchy.
    Invalid {
        /// The section.
        tag: Tag,
        /// Index of the record in its section.
        record: u64,
        /// The field.
        field: &'static str,
        /// The rule it breaks.
        problem: &'static str,
        /// The offending value (an id, a count, or raw float bits).
        value: u64,
    },
    /// A record's byte range lies outside the blob it points into.
    BlobRange {
        /// The section of the record.
        tag: Tag,
        /// Index of the record in its section.
        record: u64,
        /// The field holding the range.
        field: &'static str,
        /// First byte of the range.
        offset: u32,
        /// Bytes in the range.
        len: u32,
        /// Bytes in the blob.
        blob_len: u64,
    },
    /// A string a record points to is not UTF-8.
    NotUtf8 {
        /// The section of the record.
        tag: Tag,
        /// Index of the record in its section.
        record: u64,
        /// The field naming the string.
        field: &'static str,
    },
    /// A texture path is not a relative path with `/` between its components.
    BadPath {
        /// The section of the record.
        tag: Tag,
        /// Index of the record in its section.
        record: u64,
        /// What is wrong with it.
        problem: &'static str,
    },
}

impl core::fmt::Display for FormatError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Truncated { needed, len } => {
                write!(f, "truncated: {len} bytes, at least {needed} needed")
            }
            Self::BadMagic => write!(f, "not a .clod file (magic is not CAVECLOD)"),
            Self::UnsupportedVersion { major, minor } => {
                write!(
                    f,
                    "unsupported version {major}.{minor} (this reader: {}.x)",
                    super::VERSION_MAJOR
                )
            }
            Self::BadHeader { field, value } => {
                write!(f, "header field `{field}` = {value} is not allowed")
            }
            Self::LengthMismatch { header, actual } => {
                write!(
                    f,
                    "truncated: the header records {header} bytes but {actual} were given"
                )
            }
            Self::TrailingBytes { expected, len } => {
                write!(
                    f,
                    "the file is {len} bytes, {} more than its header records; expected \
                     exactly {expected} (extra bytes after its end)",
                    len - expected
                )
            }
            Self::Paged => write!(
                f,
                "a paged file: read its root with PagedRoot (caveclod_io::PagedFile) and stream \
                 its pages"
            ),
            Self::ChecksumMismatch { stored, computed } => {
                write!(f, "checksum mismatch: stored {stored:#018x}, computed {computed:#018x} (corrupt file)")
            }
            Self::Misaligned { tag } => {
                write!(
                    f,
                    "section {tag}: buffer not 4-byte aligned, cannot cast records in place"
                )
            }
            Self::SectionTable {
                index,
                tag,
                problem,
            } => {
                write!(f, "section table entry {index} ({tag}): {problem}")
            }
            Self::MissingSection { tag } => write!(f, "required section {tag} is missing"),
            Self::DuplicateSection { tag } => write!(f, "section {tag} appears more than once"),
            Self::RecordSize {
                tag,
                expected,
                found,
            } => {
                write!(
                    f,
                    "section {tag}: record size {found}, this version needs {expected}"
                )
            }
            Self::Count {
                tag,
                expected,
                found,
            } => {
                write!(
                    f,
                    "section {tag}: {found} records, the counts in META imply {expected}"
                )
            }
            Self::Invalid {
                tag,
                record,
                field,
                problem,
                value,
            } => {
                write!(
                    f,
                    "section {tag} record {record} field `{field}`: {problem} (value {value})"
                )
            }
            Self::BlobRange {
                tag,
                record,
                field,
                offset,
                len,
                blob_len,
            } => {
                write!(
                    f,
                    "section {tag} record {record} field `{field}`: bytes {offset}..{} lie \
                     outside the {blob_len}-byte blob",
                    u64::from(offset) + u64::from(len)
                )
            }
            Self::NotUtf8 { tag, record, field } => {
                write!(
                    f,
                    "section {tag} record {record} field `{field}`: not UTF-8"
                )
            }
            Self::BadPath {
                tag,
                record,
                problem,
            } => {
                write!(f, "section {tag} record {record} texture path: {problem}")
            }
        }
    }
}

impl core::error::Error for FormatError {}

/// Why [`write_into`](super::write_into) could not write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WriteError {
    /// The output buffer is smaller than [`serialized_len`](super::serialized_len).
    BufferTooSmall {
        /// Bytes needed.
        needed: usize,
        /// Bytes given.
        given: usize,
    },
    /// The parts do not form a valid hierarchy; nothing invalid is ever written.
    Invalid(FormatError),
    /// An extra section uses a tag this version defines, or its bytes are not a whole number
    /// of records.
    BadExtraSection {
        /// The section.
        tag: Tag,
    },
    /// More sections than [`MAX_SECTIONS`](super::MAX_SECTIONS).
    TooManySections {
        /// Sections given.
        count: usize,
    },
    /// The file's length does not fit 64 bits.
    TooLarge,
    /// A section's bytes, as written section by section, differ in length from its plan
    /// ([`SectionWriter`](super::SectionWriter)).
    NotAsPlanned {
        /// The section (`None`: bytes given after the last section).
        tag: Option<Tag>,
        /// Its planned length in bytes.
        planned: u64,
        /// Bytes given for it.
        given: u64,
    },
}

impl core::fmt::Display for WriteError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::BufferTooSmall { needed, given } => {
                write!(f, "output buffer of {given} bytes, {needed} needed")
            }
            Self::Invalid(e) => write!(f, "refusing to write an invalid hierarchy: {e}"),
            Self::BadExtraSection { tag } => {
                write!(
                    f,
                    "extra section {tag}: reserved tag or bytes not a whole number of records"
                )
            }
            Self::TooManySections { count } => {
                write!(
                    f,
                    "{count} sections, at most {} allowed",
                    super::MAX_SECTIONS
                )
            }
            Self::TooLarge => write!(f, "the file's length does not fit 64 bits"),
            Self::NotAsPlanned {
                tag: Some(tag),
                planned,
                given,
            } => write!(f, "section {tag}: {given} bytes given, {planned} planned"),
            Self::NotAsPlanned {
                tag: None, given, ..
            } => {
                write!(f, "{given} bytes given after the last section")
            }
        }
    }
}

impl core::error::Error for WriteError {}

impl From<FormatError> for WriteError {
    fn from(e: FormatError) -> Self {
        Self::Invalid(e)
    }
}
