//! The validation check itself, and embedding in a host's instance and device.
//!
//! - An invalid call in a sacrificial context is caught, so "no validation messages" in the
//!   other tests is a check that can fail.
//! - A host engine creates instance, debug messenger, device and allocator itself, hands
//!   them to [`Context::from_raw`], renders, and tears everything down in order (ours
//!   first, then allocator, device, messenger, instance) without validation messages.

mod vulkan_support;

use std::sync::{Arc, Mutex};

use caveclod_tests::meshes;
use caveclod_vulkan::ash::vk;
use caveclod_vulkan::gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use caveclod_vulkan::{
    ash, gpu_allocator, Buffer, BufferDesc, CameraIndices, Context, DebugMessenger, Error,
    IndexSource, ValidationLog, VertexBuffer, VALIDATION_LAYER,
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

/// What a host engine owns.
struct Host {
    _entry: ash::Entry,
    instance: ash::Instance,
    messenger: DebugMessenger,
    device: ash::Device,
    physical_device: vk::PhysicalDevice,
    family: u32,
    queue: vk::Queue,
}

/// Creates instance (validation + debug utils), messenger, lavapipe device and queue the
/// way an engine would, independently of caveclod-vulkan's headless path.
fn host_engine(log: Arc<ValidationLog>) -> Host {
    // SAFETY: loading the system Vulkan loader.
    let entry = ok(unsafe { ash::Entry::load() }, "load Vulkan");
    let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_3);
    let layers = [VALIDATION_LAYER.as_ptr()];
    let extensions = [ash::ext::debug_utils::NAME.as_ptr()];
    let info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&extensions);
    // SAFETY: valid create info.
    let instance = ok(unsafe { entry.create_instance(&info, None) }, "instance");
    let messenger = ok(DebugMessenger::new(&entry, &instance, log), "messenger");
    // SAFETY: plain enumeration.
    let devices = ok(unsafe { instance.enumerate_physical_devices() }, "devices");
    let physical_device = devices
        .iter()
        .copied()
        // SAFETY: enumerated from this instance.
        .find(|&pd| unsafe { instance.get_physical_device_properties(pd) }.device_type == vk::PhysicalDeviceType::CPU)
        .unwrap_or_else(|| panic!("no lavapipe device"));
    // SAFETY: as above.
    let family = unsafe { instance.get_physical_device_queue_family_properties(physical_device) }
        .iter()
        .position(|f| {
            f.queue_flags
                .contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE)
        })
        .unwrap_or_else(|| panic!("no graphics queue")) as u32;
    let priorities = [1.0];
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(family)
        .queue_priorities(&priorities)];
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default().vulkan_memory_model(true);
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default()
        .dynamic_rendering(true)
        .synchronization2(true);
    let dinfo = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .push_next(&mut f12)
        .push_next(&mut f13);
    // SAFETY: valid create info; features supported by lavapipe.
    let device = ok(
        unsafe { instance.create_device(physical_device, &dinfo, None) },
        "device",
    );
    // SAFETY: queue 0 of `family` exists.
    let queue = unsafe { device.get_device_queue(family, 0) };
    Host {
        _entry: entry,
        instance,
        messenger,
        device,
        physical_device,
        family,
        queue,
    }
}

#[test]
fn embedded_in_a_host_engine() {
    let log = ValidationLog::new();
    let host = host_engine(log.clone());
    let allocator = ok(
        Allocator::new(&AllocatorCreateDesc {
            instance: host.instance.clone(),
            device: host.device.clone(),
            physical_device: host.physical_device,
            debug_settings: gpu_allocator::AllocatorDebugSettings::default(),
            buffer_device_address: false,
            allocation_sizes: gpu_allocator::AllocationSizes::default(),
        }),
        "host allocator",
    );
    let allocator = Arc::new(Mutex::new(allocator));
    let ctx = ok(
        Context::from_raw(
            host.instance.clone(),
            host.device.clone(),
            host.physical_device,
            host.family,
            host.queue,
            Some(allocator.clone()),
        ),
        "embed",
    )
    .with_validation_log(log.clone());

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
        IndexSource::Camera {
            hierarchy: &h,
            camera: &cam,
        },
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

    // The host tears down what it owns, in order; the allocator is the host's again.
    let allocator = match Arc::try_unwrap(allocator) {
        Ok(a) => a,
        Err(_) => panic!("the context kept a reference to the host's allocator"),
    };
    let report = match allocator.lock() {
        Ok(a) => a.generate_report(),
        Err(_) => panic!("poisoned"),
    };
    assert!(
        report.allocations.is_empty(),
        "allocations left: {:?}",
        report.allocations
    );
    drop(allocator);
    // SAFETY: everything made from the device is destroyed (checked above).
    unsafe { host.device.destroy_device(None) };
    host.messenger.destroy();
    // SAFETY: device and messenger are gone.
    unsafe { host.instance.destroy_instance(None) };
    let messages = log.take();
    assert!(
        messages.is_empty(),
        "validation messages:\n{}",
        messages.join("\n")
    );
}
