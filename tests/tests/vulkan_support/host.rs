//! A host engine as the record-path tests need it: its own instance, debug messenger,
//! device, queue and allocator, and a target it owns (colour of any format and sample
//! count, resolve, depth-stencil), rendered through its own `VkRenderPass` or dynamic
//! rendering; caveclod only records into the host's command buffer.

use std::sync::{Arc, Mutex};

use caveclod_vulkan::ash::vk;
use caveclod_vulkan::gpu_allocator::vulkan::{
    Allocation, AllocationCreateDesc, AllocationScheme, Allocator, AllocatorCreateDesc,
};
use caveclod_vulkan::gpu_allocator::{self, MemoryLocation};
use caveclod_vulkan::{
    ash, Context, DebugMessenger, DeviceFeatures, HostDevice, RgbaImage, SharedAllocator,
    TargetFormats, ValidationLog, VALIDATION_LAYER,
};

use super::ok;

/// What a host engine owns.
pub struct Host {
    _entry: ash::Entry,
    pub instance: ash::Instance,
    messenger: DebugMessenger,
    pub device: ash::Device,
    pub physical_device: vk::PhysicalDevice,
    pub family: u32,
    pub queue: vk::Queue,
    pub allocator: SharedAllocator,
    pub log: Arc<ValidationLog>,
}

impl Host {
    /// Creates instance (validation + debug utils), messenger, device (lavapipe first) with
    /// `features` and queue the way an engine would, independently of caveclod-vulkan's
    /// headless path.
    pub fn new(features: DeviceFeatures) -> Self {
        let log = ValidationLog::new();
        // SAFETY: loading the system Vulkan loader.
        let entry = ok(unsafe { ash::Entry::load() }, "load Vulkan");
        let app = vk::ApplicationInfo::default().api_version(caveclod_vulkan::API_VERSION);
        let layers = [VALIDATION_LAYER.as_ptr()];
        let extensions = [ash::ext::debug_utils::NAME.as_ptr()];
        let info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        // SAFETY: valid create info.
        let instance = ok(unsafe { entry.create_instance(&info, None) }, "instance");
        let messenger = ok(
            DebugMessenger::new(&entry, &instance, log.clone()),
            "messenger",
        );
        // SAFETY: plain enumeration.
        let devices = ok(unsafe { instance.enumerate_physical_devices() }, "devices");
        // Lavapipe where it is installed (the reference images are its), else the first
        // device, so the host-frame tests also run on a machine with only a GPU driver.
        let physical_device = devices
            .iter()
            .copied()
            // SAFETY: enumerated from this instance.
            .find(|&pd| unsafe { instance.get_physical_device_properties(pd) }.device_type == vk::PhysicalDeviceType::CPU)
            .or_else(|| devices.first().copied())
            .unwrap_or_else(|| panic!("no Vulkan device"));
        // SAFETY: as above.
        let family =
            unsafe { instance.get_physical_device_queue_family_properties(physical_device) }
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
        let mut chain = features.chain();
        let dinfo = chain.push(vk::DeviceCreateInfo::default().queue_create_infos(&queues));
        // SAFETY: valid create info; callers ask for features caveclod requires, which lavapipe
        // and the GPUs it runs on support (the device creation fails otherwise).
        let device = ok(
            unsafe { instance.create_device(physical_device, &dinfo, None) },
            "device",
        );
        // SAFETY: queue 0 of `family` exists.
        let queue = unsafe { device.get_device_queue(family, 0) };
        let allocator = ok(
            Allocator::new(&AllocatorCreateDesc {
                instance: instance.clone(),
                device: device.clone(),
                physical_device,
                debug_settings: gpu_allocator::AllocatorDebugSettings::default(),
                buffer_device_address: false,
                allocation_sizes: gpu_allocator::AllocationSizes::default(),
            }),
            "host allocator",
        );
        Self {
            _entry: entry,
            instance,
            messenger,
            device,
            physical_device,
            family,
            queue,
            allocator: Arc::new(Mutex::new(allocator)),
            log,
        }
    }

    /// The handles for [`Context::from_raw`], claiming `enabled`.
    pub fn device(&self, enabled: DeviceFeatures) -> HostDevice {
        HostDevice {
            instance: self.instance.clone(),
            device: self.device.clone(),
            physical_device: self.physical_device,
            queue_family: self.family,
            queue: self.queue,
            allocator: Some(self.allocator.clone()),
            enabled,
        }
    }

    /// caveclod's context over this host's device, recording into the host's log.
    pub fn context(&self, enabled: DeviceFeatures) -> Context {
        // SAFETY: the handles are this host's live instance, device, queue and allocator,
        // which outlive the context (the tests destroy it first); `enabled` is what
        // `Host::new` enabled.
        ok(unsafe { Context::from_raw(self.device(enabled)) }, "embed")
            .with_validation_log(self.log.clone())
    }

    /// The first of `candidates` the device can use as a depth-stencil attachment.
    pub fn depth_format(&self, candidates: &[vk::Format]) -> vk::Format {
        candidates
            .iter()
            .copied()
            .find(|&f| {
                // SAFETY: the physical device belongs to the instance.
                let p = unsafe {
                    self.instance
                        .get_physical_device_format_properties(self.physical_device, f)
                };
                p.optimal_tiling_features
                    .contains(vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT)
            })
            .unwrap_or_else(|| panic!("none of {candidates:?} is a depth attachment format"))
    }

    /// Tears down what the host owns, in order, after checking that the allocator holds
    /// no allocation and the validation log is empty.
    pub fn destroy(self) {
        let allocator = match Arc::try_unwrap(self.allocator) {
            Ok(a) => a,
            Err(_) => panic!("a context kept a reference to the host's allocator"),
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
        unsafe { self.device.destroy_device(None) };
        self.messenger.destroy();
        // SAFETY: device and messenger are gone.
        unsafe { self.instance.destroy_instance(None) };
        let messages = self.log.take();
        assert!(
            messages.is_empty(),
            "validation messages:\n{}",
            messages.join("\n")
        );
    }
}

/// How the host begins its rendering.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HostRendering {
    /// Its own render pass (colour, depth-stencil, and a resolve attachment when
    /// multisampled).
    RenderPass,
    /// `vkCmdBeginRendering` (resolving through the attachment's resolve view).
    Dynamic,
}

struct HostImage {
    image: vk::Image,
    view: vk::ImageView,
    allocation: Option<Allocation>,
}

/// A target the host owns: attachments, render pass and framebuffer (for
/// [`HostRendering::RenderPass`]), a read-back buffer, a command buffer and a fence.
pub struct HostTarget {
    pub formats: TargetFormats,
    pub rendering: HostRendering,
    pub extent: vk::Extent2D,
    colour: HostImage,
    resolve: Option<HostImage>,
    depth: HostImage,
    pub render_pass: vk::RenderPass,
    framebuffer: vk::Framebuffer,
    readback: vk::Buffer,
    readback_memory: Option<Allocation>,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
}

fn image(
    host: &Host,
    extent: vk::Extent2D,
    format: vk::Format,
    samples: vk::SampleCountFlags,
    usage: vk::ImageUsageFlags,
    aspect: vk::ImageAspectFlags,
) -> HostImage {
    let d = &host.device;
    let info = vk::ImageCreateInfo::default()
        .image_type(vk::ImageType::TYPE_2D)
        .format(format)
        .extent(extent.into())
        .mip_levels(1)
        .array_layers(1)
        .samples(samples)
        .tiling(vk::ImageTiling::OPTIMAL)
        .usage(usage)
        .initial_layout(vk::ImageLayout::UNDEFINED);
    // SAFETY: valid create info.
    let image = ok(unsafe { d.create_image(&info, None) }, "host image");
    // SAFETY: `image` is alive.
    let requirements = unsafe { d.get_image_memory_requirements(image) };
    let allocation = ok(
        ok(host.allocator.lock().map_err(|_| "poisoned"), "allocator").allocate(
            &AllocationCreateDesc {
                name: "host attachment",
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            },
        ),
        "host image memory",
    );
    // SAFETY: the allocation satisfies the requirements.
    ok(
        unsafe { d.bind_image_memory(image, allocation.memory(), allocation.offset()) },
        "bind",
    );
    let view_info = vk::ImageViewCreateInfo::default()
        .image(image)
        .view_type(vk::ImageViewType::TYPE_2D)
        .format(format)
        .subresource_range(range(aspect));
    // SAFETY: `image` is bound.
    let view = ok(unsafe { d.create_image_view(&view_info, None) }, "view");
    HostImage {
        image,
        view,
        allocation: Some(allocation),
    }
}

fn range(aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: aspect,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 1,
    }
}

fn depth_aspect(format: vk::Format) -> vk::ImageAspectFlags {
    match format {
        vk::Format::D16_UNORM_S8_UINT
        | vk::Format::D24_UNORM_S8_UINT
        | vk::Format::D32_SFLOAT_S8_UINT => {
            vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
        }
        _ => vk::ImageAspectFlags::DEPTH,
    }
}

impl HostTarget {
    /// Makes the target; with [`HostRendering::RenderPass`], also the render pass
    /// (subpass 0 draws) and framebuffer.
    pub fn new(
        host: &Host,
        formats: TargetFormats,
        rendering: HostRendering,
        w: u32,
        h: u32,
    ) -> Self {
        let extent = vk::Extent2D {
            width: w,
            height: h,
        };
        let multisampled = formats.samples != vk::SampleCountFlags::TYPE_1;
        let colour_usage = if multisampled {
            vk::ImageUsageFlags::COLOR_ATTACHMENT
        } else {
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC
        };
        let colour = image(
            host,
            extent,
            formats.colour,
            formats.samples,
            colour_usage,
            vk::ImageAspectFlags::COLOR,
        );
        let resolve = multisampled.then(|| {
            image(
                host,
                extent,
                formats.colour,
                vk::SampleCountFlags::TYPE_1,
                vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
                vk::ImageAspectFlags::COLOR,
            )
        });
        let depth = image(
            host,
            extent,
            formats.depth,
            formats.samples,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            depth_aspect(formats.depth),
        );
        let (render_pass, framebuffer) = match rendering {
            HostRendering::RenderPass => render_pass_and_framebuffer(
                host,
                formats,
                extent,
                &colour,
                resolve.as_ref(),
                &depth,
            ),
            HostRendering::Dynamic => (vk::RenderPass::null(), vk::Framebuffer::null()),
        };
        let d = &host.device;
        let size = u64::from(w) * u64::from(h) * 4;
        let binfo = vk::BufferCreateInfo::default()
            .size(size)
            .usage(vk::BufferUsageFlags::TRANSFER_DST);
        // SAFETY: valid create info.
        let readback = ok(unsafe { d.create_buffer(&binfo, None) }, "read-back buffer");
        // SAFETY: `readback` is alive.
        let requirements = unsafe { d.get_buffer_memory_requirements(readback) };
        let memory = ok(
            ok(host.allocator.lock().map_err(|_| "poisoned"), "allocator").allocate(
                &AllocationCreateDesc {
                    name: "host read-back",
                    requirements,
                    location: MemoryLocation::GpuToCpu,
                    linear: true,
                    allocation_scheme: AllocationScheme::GpuAllocatorManaged,
                },
            ),
            "read-back memory",
        );
        // SAFETY: the allocation satisfies the requirements.
        ok(
            unsafe { d.bind_buffer_memory(readback, memory.memory(), memory.offset()) },
            "bind",
        );
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(host.family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
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
        // SAFETY: valid create info.
        let fence = ok(
            unsafe { d.create_fence(&vk::FenceCreateInfo::default(), None) },
            "fence",
        );
        Self {
            formats,
            rendering,
            extent,
            colour,
            resolve,
            depth,
            render_pass,
            framebuffer,
            readback,
            readback_memory: Some(memory),
            pool,
            cmd,
            fence,
        }
    }

    /// One frame the host's way: begin its rendering (clearing to black, depth 1), let
    /// `record` record caveclod's draws into its command buffer, end, copy the (resolved)
    /// colour to the read-back buffer, submit, wait, and return the pixels as RGBA8 (BGRA
    /// formats swizzled; sRGB values as stored).
    pub fn frame(&mut self, host: &Host, record: impl FnOnce(vk::CommandBuffer)) -> RgbaImage {
        let d = &host.device;
        let cmd = self.cmd;
        // SAFETY: the previous submission of `cmd` was waited for.
        ok(
            unsafe { d.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty()) },
            "reset",
        );
        // SAFETY: `cmd` is reset.
        ok(
            unsafe { d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()) },
            "begin",
        );
        match self.rendering {
            HostRendering::RenderPass => self.begin_render_pass(d, cmd),
            HostRendering::Dynamic => self.begin_dynamic(d, cmd),
        }
        record(cmd);
        // SAFETY: `cmd` is inside the rendering begun above.
        unsafe {
            match self.rendering {
                HostRendering::RenderPass => d.cmd_end_render_pass(cmd),
                HostRendering::Dynamic => d.cmd_end_rendering(cmd),
            }
        }
        self.copy_out(d, cmd);
        // SAFETY: `cmd` is recording.
        ok(unsafe { d.end_command_buffer(cmd) }, "end");
        self.submit_and_wait(host);
        self.pixels()
    }

    /// Records `record` outside any rendering into the host's command buffer, submits it
    /// and waits (the host's uploads).
    pub fn submit(&mut self, host: &Host, record: impl FnOnce(vk::CommandBuffer)) {
        let d = &host.device;
        let cmd = self.cmd;
        // SAFETY: the previous submission of `cmd` was waited for.
        ok(
            unsafe { d.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty()) },
            "reset",
        );
        // SAFETY: `cmd` is reset.
        ok(
            unsafe { d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()) },
            "begin",
        );
        record(cmd);
        // SAFETY: `cmd` is recording.
        ok(unsafe { d.end_command_buffer(cmd) }, "end");
        self.submit_and_wait(host);
    }

    fn submit_and_wait(&self, host: &Host) {
        let d = &host.device;
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(self.cmd)];
        let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
        // SAFETY: `cmd` is executable; the fence is unsignalled.
        ok(
            unsafe { d.queue_submit2(host.queue, &submit, self.fence) },
            "submit",
        );
        // SAFETY: the fence was submitted.
        ok(
            unsafe { d.wait_for_fences(&[self.fence], true, u64::MAX) },
            "wait",
        );
        // SAFETY: the fence is signalled and no longer in use.
        ok(unsafe { d.reset_fences(&[self.fence]) }, "reset fence");
    }

    fn clear_values() -> [vk::ClearValue; 2] {
        [
            vk::ClearValue {
                color: vk::ClearColorValue {
                    float32: [0.0, 0.0, 0.0, 1.0],
                },
            },
            vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: 1.0,
                    stencil: 0,
                },
            },
        ]
    }

    fn begin_render_pass(&self, d: &ash::Device, cmd: vk::CommandBuffer) {
        let clears = Self::clear_values();
        let clears = [clears[0], clears[1], clears[0]];
        let n = if self.resolve.is_some() { 3 } else { 2 };
        let begin = vk::RenderPassBeginInfo::default()
            .render_pass(self.render_pass)
            .framebuffer(self.framebuffer)
            .render_area(vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent: self.extent,
            })
            .clear_values(&clears[..n]);
        // SAFETY: `cmd` is recording; pass and framebuffer are alive and compatible.
        unsafe { d.cmd_begin_render_pass(cmd, &begin, vk::SubpassContents::INLINE) };
    }

    fn begin_dynamic(&self, d: &ash::Device, cmd: vk::CommandBuffer) {
        let mut barriers = vec![
            layout_barrier(
                self.colour.image,
                vk::ImageAspectFlags::COLOR,
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            ),
            layout_barrier(
                self.depth.image,
                depth_aspect(self.formats.depth),
                vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
            ),
        ];
        if let Some(r) = &self.resolve {
            barriers.push(layout_barrier(
                r.image,
                vk::ImageAspectFlags::COLOR,
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            ));
        }
        let dep = vk::DependencyInfo::default().image_memory_barriers(&barriers);
        // SAFETY: `cmd` is recording; the images are alive.
        unsafe { d.cmd_pipeline_barrier2(cmd, &dep) };
        let clears = Self::clear_values();
        let mut colour = vk::RenderingAttachmentInfo::default()
            .image_view(self.colour.view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(clears[0]);
        if let Some(r) = &self.resolve {
            colour = colour
                .resolve_mode(vk::ResolveModeFlags::AVERAGE)
                .resolve_image_view(r.view)
                .resolve_image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
        }
        let colour = [colour];
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(self.depth.view)
            .image_layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::DONT_CARE)
            .clear_value(clears[1]);
        let mut info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent: self.extent,
            })
            .layer_count(1)
            .color_attachments(&colour)
            .depth_attachment(&depth);
        if depth_aspect(self.formats.depth).contains(vk::ImageAspectFlags::STENCIL) {
            info = info.stencil_attachment(&depth);
        }
        // SAFETY: `cmd` is recording; the attachments are in the layouts named.
        unsafe { d.cmd_begin_rendering(cmd, &info) };
    }

    /// The single-sample colour image: the resolve target, or the colour itself (after a
    /// [`frame`](Self::frame), in `TRANSFER_SRC_OPTIMAL`).
    pub fn single_sample(&self) -> vk::Image {
        self.resolve.as_ref().map_or(self.colour.image, |r| r.image)
    }

    fn copy_out(&self, d: &ash::Device, cmd: vk::CommandBuffer) {
        let image = self.single_sample();
        if self.rendering == HostRendering::Dynamic {
            let to_src = [vk::ImageMemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT)
                .src_access_mask(vk::AccessFlags2::COLOR_ATTACHMENT_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::COPY)
                .dst_access_mask(vk::AccessFlags2::TRANSFER_READ)
                .old_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .new_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
                .image(image)
                .subresource_range(range(vk::ImageAspectFlags::COLOR))];
            let dep = vk::DependencyInfo::default().image_memory_barriers(&to_src);
            // SAFETY: `cmd` is recording outside rendering.
            unsafe { d.cmd_pipeline_barrier2(cmd, &dep) };
        }
        let region = [vk::BufferImageCopy {
            buffer_offset: 0,
            buffer_row_length: 0,
            buffer_image_height: 0,
            image_subresource: vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            },
            image_offset: vk::Offset3D::default(),
            image_extent: self.extent.into(),
        }];
        let to_host = [vk::BufferMemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COPY)
            .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::HOST)
            .dst_access_mask(vk::AccessFlags2::HOST_READ)
            .buffer(self.readback)
            .size(vk::WHOLE_SIZE)];
        let dep = vk::DependencyInfo::default().buffer_memory_barriers(&to_host);
        // SAFETY: `cmd` is recording outside rendering; the image is in TRANSFER_SRC
        // layout (the render pass's final layout, or the barrier above); the buffer holds
        // the whole image.
        unsafe {
            d.cmd_copy_image_to_buffer(
                cmd,
                image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                self.readback,
                &region,
            );
            d.cmd_pipeline_barrier2(cmd, &dep);
        }
    }

    fn pixels(&self) -> RgbaImage {
        let n = self.extent.width as usize * self.extent.height as usize * 4;
        let bytes = self
            .readback_memory
            .as_ref()
            .and_then(|m| m.mapped_slice())
            .unwrap_or_else(|| panic!("read-back memory is not mapped"));
        let mut pixels = bytes[..n].to_vec();
        if matches!(
            self.formats.colour,
            vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB
        ) {
            for p in pixels.chunks_exact_mut(4) {
                p.swap(0, 2);
            }
        }
        RgbaImage {
            width: self.extent.width,
            height: self.extent.height,
            pixels,
        }
    }

    /// Destroys what the target made. The GPU must be idle.
    pub fn destroy(mut self, host: &Host) {
        let d = &host.device;
        let mut allocator = ok(host.allocator.lock().map_err(|_| "poisoned"), "allocator");
        // SAFETY: the GPU is idle; each object is destroyed once.
        unsafe {
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.pool, None);
            d.destroy_buffer(self.readback, None);
            if self.framebuffer != vk::Framebuffer::null() {
                d.destroy_framebuffer(self.framebuffer, None);
                d.destroy_render_pass(self.render_pass, None);
            }
        }
        if let Some(m) = self.readback_memory.take() {
            ok(allocator.free(m), "free read-back");
        }
        let images = [Some(self.colour), self.resolve, Some(self.depth)];
        for mut img in images.into_iter().flatten() {
            // SAFETY: as above.
            unsafe {
                d.destroy_image_view(img.view, None);
                d.destroy_image(img.image, None);
            }
            if let Some(a) = img.allocation.take() {
                ok(allocator.free(a), "free image");
            }
        }
    }
}

fn layout_barrier(
    image: vk::Image,
    aspect: vk::ImageAspectFlags,
    layout: vk::ImageLayout,
) -> vk::ImageMemoryBarrier2<'static> {
    vk::ImageMemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)
        .old_layout(vk::ImageLayout::UNDEFINED)
        .new_layout(layout)
        .image(image)
        .subresource_range(range(aspect))
}

/// The host's render pass: attachment 0 colour (cleared; stored unless resolved),
/// attachment 1 depth-stencil (cleared, not stored), attachment 2 the resolve target when
/// multisampled; colour ends in `TRANSFER_SRC_OPTIMAL` for the copy-out.
fn render_pass_and_framebuffer(
    host: &Host,
    formats: TargetFormats,
    extent: vk::Extent2D,
    colour: &HostImage,
    resolve: Option<&HostImage>,
    depth: &HostImage,
) -> (vk::RenderPass, vk::Framebuffer) {
    let multisampled = resolve.is_some();
    let mut attachments = vec![
        vk::AttachmentDescription::default()
            .format(formats.colour)
            .samples(formats.samples)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(if multisampled {
                vk::AttachmentStoreOp::DONT_CARE
            } else {
                vk::AttachmentStoreOp::STORE
            })
            .initial_layout(vk::ImageLayout::UNDEFINED)
            .final_layout(if multisampled {
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL
            } else {
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL
            }),
        vk::AttachmentDescription::default()
            .format(formats.depth)
            .samples(formats.samples)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::DONT_CARE)
            .stencil_load_op(vk::AttachmentLoadOp::CLEAR)
            .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
            .initial_layout(vk::ImageLayout::UNDEFINED)
            .final_layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL),
    ];
    if multisampled {
        attachments.push(
            vk::AttachmentDescription::default()
                .format(formats.colour)
                .samples(vk::SampleCountFlags::TYPE_1)
                .load_op(vk::AttachmentLoadOp::DONT_CARE)
                .store_op(vk::AttachmentStoreOp::STORE)
                .initial_layout(vk::ImageLayout::UNDEFINED)
                .final_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL),
        );
    }
    let colour_ref = [vk::AttachmentReference {
        attachment: 0,
        layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
    }];
    let depth_ref = vk::AttachmentReference {
        attachment: 1,
        layout: vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
    };
    let resolve_ref = [vk::AttachmentReference {
        attachment: 2,
        layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
    }];
    let mut subpass = vk::SubpassDescription::default()
        .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
        .color_attachments(&colour_ref)
        .depth_stencil_attachment(&depth_ref);
    if multisampled {
        subpass = subpass.resolve_attachments(&resolve_ref);
    }
    let subpasses = [subpass];
    let dependencies = [
        vk::SubpassDependency {
            src_subpass: vk::SUBPASS_EXTERNAL,
            dst_subpass: 0,
            src_stage_mask: vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT
                | vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS
                | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS
                | vk::PipelineStageFlags::TRANSFER,
            dst_stage_mask: vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT
                | vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS
                | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS,
            src_access_mask: vk::AccessFlags::COLOR_ATTACHMENT_WRITE
                | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE
                | vk::AccessFlags::TRANSFER_READ,
            dst_access_mask: vk::AccessFlags::COLOR_ATTACHMENT_WRITE
                | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_READ
                | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE,
            dependency_flags: vk::DependencyFlags::empty(),
        },
        vk::SubpassDependency {
            src_subpass: 0,
            dst_subpass: vk::SUBPASS_EXTERNAL,
            src_stage_mask: vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
            dst_stage_mask: vk::PipelineStageFlags::TRANSFER,
            src_access_mask: vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            dst_access_mask: vk::AccessFlags::TRANSFER_READ,
            dependency_flags: vk::DependencyFlags::empty(),
        },
    ];
    let info = vk::RenderPassCreateInfo::default()
        .attachments(&attachments)
        .subpasses(&subpasses)
        .dependencies(&dependencies);
    let d = &host.device;
    // SAFETY: valid create info referring to locals.
    let render_pass = ok(unsafe { d.create_render_pass(&info, None) }, "render pass");
    let mut views = vec![colour.view, depth.view];
    if let Some(r) = resolve {
        views.push(r.view);
    }
    let fb = vk::FramebufferCreateInfo::default()
        .render_pass(render_pass)
        .attachments(&views)
        .width(extent.width)
        .height(extent.height)
        .layers(1);
    // SAFETY: the views match the render pass's attachments.
    let framebuffer = ok(unsafe { d.create_framebuffer(&fb, None) }, "framebuffer");
    (render_pass, framebuffer)
}
