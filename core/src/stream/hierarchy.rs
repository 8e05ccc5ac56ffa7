//! [`StreamedHierarchy`]: a paged file's records as a camera reads them, from its root and
//! the pages resident in a pool.
//!
//! A camera refines over it exactly as over a whole file (see
//! [`HierarchyRecords`]). A record is found from its page-major id: the page is a shift, and
//! its array comes from the root (a root page, whose arrays are cast once a frame) or from
//! its pool slot, where the pool noted each array's place when it installed the page. A
//! split whose records lie in a page that is not resident is deferred by the camera, and the
//! page goes into the caller's [`FrameLists`] with the split's error excess; so do the
//! changes of which pages the fronts stand on. After the frame's refinement the host hands
//! the lists to [`Residency::apply`].
//!
//! Nothing here changes the pool: a pool borrowed by streamed hierarchies is not installing
//! or evicting, so every page seen resident stays resident while they exist.

use core::cell::Cell;

use bytemuck::Pod;

use super::config::VertexPoolLayout;
use super::frame_lists::{FrameLists, StreamedReads, Want};
use super::residency::Residency;
use crate::format::paged::{PageArray, PageContext, PageView, PagedRoot, RecordKind, SegmentedId};
use crate::format::{
    BaseFace, Meta, Node, Polygon, Position, Split, SplitBounds, Vertex, VertexKey,
};
use crate::hierarchy::{Absent, HierarchyRecords};
use crate::ids::{NodeId, PageKey, PolyId, PositionId};

/// Root pages whose arrays are cast once a frame (the others' on each read; a paged file
/// has one or a few).
const ROOT_VIEWS: usize = 4;
/// Wants looked back over for a page already listed.
const WANTS_LOOKED_BACK: usize = 8;

/// A paged file's records over its root and a pool (see the module docs).
pub struct StreamedHierarchy<'s, 'w, 'a, 'm> {
    root: &'s PagedRoot<'s>,
    pool: &'s Residency<'a, 'm>,
    file: u32,
    ids: SegmentedId,
    /// Which ids name records: the page table's counts.
    cx: PageContext<'s>,
    root_pages: u32,
    id_bound: usize,
    pages: usize,
    /// The file's first page's global index in the pool.
    first_page: usize,
    /// The first root pages' arrays.
    root_views: [Option<PageView<'s>>; ROOT_VIEWS],
    /// The first root pages' first vertex in the device vertex pool, and their vertices.
    root_vertices: [(u32, u32); ROOT_VIEWS],
    /// The pool's device vertex pool.
    vertex_pool: Option<VertexPoolLayout>,
    wants: &'w [Cell<Want>],
    want_len: &'w Cell<u32>,
    deltas: &'w [Cell<u32>],
    listed: &'w [Cell<u32>],
    touched: &'w [Cell<u32>],
    touched_len: &'w Cell<u32>,
    reads: &'w Cell<StreamedReads>,
}

impl<'s, 'w, 'a, 'm> StreamedHierarchy<'s, 'w, 'a, 'm> {
    /// The records of file `file` of `pool`, whose root is `root`; what the cameras want and
    /// change goes to `lists`, for [`Residency::apply`] once they are done.
    pub fn new(
        root: &'s PagedRoot<'s>,
        pool: &'s Residency<'a, 'm>,
        file: u32,
        lists: &'w mut FrameLists<'_>,
    ) -> Self {
        let ids = root.ids();
        let pages = root.table().len() as u64;
        let id_bound = (pages << ids.bits()).min(u64::from(u32::MAX)) as usize;
        Self {
            root,
            pool,
            file,
            ids,
            cx: root.context(),
            root_pages: root.paged().root_pages,
            id_bound,
            pages: pages as usize,
            first_page: pool.file_pages(file).map_or(usize::MAX, |(first, _)| first),
            root_views: core::array::from_fn(|p| root.root_page(p as u32)),
            root_vertices: core::array::from_fn(|p| {
                pool.root_vertex_start(file, p as u32).unwrap_or((0, 0))
            }),
            vertex_pool: pool.vertex_pool(),
            wants: Cell::from_mut(&mut *lists.wants).as_slice_of_cells(),
            want_len: Cell::from_mut(&mut lists.want_len),
            deltas: Cell::from_mut(&mut *lists.deltas).as_slice_of_cells(),
            listed: Cell::from_mut(&mut *lists.listed).as_slice_of_cells(),
            touched: Cell::from_mut(&mut *lists.touched).as_slice_of_cells(),
            touched_len: Cell::from_mut(&mut lists.touched_len),
            reads: Cell::from_mut(&mut lists.reads),
        }
    }

    /// What was read and wanted so far (the lists' totals).
    pub fn reads(&self) -> StreamedReads {
        self.reads.get()
    }

    /// One more (`delta` 1) or one fewer (-1) front node stands on `node`'s page; root
    /// pages are pinned and not counted.
    fn count_use(&self, node: NodeId, delta: i32) {
        let page = self.ids.page(node.0);
        if page < self.root_pages {
            return;
        }
        let key = PageKey {
            file: self.file,
            page,
        };
        let slot = self.pool.resident_slot(key).map(|s| s as usize);
        let cells = slot.and_then(|s| Some((s, self.deltas.get(s)?, self.listed.get(s)?)));
        let Some((slot, d, listed)) = cells else {
            let mut r = self.reads.get();
            r.untracked_uses += 1;
            self.reads.set(r);
            return;
        };
        d.set((d.get() as i32).wrapping_add(delta) as u32);
        if listed.get() == 0 {
            listed.set(1);
            let n = self.touched_len.get();
            // `touched` has a place per slot, and a slot is listed once.
            if let Some(t) = self.touched.get(n as usize) {
                t.set(slot as u32);
                self.touched_len.set(n + 1);
            }
        }
    }

    /// Whether page `page` is resident (a root page always is).
    #[inline]
    fn resident(&self, page: u32) -> bool {
        let key = PageKey {
            file: self.file,
            page,
        };
        page < self.root_pages || self.pool.resident_slot(key).is_some()
    }

    /// The array of `array` holding record `id` (`pick` takes it from a root page's arrays),
    /// and the record's index there; a read of an absent page is counted.
    #[inline]
    fn array_of<T: Pod>(
        &self,
        id: u32,
        array: PageArray,
        pick: impl FnOnce(&PageView<'s>) -> &'s [T],
    ) -> Option<(&'s [T], usize)> {
        let page = self.ids.page(id);
        let index = self.ids.index(id) as usize;
        if page < self.root_pages {
            return match self.root_views.get(page as usize) {
                Some(v) => v.as_ref().map(|v| (pick(v), index)),
                None => self.root.root_page(page).map(|v| (pick(&v), index)),
            };
        }
        let found = match self.first_page.checked_add(page as usize) {
            Some(g) if (page as usize) < self.pages => self.pool.array_at::<T>(g, array),
            _ => None,
        };
        // An id of no page (`NONE`, out of range) is no read of an absent page.
        if found.is_none() && (page as usize) < self.pages {
            let mut reads = self.reads.get();
            reads.absent_reads += 1;
            self.reads.set(reads);
        }
        found.map(|a| (a, index))
    }

    /// `Err` with the page of `id` unless it holds a record of `kind` at hand, for the split
    /// of `node`.
    fn present(&self, node: NodeId, id: u32, kind: RecordKind) -> Result<(), Absent> {
        let page = self.ids.page(id);
        let absent = Absent {
            page: PageKey {
                file: self.file,
                page,
            },
            node,
        };
        let held = self.cx.exists(id, kind) && self.resident(page);
        if held {
            Ok(())
        } else {
            Err(absent)
        }
    }
}

impl HierarchyRecords for StreamedHierarchy<'_, '_, '_, '_> {
    fn checksum(&self) -> u64 {
        self.root.checksum()
    }

    fn meta(&self) -> &Meta {
        self.root.meta()
    }

    fn roots(&self) -> &[NodeId] {
        self.root.roots()
    }

    fn base(&self) -> &[BaseFace] {
        self.root.base()
    }

    fn surface_count(&self) -> usize {
        self.root.meta().surface_count as usize
    }

    fn split_id_bound(&self) -> usize {
        self.id_bound
    }

    fn vertex_id_bound(&self) -> usize {
        self.id_bound
    }

    fn dense_ids(&self) -> bool {
        false
    }

    /// Its slot's place for a streamed page's vertex, its file's root region's for a root
    /// page's (see [`VertexPoolLayout`](super::VertexPoolLayout)); the id itself for a
    /// pool without a device vertex pool.
    #[inline]
    fn device_vertex(&self, vertex: u32) -> Option<u32> {
        let Some(layout) = self.vertex_pool else {
            return Some(vertex);
        };
        let page = self.ids.page(vertex);
        let index = self.ids.index(vertex);
        if page < self.root_pages {
            let (first, count) = match self.root_vertices.get(page as usize) {
                Some(&cached) => cached,
                None => self.pool.root_vertex_start(self.file, page)?,
            };
            return (index < count).then(|| first + index);
        }
        if page as usize >= self.pages {
            return None;
        }
        let slot = self
            .pool
            .resident_slot_at(self.first_page + page as usize)?;
        layout.slot_place(slot, index)
    }

    fn device_vertex_bound(&self) -> usize {
        match self.vertex_pool {
            Some(layout) => layout.vertices as usize,
            None => self.id_bound,
        }
    }

    #[inline]
    fn node(&self, node: NodeId) -> Option<&Node> {
        let (a, i) = self.array_of(node.0, PageArray::Nodes, |v| v.nodes)?;
        a.get(i)
    }

    #[inline]
    fn split(&self, node: NodeId) -> Option<&Split> {
        let (a, i) = self.array_of(node.0, PageArray::Splits, |v| v.splits)?;
        a.get(i)
    }

    #[inline]
    fn split_bounds(&self, node: NodeId) -> Option<&SplitBounds> {
        let (a, i) = self.array_of(node.0, PageArray::Bounds, |v| v.bounds)?;
        a.get(i)
    }

    #[inline]
    fn polygon(&self, poly: PolyId) -> Option<&Polygon> {
        let (a, i) = self.array_of(poly.0, PageArray::Polygons, |v| v.polygons)?;
        a.get(i)
    }

    #[inline]
    fn position(&self, position: PositionId) -> Option<&Position> {
        let (a, i) = self.array_of(position.0, PageArray::Positions, |v| v.positions)?;
        a.get(i)
    }

    #[inline]
    fn vertex_keys(&self, position: PositionId) -> &[VertexKey] {
        let offsets = self.array_of(position.0, PageArray::VertexTableOffsets, |v| {
            v.vertex_table_offsets
        });
        let Some((offsets, i)) = offsets else {
            return &[];
        };
        let (Some(&a), Some(&b)) = (offsets.get(i), offsets.get(i + 1)) else {
            return &[];
        };
        self.array_of(position.0, PageArray::VertexTable, |v| v.vertex_table)
            .and_then(|(table, _)| table.get(a as usize..b as usize))
            .unwrap_or(&[])
    }

    #[inline]
    fn vertex(&self, vertex: u32) -> Option<&Vertex> {
        let (a, i) = self.array_of(vertex, PageArray::Vertices, |v| v.vertices)?;
        a.get(i)
    }

    /// The node's page (its split record), its children's pages, the floating child's
    /// position and vertices, and the polygons the split creates.
    fn split_ready(&self, node: NodeId) -> Result<(), Absent> {
        let present = |id: u32, kind| self.present(node, id, kind);
        present(node.0, RecordKind::Splits)?;
        let Some(s) = self.split(node) else {
            return Ok(()); // a leaf: the camera refuses its split itself
        };
        present(s.stationary.0, RecordKind::Nodes)?;
        present(s.floating.0, RecordKind::Nodes)?;
        for f in [s.f_l, s.f_r] {
            if f.is_some() {
                present(f.0, RecordKind::Polygons)?;
            }
        }
        let Some(n) = self.node(s.floating) else {
            return Ok(());
        };
        present(n.position.0, RecordKind::Positions)?;
        for k in self.vertex_keys(n.position) {
            present(k.vertex, RecordKind::Vertices)?;
        }
        Ok(())
    }

    fn node_entered_front(&self, node: NodeId) {
        self.count_use(node, 1);
    }

    fn node_left_front(&self, node: NodeId) {
        self.count_use(node, -1);
    }

    /// Lists the absent page, and the resident pages the waiting split reads (so the pool
    /// keeps them, most recently wanted, while the split waits for the rest).
    fn want(&self, absent: Absent, excess_px: f32) {
        self.list_want(absent.page.page, excess_px);
        let node = absent.node;
        let page = |id: u32| self.ids.page(id);
        // The waiting node's own page may be the absent one (a forced split's node).
        if self.present(node, node.0, RecordKind::Splits).is_err() {
            return;
        }
        let Some(s) = self.split(node).copied() else {
            return;
        };
        for id in [node.0, s.stationary.0, s.floating.0, s.f_l.0, s.f_r.0] {
            if id != u32::MAX && page(id) >= self.root_pages && page(id) != absent.page.page {
                self.list_want(page(id), excess_px);
            }
        }
    }
}

impl StreamedHierarchy<'_, '_, '_, '_> {
    /// Puts page `page` in the wants list at `excess_px` (raising a recent entry's).
    fn list_want(&self, page: u32, excess_px: f32) {
        let page = PageKey {
            file: self.file,
            page,
        };
        let len = self.want_len.get() as usize;
        let mut r = self.reads.get();
        // A pass defers many splits into the same few pages, near one another.
        let recent = &self.wants[len.saturating_sub(WANTS_LOOKED_BACK)..len];
        if let Some(w) = recent.iter().find(|w| w.get().page == page) {
            let mut got = w.get();
            got.excess_px = got.excess_px.max(excess_px);
            w.set(got);
            return;
        }
        match self.wants.get(len) {
            Some(w) => {
                w.set(Want { page, excess_px });
                self.want_len.set(len as u32 + 1);
                r.wanted += 1;
            }
            None => r.wants_dropped += 1,
        }
        self.reads.set(r);
    }
}
