//! What a host embedding caveclod uses around the recorder, as `examples/examples/embed.rs`
//! does: its device made with `DeviceFeatures::chain` (the test host's), `HostDevice::new`
//! sharing the host's allocator, cameras built with `RecordCamera::new`, materials with
//! `SurfaceMaterial::textured`, and `ImageReadback` recorded into the host's command buffer.
//!
//! - The builders draw what the struct literals draw, pixel for pixel; a one-texel texture
//!   colours every drawn pixel by its texel.
//! - A camera with neither colours nor materials, or asking for a wireframe or geomorph
//!   pipeline the recorder lacks, is refused.
//! - The read-back of the host's colour target (BGRA, swizzled to RGBA) equals the host's
//!   own copy-out of it; a format other than RGBA8 or BGRA8 is refused.
//!
//! Every step runs with the validation layer; the host's log must stay empty, and the
//! context must leave the host's allocator empty and unshared.

mod vulkan_support;

use caveclod_core::gpu::MorphInstance;
use caveclod_core::CameraState;
use caveclod_host::{Host, TargetRendering};
use caveclod_tests::meshes;
use caveclod_vulkan::ash::vk;
use caveclod_vulkan::{
    CameraIndices, Context, DeviceFeatures, Error, HostDevice, ImageReadback, IndexSource,
    MaterialSet, Morph, MorphInstances, RecordCamera, Recorder, RecorderDesc, RgbaImage,
    SurfaceMaterial, TargetFormats, Texture, TextureDesc, VertexBuffer, Viewport,
};
use vulkan_support::host_frame::HostFrame;
use vulkan_support::*;

const SIZE: u32 = 96;
/// One texel, sRGB-encoded: red well above green and blue.
const TEXEL: [u8; 4] = [230, 60, 20, 255];

/// Records `cameras` into one frame of `target` and returns its pixels, or the recorder's
/// refusal.
fn frame(
    host: &Host,
    ctx: &Context,
    target: &mut HostFrame,
    recorder: &Recorder,
    cameras: &[RecordCamera<'_>],
) -> Result<RgbaImage, Error> {
    let mut recorded = None;
    let image = target.frame(host, |cmd| {
        recorded = Some(recorder.record(ctx, cmd, 1, cameras));
    });
    match recorded {
        Some(Ok(draws)) => {
            assert!(draws > 0, "nothing drawn");
            Ok(image)
        }
        Some(Err(e)) => Err(e),
        None => panic!("nothing recorded"),
    }
}

#[test]
fn a_host_frame_through_the_embedding_conveniences() {
    let host = host();
    let handles = HostDevice::new(
        host.instance(),
        host.device(),
        host.physical_device(),
        host.queue_family(),
        host.queue(),
    )
    .allocator(host.allocator().clone());
    assert_eq!(handles.enabled, DeviceFeatures::REQUIRED);
    // SAFETY: the host's live handles and allocator, which outlive the context (destroyed
    // first); `Host::headless` enabled the required features through `DeviceFeatures::chain`.
    let ctx =
        ok(unsafe { Context::from_raw(handles) }, "embed").with_validation_log(host.log().clone());

    let baked = caveclod_tests::bake(&meshes::terrain(12, 12, 9));
    let h = baked.hierarchy();
    let mut memory = camera_memory(&h);
    let mut cam = ok(CameraState::new(&h, &mut memory), "camera");
    let look = terrain_camera(12.0, 0.5, 0.8, 0.7);
    let viewport = Viewport::full(SIZE, SIZE);
    refine(&h, &mut cam, &look, viewport, 1.0);
    let view_proj = look.view_projection(viewport.aspect());

    let formats = TargetFormats {
        colour: vk::Format::B8G8R8A8_SRGB,
        ..TargetFormats::HEADLESS
    };
    let mut target = HostFrame::new(&host, formats, TargetRendering::RenderPass, SIZE, SIZE);
    let desc = RecorderDesc::render_pass(formats, target.render_pass(), 0);
    let recorder = ok(Recorder::new(&ctx, desc), "recorder");
    let mut uploads = None;
    target.submit(&host, |cmd| {
        let (v, c) = (h.vertices(), h.vertex_colours());
        uploads = Some((
            VertexBuffer::record_upload(&ctx, cmd, "terrain", v, c),
            Texture::record_upload(&ctx, cmd, "texel", TextureDesc::srgb(1, 1), &TEXEL),
        ));
    });
    let (v, t) = uploads.unwrap_or_else(|| panic!("no upload recorded"));
    let ((vertices, vertex_staging), (tex, tex_staging)) = (ok(v, "vertices"), ok(t, "texture"));
    ok(vertex_staging.destroy(&ctx), "vertex staging");
    ok(tex_staging.destroy(&ctx), "texture staging");
    assert_eq!(
        tex.desc(),
        TextureDesc {
            width: 1,
            height: 1,
            srgb: true
        }
    );

    let n = h.surface_count();
    let textured = vec![SurfaceMaterial::textured(&tex); n];
    let spelled_out = SurfaceMaterial {
        texture: Some(&tex),
        factor: [1.0; 4],
        alpha_cutoff: 0.0,
        blend: false,
    };
    let textured = ok(MaterialSet::new(&ctx, &recorder, &textured), "materials");
    let literal = ok(
        MaterialSet::new(&ctx, &recorder, &vec![spelled_out; n]),
        "literal materials",
    );
    let mut indices = CameraIndices::new("camera", n, 2);
    ok(indices.fill(&ctx, 1, IndexSource::camera(&h, &cam)), "fill");

    // The builder with materials against the literal.
    let built = RecordCamera::new(viewport, view_proj, &vertices, &indices).materials(&textured);
    let by_builder = ok(
        frame(&host, &ctx, &mut target, &recorder, &[built]),
        "builder",
    );
    let colour = target.single_sample();
    let mut readback = None;
    target.submit(&host, |cmd| {
        let layout = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
        let extent = vk::Extent2D {
            width: SIZE,
            height: SIZE,
        };
        readback = Some(ImageReadback::record(
            &ctx,
            cmd,
            colour,
            layout,
            formats.colour,
            extent,
        ));
        let float = vk::Format::R16G16B16A16_SFLOAT;
        match ImageReadback::record(&ctx, cmd, colour, layout, float, extent) {
            Err(Error::InvalidArgument(_)) => {}
            other => panic!("read-back of a float target: {other:?}"),
        }
    });
    let readback = ok(
        readback.unwrap_or_else(|| panic!("no read-back")),
        "read-back",
    );
    let read = ok(readback.image(), "read-back image");
    let literal_camera = RecordCamera {
        viewport,
        view_proj,
        vertices: &vertices,
        indices: &indices,
        colours: &[],
        materials: Some(&literal),
        morph: None,
        refine_morphs: None,
        wireframe: false,
    };
    let by_literal = ok(
        frame(&host, &ctx, &mut target, &recorder, &[literal_camera]),
        "literal",
    );
    save(&by_builder, "embed_textured.png");
    assert_eq!(by_builder, by_literal, "builder and literal differ");
    assert_eq!(read, by_builder, "read-back and the host's copy-out differ");
    let drawn: Vec<&[u8]> = by_builder
        .pixels
        .chunks_exact(4)
        .filter(|p| p[..3] != BACKGROUND[..3])
        .collect();
    assert!(
        drawn.len() > (SIZE * SIZE / 4) as usize,
        "{} pixels drawn",
        drawn.len()
    );
    for p in &drawn {
        assert!(
            p[0] > p[1] && p[1] >= p[2],
            "pixel {p:?} is not the texel's colour"
        );
    }

    // The builder with colours against the literal with colours.
    let coloured = RecordCamera::new(viewport, view_proj, &vertices, &indices).colours(&COLOURS);
    let literal_coloured = RecordCamera {
        colours: &COLOURS,
        materials: None,
        ..literal_camera
    };
    let a = ok(
        frame(&host, &ctx, &mut target, &recorder, &[coloured]),
        "colours",
    );
    let b = ok(
        frame(&host, &ctx, &mut target, &recorder, &[literal_coloured]),
        "literal colours",
    );
    assert_eq!(a, b, "builder and literal with colours differ");
    assert_ne!(a, by_builder, "colours drew the texture");

    // What the recorder refuses: no colours and no materials, a wireframe or geomorph draw
    // without the pipeline.
    let bare = RecordCamera::new(viewport, view_proj, &vertices, &indices);
    let instances = ok(
        MorphInstances::new(
            &ctx,
            "instance",
            &[MorphInstance {
                offset_scale: [0.0, 0.0, 0.0, 1.0],
                t: 0.5,
                _pad: [0.0; 3],
            }],
        ),
        "morph instances",
    );
    let morph = Morph {
        fine: &vertices,
        instances: &instances,
    };
    for (why, refused) in [
        ("no colours", bare),
        ("wireframe", bare.colours(&COLOURS).wireframe(true)),
        ("geomorph", bare.colours(&COLOURS).morph(morph)),
    ] {
        match frame(&host, &ctx, &mut target, &recorder, &[refused]) {
            Err(Error::InvalidArgument(_)) => {}
            other => panic!("{why}: {other:?}"),
        }
    }
    assert!(!bare.wireframe(true).wireframe(false).wireframe);

    for r in [
        readback.destroy(&ctx),
        instances.destroy(&ctx),
        indices.destroy(&ctx),
        vertices.destroy(&ctx),
    ] {
        ok(r, "destroy");
    }
    textured.destroy(&ctx);
    literal.destroy(&ctx);
    ok(tex.destroy(&ctx), "destroy texture");
    ok(recorder.destroy(&ctx), "destroy recorder");
    target.destroy(&host);
    ok(ctx.destroy(), "context");
    destroy_host(host);
}
