//! A windowless target the host owns: colour of any format and sample count, its resolve
//! image when multisampled, depth(-stencil), rendered through the host's own render pass or
//! dynamic rendering, and optionally copied into a read-back buffer after each frame.

use caveclod_vulkan::ash::vk;
use caveclod_vulkan::{Rendering, RgbaImage, TargetFormats};

use crate::error::{Error, Result};
use crate::host::Host;
use crate::image::{Image, ImageDesc, ReadbackBuffer};
use crate::rendering::{self, Attachments};

/// How the host begins its rendering.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TargetRendering {
    /// Its own `VkRenderPass` (one subpass; colour, depth-stencil, resolve when
    /// multisampled).
    RenderPass,
    /// `vkCmdBeginRendering` (resolving through the attachment's resolve view).
    Dynamic,
}

/// How to make a [`Target`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TargetDesc {
    /// Formats and sample count.
    pub formats: TargetFormats,
    /// Size.
    pub extent: vk::Extent2D,
    /// Render pass or dynamic rendering.
    pub rendering: TargetRendering,
    /// Copy the (resolved) colour into a host-visible buffer after each frame
    /// ([`Target::pixels`]).
    pub readback: bool,
    /// The colour the rendering clears to (linear RGBA).
    pub clear: [f32; 4],
}

impl TargetDesc {
    /// A `width` × `height` target of `formats` through dynamic rendering, read back,
    /// cleared to opaque black.
    pub fn new(formats: TargetFormats, width: u32, height: u32) -> Self {
        Self {
            formats,
            extent: vk::Extent2D { width, height },
            rendering: TargetRendering::Dynamic,
            readback: true,
            clear: [0.0, 0.0, 0.0, 1.0],
        }
    }
}

/// The host's windowless target (see the module docs). A frame is
/// [`begin`](Self::begin), caveclod's recording, [`end`](Self::end), the submission and,
/// once it completed, [`pixels`](Self::pixels).
pub struct Target {
    desc: TargetDesc,
    colour: Image,
    resolve: Option<Image>,
    depth: Image,
    render_pass: vk::RenderPass,
    framebuffer: vk::Framebuffer,
    readback: Option<ReadbackBuffer>,
}

impl Target {
    /// Makes the attachments, the read-back buffer and, for
    /// [`TargetRendering::RenderPass`], the render pass (subpass 0 draws) and framebuffer.
    pub fn new(host: &Host, desc: TargetDesc) -> Result<Self> {
        let (w, h) = (desc.extent.width, desc.extent.height);
        if w == 0 || h == 0 {
            return Err(Error::InvalidArgument(format!("an empty {w}x{h} target")));
        }
        let f = desc.formats;
        let multisampled = f.samples != vk::SampleCountFlags::TYPE_1;
        let single = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
        let colour = Image::new(
            host,
            "target colour",
            ImageDesc {
                format: f.colour,
                extent: desc.extent,
                samples: f.samples,
                usage: if multisampled {
                    vk::ImageUsageFlags::COLOR_ATTACHMENT
                } else {
                    single
                },
            },
        )?;
        let mut target = Self {
            desc,
            colour,
            resolve: None,
            depth: Image::null(desc.formats.depth),
            render_pass: vk::RenderPass::null(),
            framebuffer: vk::Framebuffer::null(),
            readback: None,
        };
        match target.make_rest(host, multisampled, single) {
            Ok(()) => Ok(target),
            Err(e) => {
                let _ = target.destroy(host);
                Err(e)
            }
        }
    }

    /// The resolve and depth images, the render pass and framebuffer, the read-back buffer.
    fn make_rest(
        &mut self,
        host: &Host,
        multisampled: bool,
        single: vk::ImageUsageFlags,
    ) -> Result<()> {
        let (f, extent) = (self.desc.formats, self.desc.extent);
        if multisampled {
            let desc = ImageDesc {
                format: f.colour,
                extent,
                samples: vk::SampleCountFlags::TYPE_1,
                usage: single,
            };
            self.resolve = Some(Image::new(host, "target resolve", desc)?);
        }
        let depth = ImageDesc {
            format: f.depth,
            extent,
            samples: f.samples,
            usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        };
        self.depth = Image::new(host, "target depth", depth)?;
        if self.desc.rendering == TargetRendering::RenderPass {
            let d = host.device();
            self.render_pass = rendering::create_render_pass(d, f)?;
            self.framebuffer =
                rendering::create_framebuffer(d, self.render_pass, &self.attachments())?;
        }
        if self.desc.readback {
            let size = 4 * u64::from(extent.width) * u64::from(extent.height);
            self.readback = Some(ReadbackBuffer::new(host, "target read-back", size)?);
        }
        Ok(())
    }

    /// What it was made with.
    pub fn desc(&self) -> &TargetDesc {
        &self.desc
    }

    /// Its formats and sample count.
    pub fn formats(&self) -> TargetFormats {
        self.desc.formats
    }

    /// Its size.
    pub fn extent(&self) -> vk::Extent2D {
        self.desc.extent
    }

    /// The host's render pass ([`TargetRendering::RenderPass`]; null otherwise).
    pub fn render_pass(&self) -> vk::RenderPass {
        self.render_pass
    }

    /// The rendering caveclod's recorder must be made for (subpass 0 of the render pass,
    /// or dynamic rendering).
    pub fn recorder_rendering(&self) -> Rendering {
        match self.desc.rendering {
            TargetRendering::RenderPass => Rendering::RenderPass {
                render_pass: self.render_pass,
                subpass: 0,
            },
            TargetRendering::Dynamic => Rendering::Dynamic,
        }
    }

    /// The images a frame renders into.
    pub fn attachments(&self) -> Attachments {
        Attachments {
            colour: (self.colour.raw, self.colour.view),
            resolve: self.resolve.as_ref().map(|r| (r.raw, r.view)),
            depth: (self.depth.raw, self.depth.view, self.desc.formats.depth),
            extent: self.desc.extent,
        }
    }

    /// The single-sample colour image: the resolve target, or the colour itself (after a
    /// frame with read-back, or through the render pass, in `TRANSFER_SRC_OPTIMAL`).
    pub fn single_sample(&self) -> vk::Image {
        self.attachments().single_sample()
    }

    /// Records the start of a frame into `cmd`: the host's render pass, or the layout
    /// transitions and dynamic rendering; both clear. caveclod records inside it next.
    pub fn begin(&self, host: &Host, cmd: vk::CommandBuffer) {
        let d = host.device();
        match self.desc.rendering {
            TargetRendering::RenderPass => rendering::begin_render_pass(
                d,
                cmd,
                self.render_pass,
                self.framebuffer,
                self.desc.extent,
                self.resolve.is_some(),
                self.desc.clear,
            ),
            TargetRendering::Dynamic => {
                rendering::begin_dynamic(d, cmd, &self.attachments(), self.desc.clear)
            }
        }
    }

    /// Records the end of the frame's rendering into `cmd` and, with read-back, the copy of
    /// the (resolved) colour into the read-back buffer.
    pub fn end(&self, host: &Host, cmd: vk::CommandBuffer) {
        let d = host.device();
        let layout = match self.desc.rendering {
            TargetRendering::RenderPass => {
                // SAFETY: `cmd` is inside the render pass `begin` began.
                unsafe { d.cmd_end_render_pass(cmd) };
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL
            }
            TargetRendering::Dynamic => {
                rendering::end_dynamic(d, cmd);
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL
            }
        };
        if let Some(b) = &self.readback {
            let image = self.single_sample();
            rendering::copy_out(d, cmd, image, layout, self.desc.extent, b.raw);
        }
    }

    /// The last frame's pixels as RGBA8 (BGRA formats swizzled; sRGB values as stored),
    /// once its submission completed.
    pub fn pixels(&self) -> Result<RgbaImage> {
        let b = self.readback.as_ref().ok_or_else(|| {
            Error::InvalidArgument("the target was made without read-back".into())
        })?;
        b.image(self.desc.extent, self.desc.formats.colour)
    }

    /// Destroys what the target made, in reverse order. The GPU must be done with it.
    pub fn destroy(self, host: &Host) -> Result<()> {
        let d = host.device();
        let mut result = Ok(());
        if let Some(b) = self.readback {
            result = result.and(b.destroy(host));
        }
        // SAFETY: the GPU is done with them (the caller's contract); null handles are
        // ignored.
        unsafe {
            d.destroy_framebuffer(self.framebuffer, None);
            d.destroy_render_pass(self.render_pass, None);
        }
        for image in [Some(self.depth), self.resolve, Some(self.colour)]
            .into_iter()
            .flatten()
        {
            let destroyed = image.destroy(host);
            result = result.and(destroyed);
        }
        result
    }
}
