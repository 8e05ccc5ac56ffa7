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
    /// The buffer (vertex and storage usage: the geomorph compute stages and the morphing
    /// vertex stage read it too).
    pub buffer: Buffer,
    /// Number of vertices.
    pub count: u32,
    /// One RGBA8 colour per vertex (sRGB-encoded colour, linear alpha), if the mesh has
    /// them ([`Hierarchy::vertex_colours`]); drawn multiplied with the material (vertex and
    /// storage usage: the morphing vertex stage pulls them).
    pub colours: Option<Buffer>,
}

impl VertexBuffer {
    /// Uploads a hierarchy's vertex buffer and, if it has them, its vertex colours.
    pub fn from_hierarchy(ctx: &Context, name: &str, h: &Hierarchy<'_>) -> Result<Self> {
        Self::coloured(ctx, name, h.vertices(), h.vertex_colours())
    }

    /// Uploads `vertices` and, with `colours` (one RGBA8 per vertex: sRGB-encoded colour,
    /// linear alpha), their colours: a hierarchy's own ([`from_hierarchy`](Self::from_hierarchy))
    /// or colours the application computes, a terrain tinted by height for instance. The
    /// colours are drawn multiplied with the material, and morphing vertices blend them.
    pub fn coloured(
        ctx: &Context,
        name: &str,
        vertices: &[Vertex],
        colours: Option<&[[u8; 4]]>,
    ) -> Result<Self> {
        let mut v = Self::from_vertices(ctx, name, vertices)?;
        if let Some(colours) = colours {
            match Self::colour_count(name, colours, v.count).and_then(|()| {
                upload(
                    ctx,
                    &format!("{name} colours"),
                    bytemuck::cast_slice(colours),
                    vk::BufferUsageFlags::VERTEX_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER,
                )
            }) {
                Ok(b) => v.colours = Some(b),
                Err(e) => {
                    let _ = v.destroy(ctx);
                    return Err(e);
                }
            }
        }
        Ok(v)
    }

    /// Refuses colours that are not one per vertex.
    fn colour_count(name: &str, colours: &[[u8; 4]], count: u32) -> Result<()> {
        if colours.len() == count as usize {
            Ok(())
        } else {
            Err(Error::InvalidArgument(format!(
                "vertex buffer {name}: {} colours for {count} vertices",
                colours.len()
            )))
        }
    }

    /// Uploads `vertices` through a staging buffer into a new device-local buffer (one
    /// submission on the context's queue, waited for).
    pub fn from_vertices(ctx: &Context, name: &str, vertices: &[Vertex]) -> Result<Self> {
        let count = vertex_count(name, vertices)?;
        let bytes: &[u8] = bytemuck::cast_slice(vertices);
        let buffer = upload(
            ctx,
            name,
            bytes,
            vk::BufferUsageFlags::VERTEX_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        ctx.count_vertex_upload();
        Ok(Self {
            buffer,
            count,
            colours: None,
        })
    }

    /// Records the upload of `vertices` into a new device-local buffer in the caller's
    /// command buffer `cmd` (recording, outside rendering), for hosts that submit their own
    /// work: a copy from a host-visible staging buffer, then a barrier from the copy
    /// (`COPY`, `TRANSFER_WRITE`) to every later read (`VERTEX_ATTRIBUTE_INPUT` and
    /// `COMPUTE_SHADER`; `VERTEX_ATTRIBUTE_READ` and `SHADER_STORAGE_READ`), so draws and
    /// geomorph dispatches recorded after it in submission order see the vertices.
    ///
    /// With `colours` (one RGBA8 per vertex, e.g. [`Hierarchy::vertex_colours`]), their
    /// buffer is uploaded the same way, in the same staging buffer.
    ///
    /// The returned [`Staging`] must stay alive until the GPU has executed `cmd`; then
    /// destroy it.
    pub fn record_upload(
        ctx: &Context,
        cmd: vk::CommandBuffer,
        name: &str,
        vertices: &[Vertex],
        colours: Option<&[[u8; 4]]>,
    ) -> Result<(Self, Staging)> {
        let count = vertex_count(name, vertices)?;
        if let Some(c) = colours {
            Self::colour_count(name, c, count)?;
        }
        let bytes: &[u8] = bytemuck::cast_slice(vertices);
        let staging = staging_with(ctx, name, bytes)?;
        let buffer = match Buffer::new(
            ctx,
            name,
            BufferDesc::gpu_only(
                bytes.len() as u64,
                vk::BufferUsageFlags::VERTEX_BUFFER
                    | vk::BufferUsageFlags::STORAGE_BUFFER
                    | vk::BufferUsageFlags::TRANSFER_DST,
            ),
        ) {
            Ok(b) => b,
            Err(e) => {
                staging.destroy(ctx)?;
                return Err(e);
            }
        };
        record_copy(ctx, cmd, &staging, &buffer, bytes.len() as u64);
        ctx.count_vertex_upload();
        let mut v = Self {
            buffer,
            count,
            colours: None,
        };
        let Some(colours) = colours else {
            return Ok((
                v,
                Staging {
                    buffer: staging,
                    more: None,
                },
            ));
        };
        let colour_bytes: &[u8] = bytemuck::cast_slice(colours);
        let recorded = staging_with(ctx, &format!("{name} colours"), colour_bytes).and_then(|s| {
            match Buffer::new(
                ctx,
                &format!("{name} colours"),
                BufferDesc::gpu_only(
                    colour_bytes.len() as u64,
                    vk::BufferUsageFlags::VERTEX_BUFFER
                        | vk::BufferUsageFlags::STORAGE_BUFFER
                        | vk::BufferUsageFlags::TRANSFER_DST,
                ),
            ) {
                Ok(b) => {
                    record_copy(ctx, cmd, &s, &b, colour_bytes.len() as u64);
                    Ok((b, s))
                }
                Err(e) => {
                    let _ = s.destroy(ctx);
                    Err(e)
                }
            }
        });
        match recorded {
            Ok((b, s)) => {
                v.colours = Some(b);
                Ok((
                    v,
                    Staging {
                        buffer: staging,
                        more: Some(s),
                    },
                ))
            }
            Err(e) => {
                let _ = staging.destroy(ctx);
                let _ = v.destroy(ctx);
                Err(e)
            }
        }
    }

    /// Destroys the buffers. The GPU must be done with them.
    pub fn destroy(self, ctx: &Context) -> Result<()> {
        let colours = self.colours.map_or(Ok(()), |c| c.destroy(ctx));
        self.buffer.destroy(ctx).and(colours)
    }
}

/// A staging buffer of an upload recorded into the caller's command buffer
/// ([`VertexBuffer::record_upload`]): keep it until that command buffer has executed, then
/// [`destroy`](Self::destroy) it.
#[derive(Debug)]
#[must_use = "a staging buffer must be destroyed after its upload executed"]
pub struct Staging {
    pub(crate) buffer: Buffer,
    /// A second staging buffer of the same upload (vertex colours).
    pub(crate) more: Option<Buffer>,
}

impl Staging {
    /// Destroys the staging buffers. The GPU must be done with the upload.
    pub fn destroy(self, ctx: &Context) -> Result<()> {
        let more = self.more.map_or(Ok(()), |b| b.destroy(ctx));
        self.buffer.destroy(ctx).and(more)
    }
}

/// The vertex count of `vertices` as a `u32`, refusing none and too many.
fn vertex_count(name: &str, vertices: &[Vertex]) -> Result<u32> {
    if vertices.is_empty() {
        return Err(Error::InvalidArgument(format!(
            "vertex buffer {name}: no vertices"
        )));
    }
    u32::try_from(vertices.len())
        .map_err(|_| Error::InvalidArgument(format!("vertex buffer {name}: too many vertices")))
}

/// A host-visible staging buffer holding `bytes`.
fn staging_with(ctx: &Context, name: &str, bytes: &[u8]) -> Result<Buffer> {
    let mut staging = Buffer::new(
        ctx,
        &format!("{name} (staging)"),
        BufferDesc::cpu_to_gpu(bytes.len() as u64, vk::BufferUsageFlags::TRANSFER_SRC),
    )?;
    match staging.mapped_mut() {
        Some(dst) => {
            dst[..bytes.len()].copy_from_slice(bytes);
            Ok(staging)
        }
        None => {
            staging.destroy(ctx)?;
            Err(Error::InvalidArgument(
                "staging memory is not host-visible".into(),
            ))
        }
    }
}

/// Records the copy of `size` bytes from `src` to `dst` and the barrier that makes it
/// visible to vertex input and shader storage reads.
fn record_copy(ctx: &Context, cmd: vk::CommandBuffer, src: &Buffer, dst: &Buffer, size: u64) {
    let region = [vk::BufferCopy {
        src_offset: 0,
        dst_offset: 0,
        size,
    }];
    let barrier = [vk::BufferMemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::COPY)
        .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .dst_stage_mask(
            vk::PipelineStageFlags2::VERTEX_ATTRIBUTE_INPUT
                | vk::PipelineStageFlags2::VERTEX_SHADER
                | vk::PipelineStageFlags2::COMPUTE_SHADER,
        )
        .dst_access_mask(
            vk::AccessFlags2::VERTEX_ATTRIBUTE_READ | vk::AccessFlags2::SHADER_STORAGE_READ,
        )
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .buffer(dst.raw)
        .offset(0)
        .size(vk::WHOLE_SIZE)];
    let dep = vk::DependencyInfo::default().buffer_memory_barriers(&barrier);
    // SAFETY: `cmd` is recording outside rendering (the caller's contract); both buffers
    // are alive and hold at least `size` bytes.
    unsafe {
        ctx.device.cmd_copy_buffer(cmd, src.raw, dst.raw, &region);
        ctx.device.cmd_pipeline_barrier2(cmd, &dep);
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
/// copied from a staging buffer in one submission that is waited for; the staging buffer is
/// destroyed before returning.
pub(crate) fn upload(
    ctx: &Context,
    name: &str,
    bytes: &[u8],
    usage: vk::BufferUsageFlags,
) -> Result<Buffer> {
    let size = bytes.len() as u64;
    let staging = staging_with(ctx, name, bytes)?;
    let result = Buffer::new(
        ctx,
        name,
        BufferDesc::gpu_only(size, usage | vk::BufferUsageFlags::TRANSFER_DST),
    )
    .and_then(|buffer| {
        match ctx.submit_and_wait(|cmd| record_copy(ctx, cmd, &staging, &buffer, size)) {
            Ok(()) => Ok(buffer),
            Err(e) => {
                let _ = buffer.destroy(ctx);
                Err(e)
            }
        }
    });
    staging.destroy(ctx)?;
    result
}
