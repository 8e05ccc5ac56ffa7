//! The core's golden file (a small terrain) mapped and read into aligned memory: the same
//! bytes, a valid hierarchy either way, and the same cut once one camera settles over each.

use std::path::{Path, PathBuf};

use caveclod_core::glam::Vec3;
use caveclod_core::{CameraState, Hierarchy, LookAt, RefineParams};
use caveclod_io::{AlignedBytes, ClodBytes, ClodFile};

fn golden() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../core/tests/data/terrain6.clod")
}

/// Active polygons once a camera at `eye` looking at the hierarchy's centre settles.
fn settled(h: &Hierarchy<'_>, eye: Vec3) -> u32 {
    let m = h.meta();
    let (lo, hi) = (
        Vec3::from_array(m.bounds_min),
        Vec3::from_array(m.bounds_max),
    );
    let mut memory = vec![0u32; CameraState::words_needed(h)];
    let mut cam = CameraState::new(h, &mut memory).expect("camera");
    let look = LookAt {
        eye: (lo + hi) * 0.5 + eye * (hi - lo).length(),
        target: (lo + hi) * 0.5,
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
    cam.active_polygon_count()
}

#[test]
fn a_mapped_file_refines_as_a_read_one() {
    let mapped = ClodBytes::open(&golden()).expect("map");
    assert!(mapped.is_mapped());
    let read = AlignedBytes::read(&golden()).expect("read");
    assert_eq!(mapped.bytes(), read.bytes());
    let (hm, hr) = (
        mapped.hierarchy().expect("valid"),
        read.hierarchy().expect("valid"),
    );
    for eye in [Vec3::new(0.1, 0.4, 0.6), Vec3::new(-0.3, 0.05, 0.1)] {
        let a = settled(&hm, eye);
        assert!(a as usize > hm.base_polygon_count());
        assert_eq!(a, settled(&hr, eye));
    }
    let file = ClodFile::open(golden()).expect("open");
    assert_eq!(file.hierarchy().expect("valid").meta(), hr.meta());
    assert_eq!(file.into_bytes().bytes(), read.bytes());
}
