//! The record path as a host engine drives it, for the paired frame-time comparison with
//! the headless `Renderer`: caveclod-host's target (the host's own colour and depth images,
//! no read-back) and frames (command buffers and fences for two frames in flight), its
//! barriers and dynamic rendering; caveclod's `Recorder` records the cameras.

use std::time::{Duration, Instant};

use caveclod_core::CameraState;
use caveclod_host::{Frames, Host, Target, TargetDesc};
use caveclod_vulkan::{
    CameraIndices, Context, Recorder, RecorderDesc, RendererDesc, TargetFormats, Viewport,
};

use crate::scene::{or_exit, Scene, HEIGHT, WIDTH};

/// A host's frame loop over the record path.
pub struct HostFrames<'s, 'c> {
    target: Target,
    recorder: Recorder,
    frames: Frames,
    frame: u64,
    indices: Vec<CameraIndices>,
    cams: &'s [CameraState<'c>],
    viewports: &'s [Viewport],
}

impl<'s, 'c> HostFrames<'s, 'c> {
    /// The target, recorder, frames in flight (as many as the headless renderer's) and one
    /// index ring per camera.
    pub fn new(
        host: &Host,
        scene: &Scene<'_>,
        cams: &'s [CameraState<'c>],
        viewports: &'s [Viewport],
    ) -> Self {
        let desc = TargetDesc {
            readback: false,
            ..TargetDesc::new(TargetFormats::HEADLESS, WIDTH, HEIGHT)
        };
        let target = or_exit(Target::new(host, desc), "host target");
        let recorder = or_exit(
            Recorder::new(scene.ctx, RecorderDesc::dynamic(target.formats())),
            "recorder",
        );
        let slots = RendererDesc::single(WIDTH, HEIGHT).frames_in_flight;
        let frames = or_exit(Frames::new(host, slots, false), "frames in flight");
        let surfaces = scene.h.surface_count();
        let indices = (0..cams.len())
            .map(|i| CameraIndices::new(&format!("host camera {i}"), surfaces, slots))
            .collect();
        Self {
            target,
            recorder,
            frames,
            frame: 0,
            indices,
            cams,
            viewports,
        }
    }

    /// One frame, waited for: its latency.
    pub fn frame(&mut self, host: &Host, scene: &Scene<'_>) -> Duration {
        let t = Instant::now();
        let slot = self.frames.slot_of(self.frame);
        self.frame += 1;
        or_exit(self.frames.wait(host, slot), "wait");
        scene.fill(slot, &mut self.indices, self.cams);
        let cmd = or_exit(self.frames.begin(host, slot), "begin");
        self.target.begin(host, cmd);
        let cameras = scene.cameras(&self.indices, self.viewports);
        or_exit(
            self.recorder.record(scene.ctx, cmd, slot, &cameras),
            "record",
        );
        self.target.end(host, cmd);
        or_exit(self.frames.submit(host, slot, &[], &[]), "submit");
        or_exit(self.frames.wait(host, slot), "wait");
        t.elapsed()
    }

    /// Waits for the frames, then destroys what it made, in reverse order.
    pub fn destroy(self, host: &Host, ctx: &Context) {
        or_exit(self.frames.destroy(host), "destroy frames");
        for i in self.indices {
            or_exit(i.destroy(ctx), "destroy indices");
        }
        or_exit(self.recorder.destroy(ctx), "destroy recorder");
        or_exit(self.target.destroy(host), "destroy target");
    }
}
