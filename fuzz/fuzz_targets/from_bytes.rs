//! `Hierarchy::from_bytes` on arbitrary bytes, then a camera over whatever loads (and an
//! octree cut, when the file has valid octree sections, and its materials and vertex
//! colours, when it has them).
//!
//! A 64-bit checksum stops nearly every mutation before the validator, so each input is
//! tried twice: as given (header, length and checksum checks), and, when it fails on its
//! length or checksum, again with the header's file length and checksum rewritten to match
//! (the validator and the runtime). Loading must return `Err` or a hierarchy that every
//! runtime entry point can use without panicking, and whose emission agrees with the
//! camera's counts (after an `Inconsistent` error the camera is reset, as documented).
#![no_main]

use caveclod_core::format::materials::{path_climbs_out, TextureRef};
use caveclod_core::format::{checksum64, FileHeader};
use caveclod_core::glam::Vec3;
use caveclod_core::{
    CameraConfig, CameraState, FormatError, Hierarchy, LookAt, NodeId, Octree, OctreeCut, OpError,
    RefineParams, View,
};
use libfuzzer_sys::fuzz_target;

const HEADER_LEN: usize = size_of::<FileHeader>();

/// `bytes` copied to the start of 8-byte aligned storage.
fn aligned(bytes: &[u8]) -> Vec<u64> {
    let mut words = vec![0u64; bytes.len().div_ceil(8)];
    bytemuck::cast_slice_mut::<u64, u8>(&mut words)[..bytes.len()].copy_from_slice(bytes);
    words
}

fn as_bytes(words: &[u64], len: usize) -> &[u8] {
    &bytemuck::cast_slice(words)[..len]
}

fn views(h: &Hierarchy<'_>) -> [View; 4] {
    let m = h.meta();
    let lo = Vec3::from_array(m.bounds_min);
    let hi = Vec3::from_array(m.bounds_max);
    let centre = (lo + hi) * 0.5;
    let r = ((hi - lo).length() * 0.5).max(1e-3);
    let persp = |eye: Vec3| {
        LookAt {
            eye,
            target: centre,
            up: Vec3::Y,
            fov_y: 0.9,
            near: r * 1e-3,
            far: r * 100.0,
        }
        .view(1080, 720)
    };
    [
        persp(centre + Vec3::new(0.3, 0.8, 2.0) * r),
        persp(centre + Vec3::new(-0.1, 0.05, 0.2) * r),
        View::without_frustum(centre + Vec3::new(0.0, 0.5, 0.1) * r, 1e5),
        persp(centre + Vec3::new(20.0, 3.0, -20.0) * r),
    ]
}

/// Emission into exactly sized buffers: when it succeeds, the offsets must partition the
/// output by the camera's per-surface counts and every index must name a vertex.
fn emit(h: &Hierarchy<'_>, cam: &CameraState<'_>) {
    let ns = h.surface_count();
    let total: usize = (0..ns).map(|s| cam.index_count(s)).sum();
    let mut out = vec![u32::MAX; total];
    let mut offsets = vec![0u32; ns + 1];
    if let Ok(n) = cam.emit_indices_packed(h, &mut out, &mut offsets) {
        assert_eq!(n, total);
        assert_eq!(offsets[0], 0);
        for s in 0..ns {
            assert_eq!((offsets[s + 1] - offsets[s]) as usize, cam.index_count(s));
        }
        assert!(out.iter().all(|&i| (i as usize) < h.vertices().len()));
    }
}

/// The documented recovery: after `Inconsistent` the camera is to be reset.
fn recover<T>(h: &Hierarchy<'_>, cam: &mut CameraState<'_>, r: &Result<T, OpError>) {
    if let Err(OpError::Inconsistent { .. }) = r {
        cam.reset(h);
    }
}

fn exercise(h: &Hierarchy<'_>) {
    let mut memory = vec![0u32; CameraState::words_needed(h)];
    let mut cam = CameraState::new(h, &mut memory).expect("words_needed words are enough");
    let params = [
        RefineParams::default(),
        RefineParams {
            tolerance_px: 0.1,
            frustum_culling: false,
            backface_culling: false,
            ..RefineParams::default()
        },
    ];
    for (i, view) in views(h).iter().enumerate() {
        let r = cam.refine(h, view, &params[i % 2]);
        recover(h, &mut cam, &r);
        emit(h, &cam);
    }
    // Compaction re-orders the camera's arrays; the counts stay.
    let counts = (cam.active_polygon_count(), cam.split_count());
    cam.compact(h);
    assert_eq!(counts, (cam.active_polygon_count(), cam.split_count()));
    emit(h, &cam);
    let ns = h.splits().len() as u32;
    for v in (0..ns.min(16)).map(NodeId) {
        let r = cam.force_split_own_stack(h, v);
        recover(h, &mut cam, &r);
    }
    emit(h, &cam);
    // Collapse everything legal, in bounded rounds.
    for _ in 0..=ns {
        let mut progress = false;
        for v in (0..ns).rev().map(NodeId) {
            if cam.can_collapse(h, v) {
                let r = cam.collapse(h, v);
                progress |= r.is_ok();
                recover(h, &mut cam, &r);
            }
        }
        if !progress {
            break;
        }
    }
    emit(h, &cam);
    cam.reset(h);

    let config = CameraConfig::with_polygon_budget(h, h.base_polygon_count() as u32 + 4);
    let mut small = vec![0u32; CameraState::words_needed_for(h, &config)];
    let mut cam = CameraState::with_config(h, &mut small, &config).expect("words_needed_for");
    let r = cam.refine(h, &views(h)[2], &params[1]);
    recover(h, &mut cam, &r);
    assert!(cam.split_count() <= config.max_pairs);
    emit(h, &cam);
}

/// The octree sections, when present and valid: every view's cut, emitted into exactly sized
/// buffers, partitions the output by the cut's counts and names only octree vertices.
fn exercise_octree(h: &Hierarchy<'_>) {
    let Ok(Some(t)) = Octree::from_hierarchy(h) else {
        return;
    };
    let mut memory = vec![0u32; OctreeCut::words_needed(&t)];
    let mut cut = OctreeCut::new(&t, &mut memory).expect("words_needed words are enough");
    for (i, view) in views(h).iter().enumerate() {
        let tolerance = [1.0, 0.1, 1e9, f32::NAN][i % 4];
        let stats = cut
            .select(&t, view, tolerance)
            .expect("a cut of its own octree");
        let total = cut.total_index_count();
        assert_eq!(total, 3 * stats.triangles as usize);
        let mut out = vec![u32::MAX; total];
        let mut offsets = vec![0u32; t.surface_count() + 1];
        let n = cut
            .emit_indices_packed(&t, &mut out, &mut offsets)
            .expect("exactly sized buffers");
        assert_eq!(n, total);
        for s in 0..t.surface_count() {
            assert_eq!((offsets[s + 1] - offsets[s]) as usize, cut.index_count(s));
        }
        assert!(out.iter().all(|&i| (i as usize) < t.vertices().len()));
    }
}

/// The materials and vertex colours, when present: validated at load, so every surface has
/// a material whose strings and image bytes can be read, and every vertex a colour.
fn exercise_appearance(h: &Hierarchy<'_>) {
    if let Some(m) = h.materials() {
        assert_eq!(m.len(), h.surface_count());
        for s in 0..m.len() {
            let material = m.get(s).expect("a validated material");
            if let Some(TextureRef::Path(p)) = material.texture {
                assert!(!p.is_empty() && !p.starts_with('/'));
                let _ = path_climbs_out(p);
            }
        }
        assert_eq!(m.iter().count(), m.len());
    }
    if let Some(c) = h.vertex_colours() {
        assert_eq!(c.len(), h.vertices().len());
    }
}

fuzz_target!(|data: &[u8]| {
    let mut words = aligned(data);
    let retry = match Hierarchy::from_bytes(as_bytes(&words, data.len())) {
        Ok(h) => {
            exercise(&h);
            exercise_octree(&h);
            exercise_appearance(&h);
            false
        }
        Err(
            FormatError::LengthMismatch { .. }
            | FormatError::TrailingBytes { .. }
            | FormatError::ChecksumMismatch { .. },
        ) => true,
        Err(_) => false,
    };
    if retry && data.len() >= HEADER_LEN {
        let bytes = &mut bytemuck::cast_slice_mut::<u64, u8>(&mut words)[..data.len()];
        let mut header: FileHeader = bytemuck::pod_read_unaligned(&bytes[..HEADER_LEN]);
        header.file_len = data.len() as u64;
        header.checksum = checksum64(&bytes[HEADER_LEN..]);
        bytes[..HEADER_LEN].copy_from_slice(bytemuck::bytes_of(&header));
        if let Ok(h) = Hierarchy::from_bytes(as_bytes(&words, data.len())) {
            exercise(&h);
            exercise_octree(&h);
            exercise_appearance(&h);
        }
    }
});
