//! `caveclod refine` refines one camera to rest with the documented defaults (1280 × 720,
//! 60° vertical fov, +Y up, near 0.1, far 1e5, 1 px, culling on) and prints the counts the C
//! example `capi/examples/refine.c` prints; a malformed point is refused.

use std::path::Path;
use std::process::Command;

use caveclod_core::glam::Vec3;
use caveclod_core::{CameraState, Hierarchy, LookAt, RefineParams};
use serde_json::Value;

const FILE: &str = "../core/tests/data/terrain6.clod";

fn caveclod(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_caveclod"))
        .args(args)
        .output()
        .expect("run caveclod")
}

/// The counts the core gives for the command's view: active polygons after refinement
/// settles, and the surface count.
fn expected(h: &Hierarchy<'_>, eye: Vec3, target: Vec3) -> (u32, usize) {
    let mut memory = vec![0u32; CameraState::words_needed(h)];
    let mut cam = CameraState::new(h, &mut memory).expect("camera");
    let look = LookAt {
        eye,
        target,
        up: Vec3::Y,
        fov_y: 60f32.to_radians(),
        near: 0.1,
        far: 1e5,
    };
    let view = look.view(1280, 720);
    while cam
        .refine(h, &view, &RefineParams::default())
        .expect("refine")
        .operations()
        > 0
    {}
    (cam.active_polygon_count(), h.surface_count())
}

#[test]
fn refine_prints_the_cores_counts_as_json() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(FILE);
    let bytes = std::fs::read(&path).expect("read");
    let mut words = vec![0u32; bytes.len().div_ceil(4)];
    bytemuck::cast_slice_mut::<u32, u8>(&mut words)[..bytes.len()].copy_from_slice(&bytes);
    let h = Hierarchy::from_bytes(&bytemuck::cast_slice(&words)[..bytes.len()]).expect("valid");
    let (lo, hi) = (
        Vec3::from_array(h.meta().bounds_min),
        Vec3::from_array(h.meta().bounds_max),
    );
    let (centre, size) = ((lo + hi) * 0.5, (hi - lo).length());
    let eye = centre + Vec3::new(0.1 * size, 0.4 * size, 0.6 * size);
    let point = |p: Vec3| format!("{},{},{}", p.x, p.y, p.z);
    let out = caveclod(&[
        "refine",
        path.to_str().expect("utf-8 path"),
        &format!("--eye={}", point(eye)),
        &format!("--target={}", point(centre)),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: Value = serde_json::from_slice(&out.stdout).expect("one JSON line");
    let (polygons, surfaces) = expected(&h, eye, centre);
    assert!(
        polygons as usize > h.base_polygon_count(),
        "the view refines nothing"
    );
    assert_eq!(json["active_polygons"], polygons);
    assert_eq!(json["indices"], 3 * polygons);
    assert_eq!(json["surfaces"], surfaces);
    assert_eq!(json.as_object().map(|o| o.len()), Some(3));
}

#[test]
fn refine_refuses_a_point_of_two_numbers() {
    let out = caveclod(&["refine", FILE, "--eye=1,2", "--target=0,0,0", "--json"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("3 needed"));
}
