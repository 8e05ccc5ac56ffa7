//! `flyover --pool`: the cameras fly over paged files whose pages stream into one pool of a
//! fixed size, through a page reader that can simulate a slow disk on the flight's clock
//! (60 frames a second).
//!
//! Opening reads each file's root only. Every frame, each camera refines over each file's
//! [`StreamedHierarchy`] (the root and the resident pages): splits that need an absent page
//! wait, and their pages are wanted with the splits' error excess. The pool then takes the
//! frame's lists (wants, and which pages the fronts stand on), installs the pages that
//! arrived, and schedules loads, evicting pages no front stands on. Per frame the flight
//! records requests, installs, evictions, bytes read, deferred splits, how long the oldest
//! wanted page has been waited for, and the lag: the error excess over the flight's
//! tolerance that the fronts still hold (outside the timed refinement). When the pool is
//! nearly full or the reads fall behind, a [`Pressure`] scales the cameras' tolerance up
//! (the frame records the scale); the lag is measured against the unscaled tolerance.

use std::collections::HashMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use caveclod_core::format::paged::PagedRoot;
use caveclod_core::stream::{
    FrameLists, PageKey, PageTable, PoolConfig, Pressure, PressureSignal, Residency,
    StreamedHierarchy, StreamedReads, Want,
};
use caveclod_core::{CameraConfig, CameraState, RefineParams, View};
use caveclod_io::pages::{DiskModel, ReaderConfig};
use caveclod_io::{AlignedBytes, PagedFile, Streamer};

use super::streamed_baseline::{Baseline, BaselineFlight};
use super::{morphs_for_budget, refine_params, views_over, FlyoverOptions, Ground};

/// Frames a second of the flight's clock, which the simulated disk runs on.
const FPS: f64 = 60.0;
/// Wants a frame's lists hold (more are asked again by the next frame).
const WANTS: usize = 4096;
/// Reads in flight at once.
const READS_IN_FLIGHT: usize = 256;
/// Loads started a frame at most (Nanite's cap).
const LOADS_PER_FRAME: usize = 128;

/// How the pages stream.
#[derive(Clone, Debug)]
pub struct StreamOptions {
    /// The pool's size in bytes.
    pub pool_bytes: u64,
    /// The simulated device's latency per read (zero: none).
    pub io_latency: Duration,
    /// The simulated device's bandwidth in bytes per second (0: no disk model).
    pub io_bytes_per_s: f64,
    /// Each camera's polygon budget: its memory follows it, not the files.
    pub camera_polygons: u32,
    /// The largest scale streaming pressure may put on the tolerance (1: none).
    pub max_pressure: f32,
    /// The whole-file form of the one paged file, flown after it as the baseline.
    pub baseline: Option<PathBuf>,
}

/// What one frame did, over all files and cameras.
#[derive(Clone, Copy, Debug, Default)]
pub struct StreamedFrame {
    /// Pages requested (with their absent parents).
    pub requested: u32,
    /// Pages installed.
    pub installs: u32,
    /// Pages evicted.
    pub evictions: u32,
    /// Bytes of pages read.
    pub bytes_read: u64,
    /// Pages that failed their checks or their read.
    pub faults: u32,
    /// Pages resident after the frame.
    pub resident: u32,
    /// Splits deferred for pages.
    pub deferred: u32,
    /// Active nodes of every front.
    pub active_nodes: u32,
    /// Active polygons of every front.
    pub active_polygons: u32,
    /// Frames the longest-wanted page has been wanted for, without a break.
    pub oldest_want: u32,
    /// The fronts' error excess over the tolerance, summed over their nodes (pixels).
    pub lag_px: f32,
    /// The largest excess of one node (pixels).
    pub worst_lag_px: f32,
    /// The scale streaming pressure put on the tolerance this frame.
    pub pressure: f32,
    /// Refinement operations applied, over every camera.
    pub operations: u32,
    /// The longest refinement of one camera this frame, in milliseconds.
    pub refine_max_ms: f32,
}

/// A streamed flight's record.
pub struct StreamedFlight {
    /// The files flown.
    pub files: Vec<PathBuf>,
    /// The routes flown.
    pub names: Vec<&'static str>,
    /// Per frame.
    pub frames: Vec<StreamedFrame>,
    /// Refinement time per camera-frame (each file's state counted apart), in nanoseconds.
    pub refine_ns: Vec<u64>,
    /// Each bad page, once: `file: page N: what`.
    pub faults: Vec<String>,
    /// From opening the first file to the end of the first frame's refinement.
    pub open_to_first_frame: Duration,
    /// Pages in the files, and of them the root pages (always resident).
    pub pages: (usize, usize),
    /// The pool's bytes and its slots.
    pub pool: (usize, u32),
    /// The pool's bookkeeping and the frame lists, in bytes.
    pub bookkeeping_bytes: usize,
    /// The cameras' memory, in bytes.
    pub camera_bytes: usize,
    /// The roots read, in bytes.
    pub root_bytes: usize,
    /// What refinement read and asked for.
    pub reads: StreamedReads,
    /// The process's peak resident set, in bytes, where the system says (before the
    /// baseline flight).
    pub peak_rss: Option<u64>,
    /// The same flight over the whole file, when asked for.
    pub baseline: Option<Baseline>,
}

/// Flies `options`' cameras over the paged files `paths` with their pages streaming into
/// one pool (see the module docs).
pub fn fly_streamed(
    paths: &[PathBuf],
    options: &FlyoverOptions,
    stream: &StreamOptions,
) -> Result<StreamedFlight, String> {
    if stream.baseline.is_some() && paths.len() != 1 {
        return Err("--baseline compares one paged file with its whole form".into());
    }
    let opened = Instant::now();
    let files = paths
        .iter()
        .map(|p| PagedFile::open(p).map_err(|e| e.to_string()))
        .collect::<Result<Vec<_>, _>>()?;
    let roots = files
        .iter()
        .map(|f| f.root().map_err(|e| format!("{}: {e}", f.path().display())))
        .collect::<Result<Vec<_>, _>>()?;
    let config = pool_config(&roots, stream.pool_bytes)?;
    let mut words = vec![0u32; Residency::words_needed(&config)];
    let mut bytes = AlignedBytes::zeroed(config.pool_bytes());
    let mut tables: Vec<Option<PageTable<'_>>> = vec![None; roots.len()];
    let mut pool = Residency::new(config, &mut words, bytes.bytes_mut(), &mut tables)
        .map_err(|e| format!("pool: {e}"))?;
    for (root, f) in roots.iter().zip(&files) {
        pool.add_file(root.table(), root.paged().root_pages)
            .map_err(|e| format!("{}: {e}", f.path().display()))?;
    }
    let mut wants = vec![Want::default(); WANTS];
    let mut list_words = vec![0u32; FrameLists::words_needed(&config)];
    let mut lists =
        FrameLists::new(&config, &mut wants, &mut list_words).map_err(|e| e.to_string())?;

    let ground = Ground::of_points(|| roots.iter().flat_map(root_points));
    let (names, views) = views_over(&ground, options);
    let params = refine_params(options)?;
    let morphs = if options.geomorphs {
        morphs_for_budget(stream.camera_polygons)
    } else {
        0
    };
    let params = if morphs > 0 {
        params
    } else {
        params.without_morphs()
    };
    let mut memories = camera_memories(&roots, &pool, &mut lists, views.len(), stream, morphs);
    let mut cameras = make_cameras(&roots, &pool, &mut lists, &mut memories, stream, morphs)?;

    let mut streamer = streamer_for(&files, &config, stream)?;
    let mut flight = StreamedFlight::new(paths, names, &files, &roots, &config, &cameras);
    flight.frames.reserve(options.frames);
    flight.refine_ns.reserve(options.frames * cameras.len());
    let mut waited: HashMap<PageKey, usize> = HashMap::new();
    let mut faults = Vec::new();
    let mut pressure = Pressure::new().with_max_scale(stream.max_pressure);
    for f in 0..options.frames {
        pool.begin_frame();
        let mut frame = StreamedFrame {
            pressure: pressure.scale(),
            ..StreamedFrame::default()
        };
        let fly = Fly {
            roots: &roots,
            views: &views,
            params: &pressure.params(params),
            base: &params,
            frame: f,
        };
        fly.refine(
            &pool,
            &mut lists,
            &mut cameras,
            &mut frame,
            &mut flight.refine_ns,
        )?;
        if f == 0 {
            flight.open_to_first_frame = opened.elapsed();
        }
        frame.oldest_want = ages(&mut waited, lists.wants(), f);
        pool.apply(&mut lists)
            .map_err(|e| format!("frame {f}: {e}"))?;
        let now = Duration::from_secs_f64(f as f64 / FPS);
        let s = streamer.frame(&mut pool, &roots, now, &mut faults);
        frame.requested = s.schedule.requested;
        frame.installs = s.installs;
        frame.evictions = s.schedule.evictions;
        frame.bytes_read = s.bytes_read;
        frame.faults = s.faults;
        let stats = pool.stats();
        frame.resident = stats.resident;
        pressure.update(&PressureSignal::new(
            config.slots,
            &stats,
            &s.schedule,
            frame.deferred,
            frame.active_nodes,
        ));
        flight.frames.push(frame);
    }
    flight.reads = lists.reads();
    flight.faults = faults
        .iter()
        .map(|e| format!("{}: {e}", paths[e.key.file as usize].display()))
        .collect();
    flight.peak_rss = caveclod_bake::ooc::peak_rss_bytes();
    if let Some(path) = &stream.baseline {
        let scales: Vec<f32> = flight.frames.iter().map(|f| f.pressure).collect();
        let baseline = BaselineFlight {
            root: &roots[0],
            views: &views,
            params: &params,
            scales: &scales,
            camera_polygons: stream.camera_polygons,
            morphs,
        };
        flight.baseline = Some(baseline.fly(path)?);
    }
    Ok(flight)
}

impl StreamedFlight {
    /// An empty record of a flight over `files`, with the memory it holds.
    fn new(
        paths: &[PathBuf],
        names: Vec<&'static str>,
        files: &[PagedFile],
        roots: &[PagedRoot<'_>],
        config: &PoolConfig,
        cameras: &[CameraState<'_>],
    ) -> Self {
        Self {
            files: paths.to_vec(),
            names,
            frames: Vec::new(),
            refine_ns: Vec::new(),
            faults: Vec::new(),
            open_to_first_frame: Duration::ZERO,
            pages: (
                roots.iter().map(|r| r.table().len()).sum(),
                roots.iter().map(|r| r.paged().root_pages as usize).sum(),
            ),
            pool: (config.pool_bytes(), config.slots),
            bookkeeping_bytes: 4 * (words_len(config)) + WANTS * std::mem::size_of::<Want>(),
            camera_bytes: cameras.iter().map(CameraState::bytes).sum(),
            root_bytes: files.iter().map(|f| f.root_bytes().len()).sum(),
            reads: StreamedReads::default(),
            peak_rss: None,
            baseline: None,
        }
    }
}

/// One frame's refinement of every camera over every file.
struct Fly<'a> {
    roots: &'a [PagedRoot<'a>],
    views: &'a [Vec<View>],
    /// The parameters refined with: the flight's, under the pool's pressure.
    params: &'a RefineParams,
    /// The flight's own, which the lag is measured against.
    base: &'a RefineParams,
    frame: usize,
}

impl Fly<'_> {
    /// Refines each camera over each file's streamed records (timed), then measures its lag
    /// (not timed).
    fn refine(
        &self,
        pool: &Residency<'_, '_>,
        lists: &mut FrameLists<'_>,
        cameras: &mut [CameraState<'_>],
        frame: &mut StreamedFrame,
        refine_ns: &mut Vec<u64>,
    ) -> Result<(), String> {
        let per_file = self.views.len();
        for (i, root) in self.roots.iter().enumerate() {
            let records = StreamedHierarchy::new(root, pool, i as u32, lists);
            for (k, cam) in cameras[i * per_file..(i + 1) * per_file]
                .iter_mut()
                .enumerate()
            {
                let view = &self.views[k][self.frame];
                let t = Instant::now();
                let st = cam
                    .refine(&records, view, self.params)
                    .map_err(|e| format!("frame {}: camera {k}: {e}", self.frame))?;
                let ns = t.elapsed().as_nanos() as u64;
                refine_ns.push(ns);
                frame.refine_max_ms = frame.refine_max_ms.max(ns as f32 / 1e6);
                frame.operations += st.operations();
                frame.deferred += st.deferred_splits;
                frame.active_nodes += st.active_nodes;
                frame.active_polygons += st.active_polygons;
                let lag = cam
                    .lag(&records, view, self.base)
                    .map_err(|e| e.to_string())?;
                frame.lag_px += lag.excess_px;
                frame.worst_lag_px = frame.worst_lag_px.max(lag.worst_excess_px);
            }
        }
        Ok(())
    }
}

/// The page reader for `files`, through the simulated disk `stream` describes.
fn streamer_for(
    files: &[PagedFile],
    config: &PoolConfig,
    stream: &StreamOptions,
) -> Result<Streamer, String> {
    let reader = ReaderConfig {
        max_in_flight: READS_IN_FLIGHT,
        max_read_len: config.slot_bytes,
        disk: (stream.io_bytes_per_s > 0.0)
            .then(|| DiskModel::new(stream.io_latency, stream.io_bytes_per_s)),
        ..ReaderConfig::default()
    };
    let sources = files.iter().map(PagedFile::source).collect();
    Streamer::new(sources, reader, LOADS_PER_FRAME).map_err(|e| format!("page reader: {e}"))
}

/// The pool for `roots`' files: slots of their largest streamed page.
fn pool_config(roots: &[PagedRoot<'_>], pool_bytes: u64) -> Result<PoolConfig, String> {
    let largest = roots
        .iter()
        .map(|r| r.paged().largest_page)
        .max()
        .unwrap_or(0)
        .max(64);
    let pages: usize = roots.iter().map(|r| r.table().len()).sum();
    let pages = u32::try_from(pages).map_err(|_| "more pages than a pool counts".to_string())?;
    let config = PoolConfig::new(
        pool_bytes,
        largest.next_multiple_of(64),
        roots.len() as u32,
        pages,
    );
    if config.slots == 0 {
        return Err(format!(
            "--pool {pool_bytes} bytes holds no page of {} bytes",
            config.slot_bytes
        ));
    }
    Ok(config)
}

fn words_len(config: &PoolConfig) -> usize {
    Residency::words_needed(config) + FrameLists::words_needed(config)
}

/// Points the flight's ground is made of, within the file's bounds: the root pages'
/// positions, and the top corners of each small page box (a page's box holds its nodes'
/// bounding spheres, so it is above the surface there; boxes wider than an eighth of the
/// file are left out, being far above it).
fn root_points<'a>(root: &'a PagedRoot<'a>) -> impl Iterator<Item = [f32; 3]> + 'a {
    let (lo, hi) = (root.meta().bounds_min, root.meta().bounds_max);
    let small = (hi[0] - lo[0]).max(hi[2] - lo[2]) / 8.0;
    let inside = (0..root.paged().root_pages)
        .filter_map(|p| root.root_page(p))
        .flat_map(|v| v.positions.iter().map(|p| p.xyz));
    let clamp =
        move |x: f32, z: f32, y: f32| [x.clamp(lo[0], hi[0]), y.min(hi[1]), z.clamp(lo[2], hi[2])];
    let boxes = root
        .table()
        .entries()
        .iter()
        .filter(move |e| {
            (e.bounds_max[0] - e.bounds_min[0]).max(e.bounds_max[2] - e.bounds_min[2]) <= small
        })
        .flat_map(move |e| {
            let (a, b) = (e.bounds_min, e.bounds_max);
            [
                clamp(a[0], a[2], b[1]),
                clamp(b[0], a[2], b[1]),
                clamp(a[0], b[2], b[1]),
                clamp(b[0], b[2], b[1]),
            ]
        });
    inside.chain(boxes)
}

/// Words of each camera's memory, per file and camera (file-major).
fn camera_memories(
    roots: &[PagedRoot<'_>],
    pool: &Residency<'_, '_>,
    lists: &mut FrameLists<'_>,
    per_file: usize,
    stream: &StreamOptions,
    morphs: u32,
) -> Vec<Vec<u32>> {
    let mut out = Vec::new();
    for (i, root) in roots.iter().enumerate() {
        let records = StreamedHierarchy::new(root, pool, i as u32, lists);
        let c =
            CameraConfig::with_polygon_budget(&records, stream.camera_polygons).with_morphs(morphs);
        let words = CameraState::words_needed_for(&records, &c);
        out.extend((0..per_file).map(|_| vec![0u32; words]));
    }
    out
}

/// The cameras over `memories`, file-major, each at its file's base mesh.
fn make_cameras<'m>(
    roots: &[PagedRoot<'_>],
    pool: &Residency<'_, '_>,
    lists: &mut FrameLists<'_>,
    memories: &'m mut [Vec<u32>],
    stream: &StreamOptions,
    morphs: u32,
) -> Result<Vec<CameraState<'m>>, String> {
    let per_file = memories.len() / roots.len().max(1);
    let mut cameras = Vec::with_capacity(memories.len());
    for (i, memory) in memories.iter_mut().enumerate() {
        let file = i / per_file.max(1);
        let records = StreamedHierarchy::new(&roots[file], pool, file as u32, lists);
        let c =
            CameraConfig::with_polygon_budget(&records, stream.camera_polygons).with_morphs(morphs);
        let cam = CameraState::with_config(&records, memory, &c).map_err(|e| e.to_string())?;
        cameras.push(cam);
    }
    Ok(cameras)
}

/// Since when each wanted page has been wanted without a break, updated for frame `f`'s
/// wants: the longest wait, in frames.
fn ages(waited: &mut HashMap<PageKey, usize>, wants: &[Want], f: usize) -> u32 {
    let mut oldest = 0;
    let mut seen = std::collections::HashSet::with_capacity(wants.len());
    for w in wants {
        let since = *waited.entry(w.page).or_insert(f);
        oldest = oldest.max(f - since);
        seen.insert(w.page);
    }
    waited.retain(|k, _| seen.contains(k));
    oldest as u32
}
