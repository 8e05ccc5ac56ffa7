//! The fly-over experiment on a small generated terrain: every mode flies, reports the stable
//! JSON keys, and per-camera state needs fewer operations than one shared state.

use caveclod_bake::flyover::{fly, FlyoverOptions, Mode};
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
    // Threads change nothing but the schedule: the same operations.
    assert_eq!(ops(&p), ops(&t));
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
