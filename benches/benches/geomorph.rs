//! Criterion benchmarks of g-mesh geomorphs: interpolated vertices per second on the CPU
//! (one thread, `caveclod_core::gpu::morph_vertex`), in the geomorph compute stage and in the
//! geomorph vertex stage, on lavapipe (validation off). Each interpolation is one vertex of
//! 8 floats (position, normal, UV), as the paper counts them.
//!
//! The data is level 0 of a g-mesh baked from a generated sphere (`sphere(5)`: 20,480
//! triangles, 10,242 vertices morphing towards level 1).
//!
//! - `geomorph/cpu`: `morph_vertex` over every vertex of `INSTANCES` instances, each at its own
//!   `t`, into a preallocated output.
//! - `geomorph/compute`: `Geomorph::morph` of the same count (one dispatch over all instances'
//!   vertices). It includes uploading both ends and reading the result back, which a renderer
//!   keeping the result on the GPU would not pay, so it understates the stage.
//! - `geomorph/vertex_stage`: one frame drawing `INSTANCES` instances with `geomorph_vs` (both
//!   streams bound, `t` per instance, one instanced indexed draw per surface) into a small
//!   128 × 128 target, so rasterisation costs little; counted as one interpolation per
//!   instance vertex (the vertex shader runs at least that often).
//!
//! Criterion reports each as interpolations (elements) per second; `benches/README.md` gives
//! the ratios. `cargo bench -p caveclod-benches --bench geomorph`; without `--bench` (as
//! `cargo test --benches` runs it) each runs once on fewer instances.

use std::time::Duration;

use caveclod_bake::gmesh::{build, GMeshOptions};
use caveclod_core::format::Vertex;
use caveclod_core::gmesh::GMesh;
use caveclod_core::gpu::{morph_vertex, MorphInstance};
use caveclod_tests::{bake, meshes};
use caveclod_vulkan::{
    CameraIndices, Context, Geomorph, HeadlessDesc, IndexSource, LookAt, Morph, MorphInstances,
    RecordCamera, Renderer, RendererDesc, VertexBuffer, Viewport,
};
use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion, Throughput};

const COLOURS: [[f32; 4]; 2] = [[0.9, 0.6, 0.3, 1.0], [0.3, 0.7, 0.9, 1.0]];

fn or_exit<T, E: std::fmt::Display>(r: Result<T, E>, what: &str) -> T {
    match r {
        Ok(x) => x,
        Err(e) => {
            eprintln!("geomorph bench: {what}: {e}");
            std::process::exit(1)
        }
    }
}

/// Level 0 of the g-mesh of a generated sphere: its coarse and fine vertex ends and its
/// index lists, one per surface.
struct Level {
    a: Vec<Vertex>,
    b: Vec<Vertex>,
    lists: Vec<Vec<u32>>,
}

fn level_zero() -> Level {
    let baked = bake(&meshes::sphere(5));
    let h = baked.hierarchy();
    let data = or_exit(build(&h, &GMeshOptions::default()), "g-mesh levels");
    let g = or_exit(
        GMesh::new(data.parts(), h.vertices().len(), h.surface_count()),
        "g-mesh",
    );
    let level = g.level(0).unwrap_or_else(|| std::process::exit(1));
    let end = |k: usize| -> Vec<Vertex> {
        level
            .vertices
            .iter()
            .map(|p| h.vertices()[p[k] as usize])
            .collect()
    };
    let lists = (0..g.surfaces())
        .map(|s| level.surface_indices(s).to_vec())
        .collect();
    Level {
        a: end(0),
        b: end(1),
        lists,
    }
}

fn main() {
    let benchmarking = std::env::args().any(|a| a == "--bench");
    let instances_n: usize = if benchmarking { 100 } else { 4 };
    let level = level_zero();
    let ts: Vec<f32> = (0..instances_n)
        .map(|i| (i as f32 + 0.5) / instances_n as f32)
        .collect();
    let per_frame = (level.a.len() * instances_n) as u64;
    eprintln!(
        "level 0: {} vertices, {} instances: {per_frame} interpolations per frame",
        level.a.len(),
        instances_n
    );

    let ctx = or_exit(
        Context::headless(&HeadlessDesc {
            validation: false,
            prefer_lavapipe: true,
            synchronization_validation: false,
        }),
        "no Vulkan device",
    );
    eprintln!("device: {}", ctx.device_name());
    let mut c = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(8))
        .configure_from_args();
    let mut group = c.benchmark_group("geomorph");
    group.throughput(Throughput::Elements(per_frame));
    bench_cpu(&mut group, &level, &ts);
    bench_compute(&mut group, &ctx, &level, instances_n);
    bench_vertex_stage(&mut group, &ctx, &level, &ts);
    group.finish();
    c.final_summary();
    or_exit(ctx.destroy(), "destroy context");
}

type Group<'a> = BenchmarkGroup<'a, WallTime>;

/// CPU, one thread: every instance's vertices at its own `t`.
fn bench_cpu(group: &mut Group<'_>, level: &Level, ts: &[f32]) {
    let (a, b) = (&level.a, &level.b);
    let mut out = vec![a[0]; a.len() * ts.len()];
    group.bench_function("cpu", |bench| {
        bench.iter(|| {
            for (k, &t) in ts.iter().enumerate() {
                let dst = &mut out[k * a.len()..(k + 1) * a.len()];
                for ((d, &x), &y) in dst.iter_mut().zip(a).zip(b) {
                    *d = morph_vertex(x, y, t);
                }
            }
            std::hint::black_box(&out);
        })
    });
}

/// Compute stage: all instances' vertices in one dispatch (one t for the dispatch; the
/// stage's cost does not depend on t).
fn bench_compute(group: &mut Group<'_>, ctx: &Context, level: &Level, instances_n: usize) {
    let geomorph = or_exit(Geomorph::new(ctx), "geomorph pipeline");
    let big_a: Vec<Vertex> = (0..instances_n)
        .flat_map(|_| level.a.iter().copied())
        .collect();
    let big_b: Vec<Vertex> = (0..instances_n)
        .flat_map(|_| level.b.iter().copied())
        .collect();
    group.bench_function("compute", |bench| {
        bench.iter(|| {
            let r = or_exit(geomorph.morph(ctx, &big_a, &big_b, 0.4), "morph");
            std::hint::black_box(r);
        })
    });
    geomorph.destroy(ctx);
}

/// The instances on a square grid, one `t` each.
fn grid_instances(ts: &[f32]) -> (Vec<MorphInstance>, usize) {
    let side = (ts.len() as f32).sqrt().ceil() as usize;
    let instances = ts
        .iter()
        .enumerate()
        .map(|(i, &t)| MorphInstance {
            offset_scale: [
                (i % side) as f32 * 2.5,
                0.0,
                -((i / side) as f32) * 2.5,
                1.0,
            ],
            t,
            _pad: [0.0; 3],
        })
        .collect();
    (instances, side)
}

/// Vertex stage: one instanced draw of every instance, a frame at a time.
fn bench_vertex_stage(group: &mut Group<'_>, ctx: &Context, level: &Level, ts: &[f32]) {
    let coarse = or_exit(VertexBuffer::from_vertices(ctx, "a_0", &level.a), "a_0");
    let fine = or_exit(VertexBuffer::from_vertices(ctx, "a'_0", &level.b), "a'_0");
    let (instances, side) = grid_instances(ts);
    let inst_buffer = or_exit(
        MorphInstances::new(ctx, "instances", &instances),
        "instances",
    );
    let mut renderer = or_exit(
        Renderer::new(
            ctx,
            RendererDesc {
                geomorph: true,
                ..RendererDesc::single(128, 128)
            },
        ),
        "renderer",
    );
    let frames = renderer.desc().frames_in_flight;
    let mut indices = CameraIndices::new("gmesh", level.lists.len(), frames);
    let list_refs: Vec<&[u32]> = level.lists.iter().map(Vec::as_slice).collect();
    let extent = side as f32 * 2.5;
    let look = LookAt {
        eye: caveclod_core::glam::Vec3::new(extent * 0.5, extent, extent * 0.6),
        target: caveclod_core::glam::Vec3::new(extent * 0.5, 0.0, -extent * 0.5),
        up: caveclod_core::glam::Vec3::Y,
        fov_y: 60f32.to_radians(),
        near: 0.1,
        far: 10.0 * extent,
    };
    let viewport = Viewport::full(128, 128);
    group.bench_function("vertex_stage", |bench| {
        bench.iter(|| {
            let slot = or_exit(renderer.begin_frame(ctx), "begin frame");
            let source = IndexSource::Lists(&list_refs);
            or_exit(indices.fill(ctx, slot, source), "fill");
            let view_proj = look.view_projection(viewport.aspect());
            let camera = RecordCamera::new(viewport, view_proj, &coarse, &indices)
                .colours(&COLOURS)
                .morph(Morph {
                    fine: &fine,
                    instances: &inst_buffer,
                });
            or_exit(renderer.render(ctx, &[(0, camera)]), "render");
            or_exit(renderer.wait(ctx), "wait");
        })
    });
    or_exit(renderer.destroy(ctx), "destroy renderer");
    or_exit(indices.destroy(ctx), "destroy indices");
    for buffer in [coarse, fine] {
        or_exit(buffer.destroy(ctx), "destroy buffer");
    }
    or_exit(inst_buffer.destroy(ctx), "destroy instances");
}
