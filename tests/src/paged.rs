//! A generated terrain written paged, and a page pool over it that the tests fill from the
//! file's bytes synchronously, as a host's loader would.

use caveclod_bake::paged::{write_paged, PageOptions};
use caveclod_core::format::paged::PagedRoot;
use caveclod_core::stream::{
    LoadRequest, PageKey, PageTable, PoolConfig, Residency, VertexPoolLayout,
};
use caveclod_io::{AlignedBytes, PagedFile};

use crate::{bake, meshes, BakedMesh};

/// A terrain, baked, its paged form opened (the root read), and that file's bytes.
pub struct PagedTerrain {
    /// The whole hierarchy.
    pub baked: BakedMesh,
    /// The paged file.
    pub file: PagedFile,
    /// The paged file's bytes.
    pub bytes: Vec<u8>,
}

/// A `w` × `h` terrain (of `seed`) in pages of `page_bytes`.
pub fn paged_terrain(w: u32, h: u32, seed: u64, page_bytes: u32) -> PagedTerrain {
    let baked = bake(&meshes::terrain(w, h, seed));
    let dir = tempfile::tempdir().expect("dir");
    let path = dir.path().join("terrain.clod");
    write_paged(&baked.hierarchy(), &path, &PageOptions { page_bytes }).expect("paged");
    let bytes = std::fs::read(&path).expect("read");
    let file = PagedFile::open(&path).expect("open");
    PagedTerrain { baked, file, bytes }
}

/// A pool's memory: its words, its bytes and its table place, for one file.
pub struct PoolMemory<'a> {
    words: Vec<u32>,
    bytes: AlignedBytes,
    tables: Vec<Option<PageTable<'a>>>,
    /// The pool's configuration.
    pub config: PoolConfig,
}

impl<'a> PoolMemory<'a> {
    /// A pool of `slots` slots for `root`'s file.
    pub fn new(root: &PagedRoot<'_>, slots: u32) -> Self {
        let slot_bytes = root.paged().largest_page.next_multiple_of(64);
        let config = PoolConfig::new(
            u64::from(slots) * u64::from(slot_bytes),
            slot_bytes,
            1,
            root.table().len() as u32,
        );
        Self::of(config)
    }

    /// [`new`](Self::new) with a device vertex pool beside it, as small as the file allows.
    pub fn with_vertex_pool(root: &PagedRoot<'_>, slots: u32) -> Self {
        let (table, pinned) = (root.table(), root.paged().root_pages);
        let slot_vertices = table.most_vertices_from(pinned);
        let layout = VertexPoolLayout {
            slot_vertices,
            vertices: slots * slot_vertices + table.vertices_before(pinned) as u32,
        };
        Self::of(Self::new(root, slots).config.with_vertex_pool(layout))
    }

    fn of(config: PoolConfig) -> Self {
        Self {
            words: vec![0; Residency::words_needed(&config)],
            bytes: AlignedBytes::zeroed(config.pool_bytes()),
            tables: vec![None; 1],
            config,
        }
    }

    /// The residency over this memory, serving `root`'s file as file 0.
    pub fn residency<'m>(&'m mut self, root: &PagedRoot<'a>) -> Residency<'a, 'm> {
        let mut r = Residency::new(
            self.config,
            &mut self.words,
            self.bytes.bytes_mut(),
            &mut self.tables,
        )
        .expect("pool");
        r.add_file(root.table(), root.paged().root_pages)
            .expect("file");
        r
    }
}

/// Loads what `pool` schedules (at most `most` pages) from the file's `bytes`; the pages
/// installed, and the evictions.
pub fn load(
    pool: &mut Residency<'_, '_>,
    root: &PagedRoot<'_>,
    bytes: &[u8],
    most: usize,
) -> (Vec<PageKey>, u32) {
    let mut loads = vec![LoadRequest::default(); most];
    let mut evicted = vec![PageKey::default(); most];
    let st = pool.schedule(&mut loads, &mut evicted);
    let mut installed = Vec::new();
    for l in &loads[..st.loads as usize] {
        let from = &bytes[l.offset as usize..l.offset as usize + l.size as usize];
        pool.loading_slot_mut(l.slot)
            .expect("slot")
            .copy_from_slice(from);
        installed.push(pool.install(l.slot, root).expect("install"));
    }
    (installed, st.evictions)
}
