//! The record path: caveclod's draws recorded into the caller's command buffer, inside the
//! caller's rendering (the design decisions are on [`Recorder`]).

mod draw;
mod made;

use ash::vk;
use glam::Mat4;

use crate::camera_morphs::{workgroups, CameraMorphs, MorphLayout};
use crate::device::Context;
use crate::error::{Error, Result};
use crate::indices::CameraIndices;
use crate::material::{Bindings, MaterialSet};
use crate::mesh::{MorphInstances, VertexBuffer};
use crate::pipeline::{ComputePipeline, DrawPipeline, PipelineTarget, VertexStage};
use crate::target::RecorderDesc;
use crate::viewport::Viewport;

/// One camera's draws in a recorded frame.
#[derive(Clone, Copy, Debug)]
pub struct RecordCamera<'a> {
    /// Where in the caller's target.
    pub viewport: Viewport,
    /// View-projection matrix into Vulkan clip space (y down, depth 0..1).
    pub view_proj: Mat4,
    /// The mesh's persistent vertex buffer.
    pub vertices: &'a VertexBuffer,
    /// This camera's index buffers, filled for the slot being recorded
    /// ([`CameraIndices::fill`]).
    pub indices: &'a CameraIndices,
    /// Colour per surface (linear RGBA); at least one per surface. Used when `materials` is
    /// `None`, with a faint checker so texture coordinates show.
    pub colours: &'a [[f32; 4]],
    /// The surfaces' materials (base-colour texture × factor, alpha cutoff), made for this
    /// recorder; at least one per surface.
    pub materials: Option<&'a MaterialSet>,
    /// Geomorph instead of drawing `vertices` as they are (needs
    /// [`RecorderDesc::geomorph`]).
    pub morph: Option<Morph<'a>>,
    /// The camera's refinement geomorphs, filled for the slot being recorded
    /// ([`CameraMorphs::fill`]); its indices then come from morphed emission
    /// ([`IndexSource::MorphedCamera`](crate::IndexSource)). Needs
    /// [`RecorderDesc::refine_morphs`]; a [`MorphStage::Compute`](crate::MorphStage) camera
    /// also needs [`Recorder::record_morph_blends`] before the rendering.
    pub refine_morphs: Option<&'a CameraMorphs>,
    /// Draw edges only (needs [`RecorderDesc::wireframe`]).
    pub wireframe: bool,
}

impl<'a> RecordCamera<'a> {
    /// A camera drawing `vertices` through `indices` into `viewport` with `view_proj`:
    /// filled, not geomorphing, and without colours or materials, so it needs
    /// [`materials`](Self::materials) or [`colours`](Self::colours) before it is recorded.
    pub fn new(
        viewport: Viewport,
        view_proj: Mat4,
        vertices: &'a VertexBuffer,
        indices: &'a CameraIndices,
    ) -> Self {
        Self {
            viewport,
            view_proj,
            vertices,
            indices,
            colours: &[],
            materials: None,
            morph: None,
            refine_morphs: None,
            wireframe: false,
        }
    }

    /// Draws the camera's refinement geomorphs, `morphs`, filled for the slot recorded
    /// (its indices from [`IndexSource::MorphedCamera`](crate::IndexSource)).
    pub fn refine_morphs(self, morphs: &'a CameraMorphs) -> Self {
        Self {
            refine_morphs: Some(morphs),
            ..self
        }
    }

    /// Draws the surfaces with `materials`.
    pub fn materials(self, materials: &'a MaterialSet) -> Self {
        Self {
            materials: Some(materials),
            ..self
        }
    }

    /// Colours the surfaces with `colours` (when it has no materials).
    pub fn colours(self, colours: &'a [[f32; 4]]) -> Self {
        Self { colours, ..self }
    }

    /// Geomorphs with `morph`.
    pub fn morph(self, morph: Morph<'a>) -> Self {
        Self {
            morph: Some(morph),
            ..self
        }
    }

    /// Draws edges only when `wireframe`.
    pub fn wireframe(self, wireframe: bool) -> Self {
        Self { wireframe, ..self }
    }
}

/// A geomorphing draw: the camera's indices index both vertex streams alike; `vertices`
/// (of the camera) are the coarse ends, `fine` the fine ends, and each instance morphs and
/// places them by its [`MorphInstance`](caveclod_core::gpu::MorphInstance).
#[derive(Clone, Copy, Debug)]
pub struct Morph<'a> {
    /// Fine ends, as many as the coarse ones.
    pub fine: &'a VertexBuffer,
    /// Instances.
    pub instances: &'a MorphInstances,
}

/// The pipelines of one [`RecorderDesc`]: fill (always), wireframe (if asked), each with
/// the plain and, if asked, the geomorphing and the morphing vertex stage; the fill set
/// also blends.
struct Pipelines {
    draw: DrawPipeline,
    morph: Option<DrawPipeline>,
    /// The plain stage blending by alpha (fill only), for `BLEND` materials.
    blend: Option<DrawPipeline>,
    /// The morphing stage (refinement geomorphs), and its blending twin (fill only).
    morphing: Option<DrawPipeline>,
    morphing_blend: Option<DrawPipeline>,
}

impl Default for Pipelines {
    /// No pipelines: null handles, which destroying ignores.
    fn default() -> Self {
        Self {
            draw: DrawPipeline {
                raw: vk::Pipeline::null(),
                layout: vk::PipelineLayout::null(),
                stage: VertexStage::Draw,
            },
            morph: None,
            blend: None,
            morphing: None,
            morphing_blend: None,
        }
    }
}

/// Records caveclod's draws into a command buffer the caller owns.
///
/// Design decisions:
/// - **The caller owns the frame.** [`record`](Self::record) only binds pipelines and
///   buffers and issues indexed draws into `cmd`, which must be recording inside the
///   caller's rendering: `vkCmdBeginRendering`
///   ([`Rendering::Dynamic`](crate::Rendering::Dynamic)) or the subpass of the caller's
///   render pass named in [`RecorderDesc`], with attachments of
///   [`TargetFormats`](crate::TargetFormats). It does not begin or end rendering, record
///   barriers, submit, wait, or lock the queue, so it fits a render graph, a swapchain frame
///   or a test harness alike; dynamic state it sets is viewport and scissor (per camera).
/// - **The caller says which frame slot.** Each camera's [`CameraIndices`] is a ring over
///   the caller's frames in flight: the caller fills slot `s` after its fence for the
///   frame that last used slot `s` signalled, then records with `s`. Filling writes mapped
///   memory; the submission makes those host writes visible, so no barrier is needed.
///   Index buffers grow by doubling, so once the rings are sized a frame creates no Vulkan
///   resource ([`Context::resources_created`] counts them).
/// - **The vertex buffer is uploaded once**, through a staging copy submitted by the
///   context ([`VertexBuffer::from_hierarchy`]) or recorded into the caller's command
///   buffer ([`VertexBuffer::record_upload`]), and never written again.
/// - **One pipeline set per target kind.** Pipelines are made for the formats, sample
///   count and rendering given at creation; viewport and scissor are dynamic, so one
///   recorder serves every camera of a split screen.
///
/// The headless [`Renderer`](crate::Renderer) is this recorder plus targets, a command
/// pool, fences and read-back.
pub struct Recorder {
    desc: RecorderDesc,
    bindings: Bindings,
    /// The refinement-geomorph compute stage and the morph set layout.
    morphing: Option<ComputePipeline>,
    fill: Pipelines,
    wireframe: Option<Pipelines>,
}

impl Recorder {
    /// Checks the formats and features, then creates the pipelines, the material set
    /// layout and sampler, and a 1 × 1 white texture for surfaces without one (its upload
    /// is the one submission a recorder makes, here, waited for; frames never submit).
    pub fn new(ctx: &Context, desc: RecorderDesc) -> Result<Self> {
        desc.formats.check(ctx)?;
        if desc.wireframe && !ctx.features().fill_mode_non_solid {
            return Err(Error::Unsupported {
                device: ctx.device_name().to_string(),
                missing: vec!["fillModeNonSolid (wireframe; not enabled)".into()],
            });
        }
        let bindings = Bindings::new(ctx)?;
        let morphing = if desc.refine_morphs {
            match ComputePipeline::morphing(ctx) {
                Ok(m) => Some(m),
                Err(e) => {
                    let _ = bindings.destroy(ctx);
                    return Err(e);
                }
            }
        } else {
            None
        };
        let morph_set_layout = morphing
            .as_ref()
            .map_or(vk::DescriptorSetLayout::null(), |m| m.set_layout);
        let mut r = Self {
            desc,
            bindings,
            morphing,
            fill: Pipelines::default(),
            wireframe: None,
        };
        let made = Self::pipelines(
            ctx,
            &desc,
            &r.bindings,
            morph_set_layout,
            vk::PolygonMode::FILL,
        )
        .and_then(|fill| {
            r.fill = fill;
            if desc.wireframe {
                let line = vk::PolygonMode::LINE;
                r.wireframe = Some(Self::pipelines(
                    ctx,
                    &desc,
                    &r.bindings,
                    morph_set_layout,
                    line,
                )?);
            }
            Ok(())
        });
        match made {
            Ok(()) => Ok(r),
            Err(e) => {
                let _ = r.destroy(ctx);
                Err(e)
            }
        }
    }

    /// What camera morphs take of the recorder: the morph set layout (when made with
    /// [`RecorderDesc::refine_morphs`]) and the one white vertex colour.
    pub(crate) fn morph_layout(&self) -> MorphLayout<'_> {
        MorphLayout {
            set_layout: self.morphing.as_ref().map(|m| m.set_layout),
            white_colour: &self.bindings.white_colour,
        }
    }

    /// The set layout, sampler and white texture shared with material sets.
    pub(crate) fn bindings(&self) -> &Bindings {
        &self.bindings
    }

    /// The pipelines for one polygon mode. On an error, the ones made so far are destroyed.
    fn pipelines(
        ctx: &Context,
        desc: &RecorderDesc,
        bindings: &Bindings,
        morph_set_layout: vk::DescriptorSetLayout,
        polygon_mode: vk::PolygonMode,
    ) -> Result<Pipelines> {
        let target = PipelineTarget {
            formats: desc.formats,
            rendering: desc.rendering,
            polygon_mode,
            set_layout: bindings.set_layout,
            morph_set_layout,
            blend: false,
        };
        let blending = PipelineTarget {
            blend: true,
            ..target
        };
        let fill = polygon_mode == vk::PolygonMode::FILL;
        let mut p = Pipelines::default();
        let made = (|| -> Result<()> {
            p.draw = DrawPipeline::new(ctx, VertexStage::Draw, target)?;
            if desc.geomorph {
                p.morph = Some(DrawPipeline::new(ctx, VertexStage::Geomorph, target)?);
            }
            if fill {
                p.blend = Some(DrawPipeline::new(ctx, VertexStage::Draw, blending)?);
            }
            if desc.refine_morphs {
                p.morphing = Some(DrawPipeline::new(ctx, VertexStage::Morphing, target)?);
                if fill {
                    let b = DrawPipeline::new(ctx, VertexStage::Morphing, blending)?;
                    p.morphing_blend = Some(b);
                }
            }
            Ok(())
        })();
        match made {
            Ok(()) => Ok(p),
            Err(e) => {
                destroy_pipelines(ctx, p);
                Err(e)
            }
        }
    }

    /// The description.
    pub fn desc(&self) -> &RecorderDesc {
        &self.desc
    }

    /// Checks every camera, then records its draws of frame slot `slot` into `cmd` (see
    /// [`Recorder`]). Returns the indexed draws recorded (one per camera and non-empty
    /// surface). Nothing is recorded if a camera is refused.
    ///
    /// `cmd` must be a command buffer of `ctx`'s device in the recording state, inside
    /// rendering compatible with this recorder's [`RecorderDesc`]; the buffers named by
    /// `cameras` must stay alive until the GPU has executed it.
    pub fn record(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        slot: usize,
        cameras: &[RecordCamera<'_>],
    ) -> Result<u32> {
        for (i, cam) in cameras.iter().enumerate() {
            self.check_camera(i, slot, cam)?;
        }
        Ok(cameras
            .iter()
            .map(|cam| self.draw_camera(&ctx.device, cmd, slot, cam))
            .sum())
    }

    /// Refuses a camera whose draws would be invalid: an empty viewport, a slot its index
    /// ring lacks, too few colours, indices beyond its vertex buffer, refinement geomorphs
    /// over indices not filled by morphed emission, a geomorph or wireframe draw this
    /// recorder has no pipeline for.
    pub(crate) fn check_camera(&self, i: usize, slot: usize, c: &RecordCamera<'_>) -> Result<()> {
        let refuse = |why: String| Err(Error::InvalidArgument(format!("camera {i}: {why}")));
        if c.viewport.width == 0 || c.viewport.height == 0 {
            return refuse(format!("empty viewport {:?}", c.viewport));
        }
        if slot >= c.indices.frames_in_flight() {
            return refuse(format!(
                "frame slot {slot} of an index ring of {}",
                c.indices.frames_in_flight()
            ));
        }
        match c.materials {
            Some(m) if m.len() < c.indices.surface_count() => {
                return refuse(format!(
                    "{} materials for {} surfaces",
                    m.len(),
                    c.indices.surface_count()
                ));
            }
            None if c.colours.len() < c.indices.surface_count() => {
                return refuse(format!(
                    "{} colours for {} surfaces",
                    c.colours.len(),
                    c.indices.surface_count()
                ));
            }
            _ => {}
        }
        let vertex_bound = match c.refine_morphs {
            Some(m) => {
                if self.morphing.is_none() {
                    return refuse(
                        "refinement geomorphs, but the recorder was made without refine_morphs"
                            .into(),
                    );
                }
                if !c.indices.morphed(slot) {
                    return refuse(
                        "refinement geomorphs need indices filled from \
                         IndexSource::MorphedCamera"
                            .into(),
                    );
                }
                if let Err(why) = m.check(c.vertices, slot) {
                    return refuse(why);
                }
                m.vertex_bound()
            }
            None => u64::from(c.vertices.count),
        };
        if u64::from(c.indices.vertex_bound(slot)) > vertex_bound {
            return refuse(format!(
                "its indices reference {} vertices, the vertex buffer{} has {vertex_bound}",
                c.indices.vertex_bound(slot),
                if c.refine_morphs.is_some() {
                    " with its morph slots"
                } else {
                    ""
                },
            ));
        }
        if c.wireframe && self.wireframe.is_none() {
            return refuse("wireframe draw, but the recorder was made without wireframe".into());
        }
        if let Some(m) = &c.morph {
            if self.fill.morph.is_none() {
                return refuse("geomorph draw, but the recorder was made without geomorph".into());
            }
            if m.fine.count != c.vertices.count {
                return refuse(format!(
                    "{} fine and {} coarse vertices",
                    m.fine.count, c.vertices.count
                ));
            }
        }
        Ok(())
    }

    /// Records, outside rendering, the compute stage of every camera in `cameras` that
    /// blends there ([`MorphStage::Compute`](crate::MorphStage)) for frame slot `slot`: one
    /// dispatch per camera with morphing vertices, then one barrier from those compute
    /// writes (`COMPUTE_SHADER`, `SHADER_STORAGE_WRITE`) to the morphing vertex stage's
    /// reads (`VERTEX_SHADER`, `SHADER_STORAGE_READ`), a memory barrier covering every
    /// camera's blended buffer, so the draws recorded after it in
    /// submission order see the blended vertices. Cameras blending elsewhere are skipped;
    /// with nothing to dispatch nothing is recorded. Returns the dispatches recorded.
    ///
    /// `cmd` must be recording outside any rendering; each camera's slot `slot` must be
    /// filled ([`CameraMorphs::fill`]) and stay alive until the GPU has executed `cmd`.
    pub fn record_morph_blends(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        slot: usize,
        cameras: &[&CameraMorphs],
    ) -> Result<u32> {
        let Some(pipeline) = &self.morphing else {
            return Err(Error::InvalidArgument(
                "morph blends, but the recorder was made without refine_morphs".into(),
            ));
        };
        let d = &ctx.device;
        let mut dispatches = 0;
        for (set, push) in cameras.iter().filter_map(|c| c.dispatch(slot)) {
            // SAFETY: `cmd` is recording outside rendering (the caller's contract); pipeline
            // and sets are alive, and each set was written for this recorder's morph layout
            // with buffers the camera keeps alive.
            unsafe {
                if dispatches == 0 {
                    d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, pipeline.raw);
                }
                d.cmd_bind_descriptor_sets(
                    cmd,
                    vk::PipelineBindPoint::COMPUTE,
                    pipeline.layout,
                    0,
                    &[set],
                    &[],
                );
                d.cmd_push_constants(
                    cmd,
                    pipeline.layout,
                    vk::ShaderStageFlags::COMPUTE,
                    0,
                    bytemuck::bytes_of(&push),
                );
                d.cmd_dispatch(cmd, workgroups(push.slot_count), 1, 1);
            }
            dispatches += 1;
        }
        if dispatches > 0 {
            // One barrier for every camera's blended buffer: what the dispatches wrote is what
            // the morphing vertex stage reads.
            let barrier = [vk::MemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
                .src_access_mask(vk::AccessFlags2::SHADER_STORAGE_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::VERTEX_SHADER)
                .dst_access_mask(vk::AccessFlags2::SHADER_STORAGE_READ)];
            let dep = vk::DependencyInfo::default().memory_barriers(&barrier);
            // SAFETY: `cmd` is recording outside rendering.
            unsafe { d.cmd_pipeline_barrier2(cmd, &dep) };
        }
        Ok(dispatches)
    }

    /// Destroys the pipelines, the set layouts, the sampler and the white texture. The GPU
    /// must be done with every command buffer that recorded them; destroy the recorder's
    /// material sets and camera morphs first.
    pub fn destroy(self, ctx: &Context) -> Result<()> {
        destroy_pipelines(ctx, self.fill);
        if let Some(w) = self.wireframe {
            destroy_pipelines(ctx, w);
        }
        if let Some(m) = self.morphing {
            m.destroy(ctx);
        }
        self.bindings.destroy(ctx)
    }
}

fn destroy_pipelines(ctx: &Context, p: Pipelines) {
    p.draw.destroy(ctx);
    for extra in [p.morph, p.blend, p.morphing, p.morphing_blend]
        .into_iter()
        .flatten()
    {
        extra.destroy(ctx);
    }
}
