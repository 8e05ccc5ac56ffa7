//! Shared by the integration tests of caveclod-core: the golden file in aligned memory,
//! views around a hierarchy, and a short exercise of every runtime entry point.
//!
//! The golden file `data/terrain6.clod` is what `caveclod-bake` makes of
//! `meshes::terrain(6, 6, 1)`; the `caveclod-tests` package's `golden` test checks that it
//! is current (and rewrites it with `CAVECLOD_UPDATE_GOLDEN=1`).

#![allow(dead_code)] // each test binary uses a part of this module

pub mod morphs;

use std::sync::OnceLock;

use caveclod_core::format::{checksum64, FileHeader};
use caveclod_core::glam::Vec3;
use caveclod_core::{
    CameraConfig, CameraState, Hierarchy, LookAt, NodeId, OpError, RefineParams, View,
};
use proptest::test_runner::Config as ProptestConfig;

/// Owned bytes in 64-byte aligned memory, as engines on a std platform load a file
/// (caveclod-io's holder; small buffers use no huge pages, so Miri runs them).
pub use caveclod_io::AlignedBytes;

/// The golden file's bytes as `include_bytes!` gives them (alignment 1).
pub static GOLDEN: &[u8] = include_bytes!("../data/terrain6.clod");

/// `bytes` copied to start `offset` bytes after a cache line (read them as `&a[offset..]`):
/// the buffer of a reader that does not align what it loads.
pub fn with_offset(bytes: &[u8], offset: usize) -> AlignedBytes {
    let mut a = AlignedBytes::zeroed(offset + bytes.len());
    a[offset..].copy_from_slice(bytes);
    a
}

/// The golden file in aligned memory.
pub fn golden() -> AlignedBytes {
    AlignedBytes::from_slice(GOLDEN)
}

/// A property test's configuration: `cases` cases; under miri `miri_cases`, and no
/// regression file (miri isolates the file system).
pub fn proptest_config(cases: u32, miri_cases: u32) -> ProptestConfig {
    if cfg!(miri) {
        ProptestConfig {
            cases: miri_cases,
            failure_persistence: None,
            ..ProptestConfig::default()
        }
    } else {
        ProptestConfig::with_cases(cases)
    }
}

/// The golden file's hierarchy, over one aligned copy of the file per test binary.
pub fn golden_hierarchy() -> Hierarchy<'static> {
    static FILE: OnceLock<AlignedBytes> = OnceLock::new();
    Hierarchy::from_bytes(FILE.get_or_init(golden).bytes()).expect("golden file")
}

/// The header of `bytes` (at least 64 of them).
pub fn header(bytes: &[u8]) -> FileHeader {
    bytemuck::pod_read_unaligned(&bytes[..size_of::<FileHeader>()])
}

/// Writes `h` over the first 64 bytes.
pub fn set_header(bytes: &mut [u8], h: &FileHeader) {
    bytes[..size_of::<FileHeader>()].copy_from_slice(bytemuck::bytes_of(h));
}

/// Recomputes the checksum of everything after the header and stores it in the header, so
/// that a corruption reaches the validator instead of stopping at the checksum.
pub fn fix_checksum(bytes: &mut [u8]) {
    let mut h = header(bytes);
    h.checksum = checksum64(&bytes[size_of::<FileHeader>()..]);
    set_header(bytes, &h);
}

/// The generators' and tests' random numbers, shared with `caveclod-bake` by path: these
/// tests must not depend on the baker (Miri runs them).
#[path = "../../../bake/src/generate/rng.rs"]
mod rng;

/// SplitMix64: the tests need reproducible corruption, not statistical quality.
#[allow(unused_imports)] // as with the rest of this module, not every test binary draws
pub use rng::SplitMix64 as Rng;

/// Views from all around the hierarchy's bounding box: far, near, inside, grazing, plus
/// views without frustum planes. Deterministic; `count` of them.
pub fn views(h: &Hierarchy<'_>, count: usize) -> Vec<View> {
    let m = h.meta();
    let lo = Vec3::from_array(m.bounds_min);
    let hi = Vec3::from_array(m.bounds_max);
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-3);
    let mut out = Vec::with_capacity(count);
    for i in 0..count {
        let t = i as f32 / count.max(1) as f32;
        let angle = t * std::f32::consts::TAU * 3.0;
        // Distances from inside the box to far away, elevations from below to above.
        let distance = radius * [0.05, 0.6, 1.5, 4.0, 20.0][i % 5];
        let elevation = [-0.4f32, 0.1, 0.5, 1.2][i % 4];
        let dir = Vec3::new(angle.cos(), elevation, angle.sin()).normalize();
        let eye = centre + dir * distance;
        let target = centre + Vec3::new(0.0, 0.0, radius * 0.1 * t);
        if i % 7 == 6 {
            out.push(View::without_frustum(eye, 500.0 + 100.0 * i as f32));
        } else {
            let look = LookAt {
                eye,
                target,
                up: Vec3::Y,
                fov_y: 0.9,
                near: radius * 1e-3,
                far: radius * 100.0,
            };
            out.push(look.view(1280, 720));
        }
    }
    out
}

/// Refinement parameters the exercises cycle through.
pub fn params(i: usize) -> RefineParams {
    [
        RefineParams::default(),
        RefineParams {
            tolerance_px: 0.25,
            ..RefineParams::default()
        },
        RefineParams {
            tolerance_px: 4.0,
            max_ops: 7,
            ..RefineParams::default()
        },
        RefineParams {
            tolerance_px: 0.5,
            frustum_culling: false,
            backface_culling: false,
            ..RefineParams::default()
        },
    ][i % 4]
}

/// Emits the camera's indices into exactly sized buffers and checks what can be checked of
/// any hierarchy that loaded: offsets partition the output by the camera's per-surface counts,
/// and every index names a vertex. Returns each surface's triangles, sorted (an
/// order-independent picture of the front), or `None` if emission reported an error, which is
/// accepted for data the runtime cannot make sense of.
pub fn emit_checked(h: &Hierarchy<'_>, cam: &CameraState<'_>) -> Option<Vec<Vec<[u32; 3]>>> {
    let total: usize = (0..h.surface_count()).map(|s| cam.index_count(s)).sum();
    let mut out = vec![u32::MAX; total];
    let mut offsets = vec![0u32; h.surface_count() + 1];
    let n = cam.emit_indices_packed(h, &mut out, &mut offsets).ok()?;
    assert_eq!(n, total);
    assert_eq!(offsets[0], 0);
    for s in 0..h.surface_count() {
        assert!(offsets[s] <= offsets[s + 1]);
        assert_eq!((offsets[s + 1] - offsets[s]) as usize, cam.index_count(s));
    }
    assert_eq!(offsets[h.surface_count()] as usize, total);
    for &i in &out {
        assert!((i as usize) < h.vertices().len(), "index {i} out of range");
    }
    let surfaces = (0..h.surface_count())
        .map(|s| {
            let range = &out[offsets[s] as usize..offsets[s + 1] as usize];
            let mut tris: Vec<[u32; 3]> =
                range.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
            tris.sort_unstable();
            tris
        })
        .collect();
    Some(surfaces)
}

/// Compacts the camera; the front must be the same afterwards (same triangles per surface,
/// same counts).
pub fn compact_checked(h: &Hierarchy<'_>, cam: &mut CameraState<'_>) {
    let (nodes, polys, splits) = (
        cam.active_node_count(),
        cam.active_polygon_count(),
        cam.split_count(),
    );
    let before = emit_checked(h, cam);
    cam.compact(h);
    assert_eq!(
        (nodes, polys, splits),
        (
            cam.active_node_count(),
            cam.active_polygon_count(),
            cam.split_count()
        )
    );
    let after = emit_checked(h, cam);
    if before.is_some() {
        assert_eq!(before, after, "compaction changed the front");
    }
}

/// The documented recovery from an error: `OpError::Inconsistent` (data contradicting the
/// camera, which validation cannot see) leaves the camera to be reset; other errors leave a
/// valid front. Returns `true` if the camera was reset.
pub fn recover<T>(h: &Hierarchy<'_>, cam: &mut CameraState<'_>, r: &Result<T, OpError>) -> bool {
    if let Err(OpError::Inconsistent { .. }) = r {
        cam.reset(h);
        true
    } else {
        false
    }
}

/// Collapses every legal collapse until none is left; returns the number applied. An
/// `Inconsistent` collapse resets the camera, which ends the loop.
pub fn collapse_all(h: &Hierarchy<'_>, cam: &mut CameraState<'_>) -> usize {
    let ns = h.splits().len();
    let mut applied = 0;
    // Each productive round removes at least one split; `ns + 1` rounds bound the loop even
    // if the runtime misbehaves.
    for _ in 0..=ns {
        let mut progress = false;
        for v in (0..ns as u32).rev().map(NodeId) {
            if cam.can_collapse(h, v) {
                let r = cam.collapse(h, v);
                if r.is_ok() {
                    applied += 1;
                    progress = true;
                }
                recover(h, cam, &r);
            }
        }
        if !progress {
            break;
        }
    }
    applied
}

/// A short run of every runtime entry point over a hierarchy that loaded. It must not panic;
/// errors are fine (corrupt-but-valid data may make operations report `Inconsistent`, after
/// which the camera is reset as documented). Between operations, emission must agree with
/// the camera's counts.
pub fn exercise(h: &Hierarchy<'_>, view_count: usize) {
    let mut memory = vec![0u32; CameraState::words_needed(h)];
    let mut cam = CameraState::new(h, &mut memory).expect("words_needed words are enough");
    assert!(cam.is_for(h));
    assert_eq!(cam.active_polygon_count() as usize, h.base_polygon_count());
    for (i, view) in views(h, view_count).iter().enumerate() {
        let r = cam.refine(h, view, &params(i));
        recover(h, &mut cam, &r);
        emit_checked(h, &cam);
    }
    compact_checked(h, &mut cam);
    let ns = h.splits().len() as u32;
    for v in (0..ns.min(32)).map(NodeId) {
        let r = cam.force_split_own_stack(h, v);
        recover(h, &mut cam, &r);
    }
    compact_checked(h, &mut cam);
    collapse_all(h, &mut cam);
    emit_checked(h, &cam);
    cam.reset(h);
    assert_eq!(cam.split_count(), 0);

    // A camera with a small budget: refinement is refused, not failed.
    let config = CameraConfig::with_polygon_budget(h, h.base_polygon_count() as u32 + 6);
    let mut small = vec![0u32; CameraState::words_needed_for(h, &config)];
    let mut cam = CameraState::with_config(h, &mut small, &config).expect("words_needed_for words");
    for (i, view) in views(h, view_count.min(3)).iter().enumerate() {
        let r = cam.refine(h, view, &params(i));
        recover(h, &mut cam, &r);
        assert!(cam.split_count() <= config.max_pairs);
        emit_checked(h, &cam);
    }
}
