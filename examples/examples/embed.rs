//! caveclod inside a host's frame, the page to copy: the host makes instance, device, queue,
//! allocator, its own render pass and swapchain-less target, and submits; into its command
//! buffer caveclod records uploads, draws (inside the render pass) and the read-back.
//!
//! `cargo run --release -p caveclod-examples --example embed` bakes Spot and draws it
//! textured into an sRGB target, read back into `out/embed.png`.
use std::path::Path;
use std::sync::{Arc, Mutex};

use caveclod_bake::{import::ImportOptions, pipeline::bake_file};
use caveclod_core::{CameraState, LookAt, RefineParams};
use caveclod_vulkan::ash::{self, vk};
use caveclod_vulkan::gpu_allocator::vulkan::{self as alloc, Allocation, Allocator};
use caveclod_vulkan::*;
use glam::Vec3;

type Fallible<T> = std::result::Result<T, Box<dyn std::error::Error>>;
type HostImage = (vk::Image, vk::ImageView, Allocation);
const EXTENT: vk::Extent2D = vk::Extent2D {
    width: 640,
    height: 480,
};
/// The host's target: sRGB colour; depth D32, one sample (as the headless renderer's).
const FORMATS: TargetFormats = TargetFormats {
    colour: vk::Format::R8G8B8A8_SRGB,
    ..TargetFormats::HEADLESS
};
/// The attachments' layouts, in the render pass and after it.
const COLOUR_LAYOUT: vk::ImageLayout = vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL;
const DEPTH_LAYOUT: vk::ImageLayout = vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL;

/// A target image of `EXTENT` (colour or depth, by `format`) with its memory and view.
fn target_image(d: &ash::Device, a: &SharedAllocator, format: vk::Format) -> Fallible<HostImage> {
    use vk::{ImageAspectFlags as Aspect, ImageUsageFlags as Usage};
    let (usage, aspect) = if format == FORMATS.depth {
        (Usage::DEPTH_STENCIL_ATTACHMENT, Aspect::DEPTH)
    } else {
        (Usage::COLOR_ATTACHMENT | Usage::TRANSFER_SRC, Aspect::COLOR)
    };
    let info = vk::ImageCreateInfo::default()
        .image_type(vk::ImageType::TYPE_2D)
        .format(format)
        .extent(EXTENT.into())
        .mip_levels(1)
        .array_layers(1)
        .samples(FORMATS.samples)
        .usage(usage);
    // SAFETY: valid create info.
    let image = unsafe { d.create_image(&info, None) }?;
    let mut a = a.lock().map_err(|_| "allocator poisoned")?;
    let memory = a.allocate(&alloc::AllocationCreateDesc {
        name: "host target",
        // SAFETY: `image` is alive.
        requirements: unsafe { d.get_image_memory_requirements(image) },
        location: gpu_allocator::MemoryLocation::GpuOnly,
        linear: false,
        allocation_scheme: alloc::AllocationScheme::GpuAllocatorManaged,
    })?;
    // SAFETY: the allocation meets the image's requirements.
    unsafe { d.bind_image_memory(image, memory.memory(), memory.offset()) }?;
    let range = vk::ImageSubresourceRange::default()
        .aspect_mask(aspect)
        .level_count(1)
        .layer_count(1);
    let info = vk::ImageViewCreateInfo::default()
        .image(image)
        .view_type(vk::ImageViewType::TYPE_2D)
        .format(format)
        .subresource_range(range);
    // SAFETY: `image` is bound.
    let view = unsafe { d.create_image_view(&info, None) }?;
    Ok((image, view, memory))
}

/// The host's render pass: colour and depth, cleared, stored, left in their layouts.
fn render_pass(d: &ash::Device) -> Fallible<vk::RenderPass> {
    let attachment = |format, layout| {
        vk::AttachmentDescription::default()
            .format(format)
            .samples(FORMATS.samples)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .final_layout(layout)
    };
    let attachments = [
        attachment(FORMATS.colour, COLOUR_LAYOUT),
        attachment(FORMATS.depth, DEPTH_LAYOUT),
    ];
    let colour = [vk::AttachmentReference::default().layout(COLOUR_LAYOUT)];
    let depth = vk::AttachmentReference::default()
        .attachment(1)
        .layout(DEPTH_LAYOUT);
    let subpass = [vk::SubpassDescription::default()
        .color_attachments(&colour)
        .depth_stencil_attachment(&depth)];
    let info = vk::RenderPassCreateInfo::default()
        .attachments(&attachments)
        .subpasses(&subpass);
    // SAFETY: valid create info.
    Ok(unsafe { d.create_render_pass(&info, None) }?)
}

/// What the host engine owns: its instance, device with caveclod's features, queue and
/// allocator (shared with caveclod).
struct HostGpu {
    _entry: ash::Entry,
    instance: ash::Instance,
    physical_device: vk::PhysicalDevice,
    family: u32,
    device: ash::Device,
    queue: vk::Queue,
    allocator: SharedAllocator,
}

/// The host's target: colour and depth images, render pass, framebuffer, a command buffer.
struct HostTarget {
    colour: HostImage,
    depth: HostImage,
    pass: vk::RenderPass,
    framebuffer: vk::Framebuffer,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
}

fn main() -> Fallible<()> {
    let spot = Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/spot");
    let obj = spot.join("spot_triangulated.obj");
    let (baked, _) = bake_file(&obj, &ImportOptions::default(), &mut |_| {})?;
    let h = baked.hierarchy()?;
    let texture = image::open(spot.join("spot_texture.png"))?.to_rgba8();

    let gpu = host_gpu()?;
    let target = host_target(&gpu)?;

    // caveclod over the host's device: a recorder for its render pass, one refined camera.
    let d = &gpu.device;
    let host = HostDevice::new(&gpu.instance, d, gpu.physical_device, gpu.family, gpu.queue);
    // SAFETY: the host's live handles, outliving the context, with the features it enabled.
    let ctx = unsafe { Context::from_raw(host.allocator(gpu.allocator.clone())) }?;
    let recorder = Recorder::new(&ctx, RecorderDesc::render_pass(FORMATS, target.pass, 0))?;
    let look = LookAt {
        eye: Vec3::new(2.3, 0.8, -1.2),
        target: Vec3::new(0.0, 0.2, 0.0),
        up: Vec3::Y,
        fov_y: 0.8,
        near: 0.05,
        far: 50.0,
    };
    let mut memory = vec![0u32; CameraState::words_needed(&h)];
    let mut camera = CameraState::new(&h, &mut memory)?;
    let view = look.view(EXTENT.width, EXTENT.height);
    while camera.refine(&h, &view, &RefineParams::default())?.splits > 0 {}
    let mut indices = CameraIndices::new("camera", h.surface_count(), 1);
    indices.fill(&ctx, 0, IndexSource::camera(&h, &camera))?;

    // The host's frame: caveclod's uploads, its draws inside the host's render pass, the
    // read-back; the host submits and waits.
    let cmd = target.cmd;
    // SAFETY: `cmd` is fresh.
    unsafe { d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()) }?;
    let (vertices, vertex_staging) =
        VertexBuffer::record_upload(&ctx, cmd, "spot", h.vertices(), h.vertex_colours())?;
    let desc = TextureDesc::srgb(texture.width(), texture.height());
    let (tex, tex_staging) = Texture::record_upload(&ctx, cmd, "spot", desc, texture.as_raw())?;
    let surfaces = vec![SurfaceMaterial::textured(&tex); h.surface_count()];
    let materials = MaterialSet::new(&ctx, &recorder, &surfaces)?;
    begin_render_pass(d, &target);
    let viewport = Viewport::full(EXTENT.width, EXTENT.height);
    let view_proj = look.view_projection(viewport.aspect());
    let draw = RecordCamera::new(viewport, view_proj, &vertices, &indices).materials(&materials);
    recorder.record(&ctx, cmd, 0, &[draw])?;
    // SAFETY: `cmd` is inside the render pass begun above.
    unsafe { d.cmd_end_render_pass(cmd) };
    let colour = target.colour.0;
    let shot = ImageReadback::record(&ctx, cmd, colour, COLOUR_LAYOUT, FORMATS.colour, EXTENT)?;
    submit_and_wait(&gpu, cmd)?;
    std::fs::create_dir_all("out")?;
    caveclod_host::write_png(&shot.image()?, Path::new("out/embed.png"))?;

    // Teardown: caveclod's objects, then the host's, in reverse order of creation.
    materials.destroy(&ctx);
    vertex_staging.destroy(&ctx)?;
    tex_staging.destroy(&ctx)?;
    shot.destroy(&ctx)?;
    tex.destroy(&ctx)?;
    vertices.destroy(&ctx)?;
    indices.destroy(&ctx)?;
    recorder.destroy(&ctx)?;
    ctx.destroy()?;
    destroy_host(gpu, target)
}

/// The host's instance, a device with caveclod's features and a graphics queue, and its
/// allocator.
fn host_gpu() -> Fallible<HostGpu> {
    // SAFETY: loading the system's Vulkan loader.
    let entry = unsafe { ash::Entry::load() }?;
    let app = vk::ApplicationInfo::default().api_version(API_VERSION);
    let info = vk::InstanceCreateInfo::default().application_info(&app);
    // SAFETY: valid create info.
    let instance = unsafe { entry.create_instance(&info, None) }?;
    // SAFETY: plain queries of the instance's devices.
    let devices = unsafe { instance.enumerate_physical_devices() }?;
    let physical_device = *devices.first().ok_or("no Vulkan device")?;
    // SAFETY: `physical_device` belongs to `instance`.
    let families = unsafe { instance.get_physical_device_queue_family_properties(physical_device) };
    let graphics = |f: &vk::QueueFamilyProperties| f.queue_flags.contains(vk::QueueFlags::GRAPHICS);
    let family = families.iter().position(graphics);
    let family = family.ok_or("no graphics queue")? as u32;
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(family)
        .queue_priorities(&[1.0])];
    let mut features = DeviceFeatures::REQUIRED.chain();
    let info = features.push(vk::DeviceCreateInfo::default().queue_create_infos(&queues));
    // SAFETY: valid create info (Context::from_raw checks the device supports it).
    let device = unsafe { instance.create_device(physical_device, &info, None) }?;
    // SAFETY: queue 0 of `family` was created with the device.
    let queue = unsafe { device.get_device_queue(family, 0) };
    let allocator = Arc::new(Mutex::new(Allocator::new(&alloc::AllocatorCreateDesc {
        instance: instance.clone(),
        device: device.clone(),
        physical_device,
        debug_settings: Default::default(),
        buffer_device_address: false,
        allocation_sizes: Default::default(),
    })?));
    Ok(HostGpu {
        _entry: entry,
        instance,
        physical_device,
        family,
        device,
        queue,
        allocator,
    })
}

/// The host's target and a command buffer to record its frame into.
fn host_target(gpu: &HostGpu) -> Fallible<HostTarget> {
    let d = &gpu.device;
    let colour = target_image(d, &gpu.allocator, FORMATS.colour)?;
    let depth = target_image(d, &gpu.allocator, FORMATS.depth)?;
    let pass = render_pass(d)?;
    let views = [colour.1, depth.1];
    let info = vk::FramebufferCreateInfo::default()
        .render_pass(pass)
        .attachments(&views)
        .width(EXTENT.width)
        .height(EXTENT.height)
        .layers(1);
    // SAFETY: the views match the render pass's attachments.
    let framebuffer = unsafe { d.create_framebuffer(&info, None) }?;
    let info = vk::CommandPoolCreateInfo::default().queue_family_index(gpu.family);
    // SAFETY: valid create info.
    let pool = unsafe { d.create_command_pool(&info, None) }?;
    let info = vk::CommandBufferAllocateInfo::default()
        .command_pool(pool)
        .command_buffer_count(1);
    // SAFETY: `pool` is alive.
    let cmd = unsafe { d.allocate_command_buffers(&info) }?[0];
    Ok(HostTarget {
        colour,
        depth,
        pass,
        framebuffer,
        pool,
        cmd,
    })
}

/// Begins the host's render pass in its command buffer, clearing colour and depth.
fn begin_render_pass(d: &ash::Device, target: &HostTarget) {
    let mut clears = [vk::ClearValue::default(); 2];
    clears[0].color.float32 = [0.1, 0.1, 0.12, 1.0]; // the background
    clears[1].depth_stencil.depth = 1.0; // the far plane
    let begin = vk::RenderPassBeginInfo::default()
        .render_pass(target.pass)
        .framebuffer(target.framebuffer)
        .render_area(EXTENT.into())
        .clear_values(&clears);
    // SAFETY: `cmd` is recording; pass and framebuffer are alive.
    unsafe { d.cmd_begin_render_pass(target.cmd, &begin, vk::SubpassContents::INLINE) };
}

/// Ends `cmd`, submits it to the host's queue and waits for it.
fn submit_and_wait(gpu: &HostGpu, cmd: vk::CommandBuffer) -> Fallible<()> {
    let cmds = [cmd];
    // SAFETY: `cmd` is recording; nothing else uses the host's queue.
    unsafe {
        gpu.device.end_command_buffer(cmd)?;
        let submit = vk::SubmitInfo::default().command_buffers(&cmds);
        gpu.device
            .queue_submit(gpu.queue, &[submit], vk::Fence::null())?;
        gpu.device.queue_wait_idle(gpu.queue)?;
    }
    Ok(())
}

/// The host's objects, destroyed in reverse order of creation.
fn destroy_host(gpu: HostGpu, target: HostTarget) -> Fallible<()> {
    let d = &gpu.device;
    // SAFETY: the queue is idle; each object is destroyed once, before its device.
    unsafe {
        d.destroy_command_pool(target.pool, None);
        d.destroy_framebuffer(target.framebuffer, None);
        d.destroy_render_pass(target.pass, None);
        for (image, view, memory) in [target.depth, target.colour] {
            d.destroy_image_view(view, None);
            d.destroy_image(image, None);
            gpu.allocator.lock().map_err(|_| "poisoned")?.free(memory)?;
        }
        drop(gpu.allocator);
        d.destroy_device(None);
        gpu.instance.destroy_instance(None);
    }
    Ok(())
}
