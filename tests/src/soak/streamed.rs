//! The soak over a paged file streaming into a small pool: four cameras refine over one
//! [`StreamedHierarchy`] for many frames, with the pilots of the whole-file soak (teleports,
//! speeds, viewports, fixed and regulated tolerances, call bounds, culling, the morph clock)
//! and now and then a reset; one [`Pressure`] scales their tolerances when the pool or the
//! reads fall behind. Pages load synchronously from the file's bytes, at most a few a frame,
//! so splits wait and pages are evicted all the time.
//!
//! Every `check_every` frames and after the last, every camera's front is checked from
//! scratch over the streamed records ([`check_records_front`]), and every page's use count
//! against the fronts standing on it. The frame loop allocates nothing (the caller's
//! counter says), and reads no absent page (the lists count it).

use caveclod_core::format::paged::PagedRoot;
use caveclod_core::stream::{
    FrameLists, LoadRequest, PageKey, PageState, PageTable, PoolConfig, Pressure, PressureSignal,
    Residency, ScheduleStats, StreamedHierarchy, Want,
};
use caveclod_core::{CameraConfig, CameraState, RefineStats};

use caveclod_bake::generate::SplitMix64;
use caveclod_io::AlignedBytes;

use super::pilot::{one_in, Pilot, Terrain, Tolerance, MAX_MORPHS};
use super::CAMERAS;
use crate::check::check_records_front;

/// Loads issued a frame at most: a slow disk, so the pool always has work queued.
const LOADS_PER_FRAME: usize = 8;

/// What to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StreamedSoakConfig {
    /// Frames; each refines every camera once.
    pub frames: u64,
    /// The seed every random choice comes from.
    pub seed: u64,
    /// Frames between full checks.
    pub check_every: u64,
    /// The pool holds the file's streamed pages divided by this.
    pub pool_divisor: u32,
}

/// What a streamed soak did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StreamedSoakReport {
    /// Frames run.
    pub frames: u64,
    /// Refinement calls.
    pub refinements: u64,
    /// Splits and collapses applied by refinement.
    pub splits: u64,
    pub collapses: u64,
    /// Splits deferred for absent pages.
    pub deferred: u64,
    /// Morphs started.
    pub morphs_started: u64,
    /// Pages installed and evicted.
    pub installs: u64,
    pub evictions: u64,
    /// The pool's slots, and the file's streamed pages.
    pub slots: u32,
    pub streamed_pages: u32,
    /// Teleports and resets.
    pub teleports: u64,
    pub resets: u64,
    /// The largest tolerance scale pressure reached.
    pub max_pressure: f32,
    /// Full checks of a camera's front, and of the pool's use counts.
    pub front_checks: u64,
    pub use_checks: u64,
    /// Reads of absent pages, and front nodes on pages not resident (both must be 0).
    pub absent_reads: u64,
    pub untracked_uses: u64,
    /// Allocations in the frame loop (the checks excepted).
    pub allocations: u64,
}

/// The pool's memory: its words, bytes and file table.
struct PoolMemory<'a> {
    config: PoolConfig,
    words: Vec<u32>,
    bytes: AlignedBytes,
    tables: Vec<Option<PageTable<'a>>>,
}

/// Soaks four cameras over `root`'s file (whose bytes are `file`) streaming into a pool a
/// `pool_divisor`th of its streamed pages; `allocations` counts this thread's allocations.
pub fn run_streamed(
    root: &PagedRoot<'_>,
    file: &[u8],
    config: &StreamedSoakConfig,
    allocations: &dyn Fn() -> u64,
) -> Result<StreamedSoakReport, String> {
    let table = root.table();
    let streamed_pages = table.len() as u32 - root.paged().root_pages;
    let slots = (streamed_pages / config.pool_divisor.max(1)).max(1);
    let slot_bytes = root.paged().largest_page.next_multiple_of(64);
    let pool_config = PoolConfig::new(
        u64::from(slots) * u64::from(slot_bytes),
        slot_bytes,
        1,
        table.len() as u32,
    );
    let mut memory = PoolMemory {
        config: pool_config,
        words: vec![0; Residency::words_needed(&pool_config)],
        bytes: AlignedBytes::zeroed(pool_config.pool_bytes()),
        tables: vec![None; 1],
    };
    let mut pool = Residency::new(
        pool_config,
        &mut memory.words,
        memory.bytes.bytes_mut(),
        &mut memory.tables,
    )
    .map_err(|e| e.to_string())?;
    pool.add_file(table, root.paged().root_pages)
        .map_err(|e| e.to_string())?;
    let mut wants = vec![Want::default(); 1024];
    let mut list_words = vec![0u32; FrameLists::words_needed(&memory.config)];
    let mut lists =
        FrameLists::new(&memory.config, &mut wants, &mut list_words).map_err(|e| e.to_string())?;

    let mut rng = SplitMix64::new(config.seed);
    let mut memories = camera_memories(root, &pool, &mut lists, &mut rng);
    let mut cams = {
        let records = StreamedHierarchy::new(root, &pool, 0, &mut lists);
        let mut cams = Vec::with_capacity(CAMERAS);
        for (m, c) in memories.iter_mut() {
            cams.push(CameraState::with_config(&records, m, c).map_err(|e| e.to_string())?);
        }
        cams
    };
    let terrain = Terrain::of(root.meta());
    let mut pilots: Vec<Pilot> = (0..CAMERAS)
        .map(|_| Pilot::new(&mut rng, &terrain))
        .collect();
    let mut pressure = Pressure::new().with_max_scale(8.0);
    let mut report = StreamedSoakReport {
        slots,
        streamed_pages,
        ..StreamedSoakReport::default()
    };
    let check_every = config.check_every.max(1);
    let mut loads = [LoadRequest::default(); LOADS_PER_FRAME];
    let mut evicted = [PageKey::default(); LOADS_PER_FRAME];

    for frame in 0..config.frames {
        let before = allocations();
        pool.begin_frame();
        let (mut deferred, mut active_nodes) = (0, 0);
        {
            let records = StreamedHierarchy::new(root, &pool, 0, &mut lists);
            for (cam, pilot) in cams.iter_mut().zip(&mut pilots) {
                events(&records, cam, pilot, &terrain, &mut rng, &mut report);
                pilot.fly(&terrain);
                let params = pressure.params(pilot.frame_params());
                let st = cam
                    .refine(&records, &pilot.view(&terrain), &params)
                    .map_err(|e| format!("frame {frame}: refine: {e}"))?;
                if let Tolerance::Regulated(r) = &mut pilot.tolerance {
                    r.update(st.active_polygons + 2 * st.capacity_refusals);
                }
                add_pass(&mut report, &st);
                deferred += st.deferred_splits;
                active_nodes += st.active_nodes;
            }
        }
        pool.apply(&mut lists)
            .map_err(|e| format!("frame {frame}: {e}"))?;
        let s = load(&mut pool, root, file, &mut loads, &mut evicted)
            .map_err(|e| format!("frame {frame}: {e}"))?;
        report.installs += u64::from(s.loads);
        report.evictions += u64::from(s.evictions);
        let scale = pressure.update(&PressureSignal::new(
            slots,
            &pool.stats(),
            &s,
            deferred,
            active_nodes,
        ));
        report.max_pressure = report.max_pressure.max(scale);
        report.allocations += allocations() - before;
        report.frames = frame + 1;
        if report.frames.is_multiple_of(check_every) || report.frames == config.frames {
            let records = StreamedHierarchy::new(root, &pool, 0, &mut lists);
            for (c, cam) in cams.iter().enumerate() {
                check_records_front(&records, cam)
                    .map_err(|e| format!("frame {frame}: camera {c}: {e}"))?;
                report.front_checks += 1;
            }
            let fronts: Vec<&CameraState<'_>> = cams.iter().collect();
            check_page_uses(&pool, root, &fronts).map_err(|e| format!("frame {frame}: {e}"))?;
            report.use_checks += 1;
        }
    }
    let reads = lists.reads();
    report.absent_reads = reads.absent_reads;
    report.untracked_uses = u64::from(reads.untracked_uses);
    Ok(report)
}

/// Each camera's configuration (a polygon budget, morphs or none) and memory.
fn camera_memories(
    root: &PagedRoot<'_>,
    pool: &Residency<'_, '_>,
    lists: &mut FrameLists<'_>,
    rng: &mut SplitMix64,
) -> Vec<(Vec<u32>, CameraConfig)> {
    let records = StreamedHierarchy::new(root, pool, 0, lists);
    (0..CAMERAS)
        .map(|_| {
            let budget = [500, 2_000, 8_000, 30_000][rng.below(4)];
            let mut c = CameraConfig::with_polygon_budget(&records, budget);
            if !one_in(rng, 4) {
                c = c.with_morphs([16, 256, MAX_MORPHS][rng.below(3)]);
            }
            (vec![0u32; CameraState::words_needed_for(&records, &c)], c)
        })
        .collect()
}

/// Schedules the frame's loads and installs them from the file's bytes, synchronously.
fn load(
    pool: &mut Residency<'_, '_>,
    root: &PagedRoot<'_>,
    file: &[u8],
    loads: &mut [LoadRequest],
    evicted: &mut [PageKey],
) -> Result<ScheduleStats, String> {
    let s = pool.schedule(loads, evicted);
    for l in &loads[..s.loads as usize] {
        let bytes = file
            .get(l.offset as usize..l.offset as usize + l.size as usize)
            .ok_or("a page past the file's end")?;
        pool.loading_slot_mut(l.slot)
            .map_err(|e| e.to_string())?
            .copy_from_slice(bytes);
        pool.install(l.slot, root)
            .map_err(|e| format!("install: {e}"))?;
    }
    Ok(s)
}

/// A camera's random events: a teleport, a reset, new knobs.
fn events(
    records: &StreamedHierarchy<'_, '_, '_, '_>,
    cam: &mut CameraState<'_>,
    pilot: &mut Pilot,
    terrain: &Terrain,
    rng: &mut SplitMix64,
    report: &mut StreamedSoakReport,
) {
    if one_in(rng, 200) {
        pilot.teleport(rng, terrain);
        report.teleports += 1;
    }
    if one_in(rng, 1000) {
        cam.reset(records);
        report.resets += 1;
    }
    if one_in(rng, 300) {
        pilot.draw_speed(rng);
        pilot.draw_bounds(rng);
        pilot.draw_clock(rng);
        let px = pilot.tolerance_px();
        pilot.draw_tolerance(rng, px, cam.active_polygon_count().max(1000) as usize);
    }
}

fn add_pass(report: &mut StreamedSoakReport, st: &RefineStats) {
    report.refinements += 1;
    report.splits += u64::from(st.splits);
    report.collapses += u64::from(st.collapses);
    report.deferred += u64::from(st.deferred_splits);
    report.morphs_started += u64::from(st.morphs_started);
}

/// Every streamed page's use count is the number of front nodes standing on it, over all
/// `cams`, and each such page is resident.
pub fn check_page_uses(
    pool: &Residency<'_, '_>,
    root: &PagedRoot<'_>,
    cams: &[&CameraState<'_>],
) -> Result<(), String> {
    let ids = root.ids();
    let mut on = vec![0u32; root.table().len()];
    for cam in cams {
        for n in cam.active_nodes() {
            on[ids.page(n.0) as usize] += 1;
        }
    }
    for page in root.paged().root_pages..root.table().len() as u32 {
        let key = PageKey { file: 0, page };
        let want = on[page as usize];
        if pool.uses(key) != Some(want) {
            return Err(format!(
                "page {page}: {:?} uses, {want} front nodes",
                pool.uses(key)
            ));
        }
        if want > 0 && pool.state(key) != Some(PageState::Resident) {
            return Err(format!(
                "page {page} holds {want} front nodes but is not resident"
            ));
        }
    }
    Ok(())
}
