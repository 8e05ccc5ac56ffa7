//! The baked `.clod` file format.
//!
//! ```text
//! offset 0   FileHeader (64 bytes): magic "CAVECLOD", version, file length, section count,
//!            checksum of every byte after the header
//! offset 64  SectionEntry x section_count (24 bytes each): tag, record size, offset, count
//! ...        sections, each starting at a multiple of 64, zero padding between them
//! ```
//!
//! All integers are little-endian; the records ([`Node`], [`Split`], [`SplitBounds`],
//! [`Polygon`], [`Position`], [`BaseFace`], [`VertexKey`], [`Vertex`], [`Meta`]) are
//! `#[repr(C)]`, so on a little-endian machine a section is a slice of records cast in place ([`Hierarchy::from_bytes`](crate::Hierarchy::from_bytes) never copies).
//! Sections are found by tag; a reader skips tags it does not know, so later versions can add
//! sections (g-mesh levels, out-of-core octrees, materials) without breaking older readers.
//! A change to a known section's record size or meaning bumps the major version.
//!
//! Besides the hierarchy's sections ([`tags`]), a file may carry these, defined and validated
//! by their own modules and written as [`ExtraSection`]s:
//!
//! | tags   | what | defined in |
//! |--------|------|------------|
//! | `GMPC`, `GMBD`, `GMVL`, `GMVO`, `GMIO`, `GMVX`, `GMIX` | g-mesh levels | [`gmesh_tags`](crate::gmesh::gmesh_tags) |
//! | `OCMT`, `OCND`, `OCRG`, `OCVX`, `OCIX` | multiresolution octree (meta, nodes, per-surface ranges, vertices, indices) | [`octree_tags`](crate::octree::octree_tags) |
//! | `MATL`, `MBLB` | one material per surface (64-byte records) and the bytes they point into: names, texture paths, embedded images | [`materials`] |
//! | `VCOL` | one RGBA8 colour per vertex (sRGB red, green, blue; linear alpha) | [`materials`] |
//! | `INFO` | the bake's figures, UTF-8 JSON | `caveclod-bake` (`report.rs`) |
//!
//! The appearance sections (`MATL`, `MBLB`, `VCOL`) are optional, and validated with the
//! hierarchy when present: [`Hierarchy::materials`](crate::Hierarchy::materials) and
//! [`Hierarchy::vertex_colours`](crate::Hierarchy::vertex_colours) give them.
//!
//! The writer side needs no allocation either. [`write_into`] fills a buffer sized by
//! [`serialized_len`]; a file too large to hold in memory is written section by section
//! through a [`FilePlan`] and a [`SectionWriter`] (the same layout), after
//! [`validate_parts`] or followed by reading the written file back. A std caller writes
//! through a temporary file and a rename either way.

pub(crate) mod error;
pub mod materials;
pub mod paged;
mod parts;
mod plan;
pub(crate) mod records;
pub(crate) mod validate;
mod writer;

pub(crate) use error::FormatError;
pub use error::WriteError;
pub use parts::{ExtraSection, HierarchyParts};
pub use plan::{FilePlan, SectionList, SectionSpec, SectionWriter, Sink, StreamError};
pub use records::{
    octahedral_decode, octahedral_encode, BaseFace, Creator, Meta, Node, Polygon, Position,
    PositionClass, Split, SplitBounds, Vertex, VertexKey,
};
pub use validate::{OnePiece, Pieces};
pub use writer::{serialized_len, validate_parts, write_into, KNOWN_SECTIONS};

pub use crate::checksum::{checksum64, Checksum64};

use bytemuck::{Pod, Zeroable};

/// The file's first eight bytes.
pub const MAGIC: [u8; 8] = *b"CAVECLOD";
/// The major version this crate reads and writes. Files of another major version are refused.
pub const VERSION_MAJOR: u16 = 2;
/// The minor version this crate writes. Readers accept any minor version of their major.
pub const VERSION_MINOR: u16 = 0;
/// Alignment of every section's start, in bytes.
pub const SECTION_ALIGN: usize = 64;
/// The most sections a file may list.
pub const MAX_SECTIONS: u32 = 1024;

/// A four-byte section tag, e.g. `b"NODE"`.
#[repr(transparent)]
#[derive(Clone, Copy, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct Tag(pub [u8; 4]);

impl core::fmt::Debug for Tag {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        core::fmt::Display::fmt(self, f)
    }
}

impl core::fmt::Display for Tag {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        for &b in &self.0 {
            if b.is_ascii_graphic() {
                write!(f, "{}", b as char)?;
            } else {
                write!(f, "\\x{b:02x}")?;
            }
        }
        Ok(())
    }
}

/// Tags of the sections this version defines.
pub mod tags {
    use super::Tag;
    /// [`Meta`](crate::format::Meta): counts and bounds.
    pub const META: Tag = Tag(*b"META");
    /// [`Position`](crate::format::Position) per node position.
    pub const POSITIONS: Tag = Tag(*b"POSN");
    /// [`Node`](crate::format::Node) per node.
    pub const NODES: Tag = Tag(*b"NODE");
    /// [`Split`](crate::format::Split) per node that can be split.
    pub const SPLITS: Tag = Tag(*b"SPLT");
    /// [`SplitBounds`](crate::format::SplitBounds) per node that can be split.
    pub const BOUNDS: Tag = Tag(*b"BNDS");
    /// [`Polygon`](crate::format::Polygon) per full-resolution polygon.
    pub const POLYGONS: Tag = Tag(*b"POLY");
    /// [`NodeId`](crate::NodeId) per root, ascending.
    pub const ROOTS: Tag = Tag(*b"ROOT");
    /// [`BaseFace`](crate::format::BaseFace) per base polygon.
    pub const BASE: Tag = Tag(*b"BASE");
    /// `u32` per position plus one: where each position's vertex-table entries start.
    pub const VERTEX_TABLE_OFFSETS: Tag = Tag(*b"VTOF");
    /// [`VertexKey`](crate::format::VertexKey) per vertex-table entry.
    pub const VERTEX_TABLE: Tag = Tag(*b"VTAB");
    /// [`Vertex`](crate::format::Vertex) per vertex.
    pub const VERTICES: Tag = Tag(*b"VERT");
}

/// [`FileHeader::flags`]: the file is paged ([`paged`]), and its header is its root's.
pub const FLAG_PAGED: u32 = 1;

/// The fixed header at offset 0.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct FileHeader {
    /// [`MAGIC`].
    pub magic: [u8; 8],
    /// [`VERSION_MAJOR`].
    pub version_major: u16,
    /// [`VERSION_MINOR`] of the writer.
    pub version_minor: u16,
    /// `size_of::<FileHeader>()` (64).
    pub header_len: u32,
    /// Length of the whole file in bytes.
    pub file_len: u64,
    /// Entries in the section table.
    pub section_count: u32,
    /// Zero, or [`FLAG_PAGED`].
    pub flags: u32,
    /// [`checksum64`] of bytes `header_len..file_len`.
    pub checksum: u64,
    /// Zero.
    pub reserved: [u32; 6],
}

/// One entry of the section table.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct SectionEntry {
    /// What the section holds.
    pub tag: Tag,
    /// Size of one record in bytes.
    pub record_size: u32,
    /// Byte offset from the start of the file; a multiple of [`SECTION_ALIGN`].
    pub offset: u64,
    /// Number of records.
    pub record_count: u64,
}

const _: () = assert!(core::mem::size_of::<FileHeader>() == 64);
const _: () = assert!(core::mem::size_of::<SectionEntry>() == 24);

/// Rounds `n` up to a multiple of [`SECTION_ALIGN`].
pub(crate) const fn align_up(n: usize) -> usize {
    (n + SECTION_ALIGN - 1) & !(SECTION_ALIGN - 1)
}
