//! Criterion benchmarks of caveclod-vulkan on lavapipe (validation off): frame time of one
//! camera against four cameras in split screen, and index bytes uploaded per frame.
//!
//! A generated terrain (`terrain(256, 256)`: 131,072 triangles) is baked once; its vertex
//! buffer is uploaded once. Cameras are refined once for their viewports (1 px tolerance),
//! so the timed frame is what a renderer does every frame for a settled front: index
//! emission into the mapped index buffers of the frame slot, recording, submission, and
//! the wait for the frame slot's previous use (two frames in flight, so in steady state one
//! iteration is one frame of GPU work).
//!
//! - `render/frame_1_camera`: one camera, full 960 × 540 target.
//! - `render/frame_4_cameras_split`: four cameras, one quadrant each of the same target
//!   (the same pixel count), one submission.
//!
//! Index bytes per frame are printed for both (`index bytes per frame: ...`). Because
//! criterion runs one benchmark after the other, a change of machine load between them
//! skews their ratio; a paired measurement after them alternates one waited-for frame of
//! each, 100 times, and prints the medians and their ratio (`paired frame latency: ...`).
//! A second paired measurement compares four cameras through the headless `Renderer` with
//! the same four through the record path as a host drives it (`record_path.rs`, on
//! caveclod-host's target and frames: the host's own images, command buffers, fences,
//! barriers and dynamic rendering; `record path / renderer: ...`). The device and
//! caveclod's context come from caveclod-host's `Host` too, validation off.
//! `cargo bench -p caveclod-benches --bench render`; `CAVECLOD_BENCH_RENDER_SIZE=N` changes
//! the terrain. Without `--bench` (as `cargo test --benches` runs it) each benchmark runs
//! once on a small terrain.

use std::time::{Duration, Instant};

use caveclod_core::{CameraConfig, CameraState, Hierarchy, RefineParams};
use caveclod_host::{Host, HostDesc};
use caveclod_tests::{bake, meshes};
use caveclod_vulkan::{
    CameraIndices, Context, RecordCamera, Renderer, RendererDesc, VertexBuffer, Viewport,
};
use criterion::Criterion;

mod record_path;
mod scene;

use scene::{look, or_exit, Scene, HEIGHT, WIDTH};

const SEED: u64 = 7;
/// Camera states refined for `viewports` (camera `i` in `viewports[i]`).
fn refined<'m>(
    h: &Hierarchy<'_>,
    memories: &'m mut [Vec<u32>],
    viewports: &[Viewport],
    size: f32,
) -> Vec<CameraState<'m>> {
    let config = CameraConfig::full(h);
    let params = RefineParams::default();
    memories
        .iter_mut()
        .enumerate()
        .map(|(i, m)| {
            let mut cam = or_exit(CameraState::with_config(h, m, &config), "camera");
            or_exit(
                cam.refine(
                    h,
                    &look(i, size).view(viewports[i].width, viewports[i].height),
                    &params,
                ),
                "refine",
            );
            cam
        })
        .collect()
}

/// One frame of `renderer`: the rings filled, the cameras drawn into target 0.
fn render_frame(
    scene: &Scene<'_>,
    renderer: &mut Renderer,
    indices: &mut [CameraIndices],
    cams: &[CameraState<'_>],
    viewports: &[Viewport],
) -> u64 {
    let slot = or_exit(renderer.begin_frame(scene.ctx), "begin frame");
    scene.fill(slot, indices, cams);
    let draws: Vec<(usize, RecordCamera<'_>)> = scene
        .cameras(indices, viewports)
        .into_iter()
        .map(|c| (0, c))
        .collect();
    or_exit(renderer.render(scene.ctx, &draws), "render").index_bytes
}

/// One camera set's renderer and index buffers, for the paired measurement.
struct Setup<'s, 'c> {
    renderer: Renderer,
    indices: Vec<CameraIndices>,
    cams: &'s [CameraState<'c>],
    viewports: &'s [Viewport],
}

impl<'s, 'c> Setup<'s, 'c> {
    fn new(ctx: &Context, cams: &'s [CameraState<'c>], viewports: &'s [Viewport]) -> Self {
        let renderer = or_exit(
            Renderer::new(
                ctx,
                RendererDesc {
                    readback: false,
                    ..RendererDesc::single(WIDTH, HEIGHT)
                },
            ),
            "renderer",
        );
        let frames = renderer.desc().frames_in_flight;
        let surfaces = cams.first().map_or(0, |c| c.surface_polygons().len());
        let indices = (0..cams.len())
            .map(|i| CameraIndices::new(&format!("camera {i}"), surfaces, frames))
            .collect();
        Self {
            renderer,
            indices,
            cams,
            viewports,
        }
    }

    /// One frame, waited for: its latency.
    fn frame(&mut self, scene: &Scene<'_>) -> Duration {
        let t = Instant::now();
        let (cams, viewports) = (self.cams, self.viewports);
        render_frame(
            scene,
            &mut self.renderer,
            &mut self.indices,
            cams,
            viewports,
        );
        or_exit(self.renderer.wait(scene.ctx), "wait");
        t.elapsed()
    }

    fn destroy(self, ctx: &Context) {
        or_exit(self.renderer.destroy(ctx), "destroy renderer");
        for i in self.indices {
            or_exit(i.destroy(ctx), "destroy indices");
        }
    }
}

/// Frame latency of `b` against `a`, alternating one frame of each for `rounds` rounds so
/// both see the same machine load; returns the medians.
fn paired(
    rounds: usize,
    mut a: impl FnMut() -> Duration,
    mut b: impl FnMut() -> Duration,
) -> (f64, f64) {
    let (mut ta, mut tb) = (Vec::new(), Vec::new());
    for _ in 0..rounds {
        ta.push(a().as_secs_f64());
        tb.push(b().as_secs_f64());
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(0.0)
    };
    (median(&mut ta), median(&mut tb))
}

/// Benchmarks `cams` drawn into `viewports` of one target; returns index bytes per frame.
fn bench_frames(
    c: &mut Criterion,
    name: &str,
    scene: &Scene<'_>,
    cams: &[CameraState<'_>],
    viewports: &[Viewport],
) -> u64 {
    let Scene { ctx, h, .. } = *scene;
    let mut renderer = or_exit(
        Renderer::new(
            ctx,
            RendererDesc {
                readback: false,
                ..RendererDesc::single(WIDTH, HEIGHT)
            },
        ),
        "renderer",
    );
    let frames = renderer.desc().frames_in_flight;
    let mut indices: Vec<CameraIndices> = (0..cams.len())
        .map(|i| CameraIndices::new(&format!("camera {i}"), h.surface_count(), frames))
        .collect();
    let mut index_bytes = 0;
    c.bench_function(name, |b| {
        b.iter(|| {
            index_bytes = render_frame(scene, &mut renderer, &mut indices, cams, viewports);
        })
    });
    or_exit(renderer.wait(ctx), "wait");
    or_exit(renderer.destroy(ctx), "destroy renderer");
    for i in indices {
        or_exit(i.destroy(ctx), "destroy indices");
    }
    index_bytes
}

fn main() {
    let benchmarking = std::env::args().any(|a| a == "--bench");
    let size: u32 = std::env::var("CAVECLOD_BENCH_RENDER_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(if benchmarking { 256 } else { 24 });
    let t = Instant::now();
    let mesh = meshes::terrain(size, size, SEED);
    let baked = bake(&mesh);
    let h = baked.hierarchy();
    eprintln!(
        "terrain {size} x {size}: {} polygons; baked in {:.2} s",
        mesh.triangles.len(),
        t.elapsed().as_secs_f64()
    );
    let host = or_exit(
        Host::headless(&HostDesc {
            validation: false,
            ..HostDesc::default()
        }),
        "no Vulkan device",
    );
    let ctx = or_exit(host.context(), "context");
    eprintln!("device: {}", ctx.device_name());
    let vertices = or_exit(
        VertexBuffer::from_hierarchy(&ctx, "terrain", &h),
        "vertices",
    );
    let s = size as f32;
    let full = [Viewport::full(WIDTH, HEIGHT)];
    let quadrants = or_exit(Viewport::split_screen(WIDTH, HEIGHT, 4), "split screen");
    let words = CameraState::words_needed(&h);
    let mut memory_one = vec![vec![0u32; words]];
    let mut memory_four = vec![vec![0u32; words]; 4];
    let one = refined(&h, &mut memory_one, &full, s);
    let four = refined(&h, &mut memory_four, &quadrants, s);

    let mut c = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_secs(2))
        .measurement_time(Duration::from_secs(12))
        .configure_from_args();
    let scene = Scene {
        ctx: &ctx,
        h: &h,
        vertices: &vertices,
        size: s,
    };
    let bytes_one = bench_frames(&mut c, "render/frame_1_camera", &scene, &one, &full);
    let bytes_four = bench_frames(
        &mut c,
        "render/frame_4_cameras_split",
        &scene,
        &four,
        &quadrants,
    );
    c.final_summary();
    let polys = |cams: &[CameraState<'_>]| {
        cams.iter()
            .map(|c| c.active_polygon_count().to_string())
            .collect::<Vec<_>>()
            .join(" + ")
    };
    println!(
        "index bytes per frame: 1 camera {bytes_one} ({} active polygons), 4 cameras split {bytes_four} ({} active polygons); ratio {:.2}",
        polys(&one),
        polys(&four),
        bytes_four as f64 / bytes_one.max(1) as f64
    );
    // Paired latency: one frame of each set in turn, each waited for.
    let mut a = Setup::new(&ctx, &one, &full);
    let mut b = Setup::new(&ctx, &four, &quadrants);
    let rounds = if benchmarking { 100 } else { 3 };
    let (ta, tb) = paired(rounds, || a.frame(&scene), || b.frame(&scene));
    println!(
        "paired frame latency over {rounds} alternating rounds (median): 1 camera {:.2} ms, 4 cameras split {:.2} ms; ratio {:.2}",
        ta * 1e3,
        tb * 1e3,
        tb / ta.max(1e-12)
    );
    // The same four cameras through the record path, driven the way a host does.
    let mut h4 = record_path::HostFrames::new(&host, &scene, &four, &quadrants);
    let (tr, th) = paired(rounds, || b.frame(&scene), || h4.frame(&host, &scene));
    println!(
        "record path / renderer, 4 cameras split, {rounds} alternating rounds (median): renderer {:.2} ms, record path {:.2} ms; ratio {:.2}",
        tr * 1e3,
        th * 1e3,
        th / tr.max(1e-12)
    );
    h4.destroy(&host, &ctx);
    a.destroy(&ctx);
    b.destroy(&ctx);
    println!("vertex buffer uploads: {}", ctx.vertex_uploads());
    drop(one);
    drop(four);
    or_exit(vertices.destroy(&ctx), "destroy vertices");
    or_exit(ctx.destroy(), "destroy context");
    or_exit(host.destroy(), "destroy host");
}
