//! The record path as a host engine drives it, for the paired frame-time comparison with
//! the headless `Renderer`: the host's own colour and depth images (from its own
//! allocator), command buffers and fences for two frames in flight, its own barriers and
//! dynamic rendering; caveclod's `Recorder` records the cameras.

use std::time::{Duration, Instant};

use caveclod_core::CameraState;
use caveclod_vulkan::ash::vk;
use caveclod_vulkan::gpu_allocator::vulkan::{
    Allocation, AllocationCreateDesc, AllocationScheme, Allocator, AllocatorCreateDesc,
};
use caveclod_vulkan::gpu_allocator::MemoryLocation;
use caveclod_vulkan::{
    ash, CameraIndices, Context, IndexSource, RecordCamera, Recorder, RecorderDesc, TargetFormats,
    Viewport,
};

use super::{look, or_exit, Scene, COLOURS, HEIGHT, WIDTH};

/// Frames in flight, as the headless renderer's default.
const SLOTS: usize = 2;

struct Attachment {
    image: vk::Image,
    view: vk::ImageView,
    memory: Allocation,
}

/// A host's frame loop over the record path.
pub struct HostSetup<'s, 'c> {
    allocator: Allocator,
    colour: Attachment,
    depth: Attachment,
    recorder: Recorder,
    pool: vk::CommandPool,
    slots: Vec<(vk::CommandBuffer, vk::Fence)>,
    frame: u64,
    indices: Vec<CameraIndices>,
    cams: &'s [CameraState<'c>],
    viewports: &'s [Viewport],
}

fn attachment(
    ctx: &Context,
    allocator: &mut Allocator,
    format: vk::Format,
    usage: vk::ImageUsageFlags,
    aspect: vk::ImageAspectFlags,
) -> Attachment {
    let d = &ctx.device;
    let info = vk::ImageCreateInfo::default()
        .image_type(vk::ImageType::TYPE_2D)
        .format(format)
        .extent(vk::Extent3D {
            width: WIDTH,
            height: HEIGHT,
            depth: 1,
        })
        .mip_levels(1)
        .array_layers(1)
        .samples(vk::SampleCountFlags::TYPE_1)
        .usage(usage);
    // SAFETY: valid create info.
    let image = or_exit(unsafe { d.create_image(&info, None) }, "host image");
    // SAFETY: `image` is alive.
    let requirements = unsafe { d.get_image_memory_requirements(image) };
    let memory = or_exit(
        allocator.allocate(&AllocationCreateDesc {
            name: "host attachment",
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        }),
        "host image memory",
    );
    // SAFETY: the allocation meets the image's requirements.
    or_exit(
        unsafe { d.bind_image_memory(image, memory.memory(), memory.offset()) },
        "bind",
    );
    let view_info = vk::ImageViewCreateInfo::default()
        .image(image)
        .view_type(vk::ImageViewType::TYPE_2D)
        .format(format)
        .subresource_range(range(aspect));
    // SAFETY: `image` is bound.
    let view = or_exit(unsafe { d.create_image_view(&view_info, None) }, "view");
    Attachment {
        image,
        view,
        memory,
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

fn to_attachment(
    image: vk::Image,
    aspect: vk::ImageAspectFlags,
    layout: vk::ImageLayout,
) -> vk::ImageMemoryBarrier2<'static> {
    let stages = vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT
        | vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS
        | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS;
    vk::ImageMemoryBarrier2::default()
        .src_stage_mask(stages)
        .src_access_mask(
            vk::AccessFlags2::COLOR_ATTACHMENT_WRITE
                | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE,
        )
        .dst_stage_mask(stages)
        .dst_access_mask(
            vk::AccessFlags2::COLOR_ATTACHMENT_WRITE
                | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ
                | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE,
        )
        .old_layout(vk::ImageLayout::UNDEFINED)
        .new_layout(layout)
        .image(image)
        .subresource_range(range(aspect))
}

impl<'s, 'c> HostSetup<'s, 'c> {
    pub fn new(ctx: &Context, cams: &'s [CameraState<'c>], viewports: &'s [Viewport]) -> Self {
        let mut allocator = or_exit(
            Allocator::new(&AllocatorCreateDesc {
                instance: ctx.instance.clone(),
                device: ctx.device.clone(),
                physical_device: ctx.physical_device,
                debug_settings: Default::default(),
                buffer_device_address: false,
                allocation_sizes: Default::default(),
            }),
            "host allocator",
        );
        let formats = TargetFormats::HEADLESS;
        let colour = attachment(
            ctx,
            &mut allocator,
            formats.colour,
            vk::ImageUsageFlags::COLOR_ATTACHMENT,
            vk::ImageAspectFlags::COLOR,
        );
        let depth = attachment(
            ctx,
            &mut allocator,
            formats.depth,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            vk::ImageAspectFlags::DEPTH,
        );
        let recorder = or_exit(
            Recorder::new(ctx, RecorderDesc::dynamic(formats)),
            "recorder",
        );
        let d = &ctx.device;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: valid create info.
        let pool = or_exit(unsafe { d.create_command_pool(&pool_info, None) }, "pool");
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .command_buffer_count(SLOTS as u32);
        // SAFETY: the pool is alive.
        let cmds = or_exit(
            unsafe { d.allocate_command_buffers(&alloc) },
            "command buffers",
        );
        let signalled = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
        let slots = cmds
            .into_iter()
            .map(|cmd| {
                // SAFETY: valid create info.
                let fence = unsafe { d.create_fence(&signalled, None) };
                (cmd, or_exit(fence, "fence"))
            })
            .collect();
        let surfaces = cams.first().map_or(0, |c| c.surface_polygons().len());
        let indices = (0..cams.len())
            .map(|i| CameraIndices::new(&format!("host camera {i}"), surfaces, SLOTS))
            .collect();
        Self {
            allocator,
            colour,
            depth,
            recorder,
            pool,
            slots,
            frame: 0,
            indices,
            cams,
            viewports,
        }
    }

    /// One frame, waited for: its latency.
    pub fn frame(&mut self, scene: &Scene<'_>) -> Duration {
        let t = Instant::now();
        let ctx = scene.ctx;
        let d = &ctx.device;
        let slot = (self.frame % SLOTS as u64) as usize;
        self.frame += 1;
        let (cmd, fence) = self.slots[slot];
        // SAFETY: the fence is alive; once it signalled, the slot's buffers are free.
        or_exit(
            unsafe { d.wait_for_fences(&[fence], true, u64::MAX) },
            "wait",
        );
        for (i, ind) in self.indices.iter_mut().enumerate() {
            let source = IndexSource::Camera {
                hierarchy: scene.h,
                camera: &self.cams[i],
            };
            or_exit(ind.fill(ctx, slot, source), "fill");
        }
        // SAFETY: the slot's previous submission completed (fence waited).
        or_exit(
            unsafe { d.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty()) },
            "reset",
        );
        // SAFETY: `cmd` is reset.
        or_exit(
            unsafe { d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()) },
            "begin",
        );
        self.begin_rendering(d, cmd);
        let draws: Vec<RecordCamera<'_>> = self
            .indices
            .iter()
            .enumerate()
            .map(|(i, ind)| RecordCamera {
                viewport: self.viewports[i],
                view_proj: look(i, scene.size).view_projection(self.viewports[i].aspect()),
                vertices: scene.vertices,
                indices: ind,
                colours: &COLOURS,
                materials: None,
                refine_morphs: None,
                morph: None,
                wireframe: false,
            })
            .collect();
        or_exit(self.recorder.record(ctx, cmd, slot, &draws), "record");
        // SAFETY: `cmd` is inside the rendering begun above.
        unsafe { d.cmd_end_rendering(cmd) };
        // SAFETY: `cmd` is recording.
        or_exit(unsafe { d.end_command_buffer(cmd) }, "end");
        // SAFETY: the fence is signalled and no longer used by pending work.
        or_exit(unsafe { d.reset_fences(&[fence]) }, "reset fence");
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
        ctx.with_queue(|queue| {
            // SAFETY: `cmd` is executable; the queue is locked.
            or_exit(unsafe { d.queue_submit2(queue, &submit, fence) }, "submit")
        });
        // SAFETY: the fence was just submitted.
        or_exit(
            unsafe { d.wait_for_fences(&[fence], true, u64::MAX) },
            "wait",
        );
        t.elapsed()
    }

    fn begin_rendering(&self, d: &ash::Device, cmd: vk::CommandBuffer) {
        let barriers = [
            to_attachment(
                self.colour.image,
                vk::ImageAspectFlags::COLOR,
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            ),
            to_attachment(
                self.depth.image,
                vk::ImageAspectFlags::DEPTH,
                vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
            ),
        ];
        // SAFETY: `cmd` is recording; the images are alive.
        unsafe {
            d.cmd_pipeline_barrier2(
                cmd,
                &vk::DependencyInfo::default().image_memory_barriers(&barriers),
            )
        };
        let colour = [vk::RenderingAttachmentInfo::default()
            .image_view(self.colour.view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(self.depth.view)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::DONT_CARE)
            .clear_value(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: 1.0,
                    stencil: 0,
                },
            });
        let info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent: vk::Extent2D {
                    width: WIDTH,
                    height: HEIGHT,
                },
            })
            .layer_count(1)
            .color_attachments(&colour)
            .depth_attachment(&depth);
        // SAFETY: `cmd` is recording; the attachments are in the layouts named.
        unsafe { d.cmd_begin_rendering(cmd, &info) };
    }

    pub fn destroy(mut self, ctx: &Context) {
        let d = &ctx.device;
        let fences: Vec<vk::Fence> = self.slots.iter().map(|s| s.1).collect();
        // SAFETY: the fences are alive.
        or_exit(
            unsafe { d.wait_for_fences(&fences, true, u64::MAX) },
            "wait",
        );
        for i in self.indices {
            or_exit(i.destroy(ctx), "destroy indices");
        }
        or_exit(self.recorder.destroy(ctx), "destroy recorder");
        // SAFETY: no pending work uses them (fences waited); each is destroyed once.
        unsafe {
            for f in fences {
                d.destroy_fence(f, None);
            }
            d.destroy_command_pool(self.pool, None);
            for a in [&self.colour, &self.depth] {
                d.destroy_image_view(a.view, None);
                d.destroy_image(a.image, None);
            }
        }
        for a in [self.colour, self.depth] {
            or_exit(self.allocator.free(a.memory), "free");
        }
    }
}
