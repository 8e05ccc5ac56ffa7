//! The persistent vertex buffer of a baked mesh, and geomorph instances.

use ash::vk;
use caveclod_core::format::Vertex;
use caveclod_core::gpu::MorphInstance;
use caveclod_core::Hierarchy;

use crate::buffer::{Buffer, BufferDesc};
use crate::device::Context;
use crate::error::{Error, Result};

/// Bytes per vertex (position, normal, uv; the shaders' binding stride).
pub const VERTEX_STRIDE: u32 = std::mem::size_of::<Vertex>() as u32;

/// A device-local vertex buffer, written once at creation: the persistent vertex buffer of
/// a baked mesh.
///
/// A hierarchy's vertex buffer ([`Hierarchy::vertices`]) holds every vertex any front can
/// use, so it is uploaded once, through a staging buffer, into device-local memory and
/// never written again: refinement only changes index lists. Uploads are counted on the
/// context ([`Context::vertex_uploads`]) so tests can check that.
#[derive(Debug)]
pub struct VertexBuffer {
    /// The buffer (vertex and storage usage: the geomorph compute stage reads it too).
    pub buffer: Buffer,
    /// Number of vertices.
    pub count: u32,
}

impl VertexBuffer {
    /// Uploads a hierarchy's vertex buffer.
    pub fn from_hierarchy(ctx: &Context, name: &str, h: &Hierarchy<'_>) -> Result<Self> {
        Self::from_vertices(ctx, name, h.vertices())
    }

    /// Uploads `vertices` through a staging buffer into a new device-local buffer.
    pub fn from_vertices(ctx: &Context, name: &str, vertices: &[Vertex]) -> Result<Self> {
        if vertices.is_empty() {
            return Err(Error::InvalidArgument(format!(
                "vertex buffer {name}: no vertices"
            )));
        }
        let count = u32::try_from(vertices.len()).map_err(|_| {
            Error::InvalidArgument(format!("vertex buffer {name}: too many vertices"))
        })?;
        let bytes: &[u8] = bytemuck::cast_slice(vertices);
        let buffer = upload(
            ctx,
            name,
            bytes,
            vk::BufferUsageFlags::VERTEX_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        ctx.count_vertex_upload();
        Ok(Self { buffer, count })
    }

    /// Destroys the buffer. The GPU must be done with it.
    pub fn destroy(self, ctx: &Context) -> Result<()> {
        self.buffer.destroy(ctx)
    }
}

/// Per-instance parameters of the geomorphing vertex stage (`geomorph_vs`, binding 2), in a
/// device-local buffer uploaded at creation. Each instance draws the index lists once,
/// morphed by its own `t` and placed by its own offset and scale.
#[derive(Debug)]
pub struct MorphInstances {
    /// The buffer (vertex usage, per-instance rate).
    pub buffer: Buffer,
    /// Number of instances.
    pub count: u32,
}

impl MorphInstances {
    /// Uploads `instances` (at least one).
    pub fn new(ctx: &Context, name: &str, instances: &[MorphInstance]) -> Result<Self> {
        if instances.is_empty() {
            return Err(Error::InvalidArgument(format!(
                "morph instances {name}: none"
            )));
        }
        let count = u32::try_from(instances.len())
            .map_err(|_| Error::InvalidArgument(format!("morph instances {name}: too many")))?;
        let buffer = upload(
            ctx,
            name,
            bytemuck::cast_slice(instances),
            vk::BufferUsageFlags::VERTEX_BUFFER,
        )?;
        Ok(Self { buffer, count })
    }

    /// Destroys the buffer. The GPU must be done with it.
    pub fn destroy(self, ctx: &Context) -> Result<()> {
        self.buffer.destroy(ctx)
    }
}

/// Creates a device-local buffer with `usage` (plus transfer destination) holding `bytes`,
/// copied from a staging buffer that is destroyed before returning.
pub(crate) fn upload(
    ctx: &Context,
    name: &str,
    bytes: &[u8],
    usage: vk::BufferUsageFlags,
) -> Result<Buffer> {
    let size = bytes.len() as u64;
    let mut staging = Buffer::new(
        ctx,
        &format!("{name} (staging)"),
        BufferDesc::cpu_to_gpu(size, vk::BufferUsageFlags::TRANSFER_SRC),
    )?;
    let result = (|| {
        let dst = staging
            .mapped_mut()
            .ok_or_else(|| Error::InvalidArgument("staging memory is not host-visible".into()))?;
        dst[..bytes.len()].copy_from_slice(bytes);
        let buffer = Buffer::new(
            ctx,
            name,
            BufferDesc::gpu_only(size, usage | vk::BufferUsageFlags::TRANSFER_DST),
        )?;
        let copied = ctx.submit_and_wait(|cmd| {
            let region = [vk::BufferCopy {
                src_offset: 0,
                dst_offset: 0,
                size,
            }];
            // SAFETY: both buffers are alive and at least `size` bytes.
            unsafe {
                ctx.device
                    .cmd_copy_buffer(cmd, staging.raw, buffer.raw, &region)
            };
            // Make the copy visible to every later read (vertex input, storage reads).
            let barrier = [vk::BufferMemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::COPY)
                .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
                .dst_access_mask(vk::AccessFlags2::MEMORY_READ)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .buffer(buffer.raw)
                .offset(0)
                .size(vk::WHOLE_SIZE)];
            let dep = vk::DependencyInfo::default().buffer_memory_barriers(&barrier);
            // SAFETY: `cmd` is recording.
            unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &dep) };
        });
        match copied {
            Ok(()) => Ok(buffer),
            Err(e) => {
                let _ = buffer.destroy(ctx);
                Err(e)
            }
        }
    })();
    staging.destroy(ctx)?;
    result
}
