//! Materials through the record path: base-colour textures (with mip chains) times factors,
//! alpha cutoff, and the palette when a camera has no materials.
//!
//! - A texture of one texel `T` with factor `F` draws the pixels of no texture with factor
//!   `T * F`: the texture is sampled and multiplied.
//! - A texture whose alpha is below the cutoff draws nothing.
//! - Textures get a full mip chain; wrongly sized pixels are refused.
//! - Vertex colours multiply the surface colour; blended surfaces mix with what lies behind.
//! - Lighting is two-sided: a front face is lit by its normal, a back face by the reversed
//!   normal (so a triangle facing the light is lit in front and ambient-only behind).

mod vulkan_support;

use caveclod_core::CameraState;
use caveclod_tests::meshes;
use caveclod_vulkan::{
    CameraIndices, Context, IndexSource, MaterialSet, RgbaImage, SurfaceMaterial, Texture,
    TextureDesc, VertexBuffer, Viewport,
};
use vulkan_support::*;

const SIZE: u32 = 128;

/// Renders the refined camera of a small terrain (two surfaces) with `materials` for both.
fn render_with(ctx: &Context, materials: &[SurfaceMaterial<'_>]) -> RgbaImage {
    let baked = caveclod_tests::bake(&meshes::terrain(12, 12, 9));
    let h = baked.hierarchy();
    let vertices = ok(VertexBuffer::from_hierarchy(ctx, "terrain", &h), "vertices");
    let mut memory = camera_memory(&h);
    let mut cam = ok(CameraState::new(&h, &mut memory), "camera");
    let look = terrain_camera(12.0, 0.5, 0.8, 0.7);
    let viewport = Viewport::full(SIZE, SIZE);
    refine(&h, &mut cam, &look, viewport, 1.0);
    let mut renderer = ok(
        caveclod_vulkan::Renderer::new(ctx, caveclod_vulkan::RendererDesc::single(SIZE, SIZE)),
        "renderer",
    );
    let set = ok(
        MaterialSet::new(ctx, renderer.recorder(), materials),
        "material set",
    );
    let mut indices = CameraIndices::new("camera", h.surface_count(), 2);
    let slot = ok(renderer.begin_frame(ctx), "begin frame");
    ok(
        indices.fill(ctx, slot, IndexSource::camera(&h, &cam)),
        "fill",
    );
    let camera = plain_camera(viewport, &look, &vertices, &indices).materials(&set);
    ok(renderer.render(ctx, &[(0, camera)]), "render");
    let image = ok(renderer.read_target(ctx, 0), "read back");
    ok(renderer.wait(ctx), "wait");
    set.destroy(ctx);
    ok(indices.destroy(ctx), "destroy indices");
    ok(renderer.destroy(ctx), "destroy renderer");
    ok(vertices.destroy(ctx), "destroy vertices");
    image
}

fn one_texel(ctx: &Context, rgba: [u8; 4]) -> Texture {
    let desc = TextureDesc {
        width: 1,
        height: 1,
        srgb: false,
    };
    ok(Texture::new(ctx, "texel", desc, &rgba), "texture")
}

fn plain(factor: [f32; 4]) -> SurfaceMaterial<'static> {
    SurfaceMaterial {
        texture: None,
        factor,
        alpha_cutoff: 0.0,
        blend: false,
    }
}

#[test]
fn a_texel_times_its_factor_equals_the_product_as_factor() {
    let ctx = context();
    let texel = one_texel(&ctx, [255, 128, 64, 255]);
    let factor = [0.5, 1.0, 0.75, 1.0];
    let t = [1.0, 128.0 / 255.0, 64.0 / 255.0, 1.0];
    let product = [t[0] * factor[0], t[1] * factor[1], t[2] * factor[2], 1.0];
    let textured = SurfaceMaterial {
        texture: Some(&texel),
        factor,
        alpha_cutoff: 0.0,
        blend: false,
    };
    let a = render_with(&ctx, &[textured, textured]);
    let b = render_with(&ctx, &[plain(product), plain(product)]);
    let palette = render_with(&ctx, &[plain([0.2, 0.9, 0.2, 1.0]); 2]);
    save(&a, "materials_textured.png");
    let diff = ok(a.diff(&b), "diff");
    assert!(
        diff.within_one_fraction() >= 0.999,
        "texel x factor differs from the product: {diff:?}"
    );
    assert!(a.covered(BACKGROUND) > u64::from(SIZE * SIZE) / 4);
    assert!(ok(a.diff(&palette), "diff").equal_fraction() < 0.5);
    ok(texel.destroy(&ctx), "destroy texture");
    assert_clean(&ctx, "drawing textured surfaces");
    ok(ctx.destroy(), "destroy context");
}

#[test]
fn fragments_below_the_alpha_cutoff_are_discarded() {
    let ctx = context();
    let clear = one_texel(&ctx, [255, 255, 255, 40]);
    let cut = SurfaceMaterial {
        texture: Some(&clear),
        factor: [1.0; 4],
        alpha_cutoff: 0.5,
        blend: false,
    };
    let kept = SurfaceMaterial {
        alpha_cutoff: 0.1,
        ..cut
    };
    assert_eq!(render_with(&ctx, &[cut, cut]).covered(BACKGROUND), 0);
    assert!(render_with(&ctx, &[kept, kept]).covered(BACKGROUND) > u64::from(SIZE * SIZE) / 4);
    ok(clear.destroy(&ctx), "destroy texture");
    assert_clean(&ctx, "alpha cutoff");
    ok(ctx.destroy(), "destroy context");
}

#[test]
fn textures_get_a_full_mip_chain_and_reject_wrong_sizes() {
    let ctx = context();
    let (w, h) = (64u32, 16u32);
    let pixels: Vec<u8> = (0..w * h)
        .flat_map(|i| [(i % 256) as u8, (i / 4 % 256) as u8, 200, 255])
        .collect();
    let desc = TextureDesc {
        width: w,
        height: h,
        srgb: true,
    };
    let t = ok(Texture::new(&ctx, "gradient", desc, &pixels), "texture");
    assert_eq!(t.mip_levels(), 7);
    ok(t.destroy(&ctx), "destroy texture");
    assert!(Texture::new(&ctx, "short", desc, &pixels[..100]).is_err());
    assert_clean(&ctx, "mip chains");
    ok(ctx.destroy(), "destroy context");
}

/// One triangle, counter-clockwise seen from +z, its normal +z, seen from `eye_z` on the z
/// axis, its three vertices coloured `colour` if given, drawn with `material` (else the
/// palette): the pixel at the image centre.
fn triangle_pixel(
    ctx: &Context,
    eye_z: f32,
    colour: Option<[u8; 4]>,
    material: Option<SurfaceMaterial<'_>>,
) -> [u8; 4] {
    let vertex = |x: f32, y: f32| caveclod_core::format::Vertex {
        position: [x, y, 0.0],
        normal: [0.0, 0.0, 1.0],
        uv: [0.01, 0.01],
    };
    let vertices = [vertex(-1.0, -1.0), vertex(1.0, -1.0), vertex(0.0, 1.0)];
    let mut buffer = ok(
        VertexBuffer::from_vertices(ctx, "triangle", &vertices),
        "vertices",
    );
    if let Some(c) = colour {
        let desc = caveclod_vulkan::BufferDesc::cpu_to_gpu(
            12,
            caveclod_vulkan::ash::vk::BufferUsageFlags::VERTEX_BUFFER,
        );
        let mut colours = ok(
            caveclod_vulkan::Buffer::new(ctx, "colours", desc),
            "colours",
        );
        let mapped = colours.mapped_mut().unwrap_or_else(|| panic!("not mapped"));
        for k in 0..3 {
            mapped[4 * k..4 * k + 4].copy_from_slice(&c);
        }
        buffer.colours = Some(colours);
    }
    let look = caveclod_vulkan::LookAt {
        eye: glam::Vec3::new(0.0, 0.0, eye_z),
        target: glam::Vec3::ZERO,
        up: glam::Vec3::Y,
        fov_y: 1.0,
        near: 0.1,
        far: 10.0,
    };
    let list: [&[u32]; 2] = [&[0, 1, 2], &[]];
    let mut renderer = ok(
        caveclod_vulkan::Renderer::new(ctx, caveclod_vulkan::RendererDesc::single(SIZE, SIZE)),
        "renderer",
    );
    let set = material.map(|m| ok(MaterialSet::new(ctx, renderer.recorder(), &[m, m]), "set"));
    let mut indices = CameraIndices::new("triangle", 2, 2);
    let viewport = Viewport::full(SIZE, SIZE);
    let slot = ok(renderer.begin_frame(ctx), "begin frame");
    ok(indices.fill(ctx, slot, IndexSource::Lists(&list)), "fill");
    let camera = plain_camera(viewport, &look, &buffer, &indices);
    let camera = match &set {
        Some(set) => camera.materials(set),
        None => camera,
    };
    ok(renderer.render(ctx, &[(0, camera)]), "render");
    let image = ok(renderer.read_target(ctx, 0), "read back");
    ok(renderer.destroy(ctx), "destroy renderer");
    if let Some(s) = set {
        s.destroy(ctx);
    }
    ok(indices.destroy(ctx), "destroy indices");
    ok(buffer.destroy(ctx), "destroy vertices");
    image.pixel(SIZE / 2, SIZE / 2).unwrap_or([0; 4])
}

fn triangle_seen_from(ctx: &Context, eye_z: f32) -> [u8; 4] {
    triangle_pixel(ctx, eye_z, None, None)
}

/// The byte a channel of linear value `c` lit by `k` is stored as in the RGBA8 target.
fn byte(c: f32, k: f32) -> i32 {
    (c * k * 255.0).round() as i32
}

/// The lighting factor of a face looking at the light's z component (the triangle's).
fn front_light() -> f32 {
    let light = glam::Vec3::from_array(caveclod_core::gpu::LIGHT_DIRECTION).normalize();
    0.25 + 0.75 * light.z
}

#[test]
fn vertex_colours_multiply_the_surface_colour() {
    let ctx = context();
    // sRGB (255, 188, 0) is linear (1, 0.5, 0) to within a byte.
    let c = triangle_pixel(&ctx, 3.0, Some([255, 188, 0, 255]), None);
    let linear = caveclod_core::format::materials::vertex_colour_linear([255, 188, 0, 255]);
    let lit = front_light();
    for i in 0..3 {
        let want = byte(COLOURS[0][i] * linear[i], lit);
        assert!(
            (i32::from(c[i]) - want).abs() <= 1,
            "{c:?}: channel {i} wants {want}"
        );
    }
    assert_eq!(c[2], 0, "blue is multiplied by a zero vertex colour");
    assert_clean(&ctx, "vertex colours");
    ok(ctx.destroy(), "destroy context");
}

#[test]
fn blended_surfaces_mix_with_what_lies_behind() {
    let ctx = context();
    let half = SurfaceMaterial {
        texture: None,
        factor: [1.0, 1.0, 1.0, 0.5],
        alpha_cutoff: 0.0,
        blend: true,
    };
    let blended = triangle_pixel(&ctx, 3.0, None, Some(half));
    let opaque = triangle_pixel(
        &ctx,
        3.0,
        None,
        Some(SurfaceMaterial {
            blend: false,
            ..half
        }),
    );
    let lit = front_light();
    // Over the black background: half the lit white; opaque: all of it.
    for i in 0..3 {
        assert!(
            (i32::from(blended[i]) - byte(0.5, lit)).abs() <= 1,
            "{blended:?}"
        );
        assert!(
            (i32::from(opaque[i]) - byte(1.0, lit)).abs() <= 1,
            "{opaque:?}"
        );
    }
    assert_clean(&ctx, "blending");
    ok(ctx.destroy(), "destroy context");
}

#[test]
fn front_faces_are_lit_by_their_normal_and_back_faces_by_its_reverse() {
    let ctx = context();
    let lit = front_light();
    let front = triangle_seen_from(&ctx, 3.0);
    let back = triangle_seen_from(&ctx, -3.0);
    for (i, &c) in COLOURS[0][..3].iter().enumerate() {
        // The front faces the light (lambert = l.z); the back faces away (ambient only).
        assert!(
            (i32::from(front[i]) - byte(c, lit)).abs() <= 1,
            "front {front:?}"
        );
        assert!(
            (i32::from(back[i]) - byte(c, 0.25)).abs() <= 1,
            "back {back:?}"
        );
    }
    assert_clean(&ctx, "front and back faces");
    ok(ctx.destroy(), "destroy context");
}
