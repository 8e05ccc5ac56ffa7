//! The popping meter on cases whose answer is known: one split without a geomorph moves its
//! floating child from the parent's point to its own in one frame, by their projected
//! distance; with a geomorph of `n` frames the child moves by that distance over `n` frames,
//! about `1/n` of it per frame (equal steps in the world, nearly equal on the screen). And a regulated fly-over holds its target and reports it.

use std::sync::Arc;

use crate::flyover::popping::Screen;
use crate::flyover::{fly, FlyoverOptions, Ground, Mode, PopMeter, PopTables, HEIGHT, WIDTH};
use caveclod_core::glam::{Vec3, Vec4};
use caveclod_core::{CameraConfig, CameraState, Hierarchy, LookAt, NodeId, RefineParams};
use caveclod_tests::{bake, meshes};

/// The whole terrain seen from above, and its screen.
fn above(h: &Hierarchy<'_>) -> (LookAt, Screen) {
    let g = Ground::new(h);
    let centre = Vec3::new(g.centre[0], 0.0, g.centre[1]);
    let look = LookAt {
        eye: centre + Vec3::Y * g.size * 1.5,
        target: centre,
        up: Vec3::Z,
        fov_y: 1.0,
        near: 0.01,
        far: 10.0 * g.size,
    };
    let screen = Screen {
        view_proj: look.view_projection(WIDTH / HEIGHT),
        eye: look.eye,
    };
    (look, screen)
}

fn pixel(s: &Screen, p: Vec3) -> Vec3 {
    let c: Vec4 = s.view_proj * p.extend(1.0);
    Vec3::new(c.x / c.w * 0.5 * WIDTH, c.y / c.w * 0.5 * HEIGHT, 0.0)
}

/// The one node active now that was not before, and the projected distance from its
/// parent's point to its own.
fn new_child(h: &Hierarchy<'_>, before: &[NodeId], cam: &CameraState<'_>, s: &Screen) -> f32 {
    let born: Vec<NodeId> = cam.active_nodes().filter(|n| !before.contains(n)).collect();
    // The stationary child keeps the parent's point; the floating one has its own.
    let moved: Vec<f32> = born
        .iter()
        .map(|&n| {
            let parent = h.node(n).expect("node").parent;
            let (a, b) = (h.node_point(parent).unwrap(), h.node_point(n).unwrap());
            pixel(s, a.into()).distance(pixel(s, b.into()))
        })
        .filter(|&d| d > 0.0)
        .collect();
    assert_eq!(moved.len(), 1, "one floating child: {born:?}");
    moved[0]
}

/// One split, with `morph_frames` frames of refine morph (0: at once); returns the meter's
/// jumps after the split and the projected parent-child distance.
fn one_split(morph_frames: u32) -> (Vec<f32>, f32) {
    let baked = bake(&meshes::terrain(24, 24, 7));
    let h = baked.hierarchy();
    let config = CameraConfig::full(&h).with_morphs(8);
    let mut memory = vec![0u32; CameraState::words_needed_for(&h, &config)];
    let mut cam = CameraState::with_config(&h, &mut memory, &config).expect("camera");
    let (look, screen) = above(&h);
    let view = look.view(WIDTH as u32, HEIGHT as u32);
    let dt = 1.0 / 60.0;
    let params = RefineParams {
        tolerance_px: 0.01,
        max_ops: 0,
        dt_s: dt,
        refine_morph_s: morph_frames as f32 * dt,
        // The durations alone: the test counts a morph's frames.
        morph_speed_px_s: 0.0,
        ..RefineParams::default()
    };
    let mut meter = PopMeter::new(Arc::new(PopTables::new(&h)));
    cam.refine(&h, &view, &params).expect("refine");
    meter.observe(&cam, &screen);
    let before: Vec<NodeId> = cam.active_nodes().collect();
    let st = cam
        .refine(
            &h,
            &view,
            &RefineParams {
                max_ops: 1,
                ..params
            },
        )
        .expect("refine");
    assert_eq!(
        (st.splits, st.forced_splits, st.collapses),
        (1, 0, 0),
        "{st:?}"
    );
    meter.observe(&cam, &screen);
    let distance = new_child(&h, &before, &cam, &screen);
    for _ in 0..morph_frames + 2 {
        cam.refine(&h, &view, &params).expect("refine");
        meter.observe(&cam, &screen);
    }
    assert_eq!(cam.morph_count(), 0);
    (meter.jumps, distance)
}

#[test]
fn a_split_without_a_morph_pops_by_the_parent_child_distance() {
    let (jumps, distance) = one_split(0);
    assert!(distance > 1.0, "{distance}");
    assert_eq!(jumps.len(), 1, "{jumps:?}");
    assert!(
        (jumps[0] - distance).abs() < 1e-3 * distance,
        "{jumps:?} {distance}"
    );
}

#[test]
fn a_morphing_split_moves_a_share_of_the_distance_per_frame() {
    let n = 8;
    let (jumps, distance) = one_split(n);
    // `t` rises by `dt / duration` a pass: n steps, and one of rounding at most.
    assert!(
        (n as usize..=n as usize + 1).contains(&jumps.len()),
        "{jumps:?}"
    );
    // Equal steps in the world; on the screen perspective makes them differ a little.
    for j in &jumps {
        assert!(
            (j / (distance / n as f32) - 1.0).abs() < 0.1,
            "{jumps:?} {distance}"
        );
    }
    let total: f32 = jumps.iter().sum();
    assert!(
        (total - distance).abs() < 1e-3 * distance,
        "{total} {distance}"
    );
}

#[test]
fn a_regulated_flyover_holds_its_target_and_reports_popping() {
    let baked = bake(&meshes::terrain(64, 64, 3));
    let h = baked.hierarchy();
    let options = FlyoverOptions {
        cameras: 2,
        frames: 150,
        tolerance: 8.0,
        mode: Mode::PerCamera,
        target_polygons: Some(1500),
        ..FlyoverOptions::default()
    };
    let f = fly(&h, &options).expect("regulated flight");
    let j = f.json();
    for cam in j["per_camera"].as_array().expect("cameras") {
        let r = &cam["regulation"];
        assert_eq!(r["target_polygons"], 1500, "{cam}");
        let held = r["held_share"].as_f64().expect("held share");
        assert!(held >= 0.9, "{cam}");
        assert_eq!(r["out_of_reach_share"].as_f64(), Some(0.0), "{cam}");
        assert!(r["tolerance_mean_px"].as_f64().unwrap() > 0.0);
        for key in ["max_jump_px", "p99_jump_px", "surface_p99_jump_px"] {
            let v = cam[key].as_f64().expect(key);
            assert!(v.is_finite() && v >= 0.0, "{key} {cam}");
        }
    }
    let threads = FlyoverOptions {
        mode: Mode::Threads,
        ..options
    };
    assert!(fly(&h, &threads).is_err(), "a target flies on one thread");
}

/// A target above what the whole mesh holds at full resolution: the tolerance sinks to its
/// floor and stays there, and every frame after the settling ones counts as out of reach,
/// none as held.
#[test]
fn a_target_beyond_the_mesh_is_reported_out_of_reach() {
    let baked = bake(&meshes::terrain(32, 32, 3));
    let h = baked.hierarchy();
    let options = FlyoverOptions {
        cameras: 1,
        frames: 90,
        target_polygons: Some(50_000),
        ..FlyoverOptions::default()
    };
    let f = fly(&h, &options).expect("regulated flight");
    let j = f.json();
    let r = &j["per_camera"][0]["regulation"];
    assert_eq!(r["held_share"].as_f64(), Some(0.0), "{r}");
    assert_eq!(r["out_of_reach_share"].as_f64(), Some(1.0), "{r}");
    assert_eq!(
        r["tolerance_min_px"].as_f64(),
        Some(f64::from(caveclod_core::Regulator::DEFAULT_MIN_TOLERANCE)),
        "{r}"
    );
}
