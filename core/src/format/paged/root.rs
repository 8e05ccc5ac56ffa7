//! A paged file's root: read and checked on its own, without any streamed page.

use super::check::{check_page, PageContext};
use super::layout::SegmentedId;
use super::meta::{paged_tags, PagedMeta};
use super::table::{PageEntry, PageTable};
use super::view::PageView;
use crate::format::records::{BaseFace, Meta};
use crate::format::validate::{find, invalid, optional_section, section, section_table_flagged};
use crate::format::FLAG_PAGED;
use crate::format::{tags, FileHeader, FormatError, Tag};
use crate::ids::NodeId;

/// The root of a paged file, validated: its counts, its page table, the base mesh and the
/// root pages (always resident). Made from the root's bytes alone; [`PagedMeta::file_len`]
/// says how long the whole file is.
#[derive(Clone, Copy, Debug)]
pub struct PagedRoot<'a> {
    meta: Meta,
    paged: PagedMeta,
    table: PageTable<'a>,
    roots: &'a [NodeId],
    base: &'a [BaseFace],
    root_pages: &'a [u8],
    root_pages_at: u64,
    checksum: u64,
    bytes: &'a [u8],
}

fn one<T: Copy>(records: &[T], tag: Tag) -> Result<T, FormatError> {
    match records {
        [r] => Ok(*r),
        _ => Err(FormatError::Count {
            tag,
            expected: 1,
            found: records.len() as u64,
        }),
    }
}

impl<'a> PagedRoot<'a> {
    /// Reads the root in `bytes` (exactly the root: its header's length) and checks every
    /// section of it, the root pages included. `bytes` must be 4-byte aligned.
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self, FormatError> {
        let (table, checksum) = section_table_flagged(bytes, true, FLAG_PAGED)?;
        let header: FileHeader =
            bytemuck::pod_read_unaligned(&bytes[..core::mem::size_of::<FileHeader>()]);
        if header.flags != FLAG_PAGED {
            return Err(FormatError::BadHeader {
                field: "flags",
                value: header.flags.into(),
            });
        }
        let meta = one(section::<Meta>(bytes, table, tags::META)?, tags::META)?;
        let pm = paged_tags::PAGED_META;
        let paged = one(section::<PagedMeta>(bytes, table, pm)?, pm)?;
        let entries: &[PageEntry] = section(bytes, table, paged_tags::PAGE_TABLE)?;
        let parents: &[u32] = section(bytes, table, paged_tags::PAGE_PARENTS)?;
        check_paged_meta(&paged, entries.len(), bytes.len() as u64)?;
        let page_table =
            PageTable::new(entries, parents, paged.file_len).map_err(|e| FormatError::Invalid {
                tag: paged_tags::PAGE_TABLE,
                record: e.page.into(),
                field: e.field.name(),
                problem: e.problem,
                value: 0,
            })?;
        let root = Self {
            meta,
            paged,
            table: page_table,
            roots: section(bytes, table, tags::ROOTS)?,
            base: section(bytes, table, tags::BASE)?,
            root_pages: optional_section(bytes, table, paged_tags::ROOT_PAGES)?.unwrap_or(&[]),
            root_pages_at: find(table, paged_tags::ROOT_PAGES)?.map_or(0, |e| e.offset),
            checksum,
            bytes,
        };
        if paged.largest_page != page_table.largest_page_from(paged.root_pages) {
            return Err(invalid(
                pm,
                0,
                "largest_page",
                "is not the largest streamed page's size",
                paged.largest_page.into(),
            ));
        }
        root.check_page_places()?;
        root.check_root_pages()?;
        root.check_base()?;
        Ok(root)
    }

    /// The whole hierarchy's counts and bounds.
    pub fn meta(&self) -> &Meta {
        &self.meta
    }

    /// How the file is cut.
    pub fn paged(&self) -> &PagedMeta {
        &self.paged
    }

    /// The page table, root pages first.
    pub fn table(&self) -> PageTable<'a> {
        self.table
    }

    /// How ids split into page and index.
    pub fn ids(&self) -> SegmentedId {
        // Checked in `from_bytes`.
        SegmentedId::new(self.paged.page_bits).unwrap_or(SegmentedId::MAX)
    }

    /// The roots (base-mesh nodes), in root pages.
    pub fn roots(&self) -> &'a [NodeId] {
        self.roots
    }

    /// The base mesh: polygon `i` of it is polygon `PolyId(i)`, the `i`-th of root page 0.
    pub fn base(&self) -> &'a [BaseFace] {
        self.base
    }

    /// The root's checksum: cameras record it to refuse another file.
    pub fn checksum(&self) -> u64 {
        self.checksum
    }

    /// The root's bytes.
    pub fn bytes(&self) -> &'a [u8] {
        self.bytes
    }

    /// The bytes of a section of the root by tag (materials, the bake's report, ...).
    pub fn section(&self, tag: Tag) -> Option<&'a [u8]> {
        let (table, _) = section_table_flagged(self.bytes, false, FLAG_PAGED).ok()?;
        optional_section::<u8>(self.bytes, table, tag)
            .ok()
            .flatten()
    }

    /// What a page's references are checked against.
    pub fn context(&self) -> PageContext<'a> {
        PageContext {
            table: self.table,
            ids: self.ids(),
            root_pages: self.paged.root_pages,
            base_polygons: self.base.len() as u32,
            surfaces: self.meta.surface_count,
            groups: self.meta.surface_group_count,
        }
    }

    /// The arrays of root page `page` (`None` for a streamed page).
    pub fn root_page(&self, page: u32) -> Option<PageView<'a>> {
        if page >= self.paged.root_pages {
            return None;
        }
        let e = self.table.entry(page)?;
        let start = usize::try_from(e.offset.checked_sub(self.root_pages_at)?).ok()?;
        let bytes = self
            .root_pages
            .get(start..start.checked_add(e.size as usize)?)?;
        PageView::cast(bytes, &self.table.layout(page)?).ok()
    }

    /// Checks streamed page `page`'s `bytes` (its checksum was checked by the pool):
    /// `resident` gives the views of its resident parents; root pages are found here.
    pub fn check_page<'p>(
        &self,
        page: u32,
        bytes: &[u8],
        resident: impl Fn(u32) -> Option<PageView<'p>>,
    ) -> Result<(), FormatError>
    where
        'a: 'p,
    {
        let layout = self.table.layout(page).ok_or(invalid(
            paged_tags::PAGE_TABLE,
            0,
            "page",
            "no such page",
            page.into(),
        ))?;
        let view = PageView::cast(bytes, &layout)?;
        check_page(&self.context(), page, &view, |p| {
            self.root_page(p).or_else(|| resident(p))
        })
    }

    /// Root pages lie in `PGRT`; streamed pages after the root.
    fn check_page_places(&self) -> Result<(), FormatError> {
        let root_end = self.root_pages_at + self.root_pages.len() as u64;
        for (page, e) in (0u32..).zip(self.table.entries()) {
            let end = e.offset + u64::from(e.size);
            let placed = if page < self.paged.root_pages {
                e.offset >= self.root_pages_at && end <= root_end
            } else {
                e.offset >= self.bytes.len() as u64
            };
            if !placed {
                return Err(FormatError::Invalid {
                    tag: paged_tags::PAGE_TABLE,
                    record: page.into(),
                    field: "offset",
                    problem: "a root page outside PGRT, or a streamed page inside the root",
                    value: e.offset,
                });
            }
        }
        Ok(())
    }

    /// Each root page's records, in page order (parents first).
    fn check_root_pages(&self) -> Result<(), FormatError> {
        let cx = self.context();
        for page in 0..self.paged.root_pages {
            let view = self.root_page(page).ok_or(FormatError::Misaligned {
                tag: paged_tags::ROOT_PAGES,
            })?;
            check_page(&cx, page, &view, |p| self.root_page(p))?;
        }
        Ok(())
    }

    /// Roots name parentless nodes of root pages; base polygons are root page 0's first
    /// polygons, and their faces name roots and base polygons.
    fn check_base(&self) -> Result<(), FormatError> {
        let ids = self.ids();
        let node = |id: NodeId| {
            self.root_page(ids.page(id.0))
                .and_then(|v| v.nodes.get(ids.index(id.0) as usize).copied())
        };
        for (i, &r) in self.roots.iter().enumerate() {
            if node(r).is_none_or(|n| n.parent.is_some()) {
                return Err(FormatError::Invalid {
                    tag: tags::ROOTS,
                    record: i as u64,
                    field: "root",
                    problem: "names no parentless node of a root page",
                    value: r.0.into(),
                });
            }
        }
        let first = self.root_page(0).map_or(0, |v| v.polygons.len());
        let nb = self.base.len();
        if nb == 0 || nb > first || nb > (1usize << ids.bits()) {
            return Err(invalid(
                tags::BASE,
                0,
                "base",
                "not the first polygons of root page 0",
                nb as u64,
            ));
        }
        for (i, f) in self.base.iter().enumerate() {
            let corners = f.corners.iter().all(|&c| node(c).is_some());
            let neighbours = f
                .neighbours
                .iter()
                .all(|n| n.is_none() || (n.0 as usize) < nb);
            if !(corners && neighbours) {
                return Err(FormatError::Invalid {
                    tag: tags::BASE,
                    record: i as u64,
                    field: "corners",
                    problem: "names no root-page node, or no base polygon",
                    value: 0,
                });
            }
        }
        Ok(())
    }
}

fn check_paged_meta(p: &PagedMeta, pages: usize, root_len: u64) -> Result<(), FormatError> {
    let tag = paged_tags::PAGED_META;
    if SegmentedId::new(p.page_bits).is_none() {
        return Err(invalid(
            tag,
            0,
            "page_bits",
            "not within 1..=31",
            p.page_bits.into(),
        ));
    }
    if p.page_count as usize != pages || p.root_pages > p.page_count || p.root_pages == 0 {
        return Err(invalid(
            tag,
            0,
            "page_count",
            "disagrees with PGTB, or no root page",
            p.page_count.into(),
        ));
    }
    if p.file_len < root_len || p.flags != 0 || p.reserved != [0; 9] {
        return Err(invalid(
            tag,
            0,
            "file_len",
            "shorter than the root, or flags set",
            p.file_len,
        ));
    }
    Ok(())
}
