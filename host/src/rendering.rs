//! What a host records around caveclod's draws: the attachments into their layouts and the
//! rendering begun (dynamic rendering, or the host's own render pass), and after it the
//! colour image copied out for the host and handed to presentation.

use caveclod_vulkan::ash::{self, vk};
use caveclod_vulkan::TargetFormats;

use crate::error::{Result, VkExt};
use crate::image::{aspect, range};

/// The images one frame renders into.
#[derive(Clone, Copy, Debug)]
pub struct Attachments {
    /// The colour attachment (multisampled, or the image itself).
    pub colour: (vk::Image, vk::ImageView),
    /// The single-sample image a multisampled colour resolves into.
    pub resolve: Option<(vk::Image, vk::ImageView)>,
    /// The depth(-stencil) attachment and its format.
    pub depth: (vk::Image, vk::ImageView, vk::Format),
    /// The size of all of them.
    pub extent: vk::Extent2D,
}

impl Attachments {
    /// The single-sample colour image: the resolve target, or the colour itself.
    pub fn single_sample(&self) -> vk::Image {
        self.resolve.map_or(self.colour.0, |r| r.0)
    }
}

/// The clear values: colour `clear` (linear), depth 1, stencil 0.
fn clear_values(clear: [f32; 4]) -> (vk::ClearValue, vk::ClearValue) {
    (
        vk::ClearValue {
            color: vk::ClearColorValue { float32: clear },
        },
        vk::ClearValue {
            depth_stencil: vk::ClearDepthStencilValue {
                depth: 1.0,
                stencil: 0,
            },
        },
    )
}

/// Records the attachments' transitions from whatever they held into attachment layouts
/// and begins dynamic rendering over all of `a`, clearing colour to `clear` and depth to 1;
/// a multisampled colour resolves (average) into `a.resolve`. The colour waits for earlier
/// frames' attachment writes and copies of it (and, for a swapchain image, for the acquire
/// semaphore the submission waits on at the colour output stage); the depth for earlier
/// depth tests, so one depth image can serve every frame in flight.
pub fn begin_dynamic(d: &ash::Device, cmd: vk::CommandBuffer, a: &Attachments, clear: [f32; 4]) {
    let mut barriers = vec![
        colour_barrier(a.colour.0),
        depth_barrier(a.depth.0, aspect(a.depth.2)),
    ];
    if let Some((image, _)) = a.resolve {
        barriers.push(colour_barrier(image));
    }
    let dep = vk::DependencyInfo::default().image_memory_barriers(&barriers);
    let (colour_clear, depth_clear) = clear_values(clear);
    let mut colour = vk::RenderingAttachmentInfo::default()
        .image_view(a.colour.1)
        .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::STORE)
        .clear_value(colour_clear);
    if let Some((_, view)) = a.resolve {
        colour = colour
            .resolve_mode(vk::ResolveModeFlags::AVERAGE)
            .resolve_image_view(view)
            .resolve_image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
    }
    let colour = [colour];
    let depth = vk::RenderingAttachmentInfo::default()
        .image_view(a.depth.1)
        .image_layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::DONT_CARE)
        .clear_value(depth_clear);
    let mut info = vk::RenderingInfo::default()
        .render_area(vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent: a.extent,
        })
        .layer_count(1)
        .color_attachments(&colour)
        .depth_attachment(&depth);
    if aspect(a.depth.2).contains(vk::ImageAspectFlags::STENCIL) {
        info = info.stencil_attachment(&depth);
    }
    // SAFETY: `cmd` is recording outside rendering; the images and views are alive and the
    // barrier gives them the layouts the rendering names.
    unsafe {
        d.cmd_pipeline_barrier2(cmd, &dep);
        d.cmd_begin_rendering(cmd, &info);
    }
}

/// Records the end of the rendering [`begin_dynamic`] began.
pub fn end_dynamic(d: &ash::Device, cmd: vk::CommandBuffer) {
    // SAFETY: `cmd` is inside the dynamic rendering `begin_dynamic` began (the caller's
    // contract).
    unsafe { d.cmd_end_rendering(cmd) };
}

/// A colour image from whatever it held into `COLOR_ATTACHMENT_OPTIMAL`, after earlier
/// attachment writes and copies of it.
fn colour_barrier(image: vk::Image) -> vk::ImageMemoryBarrier2<'static> {
    vk::ImageMemoryBarrier2::default()
        .src_stage_mask(
            vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT | vk::PipelineStageFlags2::COPY,
        )
        .src_access_mask(vk::AccessFlags2::COLOR_ATTACHMENT_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT)
        .dst_access_mask(
            vk::AccessFlags2::COLOR_ATTACHMENT_WRITE | vk::AccessFlags2::COLOR_ATTACHMENT_READ,
        )
        .old_layout(vk::ImageLayout::UNDEFINED)
        .new_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(range(vk::ImageAspectFlags::COLOR))
}

/// A depth(-stencil) image from whatever it held into its attachment layout, after earlier
/// depth tests.
fn depth_barrier(
    image: vk::Image,
    aspect: vk::ImageAspectFlags,
) -> vk::ImageMemoryBarrier2<'static> {
    let tests = vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS
        | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS;
    vk::ImageMemoryBarrier2::default()
        .src_stage_mask(tests)
        .src_access_mask(vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE)
        .dst_stage_mask(tests)
        .dst_access_mask(
            vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ
                | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE,
        )
        .old_layout(vk::ImageLayout::UNDEFINED)
        .new_layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(range(aspect))
}

/// Records the start of the host's render pass over `framebuffer` (`extent`), clearing as
/// [`begin_dynamic`] does; `resolve` says whether it has the third, resolve attachment.
pub fn begin_render_pass(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    render_pass: vk::RenderPass,
    framebuffer: vk::Framebuffer,
    extent: vk::Extent2D,
    resolve: bool,
    clear: [f32; 4],
) {
    let (colour, depth) = clear_values(clear);
    let clears = [colour, depth, colour];
    let n = if resolve { 3 } else { 2 };
    let begin = vk::RenderPassBeginInfo::default()
        .render_pass(render_pass)
        .framebuffer(framebuffer)
        .render_area(vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent,
        })
        .clear_values(&clears[..n]);
    // SAFETY: `cmd` is recording outside rendering; pass and framebuffer are alive and
    // compatible (the caller's contract).
    unsafe { d.cmd_begin_render_pass(cmd, &begin, vk::SubpassContents::INLINE) };
}

/// Records, after the rendering, the copy of the single-sample colour `image` (in `layout`:
/// `COLOR_ATTACHMENT_OPTIMAL` after dynamic rendering, `TRANSFER_SRC_OPTIMAL` after the
/// host's render pass) into `buffer` (`4 * width * height` bytes), and the barrier that
/// makes the copy visible to host reads. The image is left in `TRANSFER_SRC_OPTIMAL`.
pub fn copy_out(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    layout: vk::ImageLayout,
    extent: vk::Extent2D,
    buffer: vk::Buffer,
) {
    if layout != vk::ImageLayout::TRANSFER_SRC_OPTIMAL {
        let to_src = [vk::ImageMemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT)
            .src_access_mask(vk::AccessFlags2::COLOR_ATTACHMENT_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::COPY)
            .dst_access_mask(vk::AccessFlags2::TRANSFER_READ)
            .old_layout(layout)
            .new_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image)
            .subresource_range(range(vk::ImageAspectFlags::COLOR))];
        let dep = vk::DependencyInfo::default().image_memory_barriers(&to_src);
        // SAFETY: `cmd` is recording outside rendering; the image is alive in `layout`.
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
        image_extent: extent.into(),
    }];
    let to_host = [vk::BufferMemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::COPY)
        .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::HOST)
        .dst_access_mask(vk::AccessFlags2::HOST_READ)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .buffer(buffer)
        .size(vk::WHOLE_SIZE)];
    let dep = vk::DependencyInfo::default().buffer_memory_barriers(&to_host);
    // SAFETY: `cmd` is recording outside rendering; the image is in TRANSFER_SRC layout
    // (given, or the barrier above); the buffer holds the whole image (the caller's
    // contract).
    unsafe {
        d.cmd_copy_image_to_buffer(
            cmd,
            image,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            buffer,
            &region,
        );
        d.cmd_pipeline_barrier2(cmd, &dep);
    }
}

/// Records the transition of a swapchain image from `layout` (after its rendering, or
/// after [`copy_out`]) to `PRESENT_SRC_KHR`; the submission's semaphore orders the
/// presentation after it.
pub fn to_present(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    layout: vk::ImageLayout,
) {
    let (stage, access) = match layout {
        vk::ImageLayout::TRANSFER_SRC_OPTIMAL => {
            (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::NONE)
        }
        _ => (
            vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
            vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
        ),
    };
    let barrier = [vk::ImageMemoryBarrier2::default()
        .src_stage_mask(stage)
        .src_access_mask(access)
        .dst_stage_mask(vk::PipelineStageFlags2::NONE)
        .dst_access_mask(vk::AccessFlags2::NONE)
        .old_layout(layout)
        .new_layout(vk::ImageLayout::PRESENT_SRC_KHR)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(range(vk::ImageAspectFlags::COLOR))];
    let dep = vk::DependencyInfo::default().image_memory_barriers(&barrier);
    // SAFETY: `cmd` is recording outside rendering; the image is alive in `layout`.
    unsafe { d.cmd_pipeline_barrier2(cmd, &dep) };
}

/// The host's render pass for `formats`: attachment 0 colour (cleared; stored unless
/// resolved), attachment 1 depth-stencil (cleared, not stored), attachment 2 the resolve
/// target when multisampled; the single-sample colour ends in `TRANSFER_SRC_OPTIMAL` for
/// the copy-out. Subpass 0 draws.
pub fn create_render_pass(d: &ash::Device, formats: TargetFormats) -> Result<vk::RenderPass> {
    let multisampled = formats.samples != vk::SampleCountFlags::TYPE_1;
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
    let dependencies = render_pass_dependencies();
    let info = vk::RenderPassCreateInfo::default()
        .attachments(&attachments)
        .subpasses(&subpasses)
        .dependencies(&dependencies);
    // SAFETY: valid create info referring to locals.
    unsafe { d.create_render_pass(&info, None) }.vk("vkCreateRenderPass")
}

/// Into the subpass after earlier frames' attachment writes and copies; out of it before
/// the copy-out.
fn render_pass_dependencies() -> [vk::SubpassDependency; 2] {
    let attachments = vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT
        | vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS
        | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS;
    [
        vk::SubpassDependency {
            src_subpass: vk::SUBPASS_EXTERNAL,
            dst_subpass: 0,
            src_stage_mask: attachments | vk::PipelineStageFlags::TRANSFER,
            dst_stage_mask: attachments,
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
    ]
}

/// A framebuffer of `render_pass` over `a`'s views (colour, depth, resolve).
pub fn create_framebuffer(
    d: &ash::Device,
    render_pass: vk::RenderPass,
    a: &Attachments,
) -> Result<vk::Framebuffer> {
    let mut views = vec![a.colour.1, a.depth.1];
    if let Some((_, view)) = a.resolve {
        views.push(view);
    }
    let info = vk::FramebufferCreateInfo::default()
        .render_pass(render_pass)
        .attachments(&views)
        .width(a.extent.width)
        .height(a.extent.height)
        .layers(1);
    // SAFETY: the views match the render pass's attachments (the caller's contract).
    unsafe { d.create_framebuffer(&info, None) }.vk("vkCreateFramebuffer")
}
