//! GPU faults on lavapipe, injected through the context's fault seams ([`Faults`]), each
//! case ending with zero validation messages, nothing left alive and the allocator empty:
//! - device memory exhausted at every allocation of a first frame (vertex upload, texture,
//!   renderer, index buffers, read-back; and a second time with the camera's refinement
//!   geomorphs blended by the compute stage) gives [`Error::OutOfMemory`]; once memory is
//!   back the same objects draw the frame, equal to the reference image; and the same in a
//!   host engine's frame, through the record path with the host's shared allocator;
//! - the device lost at every checkpoint of the first three frames (uploads, submissions,
//!   the wait for a reused frame slot, the read-back's wait) gives
//!   [`Error::DeviceLost`], stays lost, and every object and the context are still
//!   destroyed cleanly.
//!
//! [`Faults`]: caveclod_vulkan::Faults

mod vulkan_support;

use caveclod_core::{CameraConfig, CameraState, Hierarchy, LookAt, RefineParams};
use caveclod_host::{Host, TargetRendering};
use caveclod_tests::meshes;
use caveclod_vulkan::ash::vk;
use caveclod_vulkan::{
    CameraIndices, CameraMorphs, Context, Error, IndexSource, MaterialSet, MorphStage,
    RecordCamera, Recorder, RecorderDesc, Renderer, RendererDesc, RgbaImage, SurfaceMaterial,
    TargetFormats, Texture, TextureDesc, VertexBuffer, Viewport,
};
use vulkan_support::host_frame::HostFrame;
use vulkan_support::*;

const SIZE: u32 = 96;
const TEXTURE: u32 = 16;
/// Frames of the device-lost test: the third reuses the first's slot, so it waits for
/// the first's fence.
const FRAMES: usize = 3;

/// What a first frame makes, kept across a failed attempt so the next attempt (memory
/// back) reuses what was made before the fault, as an application retrying would.
#[derive(Default)]
struct Parts {
    vertices: Option<VertexBuffer>,
    texture: Option<Texture>,
    renderer: Option<Renderer>,
    materials: Option<MaterialSet>,
    indices: Option<CameraIndices>,
    morphs: Option<CameraMorphs>,
}

impl Parts {
    /// Destroys whatever was made, renderer first (it waits for the frames).
    fn destroy(self, ctx: &Context) {
        if let Some(r) = self.renderer {
            ok(r.destroy(ctx), "destroy renderer");
        }
        if let Some(m) = self.materials {
            m.destroy(ctx);
        }
        if let Some(i) = self.indices {
            ok(i.destroy(ctx), "destroy indices");
        }
        if let Some(m) = self.morphs {
            ok(m.destroy(ctx), "destroy morphs");
        }
        if let Some(t) = self.texture {
            ok(t.destroy(ctx), "destroy texture");
        }
        if let Some(v) = self.vertices {
            ok(v.destroy(ctx), "destroy vertices");
        }
    }
}

/// A checkerboard, so the texture's upload and mips show in the image.
fn checkerboard() -> Vec<u8> {
    (0..TEXTURE * TEXTURE)
        .flat_map(|i| {
            let (x, y) = (i % TEXTURE, i / TEXTURE);
            if (x / 4 + y / 4) % 2 == 0 {
                [230, 200, 60, 255]
            } else {
                [40, 90, 200, 255]
            }
        })
        .collect()
}

/// The frame's inputs: a refined camera over a small terrain, drawn with its refinement
/// geomorphs blended by `morphs` or without them.
struct Scene<'h> {
    h: &'h Hierarchy<'h>,
    cam: CameraState<'h>,
    look: LookAt,
    morphs: Option<MorphStage>,
}

/// Makes what is still missing in `parts`, draws `count` frames and reads the last back.
fn frames(
    ctx: &Context,
    scene: &Scene<'_>,
    parts: &mut Parts,
    count: usize,
) -> Result<RgbaImage, Error> {
    let h = scene.h;
    if parts.vertices.is_none() {
        parts.vertices = Some(VertexBuffer::from_hierarchy(ctx, "terrain", h)?);
    }
    if parts.texture.is_none() {
        let desc = TextureDesc::srgb(TEXTURE, TEXTURE);
        parts.texture = Some(Texture::new(ctx, "checkerboard", desc, &checkerboard())?);
    }
    if parts.renderer.is_none() {
        let desc = RendererDesc {
            refine_morphs: scene.morphs.is_some(),
            ..RendererDesc::single(SIZE, SIZE)
        };
        parts.renderer = Some(Renderer::new(ctx, desc)?);
    }
    let (Some(vertices), Some(texture), Some(renderer)) =
        (&parts.vertices, &parts.texture, &mut parts.renderer)
    else {
        return Err(Error::InvalidArgument("parts missing".into()));
    };
    if parts.materials.is_none() {
        let surfaces = [
            SurfaceMaterial::textured(texture),
            SurfaceMaterial::textured(texture),
        ];
        parts.materials = Some(MaterialSet::new(ctx, renderer.recorder(), &surfaces)?);
    }
    if let (Some(stage), None) = (scene.morphs, &parts.morphs) {
        let max = scene.cam.max_morphs();
        let recorder = renderer.recorder();
        let morphs = CameraMorphs::new(ctx, recorder, "camera", vertices, stage, max, 2)?;
        parts.morphs = Some(morphs);
    }
    let indices = parts
        .indices
        .get_or_insert_with(|| CameraIndices::new("camera", h.surface_count(), 2));
    let viewport = Viewport::full(SIZE, SIZE);
    for _ in 0..count {
        let source = match parts.morphs {
            Some(_) => IndexSource::MorphedCamera {
                hierarchy: h,
                camera: &scene.cam,
            },
            None => IndexSource::camera(h, &scene.cam),
        };
        let slot = renderer.begin_frame(ctx)?;
        indices.fill(ctx, slot, source)?;
        if let Some(m) = parts.morphs.as_mut() {
            m.fill(slot, h.vertices(), &scene.cam)?;
        }
        let mut camera = plain_camera(viewport, &scene.look, vertices, indices);
        if let Some(set) = &parts.materials {
            camera = camera.materials(set);
        }
        if let Some(m) = &parts.morphs {
            camera = camera.refine_morphs(m);
        }
        renderer.render(ctx, &[(0, camera)])?;
    }
    renderer.read_target(ctx, 0)
}

/// Fails unless nothing made through `ctx` is alive and its allocator holds nothing.
fn assert_nothing_left(ctx: &Context, when: &str) {
    let live = ctx.live_resources();
    assert!(live.is_empty(), "{when}: still alive: {live:?}");
    let report = ok(ctx.allocator_report(), "allocator report");
    assert!(
        report.allocations.is_empty() && report.total_allocated_bytes == 0,
        "{when}: the allocator still holds {} allocation(s), {} bytes",
        report.allocations.len(),
        report.total_allocated_bytes
    );
}

/// The reference image of `count` frames drawn without faults, with the allocations and
/// checkpoints they counted.
fn reference(ctx: &Context, scene: &Scene<'_>, count: usize) -> (RgbaImage, u64, u64) {
    let (a0, c0) = (ctx.faults().allocations(), ctx.faults().checkpoints());
    let mut parts = Parts::default();
    let image = ok(
        frames(ctx, scene, &mut parts, count),
        "the reference frames",
    );
    let counts = (
        ctx.faults().allocations() - a0,
        ctx.faults().checkpoints() - c0,
    );
    parts.destroy(ctx);
    assert!(image.covered(BACKGROUND) > u64::from(SIZE * SIZE) / 8);
    save(&image, "faults_reference.png");
    (image, counts.0, counts.1)
}

/// Runs `f` on the scene, with geomorphs blended by `morphs` (the camera caught mid-morph)
/// or without them.
fn with_scene(morphs: Option<MorphStage>, f: impl FnOnce(&Scene<'_>)) {
    let baked = caveclod_tests::bake(&meshes::terrain(10, 10, 5));
    let h = baked.hierarchy();
    let config = match morphs {
        Some(_) => CameraConfig::full(&h).with_morphs(64),
        None => CameraConfig::full(&h),
    };
    let mut memory = vec![0u32; CameraState::words_needed_for(&h, &config)];
    let mut cam = ok(CameraState::with_config(&h, &mut memory, &config), "camera");
    let look = terrain_camera(10.0, 0.6, 0.8, 0.6);
    let viewport = Viewport::full(SIZE, SIZE);
    refine(&h, &mut cam, &look, viewport, 1.0);
    if morphs.is_some() {
        // Closer, a tenth of a second later: new splits are mid-morph.
        let closer = terrain_camera(10.0, 0.6, 0.5, 0.4);
        let params = RefineParams {
            dt_s: 0.1,
            ..RefineParams::default()
        };
        let view = closer.view(viewport.width, viewport.height);
        ok(cam.refine(&h, &view, &params), "refine mid-morph");
        let moving = cam.morph_vertices().iter().filter(|m| !m.is_idle()).count();
        println!("{moving} vertices mid-morph");
    }
    f(&Scene {
        h: &h,
        cam,
        look,
        morphs,
    });
}

#[test]
fn memory_exhausted_at_every_allocation_of_the_first_frame() {
    exhaust_at_every_allocation(None);
}

#[test]
fn memory_exhausted_at_every_allocation_of_a_first_frame_with_compute_geomorphs() {
    exhaust_at_every_allocation(Some(MorphStage::Compute));
}

/// Exhausts device memory at each allocation of the scene's first frame in turn.
fn exhaust_at_every_allocation(morphs: Option<MorphStage>) {
    with_scene(morphs, |scene| {
        let ctx = context();
        let log = ctx.validation_log();
        let (expected, allocations, _) = reference(&ctx, scene, 1);
        assert!(allocations >= 8, "{allocations} allocations");
        println!("the first frame makes {allocations} device allocations");
        for n in 0..allocations {
            ctx.faults().exhaust_memory_after(n);
            let mut parts = Parts::default();
            let failed = frames(&ctx, scene, &mut parts, 1);
            assert!(
                matches!(failed, Err(Error::OutOfMemory { device: true, .. })),
                "allocation {n}: {:?}",
                failed.map(|_| "a frame")
            );
            ctx.faults().restore_memory();
            let image = ok(frames(&ctx, scene, &mut parts, 1), "the frame after");
            assert!(
                image.pixels == expected.pixels,
                "allocation {n}: the frame after differs: {:?}",
                image.diff(&expected)
            );
            parts.destroy(&ctx);
            assert_nothing_left(&ctx, &format!("allocation {n}"));
            assert_clean(&ctx, &format!("with allocation {n} failing"));
        }
        // Memory that runs out just after the frame leaves it alone: the count is exact.
        ctx.faults().exhaust_memory_after(allocations);
        let mut parts = Parts::default();
        let image = ok(frames(&ctx, scene, &mut parts, 1), "a frame within memory");
        assert!(image.pixels == expected.pixels);
        ctx.faults().restore_memory();
        parts.destroy(&ctx);
        assert_nothing_left(&ctx, "the frame within memory");
        assert_clean(&ctx, "the frame within memory");
        ok(ctx.destroy(), "destroy context");
        let messages = log.take();
        assert!(messages.is_empty(), "destroying the context: {messages:?}");
    });
}

#[test]
fn device_lost_at_every_checkpoint_of_the_first_frames() {
    with_scene(Some(MorphStage::Compute), |scene| {
        let checkpoints = {
            let ctx = context();
            let (_, _, checkpoints) = reference(&ctx, scene, FRAMES);
            assert_clean(&ctx, "the reference frame");
            ok(ctx.destroy(), "destroy context");
            checkpoints
        };
        assert!(checkpoints >= 4, "{checkpoints} checkpoints");
        println!("the first {FRAMES} frames pass {checkpoints} device checkpoints");
        for n in 0..checkpoints {
            let ctx = context();
            let log = ctx.validation_log();
            ctx.faults().lose_device_after(n);
            let mut parts = Parts::default();
            let lost = frames(&ctx, scene, &mut parts, FRAMES);
            assert!(
                matches!(lost, Err(Error::DeviceLost { .. })),
                "checkpoint {n}: {:?}",
                lost.map(|_| "a frame")
            );
            assert!(ctx.faults().device_lost());
            // A lost device stays lost.
            assert!(matches!(ctx.wait_idle(), Err(Error::DeviceLost { .. })));
            let again = frames(&ctx, scene, &mut parts, FRAMES);
            assert!(
                matches!(again, Err(Error::DeviceLost { .. })),
                "checkpoint {n}, again: {:?}",
                again.map(|_| "a frame")
            );
            parts.destroy(&ctx);
            assert_nothing_left(&ctx, &format!("checkpoint {n}"));
            ok(ctx.destroy(), "destroy context after a lost device");
            let messages = log.take();
            assert!(
                messages.is_empty(),
                "checkpoint {n}: {} validation message(s):\n{}",
                messages.len(),
                messages.join("\n")
            );
        }
    });
}

/// What an embedded first frame makes; the host owns the rest.
#[derive(Default)]
struct Embedded {
    recorder: Option<Recorder>,
    vertices: Option<VertexBuffer>,
    indices: Option<CameraIndices>,
}

impl Embedded {
    fn destroy(self, ctx: &Context) {
        if let Some(i) = self.indices {
            ok(i.destroy(ctx), "destroy indices");
        }
        if let Some(v) = self.vertices {
            ok(v.destroy(ctx), "destroy vertices");
        }
        if let Some(r) = self.recorder {
            ok(r.destroy(ctx), "destroy recorder");
        }
    }
}

/// A host's first frame with caveclod embedded: what is missing in `parts` is made (the
/// vertex upload recorded into the host's command buffer), the camera's indices filled and
/// its draws recorded into the host's rendering.
fn embedded_frame(
    host: &Host,
    ctx: &Context,
    target: &mut HostFrame,
    scene: &Scene<'_>,
    parts: &mut Embedded,
) -> Result<RgbaImage, Error> {
    let h = scene.h;
    if parts.recorder.is_none() {
        let desc = RecorderDesc::render_pass(target.formats(), target.render_pass(), 0);
        parts.recorder = Some(Recorder::new(ctx, desc)?);
    }
    if parts.vertices.is_none() {
        let mut uploaded = None;
        target.submit(host, |cmd| {
            let (v, c) = (h.vertices(), h.vertex_colours());
            uploaded = Some(VertexBuffer::record_upload(ctx, cmd, "terrain", v, c));
        });
        let missing = || Err(Error::InvalidArgument("no upload recorded".into()));
        let (vertices, staging) = uploaded.unwrap_or_else(missing)?;
        parts.vertices = Some(vertices);
        staging.destroy(ctx)?;
    }
    let (Some(recorder), Some(vertices)) = (&parts.recorder, &parts.vertices) else {
        return Err(Error::InvalidArgument("parts missing".into()));
    };
    let indices = parts
        .indices
        .get_or_insert_with(|| CameraIndices::new("camera", h.surface_count(), 2));
    indices.fill(ctx, 1, IndexSource::camera(h, &scene.cam))?;
    let viewport = Viewport::full(SIZE, SIZE);
    let view_proj = scene.look.view_projection(viewport.aspect());
    let camera = RecordCamera::new(viewport, view_proj, vertices, indices).colours(&COLOURS);
    let mut recorded = None;
    let image = target.frame(host, |cmd| {
        recorded = Some(recorder.record(ctx, cmd, 1, &[camera]));
    });
    let missing = || Err(Error::InvalidArgument("nothing recorded".into()));
    recorded.unwrap_or_else(missing)?;
    Ok(image)
}

#[test]
fn memory_exhausted_at_every_allocation_of_an_embedded_first_frame() {
    with_scene(None, |scene| {
        let host = host();
        let ctx = ok(host.context(), "context");
        let formats = TargetFormats {
            colour: vk::Format::B8G8R8A8_SRGB,
            ..TargetFormats::HEADLESS
        };
        let mut target = HostFrame::new(&host, formats, TargetRendering::RenderPass, SIZE, SIZE);
        // The host's own allocations (its target) share the allocator and stay.
        let host_allocations = ok(ctx.allocator_report(), "report").allocations.len();
        let before = ctx.faults().allocations();
        let mut parts = Embedded::default();
        let frame = embedded_frame(&host, &ctx, &mut target, scene, &mut parts);
        let expected = ok(frame, "the reference frame");
        let allocations = ctx.faults().allocations() - before;
        parts.destroy(&ctx);
        assert!(expected.covered(BACKGROUND) > u64::from(SIZE * SIZE) / 8);
        assert!(allocations >= 3, "{allocations} allocations");
        println!("the embedded first frame makes {allocations} device allocations");
        for n in 0..allocations {
            ctx.faults().exhaust_memory_after(n);
            let mut parts = Embedded::default();
            let failed = embedded_frame(&host, &ctx, &mut target, scene, &mut parts);
            assert!(
                matches!(failed, Err(Error::OutOfMemory { device: true, .. })),
                "allocation {n}: {:?}",
                failed.map(|_| "a frame")
            );
            ctx.faults().restore_memory();
            let frame = embedded_frame(&host, &ctx, &mut target, scene, &mut parts);
            let image = ok(frame, "the frame after");
            assert!(
                image.pixels == expected.pixels,
                "allocation {n}: the frame after differs: {:?}",
                image.diff(&expected)
            );
            parts.destroy(&ctx);
            let live = ctx.live_resources();
            assert!(live.is_empty(), "allocation {n}: still alive: {live:?}");
            let left = ok(ctx.allocator_report(), "report").allocations.len();
            assert_eq!(left, host_allocations, "allocation {n}: allocations left");
            assert_clean(&ctx, &format!("embedded, with allocation {n} failing"));
        }
        ok(ctx.destroy(), "destroy context");
        target.destroy(&host);
        // Checks that the allocator is empty and no validation message came.
        destroy_host(host);
    });
}
