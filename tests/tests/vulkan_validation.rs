//! The validation check itself, and embedding in a host's instance and device.
//!
//! - An invalid call in a sacrificial context is caught, so "no validation messages" in the
//!   other tests is a check that can fail.
//! - A host engine creates instance, debug messenger, device and allocator itself, hands
//!   them to [`Context::from_raw`], renders, and tears everything down in order (ours
//!   first, then allocator, device, messenger, instance) without validation messages; a
//!   host device without a required feature is refused, naming it.

mod vulkan_support;

use caveclod_tests::meshes;
use caveclod_vulkan::ash::vk;
use caveclod_vulkan::{
    Buffer, BufferDesc, CameraIndices, Context, DeviceFeatures, Error, IndexSource, VertexBuffer,
};
use vulkan_support::*;

#[test]
fn an_invalid_call_is_reported() {
    let ctx = context();
    assert_clean(&ctx, "after creating the context");
    let d = &ctx.device;
    let pool_info = vk::CommandPoolCreateInfo::default().queue_family_index(ctx.queue_family);
    // SAFETY: valid create info.
    let pool = ok(unsafe { d.create_command_pool(&pool_info, None) }, "pool");
    let alloc = vk::CommandBufferAllocateInfo::default()
        .command_pool(pool)
        .level(vk::CommandBufferLevel::PRIMARY)
        .command_buffer_count(1);
    // SAFETY: the pool is alive.
    let cmd = ok(
        unsafe { d.allocate_command_buffers(&alloc) },
        "command buffer",
    )[0];
    // SAFETY: deliberately invalid: a draw with no pipeline bound, outside any rendering.
    // The validation layer reports it and does not pass the call down to the driver.
    unsafe {
        ok(
            d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()),
            "begin",
        );
        d.cmd_draw(cmd, 3, 1, 0, 0);
        let _ = d.end_command_buffer(cmd);
        d.destroy_command_pool(pool, None);
    }
    let messages = ctx.take_validation_messages();
    assert!(
        messages
            .iter()
            .any(|m| m.contains("vkCmdDraw") && m.contains("ERROR")),
        "the invalid draw was not reported; messages: {messages:?}"
    );
    ok(ctx.destroy(), "destroy");
}

#[test]
fn a_leaked_buffer_is_reported_by_destroy() {
    let ctx = context();
    let log = ctx.validation_log();
    let b = ok(
        Buffer::new(
            &ctx,
            "forgotten",
            BufferDesc::cpu_to_gpu(256, vk::BufferUsageFlags::INDEX_BUFFER),
        ),
        "buffer",
    );
    assert_eq!(ctx.live_resources(), vec!["forgotten".to_string()]);
    std::mem::forget(b);
    match ctx.destroy() {
        Err(Error::Leaked(names)) => assert_eq!(names, vec!["forgotten".to_string()]),
        other => panic!("expected a leak report, got {other:?}"),
    }
    // The layer sees the buffer outliving its device too.
    assert!(!log.take().is_empty());
}

#[test]
fn embedded_in_a_host_engine() {
    let host = host();
    let ctx = ok(host.context(), "context");

    let mesh = meshes::terrain(12, 12, 5);
    let baked = caveclod_tests::bake(&mesh);
    let h = baked.hierarchy();
    let vertices = ok(
        VertexBuffer::from_hierarchy(&ctx, "terrain", &h),
        "vertices",
    );
    let mut memory = camera_memory(&h);
    let mut cam = ok(caveclod_core::CameraState::new(&h, &mut memory), "camera");
    let look = terrain_camera(12.0, 0.6, 0.9, 0.7);
    let viewport = caveclod_vulkan::Viewport::full(128, 128);
    refine(&h, &mut cam, &look, viewport, 1.0);
    let image = render_alone(
        &ctx,
        &vertices,
        h.surface_count(),
        &look,
        (128, 128),
        IndexSource::camera(&h, &cam),
    );
    assert!(
        image.covered(BACKGROUND) > 128 * 128 / 10,
        "the terrain is not in the image"
    );
    ok(vertices.destroy(&ctx), "destroy vertices");
    let unused = CameraIndices::new("never filled", 2, 2);
    ok(unused.destroy(&ctx), "destroy empty indices");
    assert_clean(&ctx, "while embedded");
    ok(ctx.destroy(), "destroy the embedded context");
    // The host tears down what it owns, in order, checking that its allocator is empty
    // and that the validation layer said nothing.
    destroy_host(host);
}

#[test]
fn a_host_device_without_a_required_feature_is_refused_by_name() {
    let host = host();
    let claimed = DeviceFeatures {
        dynamic_rendering: false,
        ..DeviceFeatures::REQUIRED
    };
    // SAFETY: the host's live handles; it enabled more than it claims.
    match unsafe { Context::from_raw(host.handles(claimed)) } {
        Err(Error::Unsupported { missing, .. }) => {
            assert_eq!(missing, vec!["dynamicRendering (not enabled)".to_string()]);
        }
        Err(e) => panic!("expected Unsupported, got {e}"),
        Ok(_) => panic!("a device without dynamicRendering was accepted"),
    }
    destroy_host(host);
}
