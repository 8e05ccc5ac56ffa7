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
mod meta;
mod root;
mod table;
mod view;

pub use crate::format::FLAG_PAGED;
pub use check::{check_page, PageContext};
pub use layout::{PageArray, PageLayout, RecordKind, SegmentedId};
pub use meta::{paged_tags, PagedMeta, PAGE_HAS_COLOURS};
pub use root::PagedRoot;
pub use table::{PageEntry, PageField, PageTable, PageTableError};
pub use view::PageView;
