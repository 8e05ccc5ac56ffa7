//! A paged file's root sections: their tags, and how the file is cut.

use bytemuck::{Pod, Zeroable};

/// [`PageEntry::flags`](crate::format::paged::PageEntry::flags): the page holds a colour per
/// vertex.
pub const PAGE_HAS_COLOURS: u32 = 1;

/// Tags of a paged file's root sections.
pub mod paged_tags {
    use crate::format::Tag;
    /// [`PagedMeta`](super::PagedMeta).
    pub const PAGED_META: Tag = Tag(*b"PGMT");
    /// [`PageEntry`](crate::format::paged::PageEntry) per page, parents before children.
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
