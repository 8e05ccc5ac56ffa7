//! The streaming path end to end: a baked terrain written paged, its root opened alone, its
//! pages wanted around a point moving over it, loaded by the page reader through a
//! simulated slow disk on a 60 Hz clock into a pool a quarter of the streamed bytes, and
//! installed with their checks; closure holds every frame and pages are evicted to make
//! room. A copy with damaged pages reports each bad page once and streams the rest.

use std::time::Duration;

use caveclod_bake::paged::{write_paged, PageOptions};
use caveclod_core::format::paged::PagedRoot;
use caveclod_core::stream::{PageFault, PageKey, PageState, PoolConfig, Residency};
use caveclod_io::pages::{DiskModel, ReaderConfig};
use caveclod_io::{AlignedBytes, PagedFile, Streamer};
use caveclod_tests::{bake, meshes};

/// A paged terrain in a temporary directory.
fn paged_terrain(dir: &std::path::Path) -> std::path::PathBuf {
    let baked = bake(&meshes::terrain(40, 40, 9));
    let path = dir.join("terrain.clod");
    write_paged(&baked.hierarchy(), &path, &PageOptions { page_bytes: 4096 }).expect("paged");
    path
}

struct Flight {
    installs: u64,
    evictions: u64,
    faults: Vec<PageFault>,
    wanted_resident: u32,
}

/// Flies a point across the terrain for `frames` frames, wanting the pages whose boxes lie
/// within a fifth of the terrain of it.
fn fly(file: &PagedFile, frames: u32) -> Flight {
    fly_installing(file, frames, usize::MAX)
}

/// [`fly`], installing at most `max_installs` pages a frame.
fn fly_installing(file: &PagedFile, frames: u32, max_installs: usize) -> Flight {
    let root = file.root().expect("root");
    let table = root.table();
    let streamed: u64 = table.entries()[1..].iter().map(|e| u64::from(e.size)).sum();
    let slot_bytes = root.paged().largest_page.next_multiple_of(64);
    let config = PoolConfig::new(streamed / 4, slot_bytes, 1, table.len() as u32);
    let mut words = vec![0u32; Residency::words_needed(&config)];
    let mut pool_bytes = AlignedBytes::zeroed(config.pool_bytes());
    let mut tables = vec![None; 1];
    let mut pool =
        Residency::new(config, &mut words, pool_bytes.bytes_mut(), &mut tables).expect("pool");
    pool.add_file(table, root.paged().root_pages).expect("file");
    let disk = DiskModel::new(Duration::from_millis(8), 20e6);
    let reader = ReaderConfig {
        threads: 2,
        max_in_flight: 16,
        max_read_len: slot_bytes,
        disk: Some(disk),
    };
    let streamer = Streamer::new(vec![file.source()], reader, 8).expect("streamer");
    let mut streamer = streamer.with_max_installs(max_installs);
    let (lo, hi) = (root.meta().bounds_min, root.meta().bounds_max);
    let reach = (hi[0] - lo[0]) / 5.0;
    let mut flight = Flight {
        installs: 0,
        evictions: 0,
        faults: Vec::new(),
        wanted_resident: 0,
    };
    for frame in 0..frames {
        let t = frame as f32 / frames as f32;
        let point = [
            lo[0] + (hi[0] - lo[0]) * t,
            0.0,
            lo[2] + (hi[2] - lo[2]) * (0.5 + 0.4 * (t * 6.0).sin()),
        ];
        pool.begin_frame();
        for (page, e) in (0..)
            .zip(table.entries())
            .skip(root.paged().root_pages as usize)
        {
            let dx = (point[0] - e.bounds_max[0])
                .max(e.bounds_min[0] - point[0])
                .max(0.0);
            let dz = (point[2] - e.bounds_max[2])
                .max(e.bounds_min[2] - point[2])
                .max(0.0);
            if dx.hypot(dz) < reach {
                pool.want(PageKey { file: 0, page }, e.max_error)
                    .expect("want");
            }
        }
        let now = Duration::from_secs_f64(f64::from(frame) / 60.0);
        let f = streamer.frame(&mut pool, &[root], now, &mut flight.faults);
        flight.installs += u64::from(f.installs);
        assert!(
            f.installs as usize <= max_installs,
            "frame {frame}: {}",
            f.installs
        );
        assert!(streamer.installed().len() <= f.installs as usize);
        for &key in streamer.installed() {
            assert_eq!(pool.state(key), Some(PageState::Resident));
        }
        flight.evictions += u64::from(f.schedule.evictions);
        assert_closure(&pool, &root);
    }
    flight.wanted_resident = pool.stats().resident;
    flight
}

/// Every resident page has its parents resident; a loading page's are resident or loading
/// (a chain loads at once and installs parents first).
fn assert_closure(pool: &Residency<'_, '_>, root: &PagedRoot<'_>) {
    let table = root.table();
    for page in 0..table.len() as u32 {
        let state = pool.state(PageKey { file: 0, page }).expect("state");
        if matches!(state, PageState::Resident | PageState::Loading) {
            for &p in table.parents(page) {
                let parent = pool.state(PageKey { file: 0, page: p });
                let ok = parent == Some(PageState::Resident)
                    || (parent == Some(PageState::Loading) && state == PageState::Loading);
                assert!(ok, "page {page} ({state:?})'s parent {p}: {parent:?}");
            }
        }
    }
}

#[test]
fn pages_stream_through_a_slow_disk_into_a_quarter_sized_pool() {
    let dir = tempfile::tempdir().expect("dir");
    let file = PagedFile::open(paged_terrain(dir.path())).expect("open");
    let flight = fly(&file, 240);
    assert!(flight.faults.is_empty(), "{:?}", flight.faults);
    assert!(flight.installs > 20, "{} installs", flight.installs);
    assert!(flight.evictions > 0, "no eviction");
    assert!(flight.wanted_resident > 0);
}

#[test]
fn a_cap_on_installs_holds_what_arrived_for_the_next_frames() {
    let dir = tempfile::tempdir().expect("dir");
    let file = PagedFile::open(paged_terrain(dir.path())).expect("open");
    let flight = fly_installing(&file, 240, 1);
    assert!(flight.faults.is_empty(), "{:?}", flight.faults);
    assert!(flight.installs > 20, "{} installs", flight.installs);
}

#[test]
fn damaged_pages_are_reported_once_and_the_rest_stream() {
    let dir = tempfile::tempdir().expect("dir");
    let path = paged_terrain(dir.path());
    let mut bytes = std::fs::read(&path).expect("read");
    let root_len = {
        let f = PagedFile::open(&path).expect("open");
        f.root_bytes().len()
    };
    let damaged: Vec<u32> = {
        let f = PagedFile::open(&path).expect("open");
        let root = f.root().expect("root");
        let table = root.table();
        // Late pages: the ones above them still stream (an early page takes its subtree).
        let n = table.len() as u32;
        let bad: Vec<u32> = (2 * n / 3..n).step_by(5).collect();
        for &p in &bad {
            let e = table.entry(p).expect("entry");
            bytes[e.offset as usize + e.size as usize / 2] ^= 0x10;
        }
        bad
    };
    assert!(root_len < bytes.len());
    let copy = dir.path().join("damaged.clod");
    std::fs::write(&copy, &bytes).expect("write");
    let file = PagedFile::open(&copy).expect("the root is intact");
    let flight = fly(&file, 240);
    let mut reported: Vec<u32> = flight.faults.iter().map(|f| f.key.page).collect();
    let before = reported.len();
    reported.sort_unstable();
    reported.dedup();
    assert_eq!(reported.len(), before, "a page was reported twice");
    assert!(!reported.is_empty());
    assert!(reported.iter().all(|p| damaged.contains(p)), "{reported:?}");
    assert!(flight.installs > 10, "{} installs", flight.installs);
}
