//! A `.clod` file read through a memory map gives what the same file read into the heap
//! gives: the same report, the same refined cuts, and `caveclod info` (which maps the file)
//! prints that report.

use std::path::Path;
use std::process::Command;

use caveclod_cli::aligned::AlignedBytes;
use caveclod_cli::mapped::ClodBytes;
use caveclod_core::glam::Vec3;
use caveclod_core::{CameraState, Hierarchy, LookAt, RefineParams};
use serde_json::Value;

const FILE: &str = "../core/tests/data/terrain6.clod";

/// Active polygons once one camera at `eye` settles, and how many refinement passes that took.
fn settled(h: &Hierarchy<'_>, eye: Vec3, target: Vec3) -> (u32, u32) {
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
    let mut passes = 0;
    while cam
        .refine(h, &view, &RefineParams::default())
        .expect("refine")
        .operations()
        > 0
    {
        passes += 1;
    }
    (cam.active_polygon_count(), passes)
}

#[test]
fn a_mapped_file_reports_and_refines_as_a_read_one() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(FILE);
    let mapped = ClodBytes::open(&path).expect("map");
    assert!(mapped.is_mapped());
    let read = AlignedBytes::read(&path).expect("read");
    assert_eq!(mapped.bytes(), read.bytes());
    let (hm, hr) = (
        mapped.hierarchy().expect("valid"),
        read.hierarchy().expect("valid"),
    );
    assert_eq!(
        caveclod_cli::info::report(&hm, None),
        caveclod_cli::info::report(&hr, None)
    );
    let (lo, hi) = (
        Vec3::from_array(hm.meta().bounds_min),
        Vec3::from_array(hm.meta().bounds_max),
    );
    let (centre, size) = ((lo + hi) * 0.5, (hi - lo).length());
    for eye in [
        centre + Vec3::new(0.1 * size, 0.4 * size, 0.6 * size),
        centre + Vec3::new(-0.3 * size, 0.05 * size, 0.1 * size),
    ] {
        let a = settled(&hm, eye, centre);
        assert!(a.0 > 0);
        assert_eq!(a, settled(&hr, eye, centre));
    }

    let out = Command::new(env!("CARGO_BIN_EXE_caveclod"))
        .args(["info", "--json"])
        .arg(&path)
        .output()
        .expect("run caveclod");
    assert!(out.status.success());
    let printed: Value = serde_json::from_slice(&out.stdout).expect("one JSON report");
    for (key, value) in caveclod_cli::info::report(&hr, None) {
        assert_eq!(printed[&key], value, "{key}");
    }
    assert_eq!(printed["valid"], true);
}
