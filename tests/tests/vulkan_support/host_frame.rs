//! The record-path tests' frame: caveclod-host's windowless target (its own images, render
//! pass or dynamic rendering, read-back) and one frame slot, each step unwrapped.

use caveclod_host::{Frames, Host, Target, TargetDesc, TargetRendering};
use caveclod_vulkan::ash::vk;
use caveclod_vulkan::{RgbaImage, TargetFormats};

use super::ok;

/// A host target and the one command buffer and fence its frames use.
pub struct HostFrame {
    target: Target,
    frames: Frames,
}

impl HostFrame {
    /// A `w` × `h` target of `formats` through `rendering`, read back, cleared to black.
    pub fn new(
        host: &Host,
        formats: TargetFormats,
        rendering: TargetRendering,
        w: u32,
        h: u32,
    ) -> Self {
        let desc = TargetDesc {
            rendering,
            ..TargetDesc::new(formats, w, h)
        };
        Self {
            target: ok(Target::new(host, desc), "host target"),
            frames: ok(Frames::new(host, 1, false), "host frame slot"),
        }
    }

    /// The target's formats.
    pub fn formats(&self) -> TargetFormats {
        self.target.formats()
    }

    /// The host's render pass (null with dynamic rendering).
    pub fn render_pass(&self) -> vk::RenderPass {
        self.target.render_pass()
    }

    /// The single-sample colour image (after a frame, in `TRANSFER_SRC_OPTIMAL`).
    pub fn single_sample(&self) -> vk::Image {
        self.target.single_sample()
    }

    /// One frame the host's way: begin its rendering, let `record` record caveclod's draws
    /// into its command buffer, end, copy out, submit, wait; the pixels as RGBA8.
    pub fn frame(&mut self, host: &Host, record: impl FnOnce(vk::CommandBuffer)) -> RgbaImage {
        let target = &self.target;
        ok(
            self.frames.submit_and_wait(host, 0, |cmd| {
                target.begin(host, cmd);
                record(cmd);
                target.end(host, cmd);
            }),
            "host frame",
        );
        ok(self.target.pixels(), "host read-back")
    }

    /// Records `record` outside any rendering, submits it and waits (the host's uploads).
    pub fn submit(&mut self, host: &Host, record: impl FnOnce(vk::CommandBuffer)) {
        ok(
            self.frames.submit_and_wait(host, 0, record),
            "host submission",
        );
    }

    /// Destroys the frame slot and the target. The GPU must be idle.
    pub fn destroy(self, host: &Host) {
        ok(self.frames.destroy(host), "destroy host frames");
        ok(self.target.destroy(host), "destroy host target");
    }
}
