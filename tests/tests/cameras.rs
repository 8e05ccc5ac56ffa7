//! Several cameras over one shared hierarchy: on separate threads, with fixed budgets, and
//! against the wrong hierarchy.

use caveclod_core::glam::Vec3;
use caveclod_core::{
    CameraConfig, CameraError, CameraState, Hierarchy, OpError, RefineParams, View,
};
use caveclod_tests::check::check_front;
use caveclod_tests::{bake, meshes};

fn view(t: f32, k: usize) -> View {
    let a = t + k as f32 * 1.7;
    let eye = Vec3::new(20.0 + 18.0 * a.cos(), 6.0 + k as f32, 20.0 + 18.0 * a.sin());
    View::perspective(
        eye,
        Vec3::new(20.0, 0.0, 20.0),
        Vec3::Y,
        1.0,
        1.6,
        0.1,
        500.0,
        720.0,
    )
}

/// Refines `frames` frames of camera `k` alone and returns its final corners.
fn run_alone(
    h: &Hierarchy<'_>,
    k: usize,
    frames: usize,
) -> Vec<Option<[caveclod_core::NodeId; 3]>> {
    let mut mem = vec![0u32; CameraState::words_needed(h)];
    let mut cam = CameraState::new(h, &mut mem).expect("sized");
    for f in 0..frames {
        cam.refine(h, &view(f as f32 * 0.05, k), &RefineParams::default())
            .expect("refine");
    }
    (0..h.polygon_count() as u32)
        .map(|f| cam.polygon_corners(h, caveclod_core::PolyId(f)))
        .collect()
}

#[test]
fn cameras_on_threads_match_cameras_alone() {
    let baked = bake(&meshes::terrain(40, 40, 11));
    let h = baked.hierarchy();
    let alone: Vec<_> = (0..4).map(|k| run_alone(&h, k, 30)).collect();
    let threaded: Vec<_> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..4)
            .map(|k| {
                let h = &h;
                s.spawn(move || run_alone(h, k, 30))
            })
            .collect();
        handles
            .into_iter()
            .map(|j| j.join().expect("thread"))
            .collect()
    });
    assert_eq!(alone, threaded);
    // Different views really give different fronts.
    assert_ne!(alone[0], alone[1]);
}

#[test]
fn camera_states_move_between_threads() {
    let baked = bake(&meshes::terrain(24, 24, 4));
    let h = baked.hierarchy();
    let mut mem = vec![0u32; CameraState::words_needed(&h)];
    let mut cam = CameraState::new(&h, &mut mem).expect("sized");
    std::thread::scope(|s| {
        s.spawn(|| {
            cam.refine(&h, &view(0.0, 0), &RefineParams::default())
                .expect("refine")
        })
        .join()
        .expect("thread");
    });
    check_front(&h, &cam).expect("front");
    assert!(cam.split_count() > 0);
}

#[test]
fn a_budgeted_camera_refuses_splits_instead_of_failing() {
    let baked = bake(&meshes::terrain(40, 40, 2));
    let h = baked.hierarchy();
    let budget = h.base_polygon_count() as u32 + 200;
    let config = CameraConfig::with_polygon_budget(&h, budget);
    let mut mem = vec![0u32; CameraState::words_needed_for(&h, &config)];
    assert!(mem.len() < CameraState::words_needed(&h));
    let mut cam = CameraState::with_config(&h, &mut mem, &config).expect("sized");
    let close = View::perspective(
        Vec3::new(20.0, 3.0, 20.0),
        Vec3::new(30.0, 0.0, 30.0),
        Vec3::Y,
        1.2,
        1.6,
        0.01,
        500.0,
        2000.0,
    );
    let st = cam
        .refine(
            &h,
            &close,
            &RefineParams {
                tolerance_px: 0.1,
                ..RefineParams::default()
            },
        )
        .expect("refine");
    assert!(st.capacity_refusals > 0, "{st:?}");
    assert!(cam.active_polygon_count() <= budget);
    assert_eq!(cam.split_count(), cam.max_pairs());
    check_front(&h, &cam).expect("front");
}

#[test]
fn capacity_and_hierarchy_errors_are_typed() {
    let baked = bake(&meshes::terrain(10, 10, 2));
    let h = baked.hierarchy();
    let needed = CameraState::words_needed(&h);
    let mut small = vec![0u32; needed - 1];
    assert_eq!(
        CameraState::new(&h, &mut small).err(),
        Some(CameraError::Capacity {
            needed,
            given: needed - 1
        })
    );
    let bytes = baked.to_bytes();
    let h_file = Hierarchy::from_bytes(&bytes).expect("valid");
    let mut mem = vec![0u32; needed];
    let mut cam = CameraState::new(&h_file, &mut mem).expect("sized");
    assert_eq!(
        cam.refine(&h, &view(0.0, 0), &RefineParams::default()),
        Err(OpError::WrongHierarchy)
    );
}
