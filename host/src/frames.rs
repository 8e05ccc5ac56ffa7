//! Frames in flight: per slot a command pool and buffer, a fence and, for a swapchain, the
//! semaphore its image's acquire signals. Frame `n` uses slot `n % slots`; the CPU records
//! a slot's next frame once the slot's last submission completed.

use caveclod_vulkan::ash::vk;

use crate::error::{Error, Result, VkExt};
use crate::host::Host;

/// One slot's command buffer and synchronisation.
struct Slot {
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    /// Signalled when the slot's last submission completed.
    fence: vk::Fence,
    /// The fence belongs to a submission (else it may be unsignalled for good: a frame
    /// whose submission failed after the fence was reset).
    pending: bool,
    /// Signalled by the acquire of the slot's swapchain image (null without a swapchain).
    image_available: vk::Semaphore,
}

/// A semaphore a submission waits for, and the stages that wait.
pub type Wait = (vk::Semaphore, vk::PipelineStageFlags2);

/// The host's frames in flight (see the module docs).
pub struct Frames {
    slots: Vec<Slot>,
}

impl Frames {
    /// `count` slots (at least one); with `acquire_semaphores`, each with the semaphore a
    /// swapchain acquire signals.
    pub fn new(host: &Host, count: usize, acquire_semaphores: bool) -> Result<Self> {
        if count == 0 {
            return Err(Error::InvalidArgument("no frames in flight".into()));
        }
        let mut frames = Self {
            slots: Vec::with_capacity(count),
        };
        for _ in 0..count {
            match Slot::new(host, acquire_semaphores) {
                Ok(s) => frames.slots.push(s),
                Err(e) => {
                    let _ = frames.destroy(host);
                    return Err(e);
                }
            }
        }
        Ok(frames)
    }

    /// Slots (frames in flight).
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// Always false: there is at least one slot.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// The slot frame `frame` uses.
    pub fn slot_of(&self, frame: u64) -> usize {
        (frame % self.slots.len() as u64) as usize
    }

    fn slot(&self, slot: usize) -> Result<&Slot> {
        self.slots.get(slot).ok_or_else(|| {
            Error::InvalidArgument(format!("frame slot {slot} of {}", self.slots.len()))
        })
    }

    /// The semaphore the acquire of `slot`'s swapchain image signals.
    pub fn image_available(&self, slot: usize) -> Result<vk::Semaphore> {
        Ok(self.slot(slot)?.image_available)
    }

    /// Waits until `slot`'s last submission completed: its command buffer, and whatever
    /// the frame wrote for the GPU (index rings, morph slots), are free again.
    pub fn wait(&mut self, host: &Host, slot: usize) -> Result<()> {
        let s = self.slot(slot)?;
        if s.pending {
            let fence = [s.fence];
            // SAFETY: the fence is alive and belongs to a submission.
            unsafe { host.device().wait_for_fences(&fence, true, u64::MAX) }
                .vk("vkWaitForFences")?;
            self.slots[slot].pending = false;
        }
        Ok(())
    }

    /// Waits for every slot's last submission.
    pub fn wait_all(&mut self, host: &Host) -> Result<()> {
        (0..self.slots.len()).try_for_each(|s| self.wait(host, s))
    }

    /// Waits for `slot` ([`wait`](Self::wait)), then resets and begins its command buffer
    /// (one submission); returns it for the frame's commands.
    pub fn begin(&mut self, host: &Host, slot: usize) -> Result<vk::CommandBuffer> {
        self.wait(host, slot)?;
        let cmd = self.slot(slot)?.cmd;
        let d = host.device();
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the slot's last submission completed (waited for above) and its pool
        // allows resetting the buffer.
        unsafe {
            d.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())
                .vk("vkResetCommandBuffer")?;
            d.begin_command_buffer(cmd, &begin)
                .vk("vkBeginCommandBuffer")?;
        }
        Ok(cmd)
    }

    /// Ends `slot`'s command buffer (begun by [`begin`](Self::begin)) and submits it to the
    /// host's queue, waiting for `waits` and signalling `signals` and the slot's fence.
    pub fn submit(
        &mut self,
        host: &Host,
        slot: usize,
        waits: &[Wait],
        signals: &[vk::Semaphore],
    ) -> Result<()> {
        let (cmd, fence) = {
            let s = self.slot(slot)?;
            (s.cmd, s.fence)
        };
        let d = host.device();
        // SAFETY: `cmd` is recording (begun by `begin`).
        unsafe { d.end_command_buffer(cmd) }.vk("vkEndCommandBuffer")?;
        let waits: Vec<vk::SemaphoreSubmitInfo<'_>> = waits
            .iter()
            .map(|&(semaphore, stages)| {
                vk::SemaphoreSubmitInfo::default()
                    .semaphore(semaphore)
                    .stage_mask(stages)
            })
            .collect();
        let signals: Vec<vk::SemaphoreSubmitInfo<'_>> = signals
            .iter()
            .map(|&semaphore| {
                vk::SemaphoreSubmitInfo::default()
                    .semaphore(semaphore)
                    .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            })
            .collect();
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = [vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cmds)
            .signal_semaphore_infos(&signals)];
        // SAFETY: no pending work uses the fence (`begin` waited for the slot); `cmd` is
        // executable and references live objects; the semaphores are the caller's, with a
        // pending signal for each wait; the host submits from one thread.
        unsafe {
            d.reset_fences(&[fence]).vk("vkResetFences")?;
            d.queue_submit2(host.queue(), &submit, fence)
                .vk("vkQueueSubmit2")?;
        }
        self.slots[slot].pending = true;
        Ok(())
    }

    /// Records `record` into `slot`'s command buffer, submits it and waits for it: a
    /// one-off submission (uploads, a frame read back at once).
    pub fn submit_and_wait(
        &mut self,
        host: &Host,
        slot: usize,
        record: impl FnOnce(vk::CommandBuffer),
    ) -> Result<()> {
        let cmd = self.begin(host, slot)?;
        record(cmd);
        self.submit(host, slot, &[], &[])?;
        self.wait(host, slot)
    }

    /// Waits for every slot, then destroys the semaphores, fences and pools (with their
    /// command buffers).
    pub fn destroy(mut self, host: &Host) -> Result<()> {
        let waited = self.wait_all(host);
        let d = host.device();
        for s in self.slots {
            // SAFETY: every submission of the slot completed (waited for above; a lost
            // device's objects may be destroyed too); null handles are ignored.
            unsafe {
                d.destroy_semaphore(s.image_available, None);
                d.destroy_fence(s.fence, None);
                d.destroy_command_pool(s.pool, None);
            }
        }
        waited
    }
}

impl Slot {
    fn new(host: &Host, acquire_semaphore: bool) -> Result<Self> {
        let d = host.device();
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(host.queue_family())
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: valid create info.
        let pool = unsafe { d.create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool")?;
        let mut slot = Self {
            pool,
            cmd: vk::CommandBuffer::null(),
            fence: vk::Fence::null(),
            pending: false,
            image_available: vk::Semaphore::null(),
        };
        match slot.fill(host, acquire_semaphore) {
            Ok(()) => Ok(slot),
            Err(e) => {
                // SAFETY: nothing of the slot was submitted; null handles are ignored.
                unsafe {
                    d.destroy_semaphore(slot.image_available, None);
                    d.destroy_fence(slot.fence, None);
                    d.destroy_command_pool(slot.pool, None);
                }
                Err(e)
            }
        }
    }

    /// The command buffer, the fence and the acquire semaphore.
    fn fill(&mut self, host: &Host, acquire_semaphore: bool) -> Result<()> {
        let d = host.device();
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool is alive.
        self.cmd = unsafe { d.allocate_command_buffers(&alloc) }
            .vk("vkAllocateCommandBuffers")?
            .first()
            .copied()
            .ok_or_else(|| Error::InvalidArgument("no command buffer allocated".into()))?;
        // SAFETY: valid create info.
        self.fence =
            unsafe { d.create_fence(&vk::FenceCreateInfo::default(), None) }.vk("vkCreateFence")?;
        if acquire_semaphore {
            // SAFETY: valid create info.
            self.image_available =
                unsafe { d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
                    .vk("vkCreateSemaphore")?;
        }
        Ok(())
    }
}
