//! The headless renderer: targets, frames in flight, read-back and submission around the
//! record path (the frame's steps are on [`Renderer`]; recording a target's commands is in
//! `record`, one function per step).

mod record;

use ash::vk;
use glam::Mat4;

use crate::buffer::{Buffer, BufferDesc};
use crate::camera_morphs::CameraMorphs;
use crate::device::Context;
use crate::error::{Error, Result, VkResultExt};
use crate::image::{Image, ImageDesc};
use crate::indices::{CameraIndices, IndexSource};
use crate::material::MaterialSet;
use crate::mesh::VertexBuffer;
use crate::readback::RgbaImage;
use crate::record::{Morph, RecordCamera, Recorder, RecorderDesc, TargetFormats, Viewport};

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
    /// Also create the geomorphing pipeline (`geomorph_vs`), for [`CameraDraw::morph`].
    pub geomorph: bool,
    /// Also create the refinement-geomorph pipelines, for [`CameraDraw::refine_morphs`].
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

/// One camera's part of a frame.
pub struct CameraDraw<'a, 'c> {
    /// Which target (index into [`RendererDesc::targets`]).
    pub target: usize,
    /// Where in the target.
    pub viewport: Viewport,
    /// View-projection matrix into Vulkan clip space (y down, depth 0..1).
    pub view_proj: Mat4,
    /// The mesh's persistent vertex buffer.
    pub vertices: &'a VertexBuffer,
    /// This camera's index buffers.
    pub indices: &'a mut CameraIndices,
    /// Where this frame's indices come from.
    pub source: IndexSource<'a, 'c>,
    /// Colour per surface (linear RGBA); at least one per surface (used without
    /// `materials`).
    pub colours: &'a [[f32; 4]],
    /// The surfaces' materials, made for [`Renderer::recorder`].
    pub materials: Option<&'a MaterialSet>,
    /// Geomorph instead of drawing `vertices` as they are (needs [`RendererDesc::geomorph`]).
    pub morph: Option<Morph<'a>>,
    /// The camera's refinement geomorphs (needs [`RendererDesc::refine_morphs`] and
    /// `source` [`IndexSource::MorphedCamera`]), filled from the camera each frame.
    pub refine_morphs: Option<&'a mut CameraMorphs>,
}

impl CameraDraw<'_, '_> {
    /// What the recorder draws of this camera.
    fn record_camera(&self) -> RecordCamera<'_> {
        RecordCamera {
            viewport: self.viewport,
            view_proj: self.view_proj,
            vertices: self.vertices,
            indices: self.indices,
            colours: self.colours,
            materials: self.materials,
            morph: self.morph,
            refine_morphs: self.refine_morphs.as_deref(),
            wireframe: false,
        }
    }
}

/// Fills camera `i`'s morphs, if it has any, for frame slot `slot` from the camera its
/// indices come from.
fn fill_morphs(i: usize, slot: usize, cam: &mut CameraDraw<'_, '_>) -> Result<()> {
    let Some(morphs) = cam.refine_morphs.as_deref_mut() else {
        return Ok(());
    };
    match cam.source {
        IndexSource::MorphedCamera { hierarchy, camera } => {
            morphs.fill(slot, hierarchy.vertices(), camera)?;
            Ok(())
        }
        _ => Err(Error::InvalidArgument(format!(
            "camera {i}: refinement geomorphs need IndexSource::MorphedCamera"
        ))),
    }
}

/// What one frame did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FrameStats {
    /// Frame number (0 for the first).
    pub frame: u64,
    /// Frame slot used.
    pub slot: usize,
    /// Index bytes written for the GPU this frame, all cameras.
    pub index_bytes: u64,
    /// Index bytes per camera.
    pub camera_index_bytes: Vec<u64>,
    /// Indexed draws recorded (one per camera and non-empty surface).
    pub draws: u32,
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
/// [`Recorder`] in their own frame instead; this is what the tests and the CLI use.
///
/// One [`Renderer::render`] call is one frame and one queue submission:
/// 1. wait for the frame slot's fence (its command buffer and index buffers are free);
/// 2. fill each camera's index buffers for that slot ([`CameraIndices::fill`]);
/// 3. per target: transition colour + depth, begin dynamic rendering (clear), then
///    [`Recorder::record`] of the target's cameras;
/// 4. optionally copy each colour target into the slot's read-back buffer;
/// 5. submit with synchronization2 and the slot's fence.
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

    /// The recorder it draws through (for [`MaterialSet::new`]).
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

    /// Records and submits one frame of every camera in `cameras` (the steps are on
    /// [`Renderer`]).
    pub fn render(
        &mut self,
        ctx: &Context,
        cameras: &mut [CameraDraw<'_, '_>],
    ) -> Result<FrameStats> {
        let slot_index = (self.frame % self.slots.len() as u64) as usize;
        self.check(cameras)?;
        let d = &ctx.device;
        let (cmd, fence, pending) = {
            let s = &self.slots[slot_index];
            (s.cmd, s.fence, s.pending)
        };
        if pending {
            ctx.checkpoint("vkWaitForFences")?;
            // SAFETY: the fence is alive; waiting makes the slot's buffers free to write.
            unsafe { d.wait_for_fences(&[fence], true, u64::MAX) }.vk("vkWaitForFences")?;
            self.slots[slot_index].pending = false;
        }

        let mut stats = FrameStats {
            frame: self.frame,
            slot: slot_index,
            ..FrameStats::default()
        };
        for (i, cam) in cameras.iter_mut().enumerate() {
            let bytes = cam
                .indices
                .fill_camera(ctx, slot_index, Some(i), cam.source)?;
            stats.index_bytes += bytes;
            stats.camera_index_bytes.push(bytes);
            fill_morphs(i, slot_index, cam)?;
        }
        let records: Vec<(usize, RecordCamera<'_>)> = cameras
            .iter()
            .map(|c| (c.target, c.record_camera()))
            .collect();
        for (i, (_, r)) in records.iter().enumerate() {
            self.recorder.check_camera(i, slot_index, r)?;
        }

        // SAFETY: the slot's previous submission completed (fence waited).
        unsafe { d.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty()) }
            .vk("vkResetCommandBuffer")?;
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: `cmd` is reset.
        unsafe { d.begin_command_buffer(cmd, &begin) }.vk("vkBeginCommandBuffer")?;
        let morphs: Vec<&CameraMorphs> = records
            .iter()
            .filter_map(|(_, r)| r.refine_morphs)
            .collect();
        if !morphs.is_empty() {
            self.recorder
                .record_morph_blends(ctx, cmd, slot_index, &morphs)?;
        }
        for t in 0..self.targets.len() {
            stats.draws += self.record_target(ctx, cmd, t, slot_index, &records);
        }
        // SAFETY: `cmd` is recording.
        unsafe { d.end_command_buffer(cmd) }.vk("vkEndCommandBuffer")?;

        // SAFETY: no pending work uses the fence (waited for above, or never submitted).
        unsafe { d.reset_fences(&[fence]) }.vk("vkResetFences")?;
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
        ctx.checkpoint("vkQueueSubmit2")?;
        {
            let q = ctx.queue();
            // SAFETY: `cmd` is executable and references live objects; the queue is locked.
            unsafe { d.queue_submit2(*q, &submit, fence) }.vk("vkQueueSubmit2")?;
        }
        self.slots[slot_index].pending = true;
        self.last_slot = Some(slot_index);
        self.frame += 1;
        Ok(stats)
    }

    fn check(&self, cameras: &[CameraDraw<'_, '_>]) -> Result<()> {
        for (i, c) in cameras.iter().enumerate() {
            let Some(&(w, h)) = self.desc.targets.get(c.target) else {
                return Err(Error::InvalidArgument(format!(
                    "camera {i}: target {} of {}",
                    c.target,
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
        let s = &self.slots[slot];
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
