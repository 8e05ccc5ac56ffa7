//! Criterion benchmarks of a camera's draw preparation each frame, on a terrain of about a
//! million polygons (`terrain(708, 708)`), baked once per run outside the timed code: full
//! morphed emission against index edits, after the same moving refine pass.
//!
//! Two geomorphing cameras (the default durations at 60 passes per second) fly the same low
//! pass along the terrain's diagonal, one view per iteration. Each iteration refines both,
//! untimed; then one camera's emission (`draw/emit_packed_morphed`: every index of the
//! front) or the other's index edits (`draw/index_edits`: the places that changed, at most
//! 64 holes closed) is timed. Throughput: active polygons, so the two read as the same unit;
//! the edits handed out per frame are printed after.
//!
//! `cargo bench -p caveclod-benches --bench draw`; `CAVECLOD_BENCH_SIZE=N` changes the
//! terrain. Without `--bench` (as `cargo test --benches` runs it) each runs once on a small
//! terrain.

use std::time::{Duration, Instant};

use caveclod_benches::low_pass_view;
use caveclod_core::glam::Vec3;
use caveclod_core::{
    CameraConfig, CameraState, Hierarchy, IndexEdit, RefineParams, SurfaceDraw, View,
};
use caveclod_tests::{bake, meshes};
use criterion::{Criterion, Throughput};

const SEED: u64 = 7;
const MAX_MORPHS: u32 = 4096;
const EDIT_LIST: u32 = 16_384;
const MOVES: u32 = 64;

fn must<T, E: std::fmt::Display>(r: Result<T, E>) -> T {
    match r {
        Ok(x) => x,
        Err(e) => panic!("{e}"),
    }
}

/// A low pass along the diagonal at a height clear of the terrain (`top`), `steps` views a
/// six-hundredth of the side apart, out and back.
fn flight(size: f32, top: f32, steps: usize) -> Vec<View> {
    let forward = Vec3::new(1.0, 0.0, 1.0).normalize();
    (0..2 * steps)
        .map(|i| {
            let u = if i < steps { i } else { 2 * steps - i } as f32 / 600.0;
            let p = size * (0.15 + 0.7 * u);
            low_pass_view(Vec3::new(p, top + 0.015 * size, p), forward, 2.0 * size)
        })
        .collect()
}

/// Times `prepare` after an untimed refine of both cameras to the next view, `iters` times.
fn timed(
    h: &Hierarchy<'_>,
    cams: &mut [CameraState<'_>; 2],
    views: &[View],
    k: &mut usize,
    iters: u64,
    mut prepare: impl FnMut(&mut [CameraState<'_>; 2]),
) -> Duration {
    let p = RefineParams {
        dt_s: 1.0 / 60.0,
        ..RefineParams::default()
    };
    let mut total = Duration::ZERO;
    for _ in 0..iters {
        *k = (*k + 1) % views.len();
        for cam in cams.iter_mut() {
            must(cam.refine(h, &views[*k], &p));
        }
        let t = Instant::now();
        prepare(cams);
        total += t.elapsed();
    }
    total
}

fn main() {
    let benchmarking = std::env::args().any(|a| a == "--bench");
    let size: u32 = std::env::var("CAVECLOD_BENCH_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(if benchmarking { 708 } else { 48 });
    let mesh = meshes::terrain(size, size, SEED);
    let top = mesh.positions.iter().map(|p| p[1]).fold(f32::MIN, f32::max);
    let baked = bake(&mesh);
    drop(mesh);
    let h = baked.hierarchy();
    let views = flight(size as f32, top, 100);
    let config = CameraConfig::full(&h)
        .with_morphs(MAX_MORPHS)
        .with_index_edits(EDIT_LIST);
    let words = CameraState::words_needed_for(&h, &config);
    let (mut a, mut b) = (vec![0u32; words], vec![0u32; words]);
    let mut cams = [
        must(CameraState::with_config(&h, &mut a, &config)),
        must(CameraState::with_config(&h, &mut b, &config)),
    ];
    let mut out = vec![0u32; 3 * cams[0].index_places()];
    let mut offsets = vec![0u32; h.surface_count() + 1];
    let mut edits = vec![IndexEdit::default(); cams[1].index_places() + MOVES as usize];
    let mut draws = vec![SurfaceDraw::default(); h.surface_count()];
    // The first pass settles from the base mesh, and the first edits write every place.
    let mut k = 0;
    timed(&h, &mut cams, &views, &mut k, views.len() as u64, |c| {
        must(c[1].index_edits(&h, MOVES, &mut edits, &mut draws));
    });
    let polygons = u64::from(cams[0].active_polygon_count());
    eprintln!("terrain {size} x {size}: {polygons} active polygons per camera on the flight");

    let mut c = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4))
        .configure_from_args();
    let mut g = c.benchmark_group("draw");
    g.throughput(Throughput::Elements(polygons));
    g.bench_function("emit_packed_morphed", |bench| {
        bench.iter_custom(|iters| {
            timed(&h, &mut cams, &views, &mut k, iters, |c| {
                // The other camera's edits are taken untimed below: it stays in step.
                must(c[0].emit_indices_packed_morphed(&h, &mut out, &mut offsets));
            })
        })
    });
    // Both cameras are refined in every iteration; the edits camera hands out what the
    // emission iterations left it before its first timed call.
    must(cams[1].index_edits(&h, MOVES, &mut edits, &mut draws));
    let mut handed = (0u64, 0u64);
    g.bench_function("index_edits", |bench| {
        bench.iter_custom(|iters| {
            timed(&h, &mut cams, &views, &mut k, iters, |c| {
                let e = must(c[1].index_edits(&h, MOVES, &mut edits, &mut draws));
                handed = (handed.0 + 1, handed.1 + e.edits as u64);
            })
        })
    });
    g.finish();
    if handed.0 > 0 {
        eprintln!(
            "draw/index_edits: {:.0} edits per frame on average ({} bytes each) against {} \
             indices emitted",
            handed.1 as f64 / handed.0 as f64,
            std::mem::size_of::<IndexEdit>(),
            cams[0].total_index_count()
        );
    }
}
