//! caveclod inside a host's frame, the page to copy: the host makes instance, device,
//! queue, allocator, its own render pass and a swapchain-less target; caveclod only uploads
//! (into the host's command buffer) and records draws (inside the host's render pass).
//!
//! `cargo run --release -p caveclod-examples --example embed [-- OUT.png]` bakes Spot and
//! draws it textured into an sRGB target (default `out/embed.png`).
use std::path::Path;
use std::sync::{Arc, Mutex};

use caveclod_bake::{import::ImportOptions, pipeline::bake_file};
use caveclod_core::{CameraState, LookAt, RefineParams};
use caveclod_vulkan::ash::{self, vk};
use caveclod_vulkan::gpu_allocator::vulkan::{Allocation, AllocationCreateDesc as Alloc};
use caveclod_vulkan::gpu_allocator::vulkan::{AllocationScheme, Allocator, AllocatorCreateDesc};
use caveclod_vulkan::*;
use glam::Vec3;

type Fallible<T> = std::result::Result<T, Box<dyn std::error::Error>>;
const EXTENT: vk::Extent2D = vk::Extent2D {
    width: 640,
    height: 480,
};
const COLOUR: vk::Format = vk::Format::R8G8B8A8_SRGB;
const DEPTH: vk::Format = vk::Format::D32_SFLOAT;

/// The host's device: a device with caveclod's features enabled, its queue, an allocator.
fn host_device(instance: &ash::Instance) -> Fallible<HostDevice> {
    // SAFETY: plain enumeration and queries of this instance's devices.
    let (physical_device, family) = unsafe { instance.enumerate_physical_devices() }?
        .into_iter()
        .find_map(|pd| {
            // SAFETY: `pd` belongs to `instance`.
            let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
            let graphics =
                |f: &vk::QueueFamilyProperties| f.queue_flags.contains(vk::QueueFlags::GRAPHICS);
            Some((pd, families.iter().position(graphics)? as u32))
        })
        .ok_or("no Vulkan device with a graphics queue")?;
    let (mut f10, mut f12, mut f13) = Default::default();
    DeviceFeatures::REQUIRED.enable(&mut f10, &mut f12, &mut f13);
    let queue_info = vk::DeviceQueueCreateInfo::default().queue_priorities(&[1.0]);
    let queues = [queue_info.queue_family_index(family)];
    let info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_features(&f10);
    let info = info.push_next(&mut f12).push_next(&mut f13);
    // SAFETY: valid create info (Context::from_raw checks the device supports it).
    let device = unsafe { instance.create_device(physical_device, &info, None) }?;
    let (instance, debug_settings) = (instance.clone(), Default::default());
    let allocator = Allocator::new(&AllocatorCreateDesc {
        instance: instance.clone(),
        device: device.clone(),
        physical_device,
        debug_settings,
        buffer_device_address: false,
        allocation_sizes: Default::default(),
    })?;
    // SAFETY: queue 0 of `family` was created with the device.
    let queue = unsafe { device.get_device_queue(family, 0) };
    let allocator = Some(Arc::new(Mutex::new(allocator)));
    let enabled = DeviceFeatures::REQUIRED;
    Ok(HostDevice {
        instance,
        device,
        physical_device,
        queue_family: family,
        queue,
        allocator,
        enabled,
    })
}

/// A host image with its memory and view.
fn image(
    d: &ash::Device,
    a: &mut Allocator,
    format: vk::Format,
    usage: vk::ImageUsageFlags,
) -> Fallible<(vk::Image, vk::ImageView, Allocation)> {
    let info = vk::ImageCreateInfo::default()
        .image_type(vk::ImageType::TYPE_2D)
        .format(format);
    let info = info
        .extent(EXTENT.into())
        .mip_levels(1)
        .array_layers(1)
        .usage(usage);
    // SAFETY: valid create info.
    let image = unsafe { d.create_image(&info.samples(vk::SampleCountFlags::TYPE_1), None) }?;
    // SAFETY: `image` is alive.
    let requirements = unsafe { d.get_image_memory_requirements(image) };
    let (location, scheme) = (
        gpu_allocator::MemoryLocation::GpuOnly,
        AllocationScheme::GpuAllocatorManaged,
    );
    let memory = a.allocate(&Alloc {
        name: "target",
        requirements,
        location,
        linear: false,
        allocation_scheme: scheme,
    })?;
    // SAFETY: the allocation meets the image's requirements.
    unsafe { d.bind_image_memory(image, memory.memory(), memory.offset()) }?;
    let aspect = if format == DEPTH {
        vk::ImageAspectFlags::DEPTH
    } else {
        vk::ImageAspectFlags::COLOR
    };
    let range = vk::ImageSubresourceRange {
        aspect_mask: aspect,
        level_count: 1,
        layer_count: 1,
        ..Default::default()
    };
    let view = vk::ImageViewCreateInfo::default()
        .image(image)
        .view_type(vk::ImageViewType::TYPE_2D);
    // SAFETY: `image` is bound.
    let view = unsafe { d.create_image_view(&view.format(format).subresource_range(range), None) }?;
    Ok((image, view, memory))
}

/// The host's render pass: colour (cleared, stored, left for the copy-out) and depth.
fn render_pass(d: &ash::Device) -> Fallible<vk::RenderPass> {
    let attachment = |format, layout| {
        let a = vk::AttachmentDescription::default()
            .format(format)
            .samples(vk::SampleCountFlags::TYPE_1);
        a.load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .final_layout(layout)
    };
    let attachments = [
        attachment(COLOUR, vk::ImageLayout::TRANSFER_SRC_OPTIMAL),
        attachment(DEPTH, vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL),
    ];
    let colour = [vk::AttachmentReference {
        attachment: 0,
        layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
    }];
    let depth = vk::AttachmentReference {
        attachment: 1,
        layout: vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
    };
    let subpass = [vk::SubpassDescription::default()
        .color_attachments(&colour)
        .depth_stencil_attachment(&depth)];
    // The copy-out after the pass waits for its colour writes.
    let out = [vk::SubpassDependency {
        src_subpass: 0,
        dst_subpass: vk::SUBPASS_EXTERNAL,
        src_stage_mask: vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
        dst_stage_mask: vk::PipelineStageFlags::TRANSFER,
        src_access_mask: vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
        dst_access_mask: vk::AccessFlags::TRANSFER_READ,
        dependency_flags: vk::DependencyFlags::empty(),
    }];
    let info = vk::RenderPassCreateInfo::default()
        .attachments(&attachments)
        .subpasses(&subpass);
    // SAFETY: valid create info.
    Ok(unsafe { d.create_render_pass(&info.dependencies(&out), None) }?)
}

fn main() -> Fallible<()> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "out/embed.png".into());
    let spot = Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/spot");
    let (baked, _) = bake_file(
        &spot.join("spot_triangulated.obj"),
        &ImportOptions::default(),
        &mut |_| {},
    )?;
    let h = baked.hierarchy()?;
    let texture = image::open(spot.join("spot_texture.png"))?.to_rgba8();

    // The host: instance, device, allocator, target, render pass, framebuffer, command buffer.
    // SAFETY: loading the system's Vulkan loader.
    let entry = unsafe { ash::Entry::load() }?;
    let app = vk::ApplicationInfo::default().api_version(API_VERSION);
    // SAFETY: valid create info.
    let instance = unsafe {
        entry.create_instance(
            &vk::InstanceCreateInfo::default().application_info(&app),
            None,
        )
    }?;
    let host = host_device(&instance)?;
    let (d, queue, family) = (host.device.clone(), host.queue, host.queue_family);
    let allocator = host.allocator.clone().ok_or("no allocator")?;
    let mut a = allocator.lock().map_err(|_| "allocator poisoned")?;
    let colour_usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
    let images = [
        image(&d, &mut a, COLOUR, colour_usage)?,
        image(
            &d,
            &mut a,
            DEPTH,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        )?,
    ];
    drop(a);
    let pass = render_pass(&d)?;
    let views = [images[0].1, images[1].1];
    let fb = vk::FramebufferCreateInfo::default()
        .render_pass(pass)
        .attachments(&views)
        .layers(1);
    // SAFETY: the views match the render pass's attachments; valid create infos.
    let framebuffer =
        unsafe { d.create_framebuffer(&fb.width(EXTENT.width).height(EXTENT.height), None) }?;
    // SAFETY: as above.
    let pool = unsafe {
        d.create_command_pool(
            &vk::CommandPoolCreateInfo::default().queue_family_index(family),
            None,
        )
    }?;
    let alloc = vk::CommandBufferAllocateInfo::default()
        .command_pool(pool)
        .command_buffer_count(1);
    // SAFETY: as above.
    let cmd = unsafe { d.allocate_command_buffers(&alloc) }?[0];

    // caveclod over the host's device: a recorder for its render pass, one refined camera.
    // SAFETY: the host's live handles, outliving the context; `enabled` is what it enabled.
    let ctx = unsafe { Context::from_raw(host) }?;
    let formats = TargetFormats {
        colour: COLOUR,
        depth: DEPTH,
        samples: vk::SampleCountFlags::TYPE_1,
    };
    let recorder = Recorder::new(&ctx, RecorderDesc::render_pass(formats, pass, 0))?;
    let (eye, target) = (Vec3::new(2.3, 0.8, -1.2), Vec3::new(0.0, 0.2, 0.0));
    let look = LookAt {
        eye,
        target,
        up: Vec3::Y,
        fov_y: 0.8,
        near: 0.05,
        far: 50.0,
    };
    let mut memory = vec![0u32; CameraState::words_needed(&h)];
    let mut camera = CameraState::new(&h, &mut memory)?;
    while camera
        .refine(
            &h,
            &look.view(EXTENT.width, EXTENT.height),
            &RefineParams::default(),
        )?
        .splits
        > 0
    {}
    let mut indices = CameraIndices::new("camera", h.surface_count(), 1);
    indices.fill(
        &ctx,
        0,
        IndexSource::Camera {
            hierarchy: &h,
            camera: &camera,
        },
    )?;
    let readback_size = u64::from(EXTENT.width * EXTENT.height * 4);
    let readback = Buffer::new(
        &ctx,
        "read-back",
        BufferDesc::gpu_to_cpu(readback_size, vk::BufferUsageFlags::TRANSFER_DST),
    )?;

    // The host's frame: caveclod's uploads, then its draws inside the host's render pass.
    // SAFETY: `cmd` is fresh.
    unsafe { d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()) }?;
    let (vertices, vertex_staging) =
        VertexBuffer::record_upload(&ctx, cmd, "spot", h.vertices(), h.vertex_colours())?;
    let desc = TextureDesc {
        width: texture.width(),
        height: texture.height(),
        srgb: true,
    };
    let (tex, tex_staging) =
        Texture::record_upload(&ctx, cmd, "spot texture", desc, texture.as_raw())?;
    let surface = SurfaceMaterial {
        texture: Some(&tex),
        factor: [1.0; 4],
        alpha_cutoff: 0.0,
        blend: false,
    };
    let materials = MaterialSet::new(&ctx, &recorder, &vec![surface; h.surface_count()])?;
    let clear = vk::ClearValue {
        color: vk::ClearColorValue {
            float32: [0.1, 0.1, 0.12, 1.0],
        },
    };
    let depth = vk::ClearValue {
        depth_stencil: vk::ClearDepthStencilValue {
            depth: 1.0,
            stencil: 0,
        },
    };
    let (clears, area) = (
        [clear, depth],
        vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent: EXTENT,
        },
    );
    let begin = vk::RenderPassBeginInfo::default()
        .render_pass(pass)
        .framebuffer(framebuffer)
        .render_area(area);
    // SAFETY: `cmd` is recording; pass and framebuffer are alive.
    unsafe {
        d.cmd_begin_render_pass(
            cmd,
            &begin.clear_values(&clears),
            vk::SubpassContents::INLINE,
        )
    };
    let viewport = Viewport::full(EXTENT.width, EXTENT.height);
    let view_proj = look.view_projection(viewport.aspect());
    let (vertices_ref, materials_ref) = (&vertices, Some(&materials));
    let draw = RecordCamera {
        viewport,
        view_proj,
        vertices: vertices_ref,
        indices: &indices,
        colours: &[],
        materials: materials_ref,
        refine_morphs: None,
        morph: None,
        wireframe: false,
    };
    recorder.record(&ctx, cmd, 0, &[draw])?;
    let layers = vk::ImageSubresourceLayers {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        layer_count: 1,
        ..Default::default()
    };
    let region = [vk::BufferImageCopy {
        image_subresource: layers,
        image_extent: EXTENT.into(),
        ..Default::default()
    }];
    let cmds = [cmd];
    // SAFETY: the pass left the colour image in TRANSFER_SRC; the buffer holds the image.
    unsafe {
        d.cmd_end_render_pass(cmd);
        d.cmd_copy_image_to_buffer(
            cmd,
            images[0].0,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            readback.raw,
            &region,
        );
        d.end_command_buffer(cmd)?;
        d.queue_submit(
            queue,
            &[vk::SubmitInfo::default().command_buffers(&cmds)],
            vk::Fence::null(),
        )?;
        d.queue_wait_idle(queue)?;
    }
    let pixels =
        readback.mapped().ok_or("read-back not mapped")?[..readback_size as usize].to_vec();
    std::fs::create_dir_all(Path::new(&out).parent().unwrap_or(Path::new(".")))?;
    let image = RgbaImage {
        width: EXTENT.width,
        height: EXTENT.height,
        pixels,
    };
    caveclod_cli::snapshot::write_png(&image, Path::new(&out))?;
    println!(
        "{} active polygons, wrote {out}",
        camera.active_polygon_count()
    );

    // Teardown: caveclod's objects, then the host's, in reverse order of creation.
    materials.destroy(&ctx);
    let staging = [
        vertex_staging.destroy(&ctx),
        tex_staging.destroy(&ctx),
        readback.destroy(&ctx),
    ];
    let rest = [
        tex.destroy(&ctx),
        vertices.destroy(&ctx),
        indices.destroy(&ctx),
        recorder.destroy(&ctx),
    ];
    staging.into_iter().chain(rest).try_for_each(|r| r)?;
    ctx.destroy()?;
    let mut a = allocator.lock().map_err(|_| "allocator poisoned")?;
    // SAFETY: the queue is idle; each object is destroyed once, before its device.
    unsafe {
        (
            d.destroy_command_pool(pool, None),
            d.destroy_framebuffer(framebuffer, None),
        )
    };
    // SAFETY: as above.
    unsafe { d.destroy_render_pass(pass, None) };
    for (image, view, memory) in images {
        // SAFETY: as above.
        unsafe {
            (
                d.destroy_image_view(view, None),
                d.destroy_image(image, None),
            )
        };
        a.free(memory)?;
    }
    drop(a);
    drop(allocator);
    // SAFETY: every object made from the device and instance is destroyed.
    unsafe { (d.destroy_device(None), instance.destroy_instance(None)) };
    Ok(())
}
