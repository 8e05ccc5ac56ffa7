//! g-mesh geomorphs on lavapipe: one level of a baked g-mesh, drawn for several instances at
//! different morph factors three ways — the geomorph vertex stage (both attribute streams,
//! `t` per instance, one instanced draw), the geomorph compute stage (interpolated vertices
//! written by `geomorph_cs`, then drawn plainly), and the CPU reference (`morph_vertex`) —
//! gives the same image, with zero validation messages.

mod vulkan_support;

use caveclod_bake::gmesh::{build, GMeshOptions};
use caveclod_core::format::Vertex;
use caveclod_core::gmesh::GMesh;
use caveclod_core::gpu::{morph_vertex, MorphInstance};
use caveclod_tests::{bake, meshes};
use caveclod_vulkan::{Geomorph, IndexSource, LookAt, Morph, MorphInstances, VertexBuffer};
use glam::Vec3;
use vulkan_support::*;

const SIZE: u32 = 256;

#[test]
fn vertex_stage_compute_stage_and_cpu_draw_the_same_gmesh_level() {
    let ctx = context();
    let baked = bake(&meshes::sphere(3));
    let h = baked.hierarchy();
    let data = ok(build(&h, &GMeshOptions::default()), "g-mesh levels");
    let g = ok(
        GMesh::new(data.parts(), h.vertices().len(), h.surface_count()),
        "valid g-mesh",
    );
    assert!(g.levels() >= 3);
    // Level 1: its vertices morph towards level 2's positions.
    let level = g.level(1).expect("level 1");
    let gather = |side: usize| -> Vec<Vertex> {
        level
            .vertices
            .iter()
            .map(|p| h.vertices()[p[side] as usize])
            .collect()
    };
    let (a, b) = (gather(0), gather(1));
    assert!(a != b, "level 1 must morph somewhere");
    let lists: Vec<Vec<u32>> = (0..g.surfaces())
        .map(|s| level.surface_indices(s).to_vec())
        .collect();
    let instances = [
        MorphInstance {
            offset_scale: [-2.3, 0.0, 0.0, 1.0],
            t: 0.15,
            _pad: [0.0; 3],
        },
        MorphInstance {
            offset_scale: [0.0, 0.0, 0.0, 1.0],
            t: 0.6,
            _pad: [0.0; 3],
        },
        MorphInstance {
            offset_scale: [2.3, 0.0, 0.0, 1.0],
            t: 1.0,
            _pad: [0.0; 3],
        },
    ];
    let look = LookAt {
        eye: Vec3::new(0.0, 1.5, 5.5),
        target: Vec3::ZERO,
        up: Vec3::Y,
        fov_y: 60f32.to_radians(),
        near: 0.1,
        far: 50.0,
    };

    // CPU reference and compute stage: every instance's vertices in one buffer, each
    // instance's lists offset to its block.
    let n = a.len() as u32;
    let geomorph = ok(Geomorph::new(&ctx), "geomorph pipeline");
    let mut cpu = Vec::with_capacity(a.len() * instances.len());
    let mut gpu = Vec::with_capacity(a.len() * instances.len());
    for inst in &instances {
        cpu.extend(
            a.iter()
                .zip(&b)
                .map(|(&x, &y)| place(morph_vertex(x, y, inst.t), inst)),
        );
        let morphed = ok(geomorph.morph(&ctx, &a, &b, inst.t), "compute morph");
        gpu.extend(morphed.into_iter().map(|v| place(v, inst)));
    }
    let all_lists: Vec<Vec<u32>> = lists
        .iter()
        .map(|l| {
            (0..instances.len() as u32)
                .flat_map(|i| l.iter().map(move |&x| x + i * n))
                .collect()
        })
        .collect();
    let all_refs: Vec<&[u32]> = all_lists.iter().map(Vec::as_slice).collect();
    let surfaces = lists.len();
    let cpu_buffer = ok(VertexBuffer::from_vertices(&ctx, "cpu", &cpu), "cpu buffer");
    let gpu_buffer = ok(VertexBuffer::from_vertices(&ctx, "gpu", &gpu), "gpu buffer");
    let cpu_image = render_alone(
        &ctx,
        &cpu_buffer,
        surfaces,
        &look,
        (SIZE, SIZE),
        IndexSource::Lists(&all_refs),
    );
    let compute_image = render_alone(
        &ctx,
        &gpu_buffer,
        surfaces,
        &look,
        (SIZE, SIZE),
        IndexSource::Lists(&all_refs),
    );

    // Vertex stage: both streams, one instanced draw.
    let coarse = ok(VertexBuffer::from_vertices(&ctx, "a_i", &a), "a_i");
    let fine = ok(VertexBuffer::from_vertices(&ctx, "a'_i", &b), "a'_i");
    let inst_buffer = ok(
        MorphInstances::new(&ctx, "instances", &instances),
        "instances",
    );
    let list_refs: Vec<&[u32]> = lists.iter().map(Vec::as_slice).collect();
    let vertex_image = render_morphed(
        &ctx,
        &coarse,
        Morph {
            fine: &fine,
            instances: &inst_buffer,
        },
        surfaces,
        &look,
        (SIZE, SIZE),
        IndexSource::Lists(&list_refs),
    );

    // Unmorphed (t = 0 everywhere), to show the morph is visible at all.
    let flat: Vec<Vertex> = instances
        .iter()
        .flat_map(|inst| a.iter().map(move |&v| place(v, inst)))
        .collect();
    let flat_buffer = ok(VertexBuffer::from_vertices(&ctx, "flat", &flat), "flat");
    let flat_image = render_alone(
        &ctx,
        &flat_buffer,
        surfaces,
        &look,
        (SIZE, SIZE),
        IndexSource::Lists(&all_refs),
    );

    assert!(cpu_image.covered(BACKGROUND) > u64::from(SIZE * SIZE) / 10);
    let dc = ok(compute_image.diff(&cpu_image), "diff");
    let dv = ok(vertex_image.diff(&cpu_image), "diff");
    let df = ok(flat_image.diff(&cpu_image), "diff");
    println!("compute vs CPU: {dc:?}\nvertex stage vs CPU: {dv:?}\nunmorphed vs CPU: {df:?}");
    assert!(
        dc.within_one_fraction() >= 0.999,
        "compute path differs: {dc:?}"
    );
    assert!(
        dv.within_one_fraction() >= 0.999,
        "vertex-stage path differs: {dv:?}"
    );
    assert!(
        df.within_one_fraction() < 0.999,
        "the morph is invisible: {df:?}"
    );

    for buffer in [cpu_buffer, gpu_buffer, coarse, fine, flat_buffer] {
        ok(buffer.destroy(&ctx), "destroy buffer");
    }
    ok(inst_buffer.destroy(&ctx), "destroy instances");
    geomorph.destroy(&ctx);
    assert_clean(&ctx, "g-mesh geomorph paths");
    ok(ctx.destroy(), "destroy context");
}
