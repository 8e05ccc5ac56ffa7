//! Several cameras over one shared hierarchy: on separate threads, with fixed budgets, and
//! against the wrong hierarchy.

use caveclod_core::glam::Vec3;
use caveclod_core::{
    CameraConfig, CameraError, CameraState, Hierarchy, LookAt, OpError, RefineParams, RefineStats,
    View,
};
use caveclod_tests::check::check_front;
use caveclod_tests::{bake, meshes};

fn view(t: f32, k: usize) -> View {
    let a = t + k as f32 * 1.7;
    let eye = Vec3::new(20.0 + 18.0 * a.cos(), 6.0 + k as f32, 20.0 + 18.0 * a.sin());
    LookAt {
        eye,
        target: Vec3::new(20.0, 0.0, 20.0),
        up: Vec3::Y,
        fov_y: 1.0,
        near: 0.1,
        far: 500.0,
    }
    .view(1152, 720)
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
    let close = LookAt {
        eye: Vec3::new(20.0, 3.0, 20.0),
        target: Vec3::new(30.0, 0.0, 30.0),
        up: Vec3::Y,
        fov_y: 1.2,
        near: 0.01,
        far: 500.0,
    }
    .view(3200, 2000);
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

/// Requires `a` and `b` to hold the same active nodes in frame `f`, and `a` a sound front.
fn assert_same_fronts(h: &Hierarchy<'_>, a: &CameraState<'_>, b: &CameraState<'_>, f: usize) {
    let mut na: Vec<_> = a.active_nodes().collect();
    let mut nb: Vec<_> = b.active_nodes().collect();
    na.sort_unstable();
    nb.sort_unstable();
    assert_eq!(na, nb, "frame {f}");
    check_front(h, a).expect("front a");
}

/// Refinement remembers refused collapses until something they depend on changes; it must
/// then do exactly what refinement that checks every wanted collapse every frame does. Two
/// cameras fly the same views (closing in, pulling away and turning, so fronts coarsen as
/// well as refine); one forgets its refusals before every pass. Their statistics and their
/// fronts must agree frame by frame, while the first does skip checks.
#[test]
fn remembered_collapse_refusals_change_nothing() {
    let baked = bake(&meshes::terrain(64, 64, 5));
    let h = baked.hierarchy();
    let mut mem_a = vec![0u32; CameraState::words_needed(&h)];
    let mut mem_b = mem_a.clone();
    let mut a = CameraState::new(&h, &mut mem_a).expect("sized");
    let mut b = CameraState::new(&h, &mut mem_b).expect("sized");
    let params = RefineParams {
        tolerance_px: 0.5,
        ..RefineParams::default()
    };
    let (mut remembered, mut refused) = (0u64, 0u64);
    for f in 0..240 {
        let t = f as f32 * 0.04;
        let r = 8.0 + 30.0 * (0.5 + 0.5 * (t * 0.7).cos());
        let eye = Vec3::new(32.0 + r * t.cos(), 3.0 + 0.2 * r, 32.0 + r * t.sin());
        let target = Vec3::new(32.0 + 10.0 * (t * 1.3).sin(), 0.0, 32.0);
        let v = LookAt {
            eye,
            target,
            up: Vec3::Y,
            fov_y: 1.0,
            near: 0.1,
            far: 500.0,
        }
        .view(1152, 720);
        if f % 50 == 25 {
            a.compact(&h);
            b.compact(&h);
        }
        b.forget_refused_collapses();
        let sa = a.refine(&h, &v, &params).expect("refine a");
        let sb = b.refine(&h, &v, &params).expect("refine b");
        assert_eq!(sb.refusals_remembered, 0, "frame {f}");
        assert_eq!(
            (sa.splits, sa.collapses, sa.active_nodes, sa.active_polygons),
            (sb.splits, sb.collapses, sb.active_nodes, sb.active_polygons),
            "frame {f}"
        );
        assert_eq!(
            sa.collapses_refused + sa.refusals_remembered,
            sb.collapses_refused,
            "frame {f}: the same collapses are wanted and refused"
        );
        assert_same_fronts(&h, &a, &b, f);
        remembered += u64::from(sa.refusals_remembered);
        refused += u64::from(sb.collapses_refused);
    }
    assert!(
        remembered > refused / 2,
        "{remembered} of {refused} refusals remembered"
    );
}

/// Certificates skip the bounds of questions whose answers cannot have changed since they
/// were last asked; refinement must then decide exactly as refinement that reads every
/// bound. Two cameras fly the same views (closing in, pulling away, turning, with a jump, a
/// change of tolerance and of the culling switches on the way); one forgets its
/// certificates before every pass. Their statistics and fronts must agree frame by frame,
/// while the first does skip reads.
#[test]
fn certificates_change_nothing() {
    let baked = bake(&meshes::terrain(64, 64, 5));
    let h = baked.hierarchy();
    let mut mem_a = vec![0u32; CameraState::words_needed(&h)];
    let mut mem_b = mem_a.clone();
    let mut a = CameraState::new(&h, &mut mem_a).expect("sized");
    let mut b = CameraState::new(&h, &mut mem_b).expect("sized");
    let (mut certified, mut visited) = (0u64, 0u64);
    for f in 0..320 {
        let t = f as f32 * 0.03;
        let r = 6.0 + 30.0 * (0.5 + 0.5 * (t * 0.7).cos());
        let mut eye = Vec3::new(32.0 + r * t.cos(), 2.0 + 0.2 * r, 32.0 + r * t.sin());
        if (150..160).contains(&f) {
            eye += Vec3::new(25.0, 10.0, -5.0); // a jump there and back
        }
        let target = Vec3::new(32.0 + 12.0 * (t * 1.3).sin(), 0.0, 32.0 + 6.0 * t.cos());
        let v = LookAt {
            eye,
            target,
            up: Vec3::Y,
            fov_y: 1.0,
            near: 0.1,
            far: 500.0,
        }
        .view(1152, 720);
        let params = RefineParams {
            tolerance_px: if (200..240).contains(&f) { 1.5 } else { 0.5 },
            frustum_culling: !(250..270).contains(&f),
            backface_culling: !(280..300).contains(&f),
            ..RefineParams::default()
        };
        if f % 50 == 25 {
            a.compact(&h);
            b.compact(&h);
        }
        b.forget_certificates();
        let sa = a.refine(&h, &v, &params).expect("refine a");
        let sb = b.refine(&h, &v, &params).expect("refine b");
        assert_eq!(sb.certified, 0, "frame {f}");
        assert_eq!(RefineStats { certified: 0, ..sa }, sb, "frame {f}");
        assert_same_fronts(&h, &a, &b, f);
        certified += u64::from(sa.certified);
        visited += u64::from(sa.nodes_visited);
    }
    assert!(
        certified * 5 > visited,
        "{certified} answers certified in {visited} visits"
    );
    // Settled: a pass that repeats the last view reads no bounds at all, whatever the
    // answers (too fine, outside the frustum, facing away, a collapse refused).
    let v = LookAt {
        eye: Vec3::new(20.0, 3.0, 50.0),
        target: Vec3::new(40.0, 0.0, 20.0),
        up: Vec3::Y,
        fov_y: 1.0,
        near: 0.1,
        far: 500.0,
    }
    .view(1152, 720);
    let params = RefineParams {
        tolerance_px: 0.5,
        ..RefineParams::default()
    };
    for _ in 0..100 {
        if a.refine(&h, &v, &params).expect("settle").operations() == 0 {
            break;
        }
    }
    let settled = a.refine(&h, &v, &params).expect("settled pass");
    assert_eq!(settled.operations(), 0, "not settled: {settled:?}");
    // A visit asks about its node if that can split, and about the parent when the node is
    // the parent's stationary child.
    let questions: usize = a
        .active_nodes()
        .map(|n| {
            let own = h.split_bounds(n).is_some();
            let parent = h.node(n).is_some_and(|node| {
                h.node(node.parent).is_some_and(|p| {
                    p.position == node.position && h.split_bounds(node.parent).is_some()
                })
            });
            usize::from(own) + usize::from(parent)
        })
        .sum();
    let questions = questions as u32;
    assert!(
        settled.certified * 100 >= questions * 99,
        "{} of {questions} questions certified: {settled:?}",
        settled.certified
    );
    assert!(
        settled.refusals_remembered > 0,
        "no refused collapse to certify: {settled:?}"
    );
}

/// A camera that may hold 65,535 pairs or more keeps its split-to-pair map in 32-bit
/// entries (below that, 16-bit); both must refine and coarsen alike.
#[test]
fn wide_and_narrow_pair_maps_refine_alike() {
    let baked = bake(&meshes::terrain(258, 258, 3));
    let h = baked.hierarchy();
    let splits = h.splits().len() as u32;
    assert!(
        splits >= 65_535,
        "{splits} splits: too few for a 32-bit map"
    );
    let wide = CameraConfig::full(&h);
    let narrow = CameraConfig {
        max_pairs: 65_534,
        ..wide
    };
    let mut mem_w = vec![0u32; CameraState::words_needed_for(&h, &wide)];
    let mut mem_n = vec![0u32; CameraState::words_needed_for(&h, &narrow)];
    assert!(
        mem_n.len() + (splits as usize) / 2 - 1 <= mem_w.len(),
        "16-bit entries"
    );
    let mut w = CameraState::with_config(&h, &mut mem_w, &wide).expect("sized");
    let mut n = CameraState::with_config(&h, &mut mem_n, &narrow).expect("sized");
    let params = RefineParams::default();
    for f in 0..12 {
        let t = f as f32 * 0.3;
        let eye = Vec3::new(
            129.0 + 60.0 * t.cos(),
            4.0 + 2.0 * f as f32,
            129.0 + 60.0 * t.sin(),
        );
        let v = LookAt {
            eye,
            target: Vec3::new(129.0, 0.0, 129.0),
            up: Vec3::Y,
            fov_y: 1.0,
            near: 0.1,
            far: 900.0,
        }
        .view(1152, 720);
        let sw = w.refine(&h, &v, &params).expect("refine wide");
        let sn = n.refine(&h, &v, &params).expect("refine narrow");
        assert_eq!(sw, sn, "frame {f}");
    }
    assert!(w.split_count() > 1000, "{} splits applied", w.split_count());
    check_front(&h, &w).expect("wide front");
    check_front(&h, &n).expect("narrow front");
}
