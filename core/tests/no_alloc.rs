//! The runtime allocates nothing: with a counting global allocator, refinement from 20
//! views (full and amortised), compaction (whole and in steps), forced splits, collapses, index emission, and geomorphs (their
//! refinement and morphed emission) leave the count unchanged once the hierarchy, the camera
//! memory and the output buffers exist.
//!
//! Allocations are counted per thread (the test harness allocates on its own threads), and
//! the test shows the counter works by watching one `Vec::with_capacity(1)` change it.

mod common;
mod counting;

use std::hint::black_box;

use caveclod_core::{CameraConfig, CameraState, Hierarchy, NodeId, RefineParams};
use common::{golden, params, views};
use counting::{allocations, assert_counting};

#[test]
fn the_runtime_does_not_allocate() {
    // Set-up: everything that may allocate.
    let file = golden();
    let h = Hierarchy::from_bytes(file.bytes()).expect("golden file");
    let mut memory = vec![0u32; CameraState::words_needed(&h)];
    let views = views(&h, 20);
    let all_params: Vec<_> = (0..views.len()).map(params).collect();
    let max_indices = 3 * h.polygon_count();
    let mut packed = vec![0u32; max_indices];
    let mut offsets = vec![0u32; h.surface_count() + 1];
    let mut lists: Vec<Vec<u32>> = (0..h.surface_count())
        .map(|_| vec![0u32; max_indices])
        .collect();
    let mut slices: Vec<&mut [u32]> = lists.iter_mut().map(|l| l.as_mut_slice()).collect();
    let mut written = vec![0u32; h.surface_count()];

    assert_counting();

    let before = allocations();
    let mut cam = CameraState::new(&h, &mut memory).expect("memory");
    let mut work = 0u64;
    for (view, p) in views.iter().zip(&all_params) {
        let stats = cam.refine(&h, view, p).expect("refine");
        work += u64::from(stats.operations());
        let n = cam
            .emit_indices_packed(&h, &mut packed, &mut offsets)
            .expect("emit packed");
        let m = cam
            .emit_indices(&h, &mut slices, &mut written)
            .expect("emit lists");
        assert_eq!(n, m);
        cam.compact(&h);
        // Amortised refinement and compaction steps.
        let stats = cam
            .refine(&h, view, &p.amortised(1.0 / 3.0))
            .expect("refine");
        work += u64::from(stats.operations());
        cam.compact_step(&h, 50);
        black_box(cam.lag(&h, view, p).expect("lag"));
    }
    for v in (0..h.splits().len() as u32).map(NodeId) {
        if cam.is_node_active(&h, v) {
            work += u64::from(cam.force_split_own_stack(&h, v).expect("force split"));
        }
    }
    cam.emit_indices_packed(&h, &mut packed, &mut offsets)
        .expect("emit packed");
    for v in (0..h.splits().len() as u32).rev().map(NodeId) {
        if cam.can_collapse(&h, v) {
            cam.collapse(&h, v).expect("collapse");
            work += 1;
        }
    }
    cam.reset(&h);
    let after = allocations();
    black_box(work);
    assert!(work > 0, "the views must make the runtime do something");
    assert_eq!(
        after,
        before,
        "the runtime allocated {} times",
        after - before
    );
}

#[test]
fn geomorphs_do_not_allocate() {
    let file = golden();
    let h = Hierarchy::from_bytes(file.bytes()).expect("golden file");
    let config = CameraConfig::full(&h).with_morphs(6);
    let mut memory = vec![0u32; CameraState::words_needed_for(&h, &config)];
    let views = views(&h, 20);
    let dts = [0.0f32, 1.0 / 60.0, 0.1, 0.5];
    let max_indices = 3 * h.polygon_count();
    let mut packed = vec![0u32; max_indices];
    let mut offsets = vec![0u32; h.surface_count() + 1];
    let mut lists: Vec<Vec<u32>> = (0..h.surface_count())
        .map(|_| vec![0u32; max_indices])
        .collect();
    let mut slices: Vec<&mut [u32]> = lists.iter_mut().map(|l| l.as_mut_slice()).collect();
    let mut written = vec![0u32; h.surface_count()];

    let before = allocations();
    let mut cam = CameraState::with_config(&h, &mut memory, &config).expect("memory");
    let mut morphs = 0u64;
    for (i, view) in views.iter().enumerate() {
        let p = RefineParams {
            dt_s: dts[i % dts.len()],
            ..params(i)
        };
        let stats = cam.refine(&h, view, &p).expect("refine");
        morphs += u64::from(stats.morphs_started + stats.morphs_finished + stats.morphs_dropped);
        black_box(cam.morph_vertices());
        cam.emit_indices_packed_morphed(&h, &mut packed, &mut offsets)
            .expect("emit packed");
        cam.emit_indices_morphed(&h, &mut slices, &mut written)
            .expect("emit lists");
        if i % 6 == 5 {
            cam.compact(&h);
        }
    }
    cam.finish_morphs();
    cam.reset(&h);
    let after = allocations();
    assert!(morphs > 0, "the views must make the camera morph");
    assert_eq!(
        after,
        before,
        "geomorphs allocated {} times",
        after - before
    );
}
