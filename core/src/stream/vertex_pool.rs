//! The device vertex pool: where the vertices of a pool's pages lie in the renderer's
//! vertex buffer, so that index lists name them there.
//!
//! A renderer keeps the vertices of the resident pages in a device buffer of a fixed size,
//! slot for slot beside the pool's bytes: the page in slot `s` has its vertices at
//! `s × slot_vertices`, in the page's order. The files' root pages, always resident, follow
//! the slots, each file's after those of the file added before it. Over a
//! [`StreamedHierarchy`](super::StreamedHierarchy) of such a pool, emission, the index
//! edits and the morph slots name vertices there
//! ([`HierarchyRecords::device_vertex`](crate::HierarchyRecords::device_vertex)), and a
//! morphing corner is `vertices + slot`, past the whole pool, as over a whole file it is
//! past the persistent vertex buffer.
//!
//! A slot's vertices change only when a page is installed into it, and a page is evicted
//! only once no front stands on it, so an index written for a polygon stays valid while the
//! polygon is drawn. The renderer uploads a page's vertices ([`Residency::page_vertices`])
//! when the pool installs it, before the first frame whose fronts may use it, and each
//! file's root vertices ([`Residency::root_vertices`]) once.

use super::config::{PoolError, VertexPoolLayout};
use super::residency::{Residency, PINNED};
use crate::format::paged::{PageTable, PageView, PagedRoot, RecordKind};
use crate::format::Vertex;
use crate::ids::PageKey;

/// Vertices to copy into the device pool: `vertices` (and their colours, if the page has
/// them) go to `first..first + vertices.len()`.
#[derive(Clone, Copy, Debug)]
pub struct VertexInstall<'p> {
    /// The device pool index of the first vertex.
    pub first: u32,
    /// The vertices, in the page's order.
    pub vertices: &'p [Vertex],
    /// One RGBA8 colour per vertex (sRGB-encoded colour, linear alpha), if the page has them.
    pub colours: Option<&'p [[u8; 4]]>,
}

impl Residency<'_, '_> {
    /// The device vertex pool's layout, if the pool has one.
    pub fn vertex_pool(&self) -> Option<VertexPoolLayout> {
        self.config.vertex_pool
    }

    /// The vertices of resident, streamed page `key` and where they go in the device vertex
    /// pool: its slot's place. `None` without a vertex pool, or for a page that is not
    /// streamed and resident.
    pub fn page_vertices(&self, key: PageKey) -> Option<VertexInstall<'_>> {
        let layout = self.config.vertex_pool?;
        let slot = self.resident_slot(key)?;
        let layout_of_page = self.table(key.file)?.layout(key.page)?;
        let view = PageView::cast(self.page_bytes(key)?, &layout_of_page).ok()?;
        Some(VertexInstall {
            first: layout.slot_place(slot, 0)?,
            vertices: view.vertices,
            colours: (!view.colours.is_empty()).then_some(view.colours),
        })
    }

    /// The vertices of file `file`'s root page `page` (of `root`, that file's root) and
    /// where they go in the device vertex pool; `None` without a vertex pool, or for a page
    /// that is not a root page of that file.
    pub fn root_vertices<'r>(
        &self,
        file: u32,
        root: &PagedRoot<'r>,
        page: u32,
    ) -> Option<VertexInstall<'r>> {
        let (first, _) = self.root_vertex_start(file, page)?;
        let view = root.root_page(page)?;
        Some(VertexInstall {
            first,
            vertices: view.vertices,
            colours: (!view.colours.is_empty()).then_some(view.colours),
        })
    }

    /// The device pool index of the first vertex of file `file`'s root page `page`, and
    /// how many vertices the page holds.
    pub(crate) fn root_vertex_start(&self, file: u32, page: u32) -> Option<(u32, u32)> {
        self.config.vertex_pool?;
        let g = self.global(PageKey { file, page })?;
        if self.w.pages.state[g] & PINNED == 0 {
            return None;
        }
        let table = self.table(file)?;
        let start = self.config.slot_vertices_total()
            + u64::from(*self.w.file_root_vertices.get(file as usize)?)
            + table.vertices_before(page);
        let count = table.entry(page)?.counts[RecordKind::Vertices as usize];
        Some((u32::try_from(start).ok()?, count))
    }

    /// Reserves room for a new file's root vertices in the device vertex pool, and checks
    /// that its streamed pages fit a slot: at `add_file`, for file `file` of `table`'s
    /// pages, the first `pinned` of them root pages.
    pub(super) fn reserve_vertices(
        &mut self,
        file: u32,
        table: &PageTable<'_>,
        pinned: u32,
    ) -> Result<(), PoolError> {
        let Some(layout) = self.config.vertex_pool else {
            return Ok(());
        };
        let most = table.most_vertices_from(pinned);
        if most > layout.slot_vertices {
            return Err(PoolError::VertexPoolTooSmall {
                what: "a page's vertices",
                needed: u64::from(most),
                room: u64::from(layout.slot_vertices),
            });
        }
        let needed = table.vertices_before(pinned);
        let room = u64::from(layout.vertices)
            .saturating_sub(self.config.slot_vertices_total())
            .saturating_sub(u64::from(self.root_vertices_used));
        if needed > room {
            return Err(PoolError::VertexPoolTooSmall {
                what: "root vertices",
                needed,
                room,
            });
        }
        if let Some(w) = self.w.file_root_vertices.get_mut(file as usize) {
            *w = self.root_vertices_used;
        }
        self.root_vertices_used += needed as u32;
        Ok(())
    }
}
