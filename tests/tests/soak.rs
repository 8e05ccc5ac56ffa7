//! The runtime's soak, short: four cameras for 5,000 frames over the St. Helens terrain
//! (cropped to the quarter round the crater along each side, so a debug build bakes it in
//! seconds), with random teleports, speeds, tolerances, budgets, resets, compactions,
//! operations, geomorphs and emissions (see `caveclod_tests::soak`); the full invariants of
//! every camera every 1,000 frames; not one allocation in the frame loop; and the same
//! seed gives the same run. The long run is the `soak` example of this package.

#[path = "../../core/tests/counting/mod.rs"]
mod counting;

use std::sync::OnceLock;

use caveclod_tests::soak::terrain::{bake_terrain, st_helens};
use caveclod_tests::soak::{run, SoakConfig, SoakReport, CAMERAS};
use caveclod_tests::AlignedBytes;

/// Share of the terrain's extent along x and z the short soak keeps.
const CROP: f32 = 0.25;

fn terrain() -> &'static AlignedBytes {
    static T: OnceLock<AlignedBytes> = OnceLock::new();
    T.get_or_init(|| bake_terrain(&st_helens(), CROP).unwrap_or_else(|e| panic!("{e}")))
}

fn soak(frames: u64, seed: u64) -> SoakReport {
    let h = terrain().hierarchy().expect("the baker's output is valid");
    let config = SoakConfig {
        frames,
        seed,
        check_every: 1000,
    };
    run(&h, &config, &counting::allocations, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn five_thousand_frames_keep_every_invariant_without_allocating() {
    let r = soak(5000, 0x50A4_2026);
    eprintln!("{r:#?}");
    assert_eq!(r.frames, 5000);
    assert_eq!(r.refinements, 5000 * CAMERAS as u64);
    assert_eq!(r.invariant_checks, 5 * CAMERAS as u64);
    assert_eq!(r.allocations, 0, "the frame loop allocated");
    // The soak exercised what it claims to.
    let happened = [
        ("splits", r.splits),
        ("forced splits", r.forced_splits),
        ("collapses", r.collapses),
        ("API splits", r.api_splits),
        ("API collapses", r.api_collapses),
        ("morphs started", r.morphs_started),
        ("morphs finished", r.morphs_finished),
        ("capacity refusals", r.capacity_refusals),
        ("teleports", r.teleports),
        ("resets", r.resets),
        ("reconfigurations", r.reconfigurations),
        ("whole compactions", r.compactions),
        ("compaction cycles", r.compaction_cycles),
        ("morph finishes", r.morph_finishes),
        ("checked morph slots", r.checked.morph_slots),
    ];
    for (what, n) in happened {
        assert!(n > 0, "no {what} in the soak");
    }
    assert!(r.checked.links > 0 && r.checked.indices > 0);
}

#[test]
fn the_same_seed_runs_the_same_soak() {
    let (a, b, c) = (soak(300, 7), soak(300, 7), soak(300, 8));
    assert_eq!(a, b);
    assert_ne!(a.fingerprint, c.fingerprint);
}

#[test]
fn the_checker_refuses_a_front_that_is_not_of_its_hierarchy() {
    use caveclod_core::CameraState;
    use caveclod_tests::check::split_all;
    use caveclod_tests::soak::FrontChecker;
    use caveclod_tests::{bake, meshes};

    let (a, b) = (
        bake(&meshes::terrain(10, 8, 5)),
        bake(&meshes::terrain(12, 12, 9)),
    );
    let (ha, hb) = (a.hierarchy(), b.hierarchy());
    let mut memory = vec![0u32; CameraState::words_needed(&ha)];
    let mut cam = CameraState::new(&ha, &mut memory).expect("sized");
    split_all(&ha, &mut cam);
    let mut checker = FrontChecker::new(&ha);
    assert!(checker.check(&ha, &cam).is_ok());
    let mut other = FrontChecker::new(&hb);
    assert!(other.check(&hb, &cam).is_err());
}
