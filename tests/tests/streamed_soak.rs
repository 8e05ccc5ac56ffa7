//! The streamed soak, short: four cameras for 5,000 frames over a paged terrain streaming
//! into a pool a twentieth of its pages, with teleports, resets and redrawn knobs (see
//! `caveclod_tests::soak::streamed`); every camera's front and every page's use count
//! checked every 500 frames; no read of an absent page; not one allocation in the frame
//! loop.

#[path = "../../core/tests/counting/mod.rs"]
mod counting;

use caveclod_bake::paged::{write_paged, PageOptions};
use caveclod_io::PagedFile;
use caveclod_tests::soak::streamed::{run_streamed, StreamedSoakConfig};
use caveclod_tests::{bake, meshes};

#[test]
fn five_thousand_frames_in_a_twentieth_pool_keep_every_invariant_without_allocating() {
    counting::assert_counting();
    let baked = bake(&meshes::terrain(72, 72, 23));
    let dir = tempfile::tempdir().expect("dir");
    let path = dir.path().join("terrain.clod");
    write_paged(&baked.hierarchy(), &path, &PageOptions { page_bytes: 2048 }).expect("paged");
    let bytes = std::fs::read(&path).expect("read");
    let file = PagedFile::open(&path).expect("open");
    let root = file.root().expect("root");
    let config = StreamedSoakConfig {
        frames: 5000,
        seed: 0x57EA_2026,
        check_every: 500,
        pool_divisor: 20,
    };
    let r = run_streamed(&root, &bytes, &config, &counting::allocations)
        .unwrap_or_else(|e| panic!("{e}"));
    eprintln!("{r:#?}");
    assert_eq!(r.frames, 5000);
    assert_eq!(r.front_checks, 10 * 4);
    assert_eq!(r.allocations, 0, "the frame loop allocated");
    assert_eq!((r.absent_reads, r.untracked_uses), (0, 0));
    assert!(r.slots * 20 <= r.streamed_pages + 20, "{} slots", r.slots);
    let happened = [
        ("splits", r.splits),
        ("collapses", r.collapses),
        ("deferred splits", r.deferred),
        ("morphs started", r.morphs_started),
        (
            "installs past the pool's slots",
            r.installs.saturating_sub(u64::from(r.slots)),
        ),
        ("evictions", r.evictions),
        ("teleports", r.teleports),
        ("resets", r.resets),
    ];
    for (what, n) in happened {
        assert!(n > 0, "no {what}: {r:#?}");
    }
    assert!(r.max_pressure > 1.0, "the small pool never pressed: {r:#?}");
}
