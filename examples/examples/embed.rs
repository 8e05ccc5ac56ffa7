//! caveclod inside a host's frame, the page to copy: the host makes instance, device,
//! queue, allocator, its own render pass and a swapchain-less target; caveclod only uploads
//! (into the host's command buffer) and records draws (inside the host's render pass).
//!
//! `cargo run --release -p caveclod-examples --example embed [-- OUT.png]` bakes Spot, draws
//! it textured into an sRGB target and writes `out/embed.png`.
use std::sync::{Arc, Mutex};

use caveclod_bake::{import::ImportOptions, pipeline::bake_file};
use caveclod_core::{CameraState, LookAt, RefineParams};
use caveclod_vulkan::ash::{self, vk};
use caveclod_vulkan::gpu_allocator::vulkan::{
    Allocation, AllocationCreateDesc, Allocator, AllocatorCreateDesc,
};
use caveclod_vulkan::gpu_allocator::{vulkan::AllocationScheme, MemoryLocation};
use caveclod_vulkan::*;
use glam::Vec3;

type Fallible<T> = std::result::Result<T, Box<dyn std::error::Error>>;
const W: u32 = 640;
const H: u32 = 480;
const COLOUR: vk::Format = vk::Format::R8G8B8A8_SRGB;
const DEPTH: vk::Format = vk::Format::D32_SFLOAT;

/// The host's device: instance, a device with caveclod's features enabled, queue, allocator.
fn host_device(entry: &ash::Entry) -> Fallible<HostDevice> {
    let app = vk::ApplicationInfo::default().api_version(API_VERSION);
    // SAFETY: valid create info.
    let instance = unsafe {
        entry.create_instance(
            &vk::InstanceCreateInfo::default().application_info(&app),
            None,
        )
    }?;
    // SAFETY: plain enumeration and queries of this instance's devices.
    let (physical_device, family) = unsafe { instance.enumerate_physical_devices() }?
        .into_iter()
        .find_map(|pd| {
            // SAFETY: `pd` belongs to `instance`.
            let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
            let f = families
                .iter()
                .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS))?;
            Some((pd, f as u32))
        })
        .ok_or("no Vulkan device with a graphics queue")?;
    let (mut f10, mut f12, mut f13) = Default::default();
    DeviceFeatures::REQUIRED.enable(&mut f10, &mut f12, &mut f13);
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(family)
        .queue_priorities(&[1.0])];
    let info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_features(&f10)
        .push_next(&mut f12)
        .push_next(&mut f13);
    // SAFETY: valid create info (Context::from_raw checks the device supports it).
    let device = unsafe { instance.create_device(physical_device, &info, None) }?;
    let allocator = Allocator::new(&AllocatorCreateDesc {
        instance: instance.clone(),
        device: device.clone(),
        physical_device,
        debug_settings: Default::default(),
        buffer_device_address: false,
        allocation_sizes: Default::default(),
    })?;
    // SAFETY: queue 0 of `family` was created with the device.
    let queue = unsafe { device.get_device_queue(family, 0) };
    let allocator = Some(Arc::new(Mutex::new(allocator)));
    Ok(HostDevice {
        instance,
        device,
        physical_device,
        queue_family: family,
        queue,
        allocator,
        enabled: DeviceFeatures::REQUIRED,
    })
}

/// The host's target: colour + depth images, a render pass ending in TRANSFER_SRC, a
/// framebuffer and a read-back buffer, all from the host's allocator.
struct Target {
    images: Vec<(vk::Image, vk::ImageView, Allocation)>,
    render_pass: vk::RenderPass,
    framebuffer: vk::Framebuffer,
    readback: (vk::Buffer, Allocation),
}

fn image(
    d: &ash::Device,
    a: &mut Allocator,
    format: vk::Format,
    usage: vk::ImageUsageFlags,
    aspect: vk::ImageAspectFlags,
) -> Fallible<(vk::Image, vk::ImageView, Allocation)> {
    let info = vk::ImageCreateInfo::default()
        .image_type(vk::ImageType::TYPE_2D)
        .format(format)
        .extent(vk::Extent3D {
            width: W,
            height: H,
            depth: 1,
        })
        .mip_levels(1)
        .array_layers(1)
        .samples(vk::SampleCountFlags::TYPE_1)
        .usage(usage);
    // SAFETY: valid create info.
    let image = unsafe { d.create_image(&info, None) }?;
    // SAFETY: `image` is alive.
    let requirements = unsafe { d.get_image_memory_requirements(image) };
    let memory = a.allocate(&AllocationCreateDesc {
        name: "target",
        requirements,
        location: MemoryLocation::GpuOnly,
        linear: false,
        allocation_scheme: AllocationScheme::GpuAllocatorManaged,
    })?;
    // SAFETY: the allocation meets the requirements; the view covers the bound image.
    unsafe { d.bind_image_memory(image, memory.memory(), memory.offset()) }?;
    let range = vk::ImageSubresourceRange {
        aspect_mask: aspect,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 1,
    };
    let view_info = vk::ImageViewCreateInfo::default()
        .image(image)
        .view_type(vk::ImageViewType::TYPE_2D)
        .format(format)
        .subresource_range(range);
    // SAFETY: `image` is bound.
    let view = unsafe { d.create_image_view(&view_info, None) }?;
    Ok((image, view, memory))
}

impl Target {
    fn new(d: &ash::Device, a: &mut Allocator) -> Fallible<Self> {
        let colour = image(
            d,
            a,
            COLOUR,
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
            vk::ImageAspectFlags::COLOR,
        )?;
        let depth = image(
            d,
            a,
            DEPTH,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            vk::ImageAspectFlags::DEPTH,
        )?;
        let attachment = |format, final_layout| {
            vk::AttachmentDescription::default()
                .format(format)
                .samples(vk::SampleCountFlags::TYPE_1)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::STORE)
                .final_layout(final_layout)
        };
        let attachments = [
            attachment(COLOUR, vk::ImageLayout::TRANSFER_SRC_OPTIMAL),
            attachment(DEPTH, vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL),
        ];
        let colour_ref = [vk::AttachmentReference {
            attachment: 0,
            layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
        }];
        let depth_ref = vk::AttachmentReference {
            attachment: 1,
            layout: vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
        };
        let subpass = [vk::SubpassDescription::default()
            .color_attachments(&colour_ref)
            .depth_stencil_attachment(&depth_ref)];
        // The copy-out after the pass waits for its colour writes.
        let out = [vk::SubpassDependency {
            src_subpass: 0,
            dst_subpass: vk::SUBPASS_EXTERNAL,
            src_stage_mask: vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
            dst_stage_mask: vk::PipelineStageFlags::TRANSFER,
            src_access_mask: vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            dst_access_mask: vk::AccessFlags::TRANSFER_READ,
            dependency_flags: Default::default(),
        }];
        let info = vk::RenderPassCreateInfo::default()
            .attachments(&attachments)
            .subpasses(&subpass)
            .dependencies(&out);
        // SAFETY: valid create info; the framebuffer's views match its attachments.
        let render_pass = unsafe { d.create_render_pass(&info, None) }?;
        let views = [colour.1, depth.1];
        let fb = vk::FramebufferCreateInfo::default()
            .render_pass(render_pass)
            .attachments(&views)
            .width(W)
            .height(H)
            .layers(1);
        // SAFETY: as above.
        let framebuffer = unsafe { d.create_framebuffer(&fb, None) }?;
        let buffer_info = vk::BufferCreateInfo::default()
            .size(u64::from(W * H * 4))
            .usage(vk::BufferUsageFlags::TRANSFER_DST);
        // SAFETY: valid create info; the allocation meets the buffer's requirements.
        let buffer = unsafe { d.create_buffer(&buffer_info, None) }?;
        // SAFETY: `buffer` is alive.
        let requirements = unsafe { d.get_buffer_memory_requirements(buffer) };
        let memory = a.allocate(&AllocationCreateDesc {
            name: "read-back",
            requirements,
            location: MemoryLocation::GpuToCpu,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        })?;
        // SAFETY: as above.
        unsafe { d.bind_buffer_memory(buffer, memory.memory(), memory.offset()) }?;
        Ok(Self {
            images: vec![colour, depth],
            render_pass,
            framebuffer,
            readback: (buffer, memory),
        })
    }

    fn destroy(self, d: &ash::Device, a: &mut Allocator) -> Fallible<()> {
        // SAFETY: the device is idle; each object is destroyed once.
        unsafe {
            d.destroy_framebuffer(self.framebuffer, None);
            d.destroy_render_pass(self.render_pass, None);
            d.destroy_buffer(self.readback.0, None)
        };
        a.free(self.readback.1)?;
        for (image, view, memory) in self.images {
            // SAFETY: as above.
            unsafe {
                d.destroy_image_view(view, None);
                d.destroy_image(image, None)
            };
            a.free(memory)?;
        }
        Ok(())
    }
}

fn main() -> Fallible<()> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "out/embed.png".into());
    let spot = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/spot");
    let (baked, _) = bake_file(
        &spot.join("spot_triangulated.obj"),
        &ImportOptions::default(),
        &mut |_| {},
    )?;
    let h = baked.hierarchy()?;
    let texture = image::open(spot.join("spot_texture.png"))?.to_rgba8();

    // SAFETY: loading the system's Vulkan loader.
    let entry = unsafe { ash::Entry::load() }?;
    let host = host_device(&entry)?;
    let (d, queue, family, allocator) = (
        host.device.clone(),
        host.queue,
        host.queue_family,
        host.allocator.clone().ok_or("no allocator")?,
    );
    let instance = host.instance.clone();
    let target = Target::new(
        &d,
        &mut *allocator.lock().map_err(|_| "allocator poisoned")?,
    )?;
    // SAFETY: the host's live handles, outliving the context; `enabled` is what it enabled.
    let ctx = unsafe { Context::from_raw(host) }?;
    let formats = TargetFormats {
        colour: COLOUR,
        depth: DEPTH,
        samples: vk::SampleCountFlags::TYPE_1,
    };
    let recorder = Recorder::new(
        &ctx,
        RecorderDesc::render_pass(formats, target.render_pass, 0),
    )?;

    // One camera, refined to 1 px for this view.
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
    while camera
        .refine(&h, &look.view(W, H), &RefineParams::default())?
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

    // The host's frame: its command buffer, caveclod's uploads and draws, its render pass.
    // SAFETY: valid create infos; one command buffer from the pool.
    let pool = unsafe {
        d.create_command_pool(
            &vk::CommandPoolCreateInfo::default().queue_family_index(family),
            None,
        )
    }?;
    // SAFETY: as above.
    let cmd = unsafe {
        d.allocate_command_buffers(
            &vk::CommandBufferAllocateInfo::default()
                .command_pool(pool)
                .command_buffer_count(1),
        )
    }?[0];
    // SAFETY: `cmd` is fresh.
    unsafe { d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()) }?;
    let (vertices, vertex_staging) = VertexBuffer::record_upload(&ctx, cmd, "spot", h.vertices())?;
    let desc = TextureDesc {
        width: texture.width(),
        height: texture.height(),
        srgb: true,
    };
    let (tex, tex_staging) =
        Texture::record_upload(&ctx, cmd, "spot texture", desc, texture.as_raw())?;
    let surfaces = vec![
        SurfaceMaterial {
            texture: Some(&tex),
            factor: [1.0; 4],
            alpha_cutoff: 0.0
        };
        h.surface_count()
    ];
    let materials = MaterialSet::new(&ctx, &recorder, &surfaces)?;
    let clears = [
        vk::ClearValue {
            color: vk::ClearColorValue {
                float32: [0.1, 0.1, 0.12, 1.0],
            },
        },
        vk::ClearValue {
            depth_stencil: vk::ClearDepthStencilValue {
                depth: 1.0,
                stencil: 0,
            },
        },
    ];
    let area = vk::Rect2D {
        offset: Default::default(),
        extent: vk::Extent2D {
            width: W,
            height: H,
        },
    };
    let begin = vk::RenderPassBeginInfo::default()
        .render_pass(target.render_pass)
        .framebuffer(target.framebuffer)
        .render_area(area)
        .clear_values(&clears);
    // SAFETY: `cmd` is recording; pass and framebuffer are alive.
    unsafe { d.cmd_begin_render_pass(cmd, &begin, vk::SubpassContents::INLINE) };
    let viewport = Viewport::full(W, H);
    let draw = RecordCamera {
        viewport,
        view_proj: look.view_projection(viewport.aspect()),
        vertices: &vertices,
        indices: &indices,
        colours: &[],
        materials: Some(&materials),
        morph: None,
        wireframe: false,
    };
    recorder.record(&ctx, cmd, 0, &[draw])?;
    let layers = vk::ImageSubresourceLayers {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        mip_level: 0,
        base_array_layer: 0,
        layer_count: 1,
    };
    let region = [vk::BufferImageCopy {
        image_subresource: layers,
        image_extent: area.extent.into(),
        ..Default::default()
    }];
    // SAFETY: the pass left the colour image in TRANSFER_SRC; the buffer holds W * H * 4 bytes.
    unsafe {
        d.cmd_end_render_pass(cmd);
        d.cmd_copy_image_to_buffer(
            cmd,
            target.images[0].0,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            target.readback.0,
            &region,
        );
        d.end_command_buffer(cmd)?;
        let cmds = [cmd];
        d.queue_submit(
            queue,
            &[vk::SubmitInfo::default().command_buffers(&cmds)],
            vk::Fence::null(),
        )?;
        d.queue_wait_idle(queue)?;
    }
    let pixels = target
        .readback
        .1
        .mapped_slice()
        .ok_or("read-back not mapped")?[..(W * H * 4) as usize]
        .to_vec();
    std::fs::create_dir_all(
        std::path::Path::new(&out)
            .parent()
            .unwrap_or(std::path::Path::new(".")),
    )?;
    caveclod_cli::snapshot::write_png(
        &RgbaImage {
            width: W,
            height: H,
            pixels,
        },
        std::path::Path::new(&out),
    )?;
    println!(
        "{} active polygons, wrote {out}",
        camera.active_polygon_count()
    );

    // Teardown: caveclod's objects, then the host's, in reverse order of creation.
    materials.destroy(&ctx);
    for r in [
        vertex_staging.destroy(&ctx),
        tex_staging.destroy(&ctx),
        tex.destroy(&ctx),
        vertices.destroy(&ctx),
        indices.destroy(&ctx),
        recorder.destroy(&ctx),
    ] {
        r?;
    }
    ctx.destroy()?;
    // SAFETY: the queue is idle.
    unsafe { d.destroy_command_pool(pool, None) };
    target.destroy(
        &d,
        &mut *allocator.lock().map_err(|_| "allocator poisoned")?,
    )?;
    drop(allocator);
    // SAFETY: every object made from the device and instance is destroyed.
    unsafe {
        d.destroy_device(None);
        instance.destroy_instance(None)
    };
    Ok(())
}
