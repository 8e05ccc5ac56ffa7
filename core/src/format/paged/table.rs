//! The page table of a paged file: where each page lies, how to check it, which pages must
//! be resident before it, and what loading it is worth.

use bytemuck::{Pod, Zeroable};

use super::layout::{PageLayout, RecordKind};
use super::meta::PAGE_HAS_COLOURS;
use crate::format::SECTION_ALIGN;

/// One page of a paged file (96 bytes): where it lies, how to check it, what must be
/// resident before it, what loading it is worth, and how many records of each kind it holds
/// (so references into it are checked while it is absent).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct PageEntry {
    /// Where the page's bytes start in the file: a multiple of
    /// [`SECTION_ALIGN`](crate::format::SECTION_ALIGN), so records cast in place from a slot.
    pub offset: u64,
    /// [`checksum64`](crate::format::checksum64) of the page's bytes.
    pub checksum: u64,
    /// The page's length in bytes.
    pub size: u32,
    /// Where this page's parents start in [`PAGE_PARENTS`](super::meta::paged_tags::PAGE_PARENTS).
    pub parents_start: u32,
    /// How many parents the page has: pages that must be resident before it (none when its
    /// nodes hang from the root only).
    pub parent_count: u32,
    /// The largest error bound of the page's splits (world units): the most a camera can
    /// gain by loading it.
    pub max_error: f32,
    /// Lower corner of the box around everything the page's splits touch.
    pub bounds_min: [f32; 3],
    /// Upper corner of that box.
    pub bounds_max: [f32; 3],
    /// How many records of each kind the page holds, in [`RecordKind`](super::RecordKind)
    /// order: nodes, splits, polygons, positions, vertex-table entries, vertices.
    pub counts: [u32; 6],
    /// Bit 0: the page holds a colour per vertex.
    pub flags: u32,
    /// Zero.
    pub reserved: [u32; 3],
}

const _: () = assert!(core::mem::size_of::<PageEntry>() == 96);

/// The field of a [`PageEntry`] a [`PageTableError`] names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PageField {
    /// [`PageEntry::offset`].
    Offset,
    /// [`PageEntry::size`].
    Size,
    /// [`PageEntry::parents_start`] and [`PageEntry::parent_count`].
    Parents,
    /// [`PageEntry::max_error`].
    MaxError,
    /// [`PageEntry::bounds_min`] and [`PageEntry::bounds_max`].
    Bounds,
    /// [`PageEntry::counts`] and [`PageEntry::flags`].
    Counts,
}

impl PageField {
    /// The field's name in the record.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Offset => "offset",
            Self::Size => "size",
            Self::Parents => "parents",
            Self::MaxError => "max_error",
            Self::Bounds => "bounds",
            Self::Counts => "counts",
        }
    }
}

/// Why a page table was refused: the page, the field and what is wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PageTableError {
    /// The page's index.
    pub page: u32,
    /// The field.
    pub field: PageField,
    /// What is wrong with it.
    pub problem: &'static str,
}

impl core::fmt::Display for PageTableError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "section {}: page {}: {}: {}",
            super::meta::paged_tags::PAGE_TABLE,
            self.page,
            self.field.name(),
            self.problem
        )
    }
}

impl core::error::Error for PageTableError {}

/// A validated page table: every page lies inside the file, its parents are earlier pages
/// (so the parent relation has no cycle and a pass in page order meets parents first), and
/// its figures are finite.
#[derive(Clone, Copy, Debug)]
pub struct PageTable<'a> {
    entries: &'a [PageEntry],
    parents: &'a [u32],
    largest: u32,
}

impl<'a> PageTable<'a> {
    /// Checks `entries` and `parents` against a file of `file_len` bytes.
    pub fn new(
        entries: &'a [PageEntry],
        parents: &'a [u32],
        file_len: u64,
    ) -> Result<Self, PageTableError> {
        if u32::try_from(entries.len()).is_err() {
            return Err(error(
                u32::MAX,
                PageField::Offset,
                "more pages than a u32 names",
            ));
        }
        let mut largest = 0;
        for (page, e) in (0u32..).zip(entries) {
            check_place(page, e, file_len)?;
            check_parents(page, e, parents)?;
            check_figures(page, e)?;
            check_counts(page, e)?;
            largest = largest.max(e.size);
        }
        Ok(Self {
            entries,
            parents,
            largest,
        })
    }

    /// The pages.
    #[inline]
    pub fn entries(&self) -> &'a [PageEntry] {
        self.entries
    }

    /// Number of pages.
    #[inline]
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// `true` if the file has no page: everything is in its root.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The layout of page `page`'s arrays (checked against its size in
    /// [`new`](Self::new)).
    pub fn layout(&self, page: u32) -> Option<PageLayout> {
        let e = self.entries.get(page as usize)?;
        PageLayout::new(e.counts, e.flags & PAGE_HAS_COLOURS != 0)
    }

    /// Page `page`'s entry (`page` below [`len`](Self::len)).
    #[inline]
    pub fn entry(&self, page: u32) -> Option<&'a PageEntry> {
        self.entries.get(page as usize)
    }

    /// The parents of page `page`, each an earlier page (empty for a page out of range).
    #[inline]
    pub fn parents(&self, page: u32) -> &'a [u32] {
        let Some(e) = self.entries.get(page as usize) else {
            return &[];
        };
        let start = e.parents_start as usize;
        // Validated in `new`.
        self.parents
            .get(start..start + e.parent_count as usize)
            .unwrap_or(&[])
    }

    /// The largest page, in bytes.
    #[inline]
    pub fn largest_page(&self) -> u32 {
        self.largest
    }

    /// The largest of the pages from `first` on, in bytes (0 if there are none): with
    /// `first` the root pages' count, what a pool's slots must hold.
    pub fn largest_page_from(&self, first: u32) -> u32 {
        let streamed = self.entries.get(first as usize..).unwrap_or(&[]);
        streamed.iter().map(|e| e.size).max().unwrap_or(0)
    }

    /// The most vertices any page from `first` on holds (0 if there are none): with `first`
    /// the root pages' count, what a device vertex pool's slots must hold.
    pub fn most_vertices_from(&self, first: u32) -> u32 {
        let streamed = self.entries.get(first as usize..).unwrap_or(&[]);
        let vertices = RecordKind::Vertices as usize;
        streamed
            .iter()
            .map(|e| e.counts[vertices])
            .max()
            .unwrap_or(0)
    }

    /// The vertices of the pages before `end` together: with `end` the root pages' count,
    /// what a file's always-resident root needs of a device vertex pool.
    pub fn vertices_before(&self, end: u32) -> u64 {
        let first = self.entries.get(..end as usize).unwrap_or(self.entries);
        let vertices = RecordKind::Vertices as usize;
        first.iter().map(|e| u64::from(e.counts[vertices])).sum()
    }
}

fn error(page: u32, field: PageField, problem: &'static str) -> PageTableError {
    PageTableError {
        page,
        field,
        problem,
    }
}

fn check_place(page: u32, e: &PageEntry, file_len: u64) -> Result<(), PageTableError> {
    if e.offset % SECTION_ALIGN as u64 != 0 {
        return Err(error(page, PageField::Offset, "not a multiple of 64"));
    }
    if e.size == 0 {
        return Err(error(page, PageField::Size, "zero"));
    }
    match e.offset.checked_add(u64::from(e.size)) {
        Some(end) if end <= file_len => Ok(()),
        _ => Err(error(
            page,
            PageField::Size,
            "runs past the end of the file",
        )),
    }
}

fn check_parents(page: u32, e: &PageEntry, parents: &[u32]) -> Result<(), PageTableError> {
    let start = e.parents_start as usize;
    let Some(list) = start
        .checked_add(e.parent_count as usize)
        .and_then(|end| parents.get(start..end))
    else {
        return Err(error(
            page,
            PageField::Parents,
            "range outside the parent list",
        ));
    };
    let mut previous = None;
    for &p in list {
        if p >= page {
            return Err(error(
                page,
                PageField::Parents,
                "names a page that is not earlier",
            ));
        }
        if previous.is_some_and(|q| q >= p) {
            return Err(error(page, PageField::Parents, "not strictly ascending"));
        }
        previous = Some(p);
    }
    Ok(())
}

fn check_counts(page: u32, e: &PageEntry) -> Result<(), PageTableError> {
    if e.flags & !PAGE_HAS_COLOURS != 0 || e.reserved != [0; 3] {
        return Err(error(
            page,
            PageField::Counts,
            "unknown flags or reserved words set",
        ));
    }
    match PageLayout::new(e.counts, e.flags & PAGE_HAS_COLOURS != 0) {
        Some(layout) if layout.len == e.size as usize => Ok(()),
        Some(_) => Err(error(
            page,
            PageField::Counts,
            "the arrays' length is not the page's size",
        )),
        None => Err(error(
            page,
            PageField::Counts,
            "more splits than nodes, or too large",
        )),
    }
}

fn check_figures(page: u32, e: &PageEntry) -> Result<(), PageTableError> {
    if !(e.max_error.is_finite() && e.max_error >= 0.0) {
        return Err(error(
            page,
            PageField::MaxError,
            "not a finite, non-negative number",
        ));
    }
    let finite = e
        .bounds_min
        .iter()
        .chain(&e.bounds_max)
        .all(|v| v.is_finite());
    let ordered = (0..3).all(|i| e.bounds_min[i] <= e.bounds_max[i]);
    if !(finite && ordered) {
        return Err(error(
            page,
            PageField::Bounds,
            "not a finite box with min <= max",
        ));
    }
    Ok(())
}
