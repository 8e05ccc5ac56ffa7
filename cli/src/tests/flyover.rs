//! The fly-over experiment on a small generated terrain: every mode flies, reports the stable
//! JSON keys, and per-camera state needs fewer operations than one shared state.

use crate::flyover::{fly, fly_interleaved_sharing, Flyover, FlyoverOptions, Mode, Sizings};
use caveclod_tests::{bake, meshes};

#[test]
fn modes_fly_and_per_camera_state_saves_operations() {
    let baked = bake(&meshes::terrain(64, 64, 3));
    let h = baked.hierarchy();
    let options = FlyoverOptions {
        cameras: 4,
        frames: 40,
        tolerance: 2.0,
        mode: Mode::PerCamera,
        full_capacity: false,
        first_route: 0,
        compact_every: 30,
        compact_step: crate::flyover::COMPACT_STEP,
        visit_fraction: crate::flyover::VISIT_FRACTION,
        frames_in_flight: 2,
        index_cache: true,
        pin_threads: true,
        hashed_pair_map: false,
        geomorphs: true,
        morph_speed_px_s: 9.0,
        morph_radius_tolerances: 16.0,
        morph_guard_rad: 0.1,
        target_polygons: None,
        index_edits: 0,
    };
    let per = fly(&h, &options).expect("per-camera flight");
    let shared = fly(
        &h,
        &FlyoverOptions {
            mode: Mode::Shared,
            ..options
        },
    )
    .expect("shared");
    let threads = fly(
        &h,
        &FlyoverOptions {
            mode: Mode::Threads,
            ..options
        },
    )
    .expect("threads");
    let (p, s, t) = (per.json(), shared.json(), threads.json());
    for j in [&p, &s, &t] {
        for key in [
            "cameras",
            "frames",
            "ops_per_camera_per_frame",
            "refine_ms_per_frame",
            "active_polygons",
            "static_bytes",
            "camera_bytes",
            "paper_camera_bytes",
        ] {
            assert!(j.get(key).is_some(), "missing {key} in {j}");
        }
    }
    let ops = |j: &serde_json::Value| j["ops_per_camera_per_frame"]["mean"].as_f64().unwrap();
    assert!(
        ops(&p) * 2.0 < ops(&s),
        "per-camera {} vs shared {}",
        ops(&p),
        ops(&s)
    );
    // Threads change nothing but the schedule: the same operations, whether the cameras
    // keep in step every frame or run up to two frames apart.
    assert_eq!(ops(&p), ops(&t));
    for frames_in_flight in [1, 3] {
        let other = fly(
            &h,
            &FlyoverOptions {
                mode: Mode::Threads,
                frames_in_flight,
                ..options
            },
        )
        .expect("threads");
        assert_eq!(other.json()["frames_in_flight"], frames_in_flight);
        assert_eq!(ops(&p), ops(&other.json()), "{frames_in_flight} in flight");
    }
    assert!(per.human().contains("per camera, budgeted"));
    assert!(fly(
        &h,
        &FlyoverOptions {
            cameras: 5,
            ..options
        }
    )
    .is_err());
}

#[test]
fn interleaved_flights_do_what_each_does_alone() {
    let baked = bake(&meshes::terrain(64, 64, 3));
    let h = baked.hierarchy();
    let base = FlyoverOptions {
        cameras: 2,
        frames: 25,
        tolerance: 2.0,
        ..FlyoverOptions::default()
    };
    let options = [
        base,
        FlyoverOptions {
            mode: Mode::Threads,
            ..base
        },
        FlyoverOptions {
            cameras: 1,
            first_route: 1,
            ..base
        },
        FlyoverOptions {
            index_cache: false,
            ..base
        },
        FlyoverOptions {
            index_cache: false,
            hashed_pair_map: true,
            ..base
        },
        // Flown again, with fresh states (and the first one's sizing flight).
        base,
    ];
    // Segments of 10 frames: 10, 10 and 5.
    let together =
        fly_interleaved_sharing(&h, &options, 10, &mut Sizings::default()).expect("interleaved");
    assert_eq!(together.len(), options.len());
    for (o, t) in options.iter().zip(&together) {
        let alone = fly(&h, o).expect("alone");
        assert_eq!(t.names, alone.names);
        assert_eq!(t.flight.segment_walls.len(), 3);
        for (a, b) in t.flight.records.iter().zip(&alone.flight.records) {
            assert_eq!(a.ops, b.ops);
            assert_eq!(a.active_polygons, b.active_polygons);
            assert_eq!(a.indices, b.indices);
        }
    }
    // The index cache and the pair map's layout change what a frame costs, not what it does.
    for lean in [&together[3], &together[4]] {
        for (a, b) in together[0].flight.records.iter().zip(&lean.flight.records) {
            assert_eq!(a.ops, b.ops);
            assert_eq!(a.indices, b.indices);
        }
    }
    assert_eq!(together[5].budget, together[0].budget);
    // The repeat shares the first one's sizing flight rather than flying it again (a flight
    // flown again would not take the same nanoseconds).
    let sizing_wall = |f: &Flyover| f.sizing.as_ref().map(|s| s.wall);
    assert!(sizing_wall(&together[0]).is_some());
    assert_eq!(sizing_wall(&together[5]), sizing_wall(&together[0]));
    assert_ne!(sizing_wall(&together[3]), sizing_wall(&together[0]));
    // Across calls too, given one set of sizings.
    let mut sizings = Sizings::default();
    let first = fly_interleaved_sharing(&h, &options[..1], 10, &mut sizings).expect("first");
    let again = fly_interleaved_sharing(&h, &options[..2], 10, &mut sizings).expect("again");
    assert_eq!(sizing_wall(&again[0]), sizing_wall(&first[0]));
    assert_eq!(
        again[0].flight.records[0].ops,
        first[0].flight.records[0].ops
    );
    assert_ne!(sizing_wall(&again[1]), sizing_wall(&first[0]));
    assert_eq!(
        together[5].flight.camera_bytes,
        together[0].flight.camera_bytes
    );
    assert!(together[0].flight.camera_bytes > together[3].flight.camera_bytes);
    // Hashed only where that is smaller (this terrain's budgets may not be).
    assert!(together[3].flight.camera_bytes >= together[4].flight.camera_bytes);
    assert_eq!(together[4].json()["hashed_pair_map"], true);
    let shared = FlyoverOptions {
        mode: Mode::Shared,
        ..base
    };
    assert!(fly_interleaved_sharing(&h, &[base, shared], 10, &mut Sizings::default()).is_err());
}
