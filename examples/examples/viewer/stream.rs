//! A paged file in the viewer: its root read when it opens, its pages streaming from the
//! file into a page pool whose twin on the GPU is a device vertex pool of the size
//! `--vertex-pool` gives (caveclod-vulkan's `VertexPool`, made by the viewer). The cameras
//! refine over the root and the resident pages; what they want is read on the streamer's
//! threads, at most [`MAX_INSTALLS`] pages installed a frame, each copied to the device in
//! the frame that installs it.

use std::time::Instant;

use caveclod_core::format::paged::PagedRoot;
use caveclod_core::stream::{
    FrameLists, PageFault, PageTable, PoolConfig, Pressure, PressureSignal, Residency,
    StreamedHierarchy, VertexInstall, VertexPoolLayout, Want,
};
use caveclod_core::{CameraConfig, RefineParams};
use caveclod_io::pages::ReaderConfig;
use caveclod_io::{AlignedBytes, PagedFile, Streamer};

/// Pages installed a frame, in the page pool and the device vertex pool alike.
pub const MAX_INSTALLS: usize = 32;
/// Reads in flight (and loads started a frame, at most).
const MAX_IN_FLIGHT: usize = 64;
/// Wants a frame's lists hold (more are asked again by the next frame).
const WANTS: usize = 4096;
/// Places a camera lists as changed between two frames' index edits.
const EDIT_LIST: u32 = 16_384;
/// Polygons a camera holds at most over a paged file: its memory follows this, not the file.
const CAMERA_POLYGONS: u32 = 400_000;
/// The most the pool's pressure scales the tolerance by.
const MAX_PRESSURE: f32 = 16.0;

/// The memory a streamed file's pool and lists borrow, sized once.
pub struct StreamMemory<'a> {
    pub config: PoolConfig,
    words: Vec<u32>,
    bytes: AlignedBytes,
    tables: Vec<Option<PageTable<'a>>>,
    wants: Vec<Want>,
    list_words: Vec<u32>,
}

impl<'a> StreamMemory<'a> {
    /// Memory for `root`'s file with a device vertex pool of `vertex_pool_bytes`: its slots
    /// hold the file's largest page's vertices, and the page pool has as many slots.
    pub fn new(root: &PagedRoot<'a>, vertex_pool_bytes: u64) -> Result<Self, String> {
        let (table, pinned) = (root.table(), root.paged().root_pages);
        let (layout, slots) = VertexPoolLayout::for_file(vertex_pool_bytes, &table, pinned)
            .ok_or_else(|| {
                format!(
                    "a vertex pool of {} MiB holds not even the root and one page",
                    vertex_pool_bytes >> 20
                )
            })?;
        let slot_bytes = root.paged().largest_page.next_multiple_of(64);
        let pool_bytes = u64::from(slots) * u64::from(slot_bytes);
        let config =
            PoolConfig::new(pool_bytes, slot_bytes, 1, table.len() as u32).with_vertex_pool(layout);
        Ok(Self {
            config,
            words: vec![0; Residency::words_needed(&config)],
            bytes: AlignedBytes::zeroed(config.pool_bytes()),
            tables: vec![None; 1],
            wants: vec![Want::default(); WANTS],
            list_words: vec![0; FrameLists::words_needed(&config)],
        })
    }
}

/// What the streaming did since the file opened.
#[derive(Clone, Copy, Debug, Default)]
pub struct StreamTotals {
    pub installs: u64,
    pub evictions: u64,
    pub faults: u64,
    /// Splits waiting for pages in the last frame, over the cameras.
    pub deferred: u32,
    /// The scale the pool's pressure puts on the tolerance.
    pub pressure: f32,
}

/// A paged file's root, its page pool and the streamer filling it.
pub struct Streamed<'h> {
    root: PagedRoot<'h>,
    pool: Residency<'h, 'h>,
    lists: FrameLists<'h>,
    streamer: Streamer,
    faults: Vec<PageFault>,
    started: Instant,
    /// Coarser fronts while the pool is nearly full or the reads fall behind.
    pressure: Pressure,
    pub totals: StreamTotals,
}

impl<'h> Streamed<'h> {
    /// The pool over `memory` serving `file`, whose root is `root`.
    pub fn new(
        file: &PagedFile,
        root: PagedRoot<'h>,
        memory: &'h mut StreamMemory<'h>,
    ) -> Result<Self, String> {
        let pool = Residency::new(
            memory.config,
            &mut memory.words,
            memory.bytes.bytes_mut(),
            &mut memory.tables,
        )
        .and_then(|mut pool| {
            pool.add_file(root.table(), root.paged().root_pages)?;
            Ok(pool)
        })
        .map_err(|e| format!("page pool: {e}"))?;
        let lists = FrameLists::new(&memory.config, &mut memory.wants, &mut memory.list_words)
            .map_err(|e| format!("frame lists: {e}"))?;
        let reader = ReaderConfig {
            max_in_flight: MAX_IN_FLIGHT,
            max_read_len: memory.config.slot_bytes,
            ..ReaderConfig::default()
        };
        let streamer = Streamer::new(vec![file.source()], reader, MAX_IN_FLIGHT)
            .map_err(|e| format!("page reader: {e}"))?
            .with_max_installs(MAX_INSTALLS);
        Ok(Self {
            root,
            pool,
            lists,
            streamer,
            faults: Vec::new(),
            started: Instant::now(),
            pressure: Pressure::new().with_max_scale(MAX_PRESSURE),
            totals: StreamTotals::default(),
        })
    }

    /// The root.
    pub fn root(&self) -> &PagedRoot<'h> {
        &self.root
    }

    /// The records the cameras refine over this frame.
    pub fn records(&mut self) -> StreamedHierarchy<'_, '_, 'h, 'h> {
        StreamedHierarchy::new(&self.root, &self.pool, 0, &mut self.lists)
    }

    /// The cameras' configuration: a polygon budget, morph memory and index edits.
    pub fn camera_config(&mut self, max_morphs: u32) -> CameraConfig {
        let h = self.records();
        CameraConfig::with_polygon_budget(&h, CAMERA_POLYGONS)
            .with_morphs(max_morphs)
            .with_index_edits(EDIT_LIST)
    }

    /// Starts a frame of the pool: the cameras refine with `params` under its pressure.
    pub fn begin_frame(&mut self, params: RefineParams) -> RefineParams {
        self.pool.begin_frame();
        self.pressure.params(params)
    }

    /// After the cameras refined (`deferred` splits waiting, `active_nodes` on their
    /// fronts): hands the pool what they want and stand on, installs what arrived, starts
    /// new reads, and updates the pressure. A bad page is reported on stderr once.
    pub fn end_frame(&mut self, deferred: u32, active_nodes: u32) -> Result<(), String> {
        self.pool
            .apply(&mut self.lists)
            .map_err(|e| format!("page pool: {e}"))?;
        let before = self.faults.len();
        let f = self.streamer.frame(
            &mut self.pool,
            std::slice::from_ref(&self.root),
            self.started.elapsed(),
            &mut self.faults,
        );
        for fault in &self.faults[before..] {
            eprintln!("streaming: {fault}");
        }
        self.totals.installs += u64::from(f.installs);
        self.totals.evictions += u64::from(f.schedule.evictions);
        self.totals.faults = self.faults.len() as u64;
        self.totals.deferred = deferred;
        let slots = self.pool.config().slots;
        let stats = self.pool.stats();
        let signal = PressureSignal::new(slots, &stats, &f.schedule, deferred, active_nodes);
        self.totals.pressure = self.pressure.update(&signal);
        Ok(())
    }

    /// The device vertex pool's layout and slots.
    pub fn vertex_pool(&self) -> Option<(VertexPoolLayout, u32)> {
        Some((self.pool.vertex_pool()?, self.pool.config().slots))
    }

    /// The root pages' vertices, for the device pool once.
    pub fn root_vertices(&self) -> Vec<VertexInstall<'_>> {
        (0..self.root.paged().root_pages)
            .filter_map(|page| self.pool.root_vertices(0, &self.root, page))
            .collect()
    }

    /// The vertices of the pages the last frame installed, for the device pool.
    pub fn installed_vertices(&self) -> Vec<VertexInstall<'_>> {
        self.streamer
            .installed()
            .iter()
            .filter_map(|&page| self.pool.page_vertices(page))
            .collect()
    }
}
