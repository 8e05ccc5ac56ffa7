//! Buffers: a Vulkan buffer with its gpu-allocator allocation, described by a value-type
//! [`BufferDesc`] and destroyed explicitly through the context (kajiya's `Buffer`).

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use crate::device::Context;
use crate::error::{Error, Result, VkResultExt};

/// What a buffer is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BufferDesc {
    /// Size in bytes (> 0).
    pub size: u64,
    /// Usage flags.
    pub usage: vk::BufferUsageFlags,
    /// Where its memory lives.
    pub location: MemoryLocation,
}

impl BufferDesc {
    /// Device-local memory, written by transfers.
    pub fn gpu_only(size: u64, usage: vk::BufferUsageFlags) -> Self {
        Self {
            size,
            usage,
            location: MemoryLocation::GpuOnly,
        }
    }

    /// Host-visible memory the CPU writes and the GPU reads.
    pub fn cpu_to_gpu(size: u64, usage: vk::BufferUsageFlags) -> Self {
        Self {
            size,
            usage,
            location: MemoryLocation::CpuToGpu,
        }
    }

    /// Host-visible memory the GPU writes and the CPU reads.
    pub fn gpu_to_cpu(size: u64, usage: vk::BufferUsageFlags) -> Self {
        Self {
            size,
            usage,
            location: MemoryLocation::GpuToCpu,
        }
    }
}

/// A buffer and its memory.
#[derive(Debug)]
pub struct Buffer {
    /// The Vulkan handle.
    pub raw: vk::Buffer,
    /// Its description.
    pub desc: BufferDesc,
    allocation: Allocation,
    id: u64,
}

impl Buffer {
    /// Creates a buffer named `name` (for leak reports and allocator reports).
    pub fn new(ctx: &Context, name: &str, desc: BufferDesc) -> Result<Self> {
        if desc.size == 0 {
            return Err(Error::InvalidArgument(format!("buffer {name}: size 0")));
        }
        let d = &ctx.device;
        let info = vk::BufferCreateInfo::default()
            .size(desc.size)
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid create info.
        let raw = unsafe { d.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        // SAFETY: `raw` is alive.
        let requirements = unsafe { d.get_buffer_memory_requirements(raw) };
        let allocated = ctx.allocate(&AllocationCreateDesc {
            name,
            requirements,
            location: desc.location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocated {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: `raw` is unused.
                unsafe { d.destroy_buffer(raw, None) };
                return Err(e);
            }
        };
        // SAFETY: the allocation satisfies `requirements` and is not bound elsewhere.
        let bound = unsafe { d.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) }
            .vk("vkBindBufferMemory");
        if let Err(e) = bound {
            // SAFETY: `raw` is unused.
            unsafe { d.destroy_buffer(raw, None) };
            let _ = ctx.free(name, allocation);
            return Err(e);
        }
        let id = ctx.track(name);
        Ok(Self {
            raw,
            desc,
            allocation,
            id,
        })
    }

    /// The mapped bytes of a host-visible buffer (`None` for device-local memory).
    pub fn mapped(&self) -> Option<&[u8]> {
        self.allocation
            .mapped_slice()
            .map(|s| &s[..(self.desc.size as usize).min(s.len())])
    }

    /// The mapped bytes of a host-visible buffer, writable.
    pub fn mapped_mut(&mut self) -> Option<&mut [u8]> {
        let size = self.desc.size as usize;
        self.allocation.mapped_slice_mut().map(|s| {
            let n = size.min(s.len());
            &mut s[..n]
        })
    }

    /// Destroys the buffer and frees its memory. The GPU must be done with it.
    pub fn destroy(self, ctx: &Context) -> Result<()> {
        // SAFETY: the caller guarantees no pending GPU work uses the buffer.
        unsafe { ctx.device.destroy_buffer(self.raw, None) };
        ctx.untrack(self.id);
        ctx.free("buffer free", self.allocation)
    }
}

/// Makes `slot` a host-visible buffer (`usage`) of at least `needed` elements of `stride`
/// bytes: kept when it holds them, else replaced by one of at least `min` elements doubled
/// until it does (so a growing need reallocates O(log n) times, never per frame), named
/// `name()`, the old one destroyed. Returns whether it grew. The GPU must be done with the
/// old buffer.
pub(crate) fn reserve_host(
    ctx: &Context,
    slot: &mut Option<Buffer>,
    name: impl FnOnce() -> String,
    (stride, min, needed): (u64, u64, u64),
    usage: vk::BufferUsageFlags,
) -> Result<bool> {
    let cap = slot.as_ref().map_or(0, |b| b.desc.size / stride.max(1));
    if needed <= cap {
        return Ok(false);
    }
    let mut new_cap = cap.max(min).max(1);
    while new_cap < needed {
        new_cap = new_cap.saturating_mul(2);
    }
    let buffer = Buffer::new(
        ctx,
        &name(),
        BufferDesc::cpu_to_gpu(new_cap * stride, usage),
    )?;
    if let Some(old) = slot.replace(buffer) {
        old.destroy(ctx)?;
    }
    Ok(true)
}

/// Records `copies` (into `cmd`, outside rendering) between two barriers: the reads
/// (`reads` stages) and copies of every earlier submission on the queue before them, so a
/// frame in flight never sees what they overwrite; and the copies before this frame's reads
/// (`reads`, `access`).
pub(crate) fn copies_between_barriers(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    (reads, access): (vk::PipelineStageFlags2, vk::AccessFlags2),
    copies: impl FnOnce(&ash::Device),
) {
    let before = [vk::MemoryBarrier2::default()
        .src_stage_mask(reads | vk::PipelineStageFlags2::COPY)
        .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::COPY)
        .dst_access_mask(vk::AccessFlags2::TRANSFER_WRITE)];
    let after = [vk::MemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::COPY)
        .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .dst_stage_mask(reads)
        .dst_access_mask(access)];
    let d = &ctx.device;
    // SAFETY: `cmd` is recording outside rendering (the callers' contract).
    unsafe {
        d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&before))
    };
    copies(d);
    // SAFETY: as above.
    unsafe { d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&after)) };
}
