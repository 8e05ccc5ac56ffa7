//! Recording one camera's draws, in order: its pipeline, viewport and scissor, its vertex
//! streams, then one indexed draw per non-empty surface; surfaces whose material blends
//! are drawn after the others, through the blending pipeline.

use ash::vk;
use caveclod_core::gpu::{DrawPush, MORPH_BLENDED, MORPH_IN_VERTEX_STAGE};
use glam::Vec4;

use super::{RecordCamera, Recorder};
use crate::camera_morphs::{CameraMorphs, MorphStage};
use crate::pipeline::{DrawPipeline, VertexStage};
use crate::viewport::Viewport;

/// Bytes per vertex colour (RGBA8).
const COLOUR_STRIDE: u64 = 4;

impl Recorder {
    /// Draws `cam`'s non-empty surfaces of frame slot `slot` (every instance, for a
    /// geomorphing camera), `cam` having passed [`Recorder::check_camera`]. Returns the
    /// draws recorded.
    pub(crate) fn draw_camera(
        &self,
        d: &ash::Device,
        cmd: vk::CommandBuffer,
        slot: usize,
        cam: &RecordCamera<'_>,
    ) -> u32 {
        let set = match (&self.wireframe, cam.wireframe) {
            (Some(w), true) => w,
            _ => &self.fill,
        };
        let (pipeline, instances, blend) = match (&cam.morph, &set.morph, &set.morphing) {
            (Some(m), Some(p), _) => (p, m.instances.count, None),
            (None, _, Some(p)) if cam.refine_morphs.is_some() => {
                (p, 1, set.morphing_blend.as_ref())
            }
            _ => (&set.draw, 1, set.blend.as_ref()),
        };
        self.bind_camera(d, cmd, slot, cam, pipeline);
        // Without a blending pipeline (wireframe, geomorph) every surface is drawn in one pass.
        let blends =
            |s: usize| blend.is_some() && cam.materials.and_then(|m| m.blends(s)).unwrap_or(false);
        let mut draws = self.draw_surfaces(d, cmd, slot, cam, pipeline, instances, |s| !blends(s));
        if let Some(b) = blend {
            if (0..cam.indices.surface_count()).any(blends) {
                // SAFETY: `cmd` is recording inside the same rendering; the blending
                // pipeline shares the layout and dynamic state, so the bindings stay valid.
                unsafe { d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, b.raw) };
                draws += self.draw_surfaces(d, cmd, slot, cam, b, 1, blends);
            }
        }
        draws
    }

    /// Binds `pipeline`, `cam`'s viewport and scissor, and its vertex streams: for the
    /// plain stage the vertices and their colours (or one white colour, stride 0); for the
    /// geomorphing stage coarse and fine vertices and the instances; for the morphing stage
    /// the camera's morph set (set 1) and the tail of its push block.
    fn bind_camera(
        &self,
        d: &ash::Device,
        cmd: vk::CommandBuffer,
        slot: usize,
        cam: &RecordCamera<'_>,
        pipeline: &DrawPipeline,
    ) {
        if pipeline.stage == VertexStage::Morphing {
            if let Some(m) = cam.refine_morphs {
                bind_morphs(d, cmd, slot, cam.viewport, m, pipeline);
                return;
            }
        }
        let (viewport, scissor) = viewport_and_scissor(cam.viewport);
        let (colours, colour_stride) = match &cam.vertices.colours {
            Some(c) => (c.raw, COLOUR_STRIDE),
            None => (self.bindings.white_colour.raw, 0),
        };
        // SAFETY: `cmd` is recording inside rendering compatible with the pipeline (the
        // caller's contract on `record`); the vertex buffers are alive, and the colour
        // stream holds a colour per vertex (stride 4) or one colour read by all (stride 0).
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline.raw);
            d.cmd_set_viewport(cmd, 0, &[viewport]);
            d.cmd_set_scissor(cmd, 0, &[scissor]);
            match &cam.morph {
                Some(m) if pipeline.stage == VertexStage::Geomorph => d.cmd_bind_vertex_buffers(
                    cmd,
                    0,
                    &[
                        cam.vertices.buffer.raw,
                        m.fine.buffer.raw,
                        m.instances.buffer.raw,
                    ],
                    &[0, 0, 0],
                ),
                _ => d.cmd_bind_vertex_buffers2(
                    cmd,
                    0,
                    &[cam.vertices.buffer.raw, colours],
                    &[0, 0],
                    None,
                    Some(&[u64::from(crate::mesh::VERTEX_STRIDE), colour_stride]),
                ),
            }
        }
    }

    /// Draws the non-empty surfaces `s` of slot `slot` for which `wanted(s)`, with
    /// `pipeline` bound: per surface its material's set and push block (or the palette
    /// colour with the white texture), its index buffer and one indexed draw.
    #[allow(clippy::too_many_arguments)]
    fn draw_surfaces(
        &self,
        d: &ash::Device,
        cmd: vk::CommandBuffer,
        slot: usize,
        cam: &RecordCamera<'_>,
        pipeline: &DrawPipeline,
        instances: u32,
        wanted: impl Fn(usize) -> bool,
    ) -> u32 {
        let mut draws = 0;
        for s in (0..cam.indices.surface_count()).filter(|&s| wanted(s)) {
            let Some((buffer, first, count)) = cam.indices.draw_range(slot, s) else {
                continue;
            };
            let (set, push) = match cam.materials.and_then(|m| m.get(s)) {
                Some((set, factor, cutoff)) => (
                    set,
                    DrawPush::material(cam.view_proj, Vec4::from_array(factor), cutoff),
                ),
                None => {
                    let colour = cam.colours.get(s).copied().unwrap_or([1.0; 4]);
                    (
                        self.bindings.white_set,
                        DrawPush::new(cam.view_proj, Vec4::from_array(colour)),
                    )
                }
            };
            // SAFETY: `cmd` is recording with `pipeline` bound; `buffer` holds `count`
            // indices from `first` below the bound vertex count (checked by `Recorder::check_camera`);
            // the set was written for this recorder's layout and names live images.
            unsafe {
                d.cmd_bind_descriptor_sets(
                    cmd,
                    vk::PipelineBindPoint::GRAPHICS,
                    pipeline.layout,
                    0,
                    &[set],
                    &[],
                );
                d.cmd_bind_index_buffer(cmd, buffer, 0, vk::IndexType::UINT32);
                d.cmd_push_constants(
                    cmd,
                    pipeline.layout,
                    vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
                    0,
                    bytemuck::bytes_of(&push),
                );
                d.cmd_draw_indexed(cmd, count, instances, first, 0, 0);
            }
            draws += 1;
        }
        draws
    }
}

/// Binds the morphing `pipeline`, the viewport and scissor, `morphs`' set of frame slot
/// `slot` as set 1, and the last 16 bytes of its `MorphingPush` (vertex count, slot count,
/// where the blended vertices come from, whether vertex colours exist); each surface
/// pushes the drawing block before it.
fn bind_morphs(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    slot: usize,
    viewport: Viewport,
    morphs: &CameraMorphs,
    pipeline: &DrawPipeline,
) {
    let (viewport, scissor) = viewport_and_scissor(viewport);
    let (vertex_count, slot_count, colours) = morphs.push_fields(slot);
    let source = match morphs.stage() {
        MorphStage::Vertex => MORPH_IN_VERTEX_STAGE,
        MorphStage::Compute | MorphStage::Host => MORPH_BLENDED,
    };
    let tail = [vertex_count, slot_count, source, u32::from(colours)];
    let draw_size = std::mem::size_of::<DrawPush>() as u32;
    // `check_camera` made sure the ring has the slot.
    let Some((set, _)) = morphs.set(slot) else {
        return;
    };
    // SAFETY: `cmd` is recording inside rendering compatible with the pipeline (the
    // caller's contract on `record`); the set was written for this recorder's morph layout
    // (set 1 of the pipeline's layout) and names live buffers; the push range of the layout
    // covers the 16 bytes after the drawing block, for both stages.
    unsafe {
        d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline.raw);
        d.cmd_set_viewport(cmd, 0, &[viewport]);
        d.cmd_set_scissor(cmd, 0, &[scissor]);
        d.cmd_bind_descriptor_sets(
            cmd,
            vk::PipelineBindPoint::GRAPHICS,
            pipeline.layout,
            1,
            &[set],
            &[],
        );
        d.cmd_push_constants(
            cmd,
            pipeline.layout,
            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            draw_size,
            bytemuck::cast_slice(&tail),
        );
    }
}

/// The Vulkan viewport (depth 0..1) and scissor of the same rectangle.
fn viewport_and_scissor(v: Viewport) -> (vk::Viewport, vk::Rect2D) {
    let viewport = vk::Viewport {
        x: v.x as f32,
        y: v.y as f32,
        width: v.width as f32,
        height: v.height as f32,
        min_depth: 0.0,
        max_depth: 1.0,
    };
    let scissor = vk::Rect2D {
        offset: vk::Offset2D {
            x: v.x as i32,
            y: v.y as i32,
        },
        extent: vk::Extent2D {
            width: v.width,
            height: v.height,
        },
    };
    (viewport, scissor)
}
