//! Refinement geomorphs on lavapipe: four cameras over one vertex buffer, each stopped in the
//! middle of its own morphs, drawn three ways — the morphing vertex stage blending each
//! morphing corner from its slot, the compute stage writing the camera's blended vertices
//! first, and the host blending them on the CPU (`gpu::morph_slot_vertex`) — give the same
//! image, with vertex colours blended alike; the morphs are visible; once they finish, the
//! morphing draw equals the plain one; bad combinations are refused. Zero validation
//! messages throughout.

mod vulkan_support;

use caveclod_core::{CameraConfig, CameraState, Hierarchy, RefineParams};
use caveclod_tests::bake::bake;
use caveclod_tests::meshes;
use caveclod_vulkan::{
    CameraIndices, CameraMorphs, Context, IndexSource, LookAt, MorphStage, RecordCamera, Renderer,
    RendererDesc, RgbaImage, VertexBuffer, Viewport,
};
use vulkan_support::{assert_clean, context, ok, plain_camera, quadrants, save, terrain_camera};

const SIZE: u32 = 384;
const MAX_MORPHS: u32 = 4096;
const FRAMES: usize = 2;

/// Four views of the terrain from around it.
fn looks(size: f32) -> [LookAt; 4] {
    [0.3f32, 1.9, 3.4, 5.0].map(|angle| terrain_camera(size, angle, 0.55, 0.35))
}

/// A colour per vertex that changes from vertex to vertex, so blended colours show.
fn vertex_colours(n: usize) -> Vec<[u8; 4]> {
    (0..n)
        .map(|i| {
            let x = (i as u32).wrapping_mul(2_654_435_761);
            [(x >> 24) as u8, (x >> 16) as u8 | 0x40, (x >> 8) as u8, 255]
        })
        .collect()
}

/// The persistent vertex buffer with vertex colours, uploaded through the record path.
fn upload(ctx: &Context, h: &Hierarchy<'_>, colours: &[[u8; 4]]) -> VertexBuffer {
    let mut made = None;
    ok(
        ctx.submit_and_wait(|cmd| {
            made = Some(VertexBuffer::record_upload(
                ctx,
                cmd,
                "terrain",
                h.vertices(),
                Some(colours),
            ));
        }),
        "upload",
    );
    let (vertices, staging) = ok(made.expect("recorded"), "record upload");
    ok(staging.destroy(ctx), "destroy staging");
    vertices
}

/// Draws camera `c`'s first picture looking away from the model (a camera's first pass
/// never morphs), refines it to its view's front, then `c + 1` more passes of 0.1 s with the
/// view still, so its refine morphs stand part-way (a different part for each camera).
fn refine_mid_morph(h: &Hierarchy<'_>, cam: &mut CameraState<'_>, look: &LookAt, c: usize) {
    let v = quadrants(SIZE)[c];
    let view = look.view(v.width, v.height);
    let first = RefineParams {
        dt_s: 0.0,
        ..RefineParams::default()
    };
    let away = LookAt {
        target: look.eye + (look.eye - look.target),
        ..*look
    };
    ok(
        cam.refine(h, &away.view(v.width, v.height), &first),
        "first picture",
    );
    ok(cam.refine(h, &view, &first), "refine");
    let step = RefineParams {
        dt_s: 0.1,
        ..RefineParams::default()
    };
    for _ in 0..=c {
        ok(cam.refine(h, &view, &step), "refine");
    }
}

/// Draws every camera into its quadrant: with morphs of `stage`, or plainly (`None`).
fn draw(
    ctx: &Context,
    vertices: &VertexBuffer,
    h: &Hierarchy<'_>,
    cams: &[CameraState<'_>],
    looks: &[LookAt; 4],
    stage: Option<MorphStage>,
) -> RgbaImage {
    let desc = RendererDesc {
        refine_morphs: true,
        ..RendererDesc::single(SIZE, SIZE)
    };
    let mut renderer = ok(Renderer::new(ctx, desc), "renderer");
    let surfaces = h.surface_count();
    let mut indices: Vec<CameraIndices> = (0..cams.len())
        .map(|c| CameraIndices::new(&format!("camera {c}"), surfaces, FRAMES))
        .collect();
    let mut morphs: Vec<CameraMorphs> = match stage {
        Some(stage) => cams
            .iter()
            .enumerate()
            .map(|(c, cam)| {
                let name = format!("camera {c}");
                let m = CameraMorphs::new(
                    ctx,
                    renderer.recorder(),
                    &name,
                    vertices,
                    stage,
                    cam.max_morphs(),
                    FRAMES,
                );
                ok(m, "camera morphs")
            })
            .collect(),
        None => Vec::new(),
    };
    let slot = ok(renderer.begin_frame(ctx), "begin frame");
    for (c, (cam, ind)) in cams.iter().zip(indices.iter_mut()).enumerate() {
        match morphs.get_mut(c) {
            Some(m) => {
                let source = IndexSource::MorphedCamera {
                    hierarchy: h,
                    camera: cam,
                };
                ok(ind.fill(ctx, slot, source), "fill");
                ok(m.fill(slot, h.vertices(), cam), "fill morphs");
            }
            None => {
                ok(ind.fill(ctx, slot, IndexSource::camera(h, cam)), "fill");
            }
        }
    }
    let draws: Vec<(usize, RecordCamera<'_>)> = indices
        .iter()
        .zip(quadrants(SIZE))
        .zip(looks)
        .enumerate()
        .map(|(c, ((ind, viewport), look))| {
            let camera = plain_camera(viewport, look, vertices, ind);
            match morphs.get(c) {
                Some(m) => (0, camera.refine_morphs(m)),
                None => (0, camera),
            }
        })
        .collect();
    ok(renderer.render(ctx, &draws), "render");
    drop(draws);
    let image = ok(renderer.read_target(ctx, 0), "read back");
    ok(renderer.destroy(ctx), "destroy renderer");
    for i in indices {
        ok(i.destroy(ctx), "destroy indices");
    }
    for m in morphs {
        ok(m.destroy(ctx), "destroy morphs");
    }
    image
}

#[test]
fn vertex_stage_compute_stage_and_cpu_draw_four_cameras_mid_morph_alike() {
    let ctx = context();
    let baked = bake(&meshes::terrain(48, 48, 11));
    let h = baked.hierarchy();
    let colours = vertex_colours(h.vertices().len());
    let vertices = upload(&ctx, &h, &colours);
    let size = 48.0;
    let looks = looks(size);
    let config = CameraConfig::full(&h).with_morphs(MAX_MORPHS);
    let mut memory: Vec<Vec<u32>> = (0..4)
        .map(|_| vec![0u32; CameraState::words_needed_for(&h, &config)])
        .collect();
    let mut cams: Vec<CameraState<'_>> = memory
        .iter_mut()
        .map(|m| ok(CameraState::with_config(&h, m, &config), "camera"))
        .collect();
    for (c, cam) in cams.iter_mut().enumerate() {
        refine_mid_morph(&h, cam, &looks[c], c);
        let t: Vec<f32> = cam
            .morph_vertices()
            .iter()
            .filter(|m| !m.is_idle())
            .map(|m| m.t)
            .collect();
        println!(
            "camera {c}: {} active polygons, {} morphs, t in {:?}",
            cam.active_polygon_count(),
            cam.morph_count(),
            t.iter()
                .copied()
                .fold(None, |r: Option<(f32, f32)>, x| Some(
                    r.map_or((x, x), |(a, b)| (a.min(x), b.max(x)))
                ))
        );
        assert!(cam.morph_count() > 20, "camera {c} must be morphing");
        assert!(
            t.iter().all(|&t| t > 0.0 && t < 1.0),
            "camera {c}: mid-morph"
        );
    }

    let cpu = draw(&ctx, &vertices, &h, &cams, &looks, Some(MorphStage::Host));
    let vertex = draw(&ctx, &vertices, &h, &cams, &looks, Some(MorphStage::Vertex));
    let compute = draw(
        &ctx,
        &vertices,
        &h,
        &cams,
        &looks,
        Some(MorphStage::Compute),
    );
    // The same fronts without their morphs: plain emission, plain drawing.
    let unmorphed = draw(&ctx, &vertices, &h, &cams, &looks, None);
    for (image, name) in [
        (&cpu, "morphs-cpu.png"),
        (&vertex, "morphs-vertex.png"),
        (&compute, "morphs-compute.png"),
        (&unmorphed, "morphs-none.png"),
    ] {
        save(image, name);
    }
    let background = [0u8, 0, 0, 255];
    for (q, v) in quadrants(SIZE).iter().enumerate() {
        let covered = (v.y..v.y + v.height)
            .flat_map(|y| (v.x..v.x + v.width).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let i = 4 * (y * SIZE + x) as usize;
                cpu.pixels[i..i + 4] != background
            })
            .count();
        assert!(
            covered > (v.width * v.height / 5) as usize,
            "quadrant {q}: {covered}"
        );
    }
    let dv = ok(vertex.diff(&cpu), "diff");
    let dc = ok(compute.diff(&cpu), "diff");
    let du = ok(unmorphed.diff(&cpu), "diff");
    println!("vertex stage vs CPU: {dv:?}\ncompute stage vs CPU: {dc:?}\nunmorphed vs CPU: {du:?}");
    assert_eq!(
        vertex.pixels, cpu.pixels,
        "vertex stage differs from the CPU: {dv:?}"
    );
    assert_eq!(
        compute.pixels, cpu.pixels,
        "compute stage differs from the CPU: {dc:?}"
    );
    assert!(
        du.within_one_fraction() < 0.999,
        "the morphs do not show: {du:?}"
    );

    // Finished morphs: the morphing draw is the plain one.
    for cam in &mut cams {
        cam.finish_morphs();
    }
    let finished = draw(
        &ctx,
        &vertices,
        &h,
        &cams,
        &looks,
        Some(MorphStage::Compute),
    );
    let plain = draw(&ctx, &vertices, &h, &cams, &looks, None);
    let df = ok(finished.diff(&plain), "diff");
    println!("finished morphs vs plain: {df:?}");
    assert!(
        df.within_one_fraction() >= 0.9999,
        "finished morphs: {df:?}"
    );

    ok(vertices.destroy(&ctx), "destroy vertices");
    assert_clean(&ctx, "refinement geomorphs");
    ok(ctx.destroy(), "destroy context");
}

#[test]
fn morph_draws_are_refused_where_they_cannot_work() {
    let ctx = context();
    let baked = bake(&meshes::sphere(2));
    let h = baked.hierarchy();
    let vertices = ok(VertexBuffer::from_hierarchy(&ctx, "sphere", &h), "vertices");
    let other = ok(VertexBuffer::from_hierarchy(&ctx, "other", &h), "vertices");
    let plain = ok(
        Renderer::new(&ctx, RendererDesc::single(64, 64)),
        "renderer",
    );
    let err = CameraMorphs::new(
        &ctx,
        plain.recorder(),
        "m",
        &vertices,
        MorphStage::Vertex,
        8,
        2,
    )
    .err()
    .map(|e| e.to_string());
    assert!(
        err.as_deref().is_some_and(|e| e.contains("refine_morphs")),
        "{err:?}"
    );
    ok(plain.destroy(&ctx), "destroy renderer");

    let desc = RendererDesc {
        refine_morphs: true,
        ..RendererDesc::single(64, 64)
    };
    let mut renderer = ok(Renderer::new(&ctx, desc), "renderer");
    let config = CameraConfig::full(&h).with_morphs(8);
    let mut memory = vec![0u32; CameraState::words_needed_for(&h, &config)];
    let cam = ok(CameraState::with_config(&h, &mut memory, &config), "camera");
    let mut morphs = ok(
        CameraMorphs::new(
            &ctx,
            renderer.recorder(),
            "m",
            &other,
            MorphStage::Compute,
            8,
            2,
        ),
        "morphs",
    );
    let zero = CameraMorphs::new(
        &ctx,
        renderer.recorder(),
        "m",
        &other,
        MorphStage::Host,
        0,
        2,
    );
    assert!(
        zero.is_err(),
        "a camera without morph memory has nothing to morph"
    );
    let mut indices = CameraIndices::new("i", h.surface_count(), 2);
    let viewport = Viewport::full(64, 64);
    let look = terrain_camera(1.0, 0.0, 2.0, 1.0);
    let mut attempt = |source, morphs: Option<&mut CameraMorphs>| {
        let slot = ok(renderer.begin_frame(&ctx), "begin frame");
        ok(indices.fill(&ctx, slot, source), "fill");
        let camera = plain_camera(viewport, &look, &vertices, &indices);
        let camera = match morphs {
            Some(m) => {
                if let Err(e) = m.fill(slot, h.vertices(), &cam) {
                    return Some(e.to_string());
                }
                camera.refine_morphs(m)
            }
            None => camera,
        };
        renderer
            .render(&ctx, &[(0, camera)])
            .err()
            .map(|e| e.to_string())
    };
    // Plain emission with morphs, and morphs made for another vertex buffer.
    let camera = IndexSource::camera(&h, &cam);
    let e = attempt(camera, Some(&mut morphs));
    assert!(
        e.as_deref().is_some_and(|e| e.contains("MorphedCamera")),
        "{e:?}"
    );
    let morphed = IndexSource::MorphedCamera {
        hierarchy: &h,
        camera: &cam,
    };
    let e = attempt(morphed, Some(&mut morphs));
    assert!(
        e.as_deref()
            .is_some_and(|e| e.contains("another vertex buffer")),
        "{e:?}"
    );
    ok(renderer.destroy(&ctx), "destroy renderer");
    ok(indices.destroy(&ctx), "destroy indices");
    ok(morphs.destroy(&ctx), "destroy morphs");
    for v in [vertices, other] {
        ok(v.destroy(&ctx), "destroy vertices");
    }
    assert_clean(&ctx, "refused morph draws");
    ok(ctx.destroy(), "destroy context");
}
