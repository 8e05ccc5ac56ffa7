//! The two runtimes of an out-of-core bake, per frame, on one generated terrain: the
//! view-dependent hierarchy (refine + emit, `CameraState`) and the multiresolution octree
//! (select + emit, `OctreeCut`), each flying the same low pass at the same pixel tolerance.
//!
//! - `frame/hierarchy_refine_emit` and `frame/octree_select_emit`: one frame per iteration,
//!   the camera a small step further each time (throughput: triangles drawn).
//! - After criterion, a paired table (both runtimes, the whole path, three alternating laps,
//!   medians): frame time, triangles drawn, and their ratios octree / hierarchy. The octree
//!   costs less per frame and draws more triangles: its nodes are whole blocks of a level with
//!   conservative error bounds, the hierarchy refines vertex by vertex.
//!
//! `cargo bench -p caveclod-benches --bench octree`; `CAVECLOD_BENCH_TRIANGLES=N` sets the
//! generated input (default 2,000,000; without `--bench`, as `cargo test --benches` runs it,
//! 20,000 and one iteration each).

use std::time::{Duration, Instant};

use caveclod_bake::generate;
use caveclod_bake::ooc::OocOptions;
use caveclod_bake::pipeline;
use caveclod_benches::low_pass_view;
use caveclod_core::glam::Vec3;
use caveclod_core::{CameraState, Hierarchy, Octree, OctreeCut, RefineParams, View};
use caveclod_io::AlignedBytes;
use criterion::{Criterion, Throughput};

const TOLERANCE_PX: f32 = 1.0;

/// Frame `i` of `n` of a low pass along the diagonal, looking ahead and 15 degrees down.
fn view_at(i: usize, n: usize, size: f32, top: f32) -> View {
    let u = i as f32 / n.max(1) as f32;
    let p = size * (0.1 + 0.8 * u);
    let eye = Vec3::new(p, top + 0.02 * size, p);
    low_pass_view(eye, Vec3::new(1.0, 0.0, 1.0).normalize(), 3.0 * size)
}

/// One hierarchy frame: refine and emit; returns the triangles drawn.
fn hierarchy_frame(
    h: &Hierarchy<'_>,
    cam: &mut CameraState<'_>,
    view: &View,
    out: &mut Vec<u32>,
    offsets: &mut [u32],
) -> u32 {
    let params = RefineParams {
        tolerance_px: TOLERANCE_PX,
        ..RefineParams::default()
    };
    cam.refine(h, view, &params).expect("refine");
    let total: usize = (0..h.surface_count()).map(|s| cam.index_count(s)).sum();
    out.resize(total, 0);
    cam.emit_indices_packed(h, out, offsets).expect("emit");
    (total / 3) as u32
}

/// One octree frame: select and emit; returns the triangles drawn.
fn octree_frame(
    t: &Octree<'_>,
    cut: &mut OctreeCut<'_>,
    view: &View,
    out: &mut Vec<u32>,
    offsets: &mut [u32],
) -> u32 {
    cut.select(t, view, TOLERANCE_PX).expect("select");
    out.resize(cut.total_index_count(), 0);
    cut.emit_indices_packed(t, out, offsets).expect("emit");
    (cut.total_index_count() / 3) as u32
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// A frame of one runtime over a view: the triangles it drew.
type Frame<'a> = dyn FnMut(&View) -> u32 + 'a;

fn main() {
    let benchmarking = std::env::args().any(|a| a == "--bench");
    let triangles: u64 = std::env::var("CAVECLOD_BENCH_TRIANGLES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(if benchmarking { 2_000_000 } else { 20_000 });
    let file = bake_terrain(triangles);
    let h = Hierarchy::from_bytes(file.bytes()).expect("hierarchy");
    let t = Octree::from_hierarchy(&h)
        .expect("octree")
        .expect("octree sections");
    eprintln!(
        "{} octree levels, {} nodes",
        t.level_count(),
        t.node_count()
    );
    let size = generate::TERRAIN_SIZE;
    let top = t.nodes()[0].max[1];
    let n = 300;
    let views: Vec<View> = (0..n).map(|i| view_at(i, n, size, top)).collect();

    let mut cam_memory = vec![0u32; CameraState::words_needed(&h)];
    let mut cam = CameraState::new(&h, &mut cam_memory).expect("camera");
    let mut cut_memory = vec![0u32; OctreeCut::words_needed(&t)];
    let mut cut = OctreeCut::new(&t, &mut cut_memory).expect("cut");
    let (mut hi, mut oi) = (Vec::new(), Vec::new());
    let (mut ho, mut oo) = (
        vec![0u32; h.surface_count() + 1],
        vec![0u32; h.surface_count() + 1],
    );
    let mut hierarchy = |v: &View| hierarchy_frame(&h, &mut cam, v, &mut hi, &mut ho);
    let mut octree = |v: &View| octree_frame(&t, &mut cut, v, &mut oi, &mut oo);
    // Settle both on the first view.
    for _ in 0..3 {
        hierarchy(&views[0]);
    }
    octree(&views[0]);
    criterion_frames(&views, &mut hierarchy, &mut octree);
    let laps = if benchmarking { 3 } else { 1 };
    paired_laps(&views, laps, &mut hierarchy, &mut octree);
}

/// A generated terrain of `triangles` baked out of core with its octree, in aligned memory.
fn bake_terrain(triangles: u64) -> AlignedBytes {
    let dir = std::env::temp_dir().join(format!("caveclod-octree-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temporary directory");
    let input = dir.join("terrain.ply");
    generate::terrain(&input, triangles, &mut |_, _| {}).expect("generate");
    let t0 = Instant::now();
    let options = OocOptions {
        temp_dir: Some(dir.clone()),
        ..OocOptions::with_budget(256 << 20)
    };
    let out = pipeline::bake_out_of_core(&input, &options, &mut |_| {}, &mut |_| {})
        .expect("out-of-core bake");
    std::fs::remove_dir_all(&dir).expect("remove the temporary directory");
    let octree = out.octree.as_ref().expect("octree");
    let bytes = out
        .baked
        .to_bytes(&octree.parts().sections())
        .expect("serialise");
    eprintln!(
        "terrain of {} triangles: clustered to {}; {:.1} s",
        out.stats.input_triangles,
        out.stats.output_triangles,
        t0.elapsed().as_secs_f64()
    );
    AlignedBytes::from_slice(&bytes)
}

/// Criterion's figures: each runtime's frames over the path, throughput in triangles drawn.
fn criterion_frames<'f>(views: &[View], hierarchy: &mut Frame<'f>, octree: &mut Frame<'f>) {
    let n = views.len();
    let mean_tris = |f: &mut Frame<'_>| views.iter().map(|v| f(v) as f64).sum::<f64>() / n as f64;
    let mut c = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4))
        .configure_from_args();
    let mut g = c.benchmark_group("frame");
    for (name, frame) in [
        ("hierarchy_refine_emit", &mut *hierarchy),
        ("octree_select_emit", &mut *octree),
    ] {
        g.throughput(Throughput::Elements(mean_tris(frame) as u64));
        let mut i = 0;
        g.bench_function(name, |b| {
            b.iter(|| {
                i = (i + 1) % n;
                frame(&views[i])
            })
        });
    }
    g.finish();
    c.final_summary();
}

/// Paired: alternating laps over the whole path, per-frame medians, printed as a table.
fn paired_laps(views: &[View], laps: usize, hierarchy: &mut Frame<'_>, octree: &mut Frame<'_>) {
    let (mut hs, mut os, mut htri, mut otri) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let lap = |frame: &mut Frame<'_>, ms: &mut Vec<f64>, tris: &mut Vec<f64>| {
        for v in views {
            let s = Instant::now();
            tris.push(f64::from(frame(v)));
            ms.push(s.elapsed().as_secs_f64() * 1e3);
        }
    };
    for _ in 0..laps {
        lap(hierarchy, &mut hs, &mut htri);
        lap(octree, &mut os, &mut otri);
    }
    let (hm, om) = (median(&mut hs), median(&mut os));
    let (htm, otm) = (median(&mut htri), median(&mut otri));
    println!("| runtime | frame ms (median) | triangles drawn (median) |");
    println!("|---|---|---|");
    println!("| hierarchy refine + emit | {hm:.3} | {htm:.0} |");
    println!("| octree select + emit | {om:.3} | {otm:.0} |");
    println!(
        "| octree / hierarchy | {:.3} | {:.2} |",
        om / hm.max(1e-9),
        otm / htm.max(1.0)
    );
}
