//! Rendering on lavapipe, every test ending with zero validation messages:
//! - a full-detail render of a baked mesh equals the input mesh drawn directly with the same
//!   shaders (within 1/255 per channel on at least 99.9% of pixels), a coarse one differs;
//! - the vertex buffer is uploaded once however many frames are drawn; index bytes per
//!   frame are reported and match the camera's index counts;
//! - four cameras in four quadrants of one image in one submission equal each camera
//!   rendered alone;
//! - the geomorph compute stage equals `caveclod_core::gpu::morph_vertex` on random data;
//! - the geomorph vertex stage draws what the CPU's morph, drawn directly, draws.

mod vulkan_support;

use caveclod_core::format::Vertex;
use caveclod_core::gpu::{morph_vertex, MorphInstance};
use caveclod_core::{CameraConfig, CameraState};
use caveclod_tests::check::split_all;
use caveclod_tests::meshes::{self, Rng};
use caveclod_vulkan::{
    CameraIndices, Geomorph, IndexSource, Morph, MorphInstances, RecordCamera, Renderer,
    RendererDesc, VertexBuffer, Viewport,
};
use vulkan_support::*;

const SIZE: u32 = 256;

#[test]
fn full_detail_equals_the_input_mesh_and_coarse_differs() {
    let ctx = context();
    let mesh = meshes::terrain(24, 24, 11);
    let baked = caveclod_tests::bake(&mesh);
    let h = baked.hierarchy();
    let surfaces = h.surface_count();
    assert_eq!(surfaces, 2);
    let look = terrain_camera(24.0, 0.5, 0.75, 0.6);
    let vertices = ok(
        VertexBuffer::from_hierarchy(&ctx, "baked", &h),
        "baked vertices",
    );

    // Full detail: every split applied.
    let mut memory = camera_memory(&h);
    let mut cam = ok(CameraState::new(&h, &mut memory), "camera");
    split_all(&h, &mut cam);
    assert_eq!(cam.active_polygon_count() as usize, mesh.triangles.len());
    let full = render_alone(
        &ctx,
        &vertices,
        surfaces,
        &look,
        (SIZE, SIZE),
        IndexSource::camera(&h, &cam),
    );

    // The input mesh drawn directly.
    let (direct_vertices, lists) = direct_mesh(&mesh);
    let direct_buffer = ok(
        VertexBuffer::from_vertices(&ctx, "direct", &direct_vertices),
        "direct vertices",
    );
    let list_refs: Vec<&[u32]> = lists.iter().map(Vec::as_slice).collect();
    let direct = render_alone(
        &ctx,
        &direct_buffer,
        surfaces,
        &look,
        (SIZE, SIZE),
        IndexSource::Lists(&list_refs),
    );

    // The base mesh.
    let mut coarse_memory = camera_memory(&h);
    let coarse_cam = ok(CameraState::new(&h, &mut coarse_memory), "coarse camera");
    assert!((coarse_cam.active_polygon_count() as usize) < mesh.triangles.len() / 4);
    let coarse = render_alone(
        &ctx,
        &vertices,
        surfaces,
        &look,
        (SIZE, SIZE),
        IndexSource::camera(&h, &coarse_cam),
    );
    save(&full, "full.png");
    save(&direct, "direct.png");
    save(&coarse, "coarse.png");

    let covered = full.covered(BACKGROUND);
    assert!(
        covered > u64::from(SIZE * SIZE) / 4,
        "terrain covers only {covered} pixels"
    );
    let d = ok(full.diff(&direct), "diff");
    println!("full vs direct: {d:?}");
    assert!(
        d.within_one_fraction() >= 0.999,
        "full detail differs from the input: {d:?}"
    );
    let c = ok(coarse.diff(&direct), "diff");
    println!("coarse vs direct: {c:?}");
    assert!(
        c.within_one_fraction() < 0.99 && c.mean_channel_difference > 0.5,
        "the coarse render does not differ measurably: {c:?}"
    );

    ok(vertices.destroy(&ctx), "destroy");
    ok(direct_buffer.destroy(&ctx), "destroy");
    assert_clean(&ctx, "rendering full, direct and coarse");
    ok(ctx.destroy(), "destroy context");
}

#[test]
fn vertex_buffer_written_once_index_bytes_reported() {
    let ctx = context();
    let mesh = meshes::terrain(20, 20, 3);
    let baked = caveclod_tests::bake(&mesh);
    let h = baked.hierarchy();
    let vertices = ok(
        VertexBuffer::from_hierarchy(&ctx, "terrain", &h),
        "vertices",
    );
    assert_eq!(ctx.vertex_uploads(), 1);
    let mut renderer = ok(
        Renderer::new(&ctx, RendererDesc::single(128, 128)),
        "renderer",
    );
    let frames_in_flight = renderer.desc().frames_in_flight;
    let mut indices = CameraIndices::new("flying", h.surface_count(), frames_in_flight);
    let mut memory = camera_memory(&h);
    let mut cam = ok(CameraState::new(&h, &mut memory), "camera");
    let viewport = Viewport::full(128, 128);
    let mut sizes = Vec::new();
    for frame in 0..12 {
        // Fly in: more detail, so index lists grow.
        let look = terrain_camera(20.0, 0.1 * frame as f32, 1.2 - 0.07 * frame as f32, 0.5);
        refine(&h, &mut cam, &look, viewport, 0.5);
        let expected: usize = (0..h.surface_count()).map(|s| cam.index_count(s)).sum();
        let slot = ok(renderer.begin_frame(&ctx), "begin frame");
        ok(
            indices.fill(&ctx, slot, IndexSource::camera(&h, &cam)),
            "fill",
        );
        let camera = plain_camera(viewport, &look, &vertices, &indices);
        let stats = ok(renderer.render(&ctx, &[(0, camera)]), "render");
        assert_eq!(stats.index_bytes, 4 * expected as u64, "frame {frame}");
        assert_eq!(stats.camera_index_bytes, vec![stats.index_bytes]);
        assert_eq!(stats.slot, frame % frames_in_flight);
        assert!(stats.draws >= 1 && stats.draws <= h.surface_count() as u32);
        sizes.push(stats.index_bytes);
    }
    println!(
        "index bytes per frame: {sizes:?}; buffer (re)allocations {}",
        indices.grow_count()
    );
    assert!(
        sizes.last() > sizes.first(),
        "the flight should add detail: {sizes:?}"
    );
    // Doubling: a few allocations per surface and slot, not one per frame.
    assert!(indices.grow_count() <= (2 * frames_in_flight * h.surface_count()) as u64 * 4);
    assert_eq!(
        ctx.vertex_uploads(),
        1,
        "the vertex buffer was written again"
    );
    let image = ok(renderer.read_target(&ctx, 0), "read back");
    assert!(image.covered(BACKGROUND) > 0);
    ok(renderer.destroy(&ctx), "destroy renderer");
    ok(indices.destroy(&ctx), "destroy indices");
    ok(vertices.destroy(&ctx), "destroy vertices");
    assert_clean(&ctx, "flying 12 frames");
    ok(ctx.destroy(), "destroy context");
}

#[test]
fn four_quadrants_in_one_submission_equal_each_camera_alone() {
    let ctx = context();
    let mesh = meshes::terrain(24, 24, 8);
    let baked = caveclod_tests::bake(&mesh);
    let h = baked.hierarchy();
    let vertices = ok(
        VertexBuffer::from_hierarchy(&ctx, "terrain", &h),
        "vertices",
    );
    let quadrants = ok(Viewport::split_screen(SIZE, SIZE, 4), "split screen");
    let looks = [
        terrain_camera(24.0, 0.3, 0.8, 0.6),
        terrain_camera(24.0, 1.9, 0.6, 0.4),
        terrain_camera(24.0, 3.4, 1.0, 0.9),
        terrain_camera(24.0, 4.8, 0.5, 0.3),
    ];
    let config = CameraConfig::full(&h);
    let words = CameraState::words_needed_for(&h, &config);
    let mut memories: Vec<Vec<u32>> = (0..4).map(|_| vec![0u32; words]).collect();
    let mut cams: Vec<CameraState<'_>> = memories
        .iter_mut()
        .map(|m| ok(CameraState::with_config(&h, m, &config), "camera"))
        .collect();
    for (i, cam) in cams.iter_mut().enumerate() {
        refine(&h, cam, &looks[i], quadrants[i], 1.0);
    }
    // Each camera refined for its own view: the fronts differ.
    assert!(cams
        .windows(2)
        .any(|w| w[0].active_polygon_count() != w[1].active_polygon_count()));

    let mut renderer = ok(
        Renderer::new(&ctx, RendererDesc::single(SIZE, SIZE)),
        "renderer",
    );
    let mut indices: Vec<CameraIndices> = (0..4)
        .map(|i| {
            CameraIndices::new(
                &format!("camera {i}"),
                h.surface_count(),
                renderer.desc().frames_in_flight,
            )
        })
        .collect();
    let slot = ok(renderer.begin_frame(&ctx), "begin frame");
    for (ind, cam) in indices.iter_mut().zip(&cams) {
        ok(ind.fill(&ctx, slot, IndexSource::camera(&h, cam)), "fill");
    }
    let draws: Vec<(usize, RecordCamera<'_>)> = indices
        .iter()
        .enumerate()
        .map(|(i, ind)| (0, plain_camera(quadrants[i], &looks[i], &vertices, ind)))
        .collect();
    let stats = ok(renderer.render(&ctx, &draws), "render four");
    assert_eq!(stats.camera_index_bytes.len(), 4);
    drop(draws);
    let split = ok(renderer.read_target(&ctx, 0), "read back");
    save(&split, "split.png");
    ok(renderer.destroy(&ctx), "destroy renderer");
    for ind in indices {
        ok(ind.destroy(&ctx), "destroy indices");
    }

    for (i, q) in quadrants.iter().enumerate() {
        let alone = render_alone(
            &ctx,
            &vertices,
            h.surface_count(),
            &looks[i],
            (q.width, q.height),
            IndexSource::camera(&h, &cams[i]),
        );
        let part = ok(split.crop(*q), "crop");
        save(&alone, &format!("alone{i}.png"));
        let d = ok(part.diff(&alone), "diff");
        println!("quadrant {i}: {d:?}");
        assert!(
            alone.covered(BACKGROUND) > u64::from(q.width * q.height) / 10,
            "camera {i} sees little"
        );
        // Rasterising at another viewport offset may round a few edge pixels differently
        // (lavapipe: at most 1/255 on a handful of pixels); the same bar as the pixel test.
        assert!(
            d.within_one_fraction() >= 0.999 && d.max_channel_difference <= 1,
            "quadrant {i} differs from camera {i} alone: {d:?}"
        );
    }
    ok(vertices.destroy(&ctx), "destroy vertices");
    assert_clean(&ctx, "rendering four cameras");
    ok(ctx.destroy(), "destroy context");
}

#[test]
fn geomorph_compute_equals_the_cpu_function() {
    let ctx = context();
    let geomorph = ok(Geomorph::new(&ctx), "geomorph pipeline");
    let mut rng = Rng(0x5eed);
    let mut value = |scale: f32| (rng.unit() * 2.0 - 1.0) * scale;
    let random_vertex = |value: &mut dyn FnMut(f32) -> f32| Vertex {
        position: [value(100.0), value(100.0), value(100.0)],
        normal: [value(1.0), value(1.0), value(1.0)],
        uv: [value(4.0), value(4.0)],
    };
    // Not a multiple of the workgroup size, so the bounds check runs too.
    let n = 1000;
    let a: Vec<Vertex> = (0..n).map(|_| random_vertex(&mut value)).collect();
    let b: Vec<Vertex> = (0..n).map(|_| random_vertex(&mut value)).collect();
    let mut worst = 0f32;
    for t in [0.0, 0.37, 0.5, 1.0] {
        let gpu = ok(geomorph.morph(&ctx, &a, &b, t), "morph");
        assert_eq!(gpu.len(), n);
        for i in 0..n {
            let cpu = morph_vertex(a[i], b[i], t);
            let g: &[f32; 8] = bytemuck::cast_ref(&gpu[i]);
            let c: &[f32; 8] = bytemuck::cast_ref(&cpu);
            let (fa, fb): (&[f32; 8], &[f32; 8]) =
                (bytemuck::cast_ref(&a[i]), bytemuck::cast_ref(&b[i]));
            for k in 0..8 {
                // Relative to the magnitude of the component's inputs and result.
                let scale = c[k]
                    .abs()
                    .max(fa[k].abs())
                    .max(fb[k].abs())
                    .max(f32::MIN_POSITIVE);
                let rel = (g[k] - c[k]).abs() / scale;
                worst = worst.max(rel);
                assert!(
                    rel <= 1e-6,
                    "vertex {i} component {k} at t {t}: gpu {} cpu {}",
                    g[k],
                    c[k]
                );
            }
        }
    }
    println!("largest relative difference {worst:e}");
    geomorph.destroy(&ctx);
    assert_clean(&ctx, "geomorph dispatches");
    ok(ctx.destroy(), "destroy context");
}

#[test]
fn geomorph_vertex_stage_equals_the_cpu_morph_drawn_directly() {
    let ctx = context();
    let mesh = meshes::terrain(16, 16, 21);
    let (coarse, lists) = direct_mesh(&mesh);
    let list_refs: Vec<&[u32]> = lists.iter().map(Vec::as_slice).collect();
    // Fine ends: a smooth function of the position, so the morphed surface stays closed.
    let fine: Vec<Vertex> = coarse
        .iter()
        .map(|v| {
            let [x, y, z] = v.position;
            let bump = (0.7 * x).sin() * (0.5 * z).cos();
            Vertex {
                position: [x, y + 1.5 * bump, z],
                normal: [
                    v.normal[0] + 0.4 * bump,
                    v.normal[1],
                    v.normal[2] - 0.3 * bump,
                ],
                uv: [v.uv[0] + 0.06, v.uv[1] - 0.04],
            }
        })
        .collect();
    let instance = MorphInstance {
        offset_scale: [0.5, 0.0, -0.25, 1.1],
        t: 0.37,
        _pad: [0.0; 3],
    };
    // The CPU's morph, placed as the instance places it, drawn with `draw_vs`.
    let expected: Vec<Vertex> = coarse
        .iter()
        .zip(&fine)
        .map(|(&a, &b)| place(morph_vertex(a, b, instance.t), &instance))
        .collect();
    let look = terrain_camera(16.0, 0.9, 0.8, 0.55);
    let surfaces = lists.len();
    let coarse_buffer = ok(
        VertexBuffer::from_vertices(&ctx, "coarse", &coarse),
        "coarse",
    );
    let fine_buffer = ok(VertexBuffer::from_vertices(&ctx, "fine", &fine), "fine");
    let expected_buffer = ok(
        VertexBuffer::from_vertices(&ctx, "expected", &expected),
        "expected",
    );
    let instances = ok(
        MorphInstances::new(&ctx, "instance", &[instance]),
        "instances",
    );

    let morphed = render_morphed(
        &ctx,
        &coarse_buffer,
        Morph {
            fine: &fine_buffer,
            instances: &instances,
        },
        surfaces,
        &look,
        (SIZE, SIZE),
        IndexSource::Lists(&list_refs),
    );
    let cpu = render_alone(
        &ctx,
        &expected_buffer,
        surfaces,
        &look,
        (SIZE, SIZE),
        IndexSource::Lists(&list_refs),
    );
    let unmorphed = render_alone(
        &ctx,
        &coarse_buffer,
        surfaces,
        &look,
        (SIZE, SIZE),
        IndexSource::Lists(&list_refs),
    );
    save(&morphed, "geomorph_gpu.png");
    save(&cpu, "geomorph_cpu.png");

    assert!(morphed.covered(BACKGROUND) > u64::from(SIZE * SIZE) / 4);
    let d = ok(morphed.diff(&cpu), "diff");
    println!("geomorph_vs vs CPU morph: {d:?}");
    assert!(
        d.within_one_fraction() >= 0.999,
        "geomorph_vs differs from the CPU morph: {d:?}"
    );
    let u = ok(morphed.diff(&unmorphed), "diff");
    assert!(
        u.within_one_fraction() < 0.9,
        "the morph changed too little to test anything: {u:?}"
    );

    for b in [coarse_buffer, fine_buffer, expected_buffer] {
        ok(b.destroy(&ctx), "destroy");
    }
    ok(instances.destroy(&ctx), "destroy instances");
    assert_clean(&ctx, "geomorph drawing");
    ok(ctx.destroy(), "destroy context");
}

#[test]
fn separate_targets_in_one_submission_equal_each_camera_alone() {
    let ctx = context();
    let mesh = meshes::sphere(3);
    let baked = caveclod_tests::bake(&mesh);
    let h = baked.hierarchy();
    let vertices = ok(VertexBuffer::from_hierarchy(&ctx, "sphere", &h), "vertices");
    let sizes = [(160u32, 120u32), (96, 128)];
    let looks: Vec<_> = [0.0f32, 2.5]
        .iter()
        .map(|&a| caveclod_vulkan::LookAt {
            eye: glam::Vec3::new(3.0 * a.sin(), 1.2, 3.0 * a.cos()),
            target: glam::Vec3::ZERO,
            up: glam::Vec3::Y,
            fov_y: 50f32.to_radians(),
            near: 0.1,
            far: 20.0,
        })
        .collect();
    let mut memories: Vec<Vec<u32>> = (0..2).map(|_| camera_memory(&h)).collect();
    let mut cams: Vec<CameraState<'_>> = memories
        .iter_mut()
        .map(|m| ok(CameraState::new(&h, m), "camera"))
        .collect();
    for (i, cam) in cams.iter_mut().enumerate() {
        refine(
            &h,
            cam,
            &looks[i],
            Viewport::full(sizes[i].0, sizes[i].1),
            2.0,
        );
    }
    let mut renderer = ok(
        Renderer::new(
            &ctx,
            RendererDesc {
                targets: sizes.to_vec(),
                ..RendererDesc::single(1, 1)
            },
        ),
        "renderer",
    );
    let mut indices: Vec<CameraIndices> = (0..2)
        .map(|i| {
            CameraIndices::new(
                &format!("camera {i}"),
                h.surface_count(),
                renderer.desc().frames_in_flight,
            )
        })
        .collect();
    let slot = ok(renderer.begin_frame(&ctx), "begin frame");
    for (ind, cam) in indices.iter_mut().zip(&cams) {
        ok(ind.fill(&ctx, slot, IndexSource::camera(&h, cam)), "fill");
    }
    let draws: Vec<(usize, RecordCamera<'_>)> = indices
        .iter()
        .enumerate()
        .map(|(i, ind)| {
            let viewport = Viewport::full(sizes[i].0, sizes[i].1);
            (i, plain_camera(viewport, &looks[i], &vertices, ind))
        })
        .collect();
    let stats = ok(renderer.render(&ctx, &draws), "render two targets");
    drop(draws);
    assert_eq!(stats.camera_index_bytes.len(), 2);
    let images: Vec<_> = (0..2)
        .map(|t| ok(renderer.read_target(&ctx, t), "read back"))
        .collect();
    ok(renderer.destroy(&ctx), "destroy renderer");
    for ind in indices {
        ok(ind.destroy(&ctx), "destroy indices");
    }
    for i in 0..2 {
        let alone = render_alone(
            &ctx,
            &vertices,
            h.surface_count(),
            &looks[i],
            sizes[i],
            IndexSource::camera(&h, &cams[i]),
        );
        assert!(alone.covered(BACKGROUND) > u64::from(sizes[i].0 * sizes[i].1) / 10);
        let d = ok(images[i].diff(&alone), "diff");
        assert_eq!(
            d.equal, d.pixels,
            "target {i} differs from camera {i} alone: {d:?}"
        );
    }
    ok(vertices.destroy(&ctx), "destroy vertices");
    assert_clean(&ctx, "rendering two targets");
    ok(ctx.destroy(), "destroy context");
}
