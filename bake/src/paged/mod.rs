//! The paged `.clod`: a baked hierarchy cut into pages that stream into a fixed pool
//! ([`caveclod_core::format::paged`] defines the form; [`caveclod_core::stream`] the pool).
//!
//! [`write_paged`] reads a whole-file hierarchy (the in-core or the blocked bake's output)
//! and writes its paged form: the top of the hierarchy and the base mesh in the root page,
//! the rest in treelets, each a subtree's top levels (`partition`), every record renumbered
//! page-major (`renumber`). Pages are written first, after the root's planned length, then
//! the root with the page table; the file is read back (every page's checksum and records)
//! before it replaces the target. The materials and the bake's report travel in the root;
//! g-mesh levels and octrees, which name whole-file ids, are not carried.

mod error;
mod pages;
mod partition;
mod renumber;
mod root;

use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::path::Path;

use caveclod_core::format::paged::PagedRoot;
use caveclod_core::Hierarchy;

use crate::base::atomic::{temporary_sibling, write_atomically_with};

pub use error::PagedError;

/// How a paged file is cut.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PageOptions {
    /// Most bytes in a streamed page (the root page may be larger when the base mesh is).
    pub page_bytes: u32,
}

impl Default for PageOptions {
    fn default() -> Self {
        Self {
            page_bytes: 128 * 1024,
        }
    }
}

/// What a paged file holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PagedSummary {
    /// Pages, the root page included.
    pub pages: u32,
    /// Bytes of the root (read when the file is opened).
    pub root_bytes: u64,
    /// Bytes of the whole file.
    pub file_bytes: u64,
    /// The largest streamed page, in bytes.
    pub largest_page: u32,
    /// Bits of an id's index within its page.
    pub page_bits: u32,
}

/// Writes the paged form of `h` to `path` (through a temporary sibling and a rename).
pub fn write_paged(
    h: &Hierarchy<'_>,
    path: &Path,
    options: &PageOptions,
) -> Result<PagedSummary, PagedError> {
    let part = partition::partition(h, options.page_bytes)?;
    let r = renumber::renumber(h, &part)?;
    let parents = root::page_parents(h, &part);
    let first = pages::build_page(h, &r, &r.pages[0])?;
    let plan = root::RootPlan::new(h, &r, &parents, first.entry.size)?;
    let shown = path.display().to_string();
    let mut outcome = Err(PagedError::TooLarge);
    let written = write_atomically_with(path, |f| {
        outcome = write_file(f, h, &r, &parents, &first, &plan).and_then(|s| {
            read_back(&temporary_sibling(path), s.root_bytes)
                .map(|()| s)
                .map_err(|what| PagedError::ReadBack {
                    path: shown.clone(),
                    what,
                })
        });
        match &outcome {
            Ok(_) => Ok(()),
            Err(_) => Err(std::io::Error::other("the paged file was not written")),
        }
    });
    match (written, outcome) {
        (Ok(()), Ok(s)) => Ok(s),
        (_, Err(PagedError::Io { source, .. })) | (Err(source), Ok(_)) => Err(PagedError::Io {
            path: shown,
            source,
        }),
        (_, Err(e)) => Err(e),
    }
}

/// Pages after the root's planned length, then the root at the start.
fn write_file(
    f: &mut File,
    h: &Hierarchy<'_>,
    r: &renumber::Renumbered,
    parents: &[Vec<u32>],
    first: &pages::BuiltPage,
    plan: &root::RootPlan,
) -> Result<PagedSummary, PagedError> {
    let io = |source| PagedError::Io {
        path: String::new(),
        source,
    };
    let root_len = plan.root_len();
    f.seek(SeekFrom::Start(root_len)).map_err(io)?;
    let mut entries = vec![first.entry];
    let mut at = root_len;
    for m in &r.pages[1..] {
        let page = pages::build_page(h, r, m)?;
        f.write_all(page.bytes()).map_err(io)?;
        let mut e = page.entry;
        e.offset = at;
        at += u64::from(e.size);
        entries.push(e);
    }
    let root = plan.write(h, r, parents, first, &mut entries, at)?;
    f.seek(SeekFrom::Start(0)).map_err(io)?;
    f.write_all(&root).map_err(io)?;
    f.flush().map_err(io)?;
    Ok(PagedSummary {
        pages: entries.len() as u32,
        root_bytes: root_len,
        file_bytes: at,
        largest_page: entries[1..].iter().map(|e| e.size).max().unwrap_or(0),
        page_bits: r.ids.bits(),
    })
}

/// Reads the written file back as a reader would: the root, then every page against its
/// checksum and its parents.
fn read_back(written: &Path, root_len: u64) -> Result<(), String> {
    let f = File::open(written).map_err(|e| e.to_string())?;
    // SAFETY: the temporary file is this process's own and nothing else writes it while
    // the map lives.
    let map = unsafe { memmap2::Mmap::map(&f) }.map_err(|e| e.to_string())?;
    // A map starts on a page boundary: records cast in place.
    let bytes: &[u8] = &map[..];
    let root = PagedRoot::from_bytes(&bytes[..root_len as usize]).map_err(|e| e.to_string())?;
    let table = root.table();
    let view = |p: u32| {
        let e = table.entry(p)?;
        let b = bytes.get(e.offset as usize..(e.offset + u64::from(e.size)) as usize)?;
        caveclod_core::format::paged::PageView::cast(b, &table.layout(p)?).ok()
    };
    for page in root.paged().root_pages..table.len() as u32 {
        let e = table.entry(page).ok_or("page table")?;
        let b = &bytes[e.offset as usize..(e.offset + u64::from(e.size)) as usize];
        if caveclod_core::format::checksum64(b) != e.checksum {
            return Err(format!("page {page}: checksum"));
        }
        root.check_page(page, b, view)
            .map_err(|e| format!("page {page}: {e}"))?;
    }
    Ok(())
}
