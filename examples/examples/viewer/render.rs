//! The host's part of a frame's command buffer around what caveclod and egui record: layout
//! transitions, dynamic rendering with a cleared colour and depth attachment, and at the
//! end the transition to presentation, optionally through a copy of the image into a
//! read-back buffer (the screenshot).

use caveclod_vulkan::ash::{self, vk};

use crate::swapchain::{colour_range, range};

/// The attachments of one frame.
#[derive(Clone, Copy, Debug)]
pub struct FrameTarget {
    pub colour: vk::Image,
    pub colour_view: vk::ImageView,
    pub depth: vk::Image,
    pub depth_view: vk::ImageView,
    pub extent: vk::Extent2D,
}

/// Resets and begins `cmd` (its pool allows resetting it), for the work recorded before
/// the rendering (caveclod's geomorph dispatches).
pub fn open(d: &ash::Device, cmd: vk::CommandBuffer) -> Result<(), String> {
    let begin =
        vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
    // SAFETY: `cmd`'s last submission completed (its slot's fence was waited for) and its
    // pool allows resetting it.
    unsafe {
        d.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())
            .map_err(|e| format!("vkResetCommandBuffer: {e}"))?;
        d.begin_command_buffer(cmd, &begin)
            .map_err(|e| format!("vkBeginCommandBuffer: {e}"))?;
    }
    Ok(())
}

/// Transitions the attachments of `cmd` (begun by [`open`]) from whatever they held and
/// begins dynamic rendering, clearing colour to `clear` (linear) and depth to 1.
pub fn begin(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    t: &FrameTarget,
    clear: [f32; 4],
) -> Result<(), String> {
    let barriers = [
        // Waits for the acquire semaphore, which the submission waits for at the colour
        // output stage.
        vk::ImageMemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT)
            .src_access_mask(vk::AccessFlags2::NONE)
            .dst_stage_mask(vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT)
            .dst_access_mask(
                vk::AccessFlags2::COLOR_ATTACHMENT_WRITE | vk::AccessFlags2::COLOR_ATTACHMENT_READ,
            )
            .old_layout(vk::ImageLayout::UNDEFINED)
            .new_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .image(t.colour)
            .subresource_range(colour_range()),
        // One depth image serves both frames in flight: wait for the previous frame's
        // depth writes before clearing it.
        vk::ImageMemoryBarrier2::default()
            .src_stage_mask(
                vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS
                    | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS,
            )
            .src_access_mask(vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE)
            .dst_stage_mask(
                vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS
                    | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS,
            )
            .dst_access_mask(
                vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ
                    | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE,
            )
            .old_layout(vk::ImageLayout::UNDEFINED)
            .new_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .image(t.depth)
            .subresource_range(range(vk::ImageAspectFlags::DEPTH)),
    ];
    let dep = vk::DependencyInfo::default().image_memory_barriers(&barriers);
    let colour = [vk::RenderingAttachmentInfo::default()
        .image_view(t.colour_view)
        .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::STORE)
        .clear_value(vk::ClearValue {
            color: vk::ClearColorValue { float32: clear },
        })];
    let depth = vk::RenderingAttachmentInfo::default()
        .image_view(t.depth_view)
        .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::DONT_CARE)
        .clear_value(vk::ClearValue {
            depth_stencil: vk::ClearDepthStencilValue {
                depth: 1.0,
                stencil: 0,
            },
        });
    let rendering = vk::RenderingInfo::default()
        .render_area(vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent: t.extent,
        })
        .layer_count(1)
        .color_attachments(&colour)
        .depth_attachment(&depth);
    // SAFETY: `cmd` is recording; the images and views are alive and the views match the
    // layouts the barrier gives them.
    unsafe {
        d.cmd_pipeline_barrier2(cmd, &dep);
        d.cmd_begin_rendering(cmd, &rendering);
    }
    Ok(())
}

/// Ends the rendering, copies the colour image into `capture` (a buffer of
/// `4 * width * height` bytes, made visible to host reads) when given, transitions it for
/// presentation and ends `cmd`.
pub fn end(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    t: &FrameTarget,
    capture: Option<vk::Buffer>,
) -> Result<(), String> {
    // SAFETY: `cmd` is inside the rendering `begin` began.
    unsafe { d.cmd_end_rendering(cmd) };
    let to_present = |from: vk::ImageLayout, stage: vk::PipelineStageFlags2, access| {
        vk::ImageMemoryBarrier2::default()
            .src_stage_mask(stage)
            .src_access_mask(access)
            .dst_stage_mask(vk::PipelineStageFlags2::NONE)
            .dst_access_mask(vk::AccessFlags2::NONE)
            .old_layout(from)
            .new_layout(vk::ImageLayout::PRESENT_SRC_KHR)
            .image(t.colour)
            .subresource_range(colour_range())
    };
    match capture {
        None => {
            let barrier = [to_present(
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
            )];
            let dep = vk::DependencyInfo::default().image_memory_barriers(&barrier);
            // SAFETY: `cmd` is recording outside rendering; the image is alive.
            unsafe { d.cmd_pipeline_barrier2(cmd, &dep) };
        }
        Some(buffer) => record_capture(d, cmd, t, buffer, to_present),
    }
    // SAFETY: `cmd` is recording.
    unsafe { d.end_command_buffer(cmd) }.map_err(|e| format!("vkEndCommandBuffer: {e}"))
}

/// The copy of the colour image into `buffer` between a transition to transfer source and
/// the one to presentation, then the barrier that makes the copy visible to the host.
fn record_capture<'a>(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    t: &FrameTarget,
    buffer: vk::Buffer,
    to_present: impl Fn(
        vk::ImageLayout,
        vk::PipelineStageFlags2,
        vk::AccessFlags2,
    ) -> vk::ImageMemoryBarrier2<'a>,
) {
    let to_transfer = [vk::ImageMemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT)
        .src_access_mask(vk::AccessFlags2::COLOR_ATTACHMENT_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::COPY)
        .dst_access_mask(vk::AccessFlags2::TRANSFER_READ)
        .old_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
        .new_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
        .image(t.colour)
        .subresource_range(colour_range())];
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
        image_extent: t.extent.into(),
    }];
    let after = [to_present(
        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        vk::PipelineStageFlags2::COPY,
        vk::AccessFlags2::NONE,
    )];
    let to_host = [vk::BufferMemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::COPY)
        .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::HOST)
        .dst_access_mask(vk::AccessFlags2::HOST_READ)
        .buffer(buffer)
        .offset(0)
        .size(vk::WHOLE_SIZE)];
    let first = vk::DependencyInfo::default().image_memory_barriers(&to_transfer);
    let last = vk::DependencyInfo::default()
        .image_memory_barriers(&after)
        .buffer_memory_barriers(&to_host);
    // SAFETY: `cmd` is recording outside rendering; `buffer` holds the image's
    // `4 * width * height` bytes (the caller's contract) and has transfer-destination usage.
    unsafe {
        d.cmd_pipeline_barrier2(cmd, &first);
        d.cmd_copy_image_to_buffer(
            cmd,
            t.colour,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            buffer,
            &region,
        );
        d.cmd_pipeline_barrier2(cmd, &last);
    }
}

/// Submits `cmd` waiting for `wait` at the colour output stage, signalling `signal` and
/// `fence`.
pub fn submit(
    d: &ash::Device,
    queue: vk::Queue,
    cmd: vk::CommandBuffer,
    wait: vk::Semaphore,
    signal: vk::Semaphore,
    fence: vk::Fence,
) -> Result<(), String> {
    let waits = [vk::SemaphoreSubmitInfo::default()
        .semaphore(wait)
        .stage_mask(vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT)];
    let signals = [vk::SemaphoreSubmitInfo::default()
        .semaphore(signal)
        .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
    let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
    let submit = [vk::SubmitInfo2::default()
        .wait_semaphore_infos(&waits)
        .command_buffer_infos(&cmds)
        .signal_semaphore_infos(&signals)];
    // SAFETY: `cmd` is executable; `fence` is unsignalled; `wait` has a pending signal
    // (the acquire) and `signal` is unsignalled (its image's last presentation waited on it).
    unsafe { d.queue_submit2(queue, &submit, fence) }.map_err(|e| format!("vkQueueSubmit2: {e}"))
}
