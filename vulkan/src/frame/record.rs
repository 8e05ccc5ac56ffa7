//! Recording one target's commands, in the order they run:
//! 1. [`to_attachment_layouts`]: colour and depth from `UNDEFINED` (their contents are
//!    cleared anyway) into attachment layouts, after the previous frame's writes and copy;
//! 2. [`begin_rendering`]: dynamic rendering over the whole target, clearing both;
//! 3. the target's cameras through [`Recorder::record`](crate::Recorder::record): pipeline,
//!    viewport and scissor, vertex streams, then one indexed draw per non-empty surface;
//! 4. end of rendering;
//! 5. with read-back, [`copy_to_readback`]: colour into `TRANSFER_SRC_OPTIMAL`, copied into
//!    the slot's host-visible buffer, made visible to host reads.

use ash::vk;

use super::{Renderer, Target};
use crate::buffer::Buffer;
use crate::device::Context;
use crate::image::Image;
use crate::readback::record_copy_out;
use crate::record::RecordCamera;

impl Renderer {
    /// Records target `t`: transitions, rendering of its cameras through the recorder,
    /// optional copy-out. Returns the draws recorded.
    pub(super) fn record_target(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        t: usize,
        slot: usize,
        cameras: &[(usize, RecordCamera<'_>)],
    ) -> u32 {
        let d = &ctx.device;
        let target = &self.targets[t];
        to_attachment_layouts(d, cmd, target);
        begin_rendering(d, cmd, target, self.desc.clear_colour);
        // Every camera passed `Recorder::check_camera` in `Renderer::render`.
        let draws = cameras
            .iter()
            .filter(|(target, _)| *target == t)
            .map(|(_, c)| self.recorder.draw_camera(d, cmd, slot, c))
            .sum();
        // SAFETY: `cmd` is recording inside the rendering begun above.
        unsafe { d.cmd_end_rendering(cmd) };
        if let Some(buffer) = self.slots[slot].readback.get(t) {
            copy_to_readback(d, cmd, target, buffer);
        }
        draws
    }
}

/// Colour and depth into attachment layouts. The colour waits for the previous frame's
/// attachment writes and its copy to the read-back buffer; the depth for its depth tests.
fn to_attachment_layouts(d: &ash::Device, cmd: vk::CommandBuffer, target: &Target) {
    let image_barriers = [
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
            .image(target.colour.raw)
            .subresource_range(Image::range(vk::ImageAspectFlags::COLOR)),
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
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(target.depth.raw)
            .subresource_range(Image::range(vk::ImageAspectFlags::DEPTH)),
    ];
    let dep = vk::DependencyInfo::default().image_memory_barriers(&image_barriers);
    // SAFETY: `cmd` is recording; the images are alive.
    unsafe { d.cmd_pipeline_barrier2(cmd, &dep) };
}

/// Begins dynamic rendering over the whole target, clearing colour to `clear_colour` and
/// depth to 1 (the depth is not stored: nothing reads it after the frame).
fn begin_rendering(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    target: &Target,
    clear_colour: [f32; 4],
) {
    let colour_attachment = [vk::RenderingAttachmentInfo::default()
        .image_view(target.colour.view)
        .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::STORE)
        .clear_value(vk::ClearValue {
            color: vk::ClearColorValue {
                float32: clear_colour,
            },
        })];
    let depth_attachment = vk::RenderingAttachmentInfo::default()
        .image_view(target.depth.view)
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
            offset: vk::Offset2D { x: 0, y: 0 },
            extent: target.colour.desc.extent,
        })
        .layer_count(1)
        .color_attachments(&colour_attachment)
        .depth_attachment(&depth_attachment);
    // SAFETY: `cmd` is recording; the attachments are in the layouts named
    // (`to_attachment_layouts` ran before).
    unsafe { d.cmd_begin_rendering(cmd, &rendering) };
}

/// Copies the colour target into `buffer` (tightly packed RGBA8 rows) and makes the copy
/// visible to host reads once the frame's fence signals.
fn copy_to_readback(d: &ash::Device, cmd: vk::CommandBuffer, target: &Target, buffer: &Buffer) {
    let layout = vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL;
    let extent = target.colour.desc.extent;
    record_copy_out(d, cmd, target.colour.raw, layout, extent, buffer.raw);
}
