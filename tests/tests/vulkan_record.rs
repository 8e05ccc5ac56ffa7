//! The record path inside a host's frame: the host owns instance, device, allocator,
//! targets, render pass, command buffers and submission; caveclod uploads (recorded into
//! the host's command buffer) and records draws.
//!
//! - Into the host's `VkRenderPass` with a `B8G8R8A8_SRGB` colour target, a depth-stencil
//!   target and 4x MSAA resolve: the image matches the headless renderer's (sRGB-encoded)
//!   on all but silhouette pixels.
//! - Into the host's dynamic rendering with `R8G8B8A8_UNORM` + `D32_SFLOAT`: the same
//!   pixels as the headless renderer.
//! - Once a camera's index ring is sized, frames create no Vulkan resource.
//! - Formats and sample counts the device cannot render are a typed error.
//!
//! Every step runs with the validation layer; the host's log must stay empty.

mod vulkan_support;

use caveclod_core::{CameraState, Hierarchy};
use caveclod_host::{Host, TargetRendering};
use caveclod_tests::meshes;
use caveclod_vulkan::ash::vk;
use caveclod_vulkan::{
    CameraIndices, Context, Error, IndexSource, LookAt, RecordCamera, Recorder, RecorderDesc,
    RgbaImage, TargetFormats, VertexBuffer, Viewport,
};
use vulkan_support::host_frame::HostFrame;
use vulkan_support::*;

const SIZE: u32 = 160;

/// The sRGB encoding of a linear value in 0..=1, as a byte.
fn srgb_byte(linear: f32) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// `image` (linear UNORM bytes) as an sRGB target would store it.
fn to_srgb(image: &RgbaImage) -> RgbaImage {
    let mut out = image.clone();
    for p in out.pixels.chunks_exact_mut(4) {
        for c in &mut p[..3] {
            *c = srgb_byte(f32::from(*c) / 255.0);
        }
    }
    out
}

/// A refined camera over a baked terrain, its view, and the headless renderer's image of
/// it (the reference).
struct Scene {
    look: LookAt,
    viewport: Viewport,
}

impl Scene {
    fn new() -> Self {
        let viewport = Viewport::full(SIZE, SIZE);
        Self {
            look: terrain_camera(16.0, 0.7, 0.8, 0.6),
            viewport,
        }
    }

    fn camera<'m>(&self, h: &Hierarchy<'_>, memory: &'m mut [u32]) -> CameraState<'m> {
        let mut cam = ok(CameraState::new(h, memory), "camera");
        refine(h, &mut cam, &self.look, self.viewport, 1.0);
        cam
    }

    fn draw<'a>(&self, vertices: &'a VertexBuffer, indices: &'a CameraIndices) -> RecordCamera<'a> {
        RecordCamera {
            viewport: self.viewport,
            view_proj: self.look.view_projection(self.viewport.aspect()),
            vertices,
            indices,
            colours: &COLOURS,
            materials: None,
            refine_morphs: None,
            morph: None,
            wireframe: false,
        }
    }
}

/// Renders `cam` into a host target of `formats` begun the host's way (`rendering`),
/// uploading the vertices through the host's command buffer.
fn host_frame(
    host: &Host,
    ctx: &Context,
    h: &Hierarchy<'_>,
    cam: &CameraState<'_>,
    scene: &Scene,
    formats: TargetFormats,
    rendering: TargetRendering,
) -> RgbaImage {
    let mut target = HostFrame::new(host, formats, rendering, SIZE, SIZE);
    let desc = match rendering {
        TargetRendering::RenderPass => RecorderDesc::render_pass(formats, target.render_pass(), 0),
        TargetRendering::Dynamic => RecorderDesc::dynamic(formats),
    };
    let recorder = ok(Recorder::new(ctx, desc), "recorder");
    let mut upload = None;
    target.submit(host, |cmd| {
        upload = Some(VertexBuffer::record_upload(
            ctx,
            cmd,
            "terrain",
            h.vertices(),
            h.vertex_colours(),
        ));
    });
    let (vertices, staging) = ok(
        upload.unwrap_or_else(|| panic!("no upload recorded")),
        "record upload",
    );
    ok(staging.destroy(ctx), "destroy staging");
    let mut indices = CameraIndices::new("host camera", h.surface_count(), 2);
    ok(indices.fill(ctx, 1, IndexSource::camera(h, cam)), "fill");
    let mut draws = 0;
    let image = target.frame(host, |cmd| {
        draws = ok(
            recorder.record(ctx, cmd, 1, &[scene.draw(&vertices, &indices)]),
            "record",
        );
    });
    assert!(draws > 0, "nothing drawn");
    ok(indices.destroy(ctx), "destroy indices");
    ok(vertices.destroy(ctx), "destroy vertices");
    ok(recorder.destroy(ctx), "destroy recorder");
    target.destroy(host);
    image
}

/// The headless renderer's image of `cam` (RGBA8 UNORM, D32, one sample).
fn reference(ctx: &Context, h: &Hierarchy<'_>, cam: &CameraState<'_>, scene: &Scene) -> RgbaImage {
    let vertices = ok(VertexBuffer::from_hierarchy(ctx, "terrain", h), "vertices");
    let image = render_alone(
        ctx,
        &vertices,
        h.surface_count(),
        &scene.look,
        (SIZE, SIZE),
        IndexSource::camera(h, cam),
    );
    ok(vertices.destroy(ctx), "destroy vertices");
    image
}

#[test]
fn host_render_pass_bgra_srgb_msaa_matches_the_renderer() {
    let host = host();
    let ctx = ok(host.context(), "context");
    let baked = caveclod_tests::bake(&meshes::terrain(16, 16, 3));
    let h = baked.hierarchy();
    let scene = Scene::new();
    let mut memory = camera_memory(&h);
    let cam = scene.camera(&h, &mut memory);
    let want = to_srgb(&reference(&ctx, &h, &cam, &scene));
    let formats = TargetFormats {
        colour: vk::Format::B8G8R8A8_SRGB,
        depth: ok(
            host.depth_format(&[
                vk::Format::D24_UNORM_S8_UINT,
                vk::Format::D32_SFLOAT_S8_UINT,
            ]),
            "depth format",
        ),
        samples: vk::SampleCountFlags::TYPE_4,
    };
    let got = host_frame(
        &host,
        &ctx,
        &h,
        &cam,
        &scene,
        formats,
        TargetRendering::RenderPass,
    );
    save(&want, "record_reference_srgb.png");
    save(&got, "record_render_pass_msaa.png");

    // Multisampling changes only pixels that triangle edges cross: silhouettes against the
    // background, and (slightly) edges between differently lit triangles.
    let pixels = (SIZE * SIZE) as usize;
    let mut close = 0;
    for (a, b) in want.pixels.chunks_exact(4).zip(got.pixels.chunks_exact(4)) {
        if a.iter().zip(b).all(|(x, y)| x.abs_diff(*y) <= 3) {
            close += 1;
        }
    }
    let covered_want = want.covered(BACKGROUND) as f64;
    let covered_got = got.covered(BACKGROUND) as f64;
    assert!(
        covered_want > pixels as f64 / 4.0,
        "the terrain is not in view"
    );
    assert!(
        (covered_got - covered_want).abs() <= 0.02 * covered_want,
        "covered pixels: {covered_got} through the host's render pass, {covered_want} alone"
    );
    assert!(
        close as f64 >= 0.97 * pixels as f64,
        "{close} of {pixels} pixels within 3/255 of the sRGB-encoded reference"
    );
    assert_clean(&ctx, "recording into the host's render pass");
    ok(ctx.destroy(), "destroy context");
    destroy_host(host);
}

#[test]
fn host_dynamic_rendering_rgba8_equals_the_renderer() {
    let host = host();
    let ctx = ok(host.context(), "context");
    let baked = caveclod_tests::bake(&meshes::terrain(16, 16, 4));
    let h = baked.hierarchy();
    let scene = Scene::new();
    let mut memory = camera_memory(&h);
    let cam = scene.camera(&h, &mut memory);
    let want = reference(&ctx, &h, &cam, &scene);
    let got = host_frame(
        &host,
        &ctx,
        &h,
        &cam,
        &scene,
        TargetFormats::HEADLESS,
        TargetRendering::Dynamic,
    );
    let diff = ok(got.diff(&want), "diff");
    assert_eq!(diff.equal, diff.pixels, "the record path differs: {diff:?}");
    assert!(want.covered(BACKGROUND) > u64::from(SIZE * SIZE) / 4);
    assert_clean(&ctx, "recording into the host's dynamic rendering");
    ok(ctx.destroy(), "destroy context");
    destroy_host(host);
}

#[test]
fn frames_create_no_resource_once_the_ring_is_sized() {
    let host = host();
    let ctx = ok(host.context(), "context");
    let baked = caveclod_tests::bake(&meshes::terrain(20, 20, 5));
    let h = baked.hierarchy();
    let scene = Scene::new();
    let formats = TargetFormats::HEADLESS;
    let mut target = HostFrame::new(&host, formats, TargetRendering::Dynamic, SIZE, SIZE);
    let recorder = ok(
        Recorder::new(&ctx, RecorderDesc::dynamic(formats)),
        "recorder",
    );
    let vertices = ok(
        VertexBuffer::from_hierarchy(&ctx, "terrain", &h),
        "vertices",
    );
    let mut indices = CameraIndices::new("moving camera", h.surface_count(), 3);
    let mut memory = camera_memory(&h);
    let mut cam = ok(CameraState::new(&h, &mut memory), "camera");
    // Full detail first, so every slot's buffers reach their largest size.
    let mut run = |frame: u64, cam: &CameraState<'_>, indices: &mut CameraIndices| {
        let slot = (frame % 3) as usize;
        let source = IndexSource::camera(&h, cam);
        ok(indices.fill(&ctx, slot, source), "fill");
        target.frame(&host, |cmd| {
            ok(
                recorder.record(&ctx, cmd, slot, &[scene.draw(&vertices, indices)]),
                "record",
            );
        });
    };
    // Nodes are numbered parents first, so forcing every split in order splits them all.
    for v in (0..h.splits().len() as u32).map(caveclod_core::NodeId) {
        if !cam.is_split(v) {
            ok(cam.force_split_own_stack(&h, v), "split everything");
        }
    }
    for frame in 0..3 {
        run(frame, &cam, &mut indices);
    }
    let sized = ctx.resources_created();
    for frame in 3..40u64 {
        let mut look = scene.look;
        look.eye.x += frame as f32 * 0.2;
        refine(
            &h,
            &mut cam,
            &look,
            scene.viewport,
            0.5 + (frame % 4) as f32,
        );
        run(frame, &cam, &mut indices);
    }
    assert_eq!(
        ctx.resources_created(),
        sized,
        "frames after the ring was sized created Vulkan resources"
    );
    assert!(indices.grow_count() > 0);
    ok(indices.destroy(&ctx), "destroy indices");
    ok(vertices.destroy(&ctx), "destroy vertices");
    ok(recorder.destroy(&ctx), "destroy recorder");
    target.destroy(&host);
    assert_clean(&ctx, "the frame loop");
    ok(ctx.destroy(), "destroy context");
    destroy_host(host);
}

#[test]
fn unsupported_targets_are_typed_errors() {
    let ctx = context();
    let bad_samples = TargetFormats {
        samples: vk::SampleCountFlags::TYPE_64,
        ..TargetFormats::HEADLESS
    };
    let bad_depth = TargetFormats {
        depth: vk::Format::R8G8B8A8_UNORM,
        ..TargetFormats::HEADLESS
    };
    for (formats, wanted) in [(bad_samples, "TYPE_64"), (bad_depth, "depth attachment")] {
        match Recorder::new(&ctx, RecorderDesc::dynamic(formats)) {
            Err(Error::Unsupported { missing, .. }) => assert!(
                missing.iter().any(|m| m.contains(wanted)),
                "{missing:?} does not name {wanted}"
            ),
            Err(e) => panic!("expected Unsupported for {formats:?}, got {e}"),
            Ok(r) => {
                ok(r.destroy(&ctx), "destroy recorder");
                panic!("{formats:?} was accepted")
            }
        }
    }
    assert_clean(&ctx, "refusing targets");
    ok(ctx.destroy(), "destroy context");
}
