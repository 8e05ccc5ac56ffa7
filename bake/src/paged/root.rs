//! The root of a paged file: its sections planned before the pages are written (their
//! lengths follow from the counts), and written once the page table is known.

use caveclod_core::format::materials::{material_tags, MaterialRecord};
use caveclod_core::format::paged::{paged_tags, PageEntry, PagedMeta, FLAG_PAGED};
use caveclod_core::format::{tags, BaseFace, FilePlan, SectionSpec, SectionWriter, Sink, Tag};
use caveclod_core::{Hierarchy, NodeId};

use super::error::PagedError;
use super::pages::BuiltPage;
use super::partition::Partition;
use super::renumber::Renumbered;
use crate::report::INFO;

/// The pages holding each page's nodes' parents, ascending, itself left out.
pub(crate) fn page_parents(h: &Hierarchy<'_>, part: &Partition) -> Vec<Vec<u32>> {
    let mut parents = vec![Vec::new(); part.pages as usize];
    for (v, n) in h.nodes().iter().enumerate() {
        let page = part.home[v];
        if let Some(p) = n.parent.get() {
            let pp = part.home[p.index()];
            if pp != page {
                parents[page as usize].push(pp);
            }
        }
    }
    for list in &mut parents {
        list.sort_unstable();
        list.dedup();
    }
    parents
}

/// The root's sections: their lengths, and the optional sections carried along.
pub(crate) struct RootPlan {
    specs: Vec<SectionSpec>,
    extras: Vec<(Tag, Vec<u8>)>,
}

fn spec(tag: Tag, record_size: usize, count: usize) -> SectionSpec {
    SectionSpec {
        tag,
        record_size: record_size as u32,
        byte_len: (record_size * count) as u64,
    }
}

impl RootPlan {
    pub(crate) fn new(
        h: &Hierarchy<'_>,
        r: &Renumbered,
        parents: &[Vec<u32>],
        root_page_bytes: u32,
    ) -> Result<Self, PagedError> {
        let mut specs = vec![
            spec(tags::META, 88, 1),
            spec(paged_tags::PAGED_META, 64, 1),
            spec(tags::ROOTS, 4, h.roots().len()),
            spec(tags::BASE, core::mem::size_of::<BaseFace>(), h.base().len()),
            spec(paged_tags::PAGE_TABLE, 96, r.pages.len()),
            spec(
                paged_tags::PAGE_PARENTS,
                4,
                parents.iter().map(Vec::len).sum(),
            ),
            spec(paged_tags::ROOT_PAGES, 1, root_page_bytes as usize),
        ];
        let record = |tag| match tag {
            t if t == material_tags::MATERIALS => core::mem::size_of::<MaterialRecord>(),
            _ => 1,
        };
        let mut extras = Vec::new();
        for tag in [material_tags::MATERIALS, material_tags::BLOB, INFO] {
            if let Some(bytes) = h.section(tag) {
                specs.push(spec(tag, record(tag), bytes.len() / record(tag)));
                extras.push((tag, bytes.to_vec()));
            }
        }
        FilePlan::new(&specs[..]).map_err(|_| PagedError::TooLarge)?;
        Ok(Self { specs, extras })
    }

    /// The root's length: where the first streamed page starts.
    pub(crate) fn root_len(&self) -> u64 {
        FilePlan::new(&self.specs[..]).map_or(0, |p| p.file_len())
    }

    /// The root's bytes, the page table completed with the root page's place and every
    /// page's parents; `file_len` is the whole file's.
    pub(crate) fn write(
        &self,
        h: &Hierarchy<'_>,
        r: &Renumbered,
        parents: &[Vec<u32>],
        first: &BuiltPage,
        entries: &mut [PageEntry],
        file_len: u64,
    ) -> Result<Vec<u8>, PagedError> {
        let plan = FilePlan::new(&self.specs[..]).map_err(|_| PagedError::TooLarge)?;
        let root_at = plan
            .entries()
            .find(|e| e.tag == paged_tags::ROOT_PAGES)
            .map_or(0, |e| e.offset);
        entries[0].offset = root_at;
        let mut start = 0u32;
        for (e, list) in entries.iter_mut().zip(parents) {
            e.parents_start = start;
            e.parent_count = list.len() as u32;
            start += list.len() as u32;
        }
        let keys = r.key_vertex.len() as u32;
        let meta = caveclod_core::format::Meta {
            vertex_count: keys,
            vertex_key_count: keys,
            ..*h.meta()
        };
        let paged = PagedMeta {
            page_bits: r.ids.bits(),
            root_pages: 1,
            page_count: entries.len() as u32,
            flags: 0,
            file_len,
            largest_page: entries[1..].iter().map(|e| e.size).max().unwrap_or(0),
            reserved: [0; 9],
        };
        let mut roots: Vec<NodeId> = h
            .roots()
            .iter()
            .map(|v| NodeId(r.node[v.index()]))
            .collect();
        roots.sort_unstable();
        let base: Vec<BaseFace> = h
            .base()
            .iter()
            .map(|f| BaseFace {
                corners: f.corners.map(|c| NodeId(r.node[c.index()])),
                ..*f
            })
            .collect();
        let flat: Vec<u32> = parents.iter().flatten().copied().collect();
        let mut w =
            SectionWriter::new(plan, VecSink(Vec::new())).map_err(|_| PagedError::TooLarge)?;
        let sections: [&[u8]; 7] = [
            bytemuck::bytes_of(&meta),
            bytemuck::bytes_of(&paged),
            bytemuck::cast_slice(&roots),
            bytemuck::cast_slice(&base),
            bytemuck::cast_slice(entries),
            bytemuck::cast_slice(&flat),
            first.bytes(),
        ];
        for bytes in sections
            .into_iter()
            .chain(self.extras.iter().map(|(_, b)| &b[..]))
        {
            w.put(bytes)
                .map_err(|_| PagedError::Shape("a root section is not as planned"))?;
        }
        let (mut header, VecSink(mut bytes)) = w
            .finish()
            .map_err(|_| PagedError::Shape("a root section is short"))?;
        header.flags = FLAG_PAGED;
        bytes[..64].copy_from_slice(bytemuck::bytes_of(&header));
        Ok(bytes)
    }
}

/// The root's bytes, gathered in memory (it is small).
struct VecSink(Vec<u8>);

impl Sink for VecSink {
    type Error = core::convert::Infallible;
    fn put(&mut self, bytes: &[u8]) -> Result<(), Self::Error> {
        self.0.extend_from_slice(bytes);
        Ok(())
    }
}
