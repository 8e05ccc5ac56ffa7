//! The paged form of a `.clod` file: a small root always read, and pages read one at a time.
//!
//! ```text
//! root     a sectioned file of its own (header flag PAGED; its length and checksum are the
//!          root's): META, PGMT, ROOT, BASE, PGTB, PGPR, PGRT, and any optional section
//! pages    from the root's end, each on 64 bytes, each with its own checksum in PGTB
//! ```
//!
//! The hierarchy's records are grouped into pages (the bake chooses their size): a page holds
//! nodes with their split records, the polygons their splits create, and the positions,
//! vertex-table entries and vertices they bring. The first [`PagedMeta::root_pages`] pages
//! lie inside the root (section `PGRT`) and are always resident: the base mesh's nodes and
//! the top of the hierarchy. A page's parents are the pages holding its nodes' parents, all
//! earlier pages; a page is resident only with its parents, so a collapse never needs I/O.
//!
//! Ids are page-major: `(page << page_bits) | index`, the index counting that kind of record
//! within the page (nodes that can be split first, as in the whole-file form, so a node's
//! split record is the one at its index). A page's records lie in [`RecordKind`] order, each
//! array on 64 bytes ([`PageLayout`]); nothing in a page is an offset, so its layout follows
//! from its counts in the page table. A page is checked when it is installed: its checksum,
//! then every reference in it (within the page in full, into other pages by their counts).

mod check;
mod layout;
mod root;
mod table;
mod view;

pub use check::{check_page, PageContext};
pub use layout::{PageLayout, RecordKind, SegmentedId};
pub use root::PagedRoot;
pub use table::{PageEntry, PageField, PageTable, PageTableError};
pub use view::PageView;

use bytemuck::{Pod, Zeroable};

/// The header flag of a paged file's root.
pub const FLAG_PAGED: u32 = 1;

/// `PageEntry::flags`: the page holds a colour per vertex.
pub const PAGE_HAS_COLOURS: u32 = 1;

/// Tags of a paged file's root sections.
pub mod paged_tags {
    use crate::format::Tag;
    /// [`PagedMeta`](super::PagedMeta).
    pub const PAGED_META: Tag = Tag(*b"PGMT");
    /// [`PageEntry`](super::PageEntry) per page, parents before children.
    pub const PAGE_TABLE: Tag = Tag(*b"PGTB");
    /// `u32` page indices: each page's parents, a range of this list per page, ascending.
    pub const PAGE_PARENTS: Tag = Tag(*b"PGPR");
    /// The root pages' bytes, one after another as the page table places them.
    pub const ROOT_PAGES: Tag = Tag(*b"PGRT");
}

/// How a paged file is cut (the `PGMT` section, 64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct PagedMeta {
    /// Bits of an id's index within its page.
    pub page_bits: u32,
    /// Pages `0..root_pages` lie in the root and are always resident.
    pub root_pages: u32,
    /// Pages in all.
    pub page_count: u32,
    /// Zero.
    pub flags: u32,
    /// The whole file's length: the root and every page.
    pub file_len: u64,
    /// The largest page, in bytes.
    pub largest_page: u32,
    /// Zero.
    pub reserved: [u32; 9],
}

const _: () = assert!(core::mem::size_of::<PagedMeta>() == 64);
