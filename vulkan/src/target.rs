//! What the caller records into: attachment formats, sample count, dynamic rendering or a
//! render pass, and the checks that the device can do it.

use ash::vk;

use crate::device::Context;
use crate::error::{Error, Result};

/// How the caller's rendering is begun, which the pipelines must match.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rendering {
    /// `vkCmdBeginRendering` with one colour attachment of [`TargetFormats::colour`] and,
    /// unless `depth` is `UNDEFINED`, a depth attachment of [`TargetFormats::depth`] (also
    /// the stencil attachment when that format has stencil).
    Dynamic,
    /// A subpass of the caller's render pass, with one colour attachment and, unless
    /// `depth` is `UNDEFINED`, a depth-stencil attachment, of the formats and sample count
    /// of [`TargetFormats`]. The render pass must outlive the [`Recorder`](crate::Recorder).
    RenderPass {
        /// The caller's render pass.
        render_pass: vk::RenderPass,
        /// The subpass caveclod draws in.
        subpass: u32,
    },
}

/// Formats and sample count of the attachments the caller renders into.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TargetFormats {
    /// Colour attachment format (any colour-attachment format: UNORM, sRGB, BGRA, float).
    pub colour: vk::Format,
    /// Depth (or depth-stencil) attachment format; `UNDEFINED` for no depth test.
    pub depth: vk::Format,
    /// Rasterization samples (the caller resolves multisampled targets).
    pub samples: vk::SampleCountFlags,
}

impl TargetFormats {
    /// RGBA8 UNORM colour, 32-bit float depth, one sample: what the headless
    /// [`Renderer`](crate::Renderer) makes (and reads back as [`RgbaImage`](crate::RgbaImage)).
    pub const HEADLESS: Self = Self {
        colour: vk::Format::R8G8B8A8_UNORM,
        depth: vk::Format::D32_SFLOAT,
        samples: vk::SampleCountFlags::TYPE_1,
    };

    /// `depth` if it has a stencil component (it is then the stencil attachment's format
    /// too), else `UNDEFINED`.
    pub(crate) fn stencil_format(&self) -> vk::Format {
        match self.depth {
            vk::Format::D16_UNORM_S8_UINT
            | vk::Format::D24_UNORM_S8_UINT
            | vk::Format::D32_SFLOAT_S8_UINT
            | vk::Format::S8_UINT => self.depth,
            _ => vk::Format::UNDEFINED,
        }
    }

    /// Refuses, with [`Error::Unsupported`], formats the device cannot render into with
    /// optimal tiling and sample counts above its framebuffer limits.
    pub(crate) fn check(&self, ctx: &Context) -> Result<()> {
        let mut missing = Vec::new();
        // SAFETY: the context's physical device belongs to its instance.
        let colour = unsafe {
            ctx.instance
                .get_physical_device_format_properties(ctx.physical_device, self.colour)
        };
        if !colour
            .optimal_tiling_features
            .contains(vk::FormatFeatureFlags::COLOR_ATTACHMENT)
        {
            missing.push(format!("{:?} as a colour attachment", self.colour));
        }
        if self.depth != vk::Format::UNDEFINED {
            // SAFETY: as above.
            let depth = unsafe {
                ctx.instance
                    .get_physical_device_format_properties(ctx.physical_device, self.depth)
            };
            if !depth
                .optimal_tiling_features
                .contains(vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT)
            {
                missing.push(format!("{:?} as a depth attachment", self.depth));
            }
        }
        // SAFETY: as above.
        let limits = unsafe {
            ctx.instance
                .get_physical_device_properties(ctx.physical_device)
        }
        .limits;
        if self.samples.as_raw().count_ones() != 1 {
            missing.push(format!(
                "sample count {:?} (one count expected)",
                self.samples
            ));
        } else {
            if !limits
                .framebuffer_color_sample_counts
                .contains(self.samples)
            {
                missing.push(format!("{:?} colour samples", self.samples));
            }
            if self.depth != vk::Format::UNDEFINED
                && !limits
                    .framebuffer_depth_sample_counts
                    .contains(self.samples)
            {
                missing.push(format!("{:?} depth samples", self.samples));
            }
        }
        if missing.is_empty() {
            Ok(())
        } else {
            Err(Error::Unsupported {
                device: ctx.device_name().to_string(),
                missing,
            })
        }
    }
}

/// How to make a [`Recorder`](crate::Recorder).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RecorderDesc {
    /// The attachments.
    pub formats: TargetFormats,
    /// Dynamic rendering or the caller's render pass.
    pub rendering: Rendering,
    /// Also make the geomorphing pipeline, for [`RecordCamera::morph`](crate::RecordCamera).
    pub geomorph: bool,
    /// Also make wireframe pipelines (needs `fillModeNonSolid`, see
    /// [`DeviceFeatures`](crate::DeviceFeatures)), for
    /// [`RecordCamera::wireframe`](crate::RecordCamera).
    pub wireframe: bool,
    /// Also make the refinement-geomorph pipelines (the morphing vertex stage and the
    /// compute stage), for [`RecordCamera::refine_morphs`](crate::RecordCamera) and
    /// [`CameraMorphs`](crate::CameraMorphs).
    pub refine_morphs: bool,
}

impl RecorderDesc {
    /// Dynamic rendering into `formats`; no geomorph, no wireframe, no refinement
    /// geomorphs.
    pub fn dynamic(formats: TargetFormats) -> Self {
        Self {
            formats,
            rendering: Rendering::Dynamic,
            geomorph: false,
            wireframe: false,
            refine_morphs: false,
        }
    }

    /// Subpass `subpass` of the caller's `render_pass`, whose attachments have `formats`;
    /// no geomorph, no wireframe, no refinement geomorphs.
    pub fn render_pass(formats: TargetFormats, render_pass: vk::RenderPass, subpass: u32) -> Self {
        Self {
            formats,
            rendering: Rendering::RenderPass {
                render_pass,
                subpass,
            },
            geomorph: false,
            wireframe: false,
            refine_morphs: false,
        }
    }
}
