//! `caveclod refine` refines one camera to rest with the documented defaults (1280 × 720,
//! 60° vertical fov, +Y up, near 0.1, far 1e5, 1 px, culling on) and prints the counts the C
//! example `capi/examples/refine.c` prints; a malformed point is refused.

mod common;

use std::path::Path;

use caveclod_core::glam::Vec3;
use caveclod_core::Hierarchy;
use common::{caveclod, centre_and_size, json, s, settled, TERRAIN6};

#[test]
fn refine_prints_the_cores_counts_as_json() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(TERRAIN6);
    let bytes = std::fs::read(&path).expect("read");
    let mut words = vec![0u32; bytes.len().div_ceil(4)];
    bytemuck::cast_slice_mut::<u32, u8>(&mut words)[..bytes.len()].copy_from_slice(&bytes);
    let h = Hierarchy::from_bytes(&bytemuck::cast_slice(&words)[..bytes.len()]).expect("valid");
    let (centre, size) = centre_and_size(&h);
    let eye = centre + Vec3::new(0.1 * size, 0.4 * size, 0.6 * size);
    let point = |p: Vec3| format!("{},{},{}", p.x, p.y, p.z);
    let printed = json(&caveclod(&[
        "refine",
        s(&path),
        &format!("--eye={}", point(eye)),
        &format!("--target={}", point(centre)),
        "--json",
    ]));
    // The core's counts for the command's view.
    let (polygons, surfaces) = (settled(&h, eye, centre).0, h.surface_count());
    assert!(
        polygons as usize > h.base_polygon_count(),
        "the view refines nothing"
    );
    assert_eq!(printed["active_polygons"], polygons);
    assert_eq!(printed["indices"], 3 * polygons);
    assert_eq!(printed["surfaces"], surfaces);
    assert_eq!(printed.as_object().map(|o| o.len()), Some(3));
}

#[test]
fn refine_refuses_a_point_of_two_numbers() {
    let out = caveclod(&["refine", TERRAIN6, "--eye=1,2", "--target=0,0,0", "--json"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("3 needed"));
}
