//! The headless renderer: targets, frames in flight, read-back and submission around the
//! record path (the frame's steps are on [`Renderer`]; recording a target's commands is in
//! `record`, one function per step).

mod record;

use ash::vk;

use crate::buffer::{Buffer, BufferDesc};
use crate::camera_morphs::CameraMorphs;
use crate::device::Context;
use crate::error::{Error, Result, VkResultExt};
use crate::image::{Image, ImageDesc};
use crate::readback::RgbaImage;
use crate::record::{RecordCamera, Recorder};
use crate::target::{RecorderDesc, TargetFormats};
use crate::vertex_pool::VertexPool;

/// How to make a [`Renderer`].
#[derive(Clone, Debug, PartialEq)]
pub struct RendererDesc {
    /// Size (width, height) of each colour + depth target.
    pub targets: Vec<(u32, u32)>,
    /// Frames in flight (index buffers per camera must have as many slots).
    pub frames_in_flight: usize,
    /// Copy every target into a host-visible buffer each frame (for [`Renderer::read_target`]).
    pub readback: bool,
    /// Clear colour (linear RGBA).
    pub clear_colour: [f32; 4],
    /// Also create the geomorphing pipeline (`geomorph_vs`), for [`RecordCamera::morph`].
    pub geomorph: bool,
    /// Also create the refinement-geomorph pipelines, for [`RecordCamera::refine_morphs`].
    pub refine_morphs: bool,
}

impl RendererDesc {
    /// One target of `width` × `height`, two frames in flight, read-back enabled.
    pub fn single(width: u32, height: u32) -> Self {
        Self {
            targets: vec![(width, height)],
            frames_in_flight: 2,
            readback: true,
            clear_colour: [0.0, 0.0, 0.0, 1.0],
            geomorph: false,
            refine_morphs: false,
        }
    }
}

/// What one frame did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FrameStats {
    /// Frame number (0 for the first).
    pub frame: u64,
    /// Frame slot used.
    pub slot: usize,
    /// Index bytes the frame's cameras draw, all cameras (what was written into their
    /// index rings' slot for the frame).
    pub index_bytes: u64,
    /// Index bytes per camera.
    pub camera_index_bytes: Vec<u64>,
    /// Indexed draws recorded (one per camera and non-empty surface).
    pub draws: u32,
    /// Vertex bytes the frame copied into vertex pools (page installs).
    pub vertex_install_bytes: u64,
}

struct Target {
    colour: Image,
    depth: Image,
}

struct FrameSlot {
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    /// The fence belongs to a submission (else it may be unsignalled for good: a frame
    /// whose submission failed after the fence was reset).
    pending: bool,
    readback: Vec<Buffer>,
}

/// A headless convenience over the record path: RGBA8 + D32 targets, a command pool,
/// frames in flight with fences, read-back, and one queue submission per frame. Engines use
/// [`Recorder`] in their own frame instead; this is what the tests and the CLI use. Its
/// cameras are the record path's [`RecordCamera`]s, each with the target it draws into.
///
/// A frame is the record path's frame with the renderer as the host:
/// 1. [`Renderer::begin_frame`] waits for the next frame slot's fence (its command buffer,
///    and the cameras' index rings and morph slots for that slot, are free) and returns
///    the slot;
/// 2. the caller fills each camera's index ring for that slot ([`CameraIndices::fill`](crate::CameraIndices::fill))
///    and, for refinement geomorphs, its morph slots ([`CameraMorphs::fill`]);
/// 3. [`Renderer::render`] records the compute stage of blending morphs, then per target:
///    transitions colour + depth, begins dynamic rendering (clear) and records the
///    target's cameras through [`Recorder`]; optionally copies each colour target into the
///    slot's read-back buffer; and submits with synchronization2 and the slot's fence.
///
/// Several cameras share a target through viewports (the paper's split screen) or use
/// separate targets; either way all of them go into the one submission.
///
/// View-projection matrices are in Vulkan's clip space (y down, depth 0..1; glam's
/// `camera::rh::proj::vulkan::perspective`, see [`LookAt`](crate::LookAt)), so viewports
/// are plain rectangles.
pub struct Renderer {
    desc: RendererDesc,
    recorder: Recorder,
    targets: Vec<Target>,
    pool: vk::CommandPool,
    slots: Vec<FrameSlot>,
    frame: u64,
    /// The slot [`Renderer::begin_frame`] handed out for the frame not yet rendered.
    begun: Option<usize>,
    last_slot: Option<usize>,
}

impl Renderer {
    /// Creates targets, pipeline, command buffers and fences.
    pub fn new(ctx: &Context, desc: RendererDesc) -> Result<Self> {
        if desc.targets.is_empty() || desc.frames_in_flight == 0 {
            return Err(Error::InvalidArgument(
                "a renderer needs at least one target and one frame in flight".into(),
            ));
        }
        let d = &ctx.device;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: valid create info.
        let pool = unsafe { d.create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool")?;
        let recorder = match Recorder::new(
            ctx,
            RecorderDesc {
                geomorph: desc.geomorph,
                refine_morphs: desc.refine_morphs,
                ..RecorderDesc::dynamic(TargetFormats::HEADLESS)
            },
        ) {
            Ok(r) => r,
            Err(e) => {
                // SAFETY: unused pool.
                unsafe { d.destroy_command_pool(pool, None) };
                return Err(e);
            }
        };
        let mut r = Self {
            desc,
            recorder,
            targets: Vec::new(),
            pool,
            slots: Vec::new(),
            frame: 0,
            begun: None,
            last_slot: None,
        };
        match r.create_resources(ctx) {
            Ok(()) => Ok(r),
            Err(e) => {
                let _ = r.destroy(ctx);
                Err(e)
            }
        }
    }

    fn create_resources(&mut self, ctx: &Context) -> Result<()> {
        let d = &ctx.device;
        for (i, &(w, h)) in self.desc.targets.iter().enumerate() {
            let colour = Image::new(
                ctx,
                &format!("target {i} colour"),
                ImageDesc::colour_target(w, h),
            )?;
            let depth = match Image::new(
                ctx,
                &format!("target {i} depth"),
                ImageDesc::depth_target(w, h),
            ) {
                Ok(x) => x,
                Err(e) => {
                    colour.destroy(ctx)?;
                    return Err(e);
                }
            };
            self.targets.push(Target { colour, depth });
        }
        for s in 0..self.desc.frames_in_flight {
            let cmd = ctx.allocate_command_buffer(self.pool)?;
            let fence_info = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
            // SAFETY: valid create info.
            let fence = unsafe { d.create_fence(&fence_info, None) }.vk("vkCreateFence")?;
            self.slots.push(FrameSlot {
                cmd,
                fence,
                pending: false,
                readback: Vec::new(),
            });
            if self.desc.readback {
                for (t, &(w, h)) in self.desc.targets.iter().enumerate() {
                    let b = Buffer::new(
                        ctx,
                        &format!("read-back f{s} t{t}"),
                        BufferDesc::gpu_to_cpu(
                            u64::from(w) * u64::from(h) * 4,
                            vk::BufferUsageFlags::TRANSFER_DST,
                        ),
                    )?;
                    if let Some(slot) = self.slots.last_mut() {
                        slot.readback.push(b);
                    }
                }
            }
        }
        Ok(())
    }

    /// The recorder it draws through (for [`MaterialSet::new`](crate::MaterialSet::new)).
    pub fn recorder(&self) -> &Recorder {
        &self.recorder
    }

    /// The description.
    pub fn desc(&self) -> &RendererDesc {
        &self.desc
    }

    /// Frames rendered so far.
    pub fn frames_rendered(&self) -> u64 {
        self.frame
    }

    /// Starts the next frame: waits until its slot's last submission completed, so that
    /// the slot of every camera's index ring and morph slots may be filled; returns the
    /// slot. Calling it again before [`render`](Self::render) returns the same slot.
    pub fn begin_frame(&mut self, ctx: &Context) -> Result<usize> {
        let slot = (self.frame % self.slots.len() as u64) as usize;
        let s = &self.slots[slot];
        if s.pending {
            ctx.checkpoint("vkWaitForFences")?;
            // SAFETY: the fence is alive; waiting makes the slot's buffers free to write.
            unsafe { ctx.device.wait_for_fences(&[s.fence], true, u64::MAX) }
                .vk("vkWaitForFences")?;
            self.slots[slot].pending = false;
        }
        self.begun = Some(slot);
        Ok(slot)
    }

    /// Records and submits the frame [`begin_frame`](Self::begin_frame) started: every
    /// camera of `cameras` (with the target it draws into), whose index rings (and morph
    /// slots) the caller filled for the frame's slot (the steps are on [`Renderer`]).
    pub fn render(
        &mut self,
        ctx: &Context,
        cameras: &[(usize, RecordCamera<'_>)],
    ) -> Result<FrameStats> {
        self.render_with_pools(ctx, &[], cameras)
    }

    /// [`render`](Self::render) with the page installs of `pools` (each
    /// [`fill`](VertexPool::fill)ed for the frame's slot) recorded before everything else:
    /// the cameras' vertices come from those pools.
    pub fn render_with_pools(
        &mut self,
        ctx: &Context,
        pools: &[&VertexPool],
        cameras: &[(usize, RecordCamera<'_>)],
    ) -> Result<FrameStats> {
        let slot = self.begun.ok_or_else(|| {
            Error::InvalidArgument("a frame is rendered after begin_frame".into())
        })?;
        self.check(cameras, slot)?;
        let mut stats = FrameStats {
            frame: self.frame,
            slot,
            ..FrameStats::default()
        };
        for (_, c) in cameras {
            let bytes = c.indices.index_bytes(slot);
            stats.index_bytes += bytes;
            stats.camera_index_bytes.push(bytes);
        }
        let cmd = self.slots[slot].cmd;
        let d = &ctx.device;
        // SAFETY: the slot's previous submission completed (fence waited in `begin_frame`).
        unsafe { d.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty()) }
            .vk("vkResetCommandBuffer")?;
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: `cmd` is reset.
        unsafe { d.begin_command_buffer(cmd, &begin) }.vk("vkBeginCommandBuffer")?;
        let morphs: Vec<&CameraMorphs> = cameras
            .iter()
            .filter_map(|(_, c)| c.refine_morphs)
            .collect();
        for p in pools {
            stats.vertex_install_bytes += p.record(ctx, cmd, slot);
        }
        for (_, c) in cameras {
            c.indices.record_edits(ctx, cmd, slot);
        }
        if !morphs.is_empty() {
            self.recorder.record_morph_blends(ctx, cmd, slot, &morphs)?;
        }
        for t in 0..self.targets.len() {
            stats.draws += self.record_target(ctx, cmd, t, slot, cameras);
        }
        // SAFETY: `cmd` is recording.
        unsafe { d.end_command_buffer(cmd) }.vk("vkEndCommandBuffer")?;
        self.submit(ctx, slot)?;
        self.begun = None;
        self.last_slot = Some(slot);
        self.frame += 1;
        Ok(stats)
    }

    /// Submits `slot`'s command buffer with its fence.
    fn submit(&mut self, ctx: &Context, slot: usize) -> Result<()> {
        let (cmd, fence) = (self.slots[slot].cmd, self.slots[slot].fence);
        let d = &ctx.device;
        // SAFETY: no pending work uses the fence (waited for in `begin_frame`, or never
        // submitted).
        unsafe { d.reset_fences(&[fence]) }.vk("vkResetFences")?;
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
        ctx.checkpoint("vkQueueSubmit2")?;
        {
            let q = ctx.queue();
            // SAFETY: `cmd` is executable and references live objects; the queue is locked.
            unsafe { d.queue_submit2(*q, &submit, fence) }.vk("vkQueueSubmit2")?;
        }
        self.slots[slot].pending = true;
        Ok(())
    }

    /// Refuses a camera whose target does not exist, whose viewport leaves its target,
    /// whose index ring has another number of slots, or that the recorder refuses.
    fn check(&self, cameras: &[(usize, RecordCamera<'_>)], slot: usize) -> Result<()> {
        for (i, (target, c)) in cameras.iter().enumerate() {
            let Some(&(w, h)) = self.desc.targets.get(*target) else {
                return Err(Error::InvalidArgument(format!(
                    "camera {i}: target {target} of {}",
                    self.targets.len()
                )));
            };
            let v = c.viewport;
            if v.width == 0
                || v.height == 0
                || u64::from(v.x) + u64::from(v.width) > u64::from(w)
                || u64::from(v.y) + u64::from(v.height) > u64::from(h)
            {
                return Err(Error::InvalidArgument(format!(
                    "camera {i}: viewport {v:?} outside its {w}x{h} target"
                )));
            }
            if c.indices.frames_in_flight() != self.slots.len() {
                return Err(Error::InvalidArgument(format!(
                    "camera {i}: index buffers for {} frames in flight, renderer has {}",
                    c.indices.frames_in_flight(),
                    self.slots.len()
                )));
            }
            self.recorder.check_camera(i, slot, c)?;
        }
        Ok(())
    }

    /// The fences of submitted frames.
    fn pending_fences(&self) -> Vec<vk::Fence> {
        self.slots
            .iter()
            .filter(|s| s.pending)
            .map(|s| s.fence)
            .collect()
    }

    /// Waits for every submitted frame.
    pub fn wait(&self, ctx: &Context) -> Result<()> {
        let fences = self.pending_fences();
        if fences.is_empty() {
            return Ok(());
        }
        ctx.checkpoint("vkWaitForFences")?;
        // SAFETY: the fences are alive.
        unsafe { ctx.device.wait_for_fences(&fences, true, u64::MAX) }.vk("vkWaitForFences")
    }

    /// Waits for the last frame and returns target `t`'s pixels (needs
    /// [`RendererDesc::readback`]).
    pub fn read_target(&self, ctx: &Context, t: usize) -> Result<RgbaImage> {
        let slot = self
            .last_slot
            .ok_or_else(|| Error::InvalidArgument("no frame rendered yet".into()))?;
        self.read_slot_target(ctx, slot, t)
    }

    /// Waits for the frame last rendered in `slot` (the slot [`render`](Self::render)
    /// reported) and returns target `t`'s pixels as that frame left them, while later frames
    /// stay in flight; valid until the slot's next [`begin_frame`](Self::begin_frame).
    pub fn read_slot_target(&self, ctx: &Context, slot: usize, t: usize) -> Result<RgbaImage> {
        let s = self.slots.get(slot).ok_or_else(|| {
            Error::InvalidArgument(format!("frame slot {slot} of {}", self.slots.len()))
        })?;
        let buffer = s.readback.get(t).ok_or_else(|| {
            Error::InvalidArgument(format!(
                "target {t}: no read-back buffer (read-back disabled or no such target)"
            ))
        })?;
        if s.pending {
            ctx.checkpoint("vkWaitForFences")?;
            // SAFETY: the fence is alive.
            unsafe { ctx.device.wait_for_fences(&[s.fence], true, u64::MAX) }
                .vk("vkWaitForFences")?;
        }
        let (w, h) = self.desc.targets[t];
        let bytes = buffer
            .mapped()
            .ok_or_else(|| Error::InvalidArgument("read-back memory is not host-visible".into()))?;
        let len = (w as usize) * (h as usize) * 4;
        Ok(RgbaImage {
            width: w,
            height: h,
            pixels: bytes[..len].to_vec(),
        })
    }

    /// Waits for pending frames and destroys everything the renderer made (after a lost
    /// device too, whose objects may be destroyed).
    pub fn destroy(self, ctx: &Context) -> Result<()> {
        let waited = ctx.wait_for_teardown(&self.pending_fences());
        let d = &ctx.device;
        let mut first_err = waited.err();
        for s in self.slots {
            // SAFETY: the fence's work completed.
            unsafe { d.destroy_fence(s.fence, None) };
            for b in s.readback {
                if let Err(e) = b.destroy(ctx) {
                    first_err.get_or_insert(e);
                }
            }
        }
        for t in self.targets {
            for img in [t.colour, t.depth] {
                if let Err(e) = img.destroy(ctx) {
                    first_err.get_or_insert(e);
                }
            }
        }
        // SAFETY: no command buffer of the pool is pending.
        unsafe { d.destroy_command_pool(self.pool, None) };
        if let Err(e) = self.recorder.destroy(ctx) {
            first_err.get_or_insert(e);
        }
        first_err.map_or(Ok(()), Err)
    }
}
