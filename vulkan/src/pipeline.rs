//! Pipelines over the committed SPIR-V module (`vulkan/spirv/caveclod_shaders.spv`, built by
//! `shaders/builder` with rust-gpu; see `vulkan/spirv/INTERFACE.md`).
//!
//! The module is embedded with `include_bytes!` and read with `ash::util::read_spv`, which
//! fixes alignment, so users of this crate never need rust-gpu. Vertex layouts, push-constant
//! ranges and descriptor bindings here mirror the interface contract: `draw_vs`/`draw_fs`
//! (binding 0: `caveclod_core::format::Vertex`, stride 32; binding 1: RGBA8 vertex colours,
//! stride dynamic; 96-byte [`DrawPush`] for vertex and fragment; set 0: the base-colour
//! texture and sampler), `geomorph_vs` (bindings 0 and 1: coarse and fine `Vertex`, binding 2:
//! [`MorphInstance`] per instance; same push constants) and `geomorph_cs` (three storage
//! buffers, 16-byte [`MorphPush`]).
//!
//! Drawing pipelines are made for the caller's target ([`RecorderDesc`]: colour and depth
//! formats, sample count, dynamic rendering or a render pass and subpass), with dynamic
//! viewport and scissor (one pipeline serves every split-screen viewport), depth test
//! `LESS`, no culling (the tests compare renders of the same triangles, whatever their
//! winding).
//!
//! [`RecorderDesc`]: crate::RecorderDesc
//!
//! [`DrawPush`]: caveclod_core::gpu::DrawPush
//! [`MorphPush`]: caveclod_core::gpu::MorphPush
//! [`MorphInstance`]: caveclod_core::gpu::MorphInstance

use std::ffi::CStr;

use ash::vk;
use caveclod_core::gpu::{DrawPush, MorphInstance, MorphPush, MorphSlotsPush, MorphingPush};

use crate::device::Context;
use crate::error::{Error, Result, VkResultExt};
use crate::mesh::VERTEX_STRIDE;
use crate::target::{Rendering, TargetFormats};

/// The committed SPIR-V module.
pub(crate) const SPIRV: &[u8] = include_bytes!("../spirv/caveclod_shaders.spv");

/// Entry point names (Rust function names of the shader crate).
pub(crate) mod entry {
    use std::ffi::CStr;
    /// Vertex stage for drawing.
    pub(crate) const DRAW_VS: &CStr = c"draw_vs";
    /// Fragment stage for drawing.
    pub(crate) const DRAW_FS: &CStr = c"draw_fs";
    /// Vertex stage for geomorphing two vertex streams by a per-instance `t`.
    pub(crate) const GEOMORPH_VS: &CStr = c"geomorph_vs";
    /// Geomorph compute stage.
    pub(crate) const GEOMORPH_CS: &CStr = c"geomorph_cs";
    /// Vertex stage pulling a camera's front with its refinement geomorphs.
    pub(crate) const MORPHING_VS: &CStr = c"morphing_vs";
    /// Refinement-geomorph compute stage.
    pub(crate) const MORPHING_CS: &CStr = c"morphing_cs";
}

/// Threads per workgroup of `geomorph_cs`.
pub(crate) const GEOMORPH_LOCAL_SIZE: u32 = 64;
/// Threads per workgroup of `morphing_cs`.
pub(crate) const MORPHING_LOCAL_SIZE: u32 = 64;

/// Creates a shader module from SPIR-V bytes.
pub(crate) fn shader_module(ctx: &Context, spirv: &[u8]) -> Result<vk::ShaderModule> {
    let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
        .map_err(|e| Error::Shader(format!("reading SPIR-V: {e}")))?;
    let info = vk::ShaderModuleCreateInfo::default().code(&words);
    // SAFETY: `words` is a SPIR-V module validated by spirv-val when it was committed.
    unsafe { ctx.device.create_shader_module(&info, None) }.vk("vkCreateShaderModule")
}

/// Which vertex stage a [`DrawPipeline`] runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum VertexStage {
    /// `draw_vs`: binding 0, `Vertex` per vertex.
    Draw,
    /// `geomorph_vs`: bindings 0 and 1, `Vertex` per vertex (coarse, fine); binding 2,
    /// `MorphInstance` per instance.
    Geomorph,
    /// `morphing_vs`: no vertex input; vertices pulled from the storage buffers of set 1
    /// ([`PipelineTarget::morph_set_layout`]), 112-byte `MorphingPush`.
    Morphing,
}

/// What a [`DrawPipeline`] draws into, and how it fills triangles.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PipelineTarget {
    /// Formats and sample count of the attachments.
    pub(crate) formats: TargetFormats,
    /// Dynamic rendering or a render pass and subpass.
    pub(crate) rendering: Rendering,
    /// `FILL`, or `LINE` for wireframe.
    pub(crate) polygon_mode: vk::PolygonMode,
    /// Set 0 (the material's texture and sampler).
    pub(crate) set_layout: vk::DescriptorSetLayout,
    /// Set 1 of the morphing stage (the camera's storage buffers); unused by the others.
    pub(crate) morph_set_layout: vk::DescriptorSetLayout,
    /// Blend by alpha over what is drawn (`src_alpha, 1 - src_alpha`), testing depth but
    /// not writing it: for `BLEND` materials.
    pub(crate) blend: bool,
}

/// A drawing pipeline (`draw_vs` or `geomorph_vs`, with `draw_fs`) and its layout (set 0
/// and the push constants).
#[derive(Debug)]
pub(crate) struct DrawPipeline {
    /// The pipeline.
    pub(crate) raw: vk::Pipeline,
    /// Its layout (set 0, push constants).
    pub(crate) layout: vk::PipelineLayout,
    /// Its vertex stage.
    pub(crate) stage: VertexStage,
}

impl DrawPipeline {
    /// Creates the pipeline for `target`.
    pub(crate) fn new(
        ctx: &Context,
        vertex_stage: VertexStage,
        target: PipelineTarget,
    ) -> Result<Self> {
        let d = &ctx.device;
        let module = shader_module(ctx, SPIRV)?;
        let (push_size, set_layouts) = match vertex_stage {
            VertexStage::Morphing => (
                std::mem::size_of::<MorphingPush>(),
                vec![target.set_layout, target.morph_set_layout],
            ),
            _ => (std::mem::size_of::<DrawPush>(), vec![target.set_layout]),
        };
        let ranges = [vk::PushConstantRange {
            stage_flags: vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            offset: 0,
            size: push_size as u32,
        }];
        let layout_info = vk::PipelineLayoutCreateInfo::default()
            .set_layouts(&set_layouts)
            .push_constant_ranges(&ranges);
        // SAFETY: valid create info.
        let layout = match unsafe { d.create_pipeline_layout(&layout_info, None) }
            .vk("vkCreatePipelineLayout")
        {
            Ok(l) => l,
            Err(e) => {
                // SAFETY: unused module.
                unsafe { d.destroy_shader_module(module, None) };
                return Err(e);
            }
        };
        let raw = Self::create(ctx, module, layout, vertex_stage, target);
        // SAFETY: the pipeline (if any) no longer needs the module.
        unsafe { d.destroy_shader_module(module, None) };
        match raw {
            Ok(raw) => Ok(Self {
                raw,
                layout,
                stage: vertex_stage,
            }),
            Err(e) => {
                // SAFETY: unused layout.
                unsafe { d.destroy_pipeline_layout(layout, None) };
                Err(e)
            }
        }
    }

    fn create(
        ctx: &Context,
        module: vk::ShaderModule,
        layout: vk::PipelineLayout,
        vertex_stage: VertexStage,
        target: PipelineTarget,
    ) -> Result<vk::Pipeline> {
        let vs = match vertex_stage {
            VertexStage::Draw => entry::DRAW_VS,
            VertexStage::Geomorph => entry::GEOMORPH_VS,
            VertexStage::Morphing => entry::MORPHING_VS,
        };
        let stages = [
            stage(vk::ShaderStageFlags::VERTEX, module, vs),
            stage(vk::ShaderStageFlags::FRAGMENT, module, entry::DRAW_FS),
        ];
        let (bindings, attributes) = vertex_input(vertex_stage);
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&bindings)
            .vertex_attribute_descriptions(&attributes);
        let assembly = vk::PipelineInputAssemblyStateCreateInfo::default()
            .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(target.polygon_mode)
            .cull_mode(vk::CullModeFlags::NONE)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(target.formats.samples);
        let has_depth = target.formats.depth != vk::Format::UNDEFINED;
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(has_depth)
            .depth_write_enable(has_depth && !target.blend)
            .depth_compare_op(vk::CompareOp::LESS);
        let blend_attachments = [vk::PipelineColorBlendAttachmentState::default()
            .blend_enable(target.blend)
            .src_color_blend_factor(vk::BlendFactor::SRC_ALPHA)
            .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
            .color_blend_op(vk::BlendOp::ADD)
            .src_alpha_blend_factor(vk::BlendFactor::ONE)
            .dst_alpha_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
            .alpha_blend_op(vk::BlendOp::ADD)
            .color_write_mask(vk::ColorComponentFlags::RGBA)];
        let blend =
            vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
        let dynamic_states = dynamic_states(vertex_stage);
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let colour_formats = [target.formats.colour];
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(&colour_formats)
            .depth_attachment_format(target.formats.depth)
            .stencil_attachment_format(target.formats.stencil_format());
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(layout);
        let info = [match target.rendering {
            Rendering::Dynamic => info.push_next(&mut rendering),
            Rendering::RenderPass {
                render_pass,
                subpass,
            } => info.render_pass(render_pass).subpass(subpass),
        }];
        // SAFETY: every pointer in `info` refers to locals alive for the call.
        let pipelines = unsafe {
            ctx.device
                .create_graphics_pipelines(vk::PipelineCache::null(), &info, None)
        }
        .map_err(|(_, e)| e)
        .vk("vkCreateGraphicsPipelines")?;
        pipelines
            .first()
            .copied()
            .ok_or_else(|| Error::Shader("no graphics pipeline returned".into()))
    }

    /// Destroys pipeline and layout. The GPU must be done with them.
    pub(crate) fn destroy(self, ctx: &Context) {
        // SAFETY: the caller guarantees no pending work uses them.
        unsafe {
            ctx.device.destroy_pipeline(self.raw, None);
            ctx.device.destroy_pipeline_layout(self.layout, None);
        }
    }
}

/// A compute pipeline over one set of storage buffers, with that set's layout and its own
/// layout: `geomorph_cs` ([`ComputePipeline::geomorph`]) or `morphing_cs`
/// ([`ComputePipeline::morphing`]).
#[derive(Debug)]
pub(crate) struct ComputePipeline {
    /// The pipeline.
    pub(crate) raw: vk::Pipeline,
    /// Its layout (one set, push constants).
    pub(crate) layout: vk::PipelineLayout,
    /// The set's layout.
    pub(crate) set_layout: vk::DescriptorSetLayout,
}

impl ComputePipeline {
    /// `geomorph_cs`: set 0 holds bindings 0 (a), 1 (b), 2 (output), storage buffers.
    pub(crate) fn geomorph(ctx: &Context) -> Result<Self> {
        let push = std::mem::size_of::<MorphPush>() as u32;
        Self::new(
            ctx,
            3,
            vk::ShaderStageFlags::COMPUTE,
            entry::GEOMORPH_CS,
            push,
        )
    }

    /// `morphing_cs`, and the set layout of a camera's morph buffers, which the morphing
    /// vertex stage binds as set 1 and the compute stage as set 0: bindings 0 (persistent
    /// vertices), 1 (morph slots), 2 (blended vertices), 3 (vertex colours), storage
    /// buffers, vertex and compute stages.
    pub(crate) fn morphing(ctx: &Context) -> Result<Self> {
        let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::COMPUTE;
        let push = std::mem::size_of::<MorphSlotsPush>() as u32;
        Self::new(ctx, 4, stages, entry::MORPHING_CS, push)
    }

    /// Entry point `name` over a set of `bindings` storage buffers visible to `stages`, with
    /// `push` bytes of push constants.
    fn new(
        ctx: &Context,
        bindings: u32,
        stages: vk::ShaderStageFlags,
        name: &CStr,
        push: u32,
    ) -> Result<Self> {
        let set_layout = storage_set_layout(ctx, bindings, stages)?;
        match compute_pipeline(ctx, set_layout, name, push) {
            Ok((raw, layout)) => Ok(Self {
                raw,
                layout,
                set_layout,
            }),
            Err(e) => {
                // SAFETY: unused.
                unsafe { ctx.device.destroy_descriptor_set_layout(set_layout, None) };
                Err(e)
            }
        }
    }

    /// Destroys pipeline and layouts. The GPU must be done with them, and with every set of
    /// the layout.
    pub(crate) fn destroy(self, ctx: &Context) {
        // SAFETY: the caller guarantees no pending work uses them.
        unsafe {
            ctx.device.destroy_pipeline(self.raw, None);
            ctx.device.destroy_pipeline_layout(self.layout, None);
            ctx.device
                .destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// A set layout of `count` storage buffers at bindings `0..count`, visible to `stages`.
fn storage_set_layout(
    ctx: &Context,
    count: u32,
    stages: vk::ShaderStageFlags,
) -> Result<vk::DescriptorSetLayout> {
    let bindings: Vec<_> = (0..count)
        .map(|b| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(b)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(1)
                .stage_flags(stages)
        })
        .collect();
    let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
    // SAFETY: valid create info.
    unsafe { ctx.device.create_descriptor_set_layout(&info, None) }
        .vk("vkCreateDescriptorSetLayout")
}

/// A compute pipeline of entry point `name` over one set of `set_layout` and
/// `push_size` bytes of push constants, with its layout.
fn compute_pipeline(
    ctx: &Context,
    set_layout: vk::DescriptorSetLayout,
    name: &CStr,
    push_size: u32,
) -> Result<(vk::Pipeline, vk::PipelineLayout)> {
    let d = &ctx.device;
    let set_layouts = [set_layout];
    let ranges = [vk::PushConstantRange {
        stage_flags: vk::ShaderStageFlags::COMPUTE,
        offset: 0,
        size: push_size,
    }];
    let layout_info = vk::PipelineLayoutCreateInfo::default()
        .set_layouts(&set_layouts)
        .push_constant_ranges(&ranges);
    // SAFETY: valid create info.
    let layout =
        unsafe { d.create_pipeline_layout(&layout_info, None) }.vk("vkCreatePipelineLayout")?;
    let raw = shader_module(ctx, SPIRV).and_then(|module| {
        let info = [vk::ComputePipelineCreateInfo::default()
            .stage(stage(vk::ShaderStageFlags::COMPUTE, module, name))
            .layout(layout)];
        // SAFETY: valid create info referring to live objects.
        let r = unsafe { d.create_compute_pipelines(vk::PipelineCache::null(), &info, None) }
            .map_err(|(_, e)| e)
            .vk("vkCreateComputePipelines");
        // SAFETY: the pipeline no longer needs the module.
        unsafe { d.destroy_shader_module(module, None) };
        r?.first()
            .copied()
            .ok_or_else(|| Error::Shader("no compute pipeline returned".into()))
    });
    match raw {
        Ok(raw) => Ok((raw, layout)),
        Err(e) => {
            // SAFETY: unused.
            unsafe { d.destroy_pipeline_layout(layout, None) };
            Err(e)
        }
    }
}

fn stage<'a>(
    stage: vk::ShaderStageFlags,
    module: vk::ShaderModule,
    name: &'a CStr,
) -> vk::PipelineShaderStageCreateInfo<'a> {
    vk::PipelineShaderStageCreateInfo::default()
        .stage(stage)
        .module(module)
        .name(name)
}

fn attribute(
    location: u32,
    binding: u32,
    format: vk::Format,
    offset: u32,
) -> vk::VertexInputAttributeDescription {
    vk::VertexInputAttributeDescription {
        location,
        binding,
        format,
        offset,
    }
}

/// The vertex bindings and attributes of `vertex_stage`: binding 0 the vertices (position,
/// normal, uv), plus the colours (drawing) or the fine ends and the instances
/// (geomorphing); the morphing stage reads its vertices from storage buffers instead.
fn vertex_input(
    vertex_stage: VertexStage,
) -> (
    Vec<vk::VertexInputBindingDescription>,
    Vec<vk::VertexInputAttributeDescription>,
) {
    let per_vertex = |binding| vk::VertexInputBindingDescription {
        binding,
        stride: VERTEX_STRIDE,
        input_rate: vk::VertexInputRate::VERTEX,
    };
    // Position, normal, uv of a `Vertex` in `binding` at locations `first..first + 3`.
    let vertex = |binding, first| {
        [
            attribute(first, binding, vk::Format::R32G32B32_SFLOAT, 0),
            attribute(first + 1, binding, vk::Format::R32G32B32_SFLOAT, 12),
            attribute(first + 2, binding, vk::Format::R32G32_SFLOAT, 24),
        ]
    };
    match vertex_stage {
        VertexStage::Draw => {
            // Binding 1: the vertex colours, RGBA8 (stride set when binding: 4, or 0
            // for one white colour).
            let colours = vk::VertexInputBindingDescription {
                binding: 1,
                stride: 4,
                input_rate: vk::VertexInputRate::VERTEX,
            };
            let mut attributes = vertex(0, 0).to_vec();
            attributes.push(attribute(3, 1, vk::Format::R8G8B8A8_UNORM, 0));
            (vec![per_vertex(0), colours], attributes)
        }
        VertexStage::Geomorph => {
            let mut attributes = vertex(0, 0).to_vec();
            attributes.extend(vertex(1, 3));
            attributes.push(attribute(6, 2, vk::Format::R32G32B32A32_SFLOAT, 0));
            attributes.push(attribute(7, 2, vk::Format::R32_SFLOAT, 16));
            let instance = vk::VertexInputBindingDescription {
                binding: 2,
                stride: std::mem::size_of::<MorphInstance>() as u32,
                input_rate: vk::VertexInputRate::INSTANCE,
            };
            (vec![per_vertex(0), per_vertex(1), instance], attributes)
        }
        VertexStage::Morphing => (Vec::new(), Vec::new()),
    }
}

/// The dynamic states of `vertex_stage`'s pipelines.
fn dynamic_states(vertex_stage: VertexStage) -> Vec<vk::DynamicState> {
    // The vertex-colour stride is set per draw (Vulkan 1.3 core dynamic state), so one
    // pipeline serves meshes with and without colours.
    match vertex_stage {
        VertexStage::Draw => vec![
            vk::DynamicState::VIEWPORT,
            vk::DynamicState::SCISSOR,
            vk::DynamicState::VERTEX_INPUT_BINDING_STRIDE,
        ],
        VertexStage::Geomorph | VertexStage::Morphing => {
            vec![vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR]
        }
    }
}
