//! A device vertex pool for streamed hierarchies (the decisions are on [`VertexPool`]).

use ash::vk;
use caveclod_core::format::Vertex;
use caveclod_core::stream::{VertexInstall, VertexPoolLayout};

use crate::buffer::{copies_between_barriers, Buffer, BufferDesc};
use crate::device::Context;
use crate::error::{Error, Result};
use crate::mesh::{VertexBuffer, VERTEX_STRIDE};

/// Bytes of one vertex colour.
const COLOUR_BYTES: u64 = 4;
/// The colour of a vertex whose page has none, in a pool with colours.
const WHITE: [u8; 4] = [255; 4];

/// One frame slot: its staging buffer and the copies of the frame last filled.
#[derive(Debug)]
struct Slot {
    staging: Buffer,
    copies: Vec<vk::BufferCopy>,
    colour_copies: Vec<vk::BufferCopy>,
}

/// The vertices of a streamed hierarchy's resident pages on the device, in a buffer of a
/// fixed size laid out by the page pool's [`VertexPoolLayout`]: slot `s`'s page at
/// `s × slot_vertices`, the files' root pages after the slots. Its [`vertices`](Self::vertices)
/// take the place of a whole file's [`VertexBuffer`] in every draw, so the draws, the
/// morphing vertex stage and the compute blends read it as they read that one; the
/// indices a camera over a [`StreamedHierarchy`](caveclod_core::stream::StreamedHierarchy)
/// writes name its places.
///
/// Design decisions:
/// - **Fixed size.** The buffer is made once, `layout.vertices` vertices, and never grows;
///   it must lie within the device's `maxStorageBufferRange`, which the morphing vertex
///   stage reads it through, whatever the size of the files it serves;
///   the page pool's slots are its slots. Its staging is one host-visible buffer per frame
///   in flight, room for `max_installs` pages, so a frame creates nothing.
/// - **Installs are copies recorded into the host's command buffer**:
///   [`fill`](Self::fill) writes the vertices of the pages the pool installed into frame
///   slot `frame`'s staging buffer (after that slot's fence), and [`record`](Self::record)
///   records their copies, outside rendering, before the frame's draws. At most
///   `max_installs` pages a frame: the host installs no more into the page pool a frame
///   (the std streamer's `max_installs`), so no page is resident before its vertices are
///   on their way.
/// - **A slot is overwritten only after every frame in flight that could read it.** The
///   page pool evicts a page only once no front stands on it, so no later frame's indices
///   name its slot; frames recorded earlier may still be drawing it. The copies wait, by a
///   barrier, for the vertex reads (vertex input, vertex and compute shaders) of every
///   earlier submission on the queue, so a frame in flight never sees the next page (the
///   caller submits its frames on one queue, in order); a second barrier makes the copies
///   visible to this frame's reads.
/// - **Roots once.** [`upload_roots`](Self::upload_roots) copies the files' root pages,
///   always resident, when the pool is made.
#[derive(Debug)]
pub struct VertexPool {
    vertices: VertexBuffer,
    layout: VertexPoolLayout,
    slots: u32,
    max_installs: u32,
    ring: Vec<Slot>,
    installed: u64,
}

impl VertexPool {
    /// A pool of `layout` beside a page pool of `slots` slots (with a colour per vertex if
    /// `colours`), installing at most `max_installs` pages a frame over `frames_in_flight`
    /// frame slots.
    pub fn new(
        ctx: &Context,
        name: &str,
        (layout, slots): (VertexPoolLayout, u32),
        colours: bool,
        max_installs: u32,
        frames_in_flight: usize,
    ) -> Result<Self> {
        check_layout(name, layout, slots, max_installs)?;
        check_storage_range(ctx, name, layout)?;
        let vertices = device_buffers(ctx, name, layout, colours)?;
        let mut pool = Self {
            vertices,
            layout,
            slots,
            max_installs,
            ring: Vec::with_capacity(frames_in_flight.max(1)),
            installed: 0,
        };
        let per_vertex = u64::from(VERTEX_STRIDE) + if colours { COLOUR_BYTES } else { 0 };
        let staging_bytes = u64::from(max_installs) * u64::from(layout.slot_vertices) * per_vertex;
        for f in 0..frames_in_flight.max(1) {
            let staging = Buffer::new(
                ctx,
                &format!("{name} vertex installs f{f}"),
                BufferDesc::cpu_to_gpu(staging_bytes, vk::BufferUsageFlags::TRANSFER_SRC),
            );
            match staging {
                Ok(staging) => pool.ring.push(Slot {
                    staging,
                    copies: Vec::with_capacity(max_installs as usize),
                    colour_copies: Vec::with_capacity(max_installs as usize),
                }),
                Err(e) => {
                    let _ = pool.destroy(ctx);
                    return Err(e);
                }
            }
        }
        Ok(pool)
    }

    /// The pool's vertex buffer, for draws and camera morphs: `layout.vertices` vertices.
    pub fn vertices(&self) -> &VertexBuffer {
        &self.vertices
    }

    /// The layout it was made with.
    pub fn layout(&self) -> VertexPoolLayout {
        self.layout
    }

    /// Device bytes it holds: the vertices, their colours, and the staging ring.
    pub fn device_bytes(&self) -> u64 {
        let colours = self.vertices.colours.as_ref().map_or(0, |c| c.desc.size);
        let staging: u64 = self.ring.iter().map(|s| s.staging.desc.size).sum();
        self.vertices.buffer.desc.size + colours + staging
    }

    /// Pages installed so far (filled, roots not counted).
    pub fn installed(&self) -> u64 {
        self.installed
    }

    /// Copies the files' root pages ([`Residency::root_vertices`](caveclod_core::stream::Residency::root_vertices))
    /// into the pool: one submission on the context's queue, waited for, when the pool is
    /// made (before any frame draws from it).
    pub fn upload_roots(&mut self, ctx: &Context, roots: &[VertexInstall<'_>]) -> Result<()> {
        let n: usize = roots.iter().map(|r| r.vertices.len()).sum();
        if n == 0 {
            return Ok(());
        }
        for r in roots {
            self.check_install(r, false)?;
        }
        let colours = self.vertices.colours.is_some();
        let per_vertex = u64::from(VERTEX_STRIDE) + if colours { COLOUR_BYTES } else { 0 };
        let mut staging = Buffer::new(
            ctx,
            "vertex pool roots (staging)",
            BufferDesc::cpu_to_gpu(n as u64 * per_vertex, vk::BufferUsageFlags::TRANSFER_SRC),
        )?;
        let mut copies = (Vec::new(), Vec::new());
        let staged = staging
            .mapped_mut()
            .ok_or_else(not_mapped)
            .map(|bytes| stage(bytes, roots, colours, n as u64, &mut copies));
        let recorded = staged.and_then(|()| {
            ctx.submit_and_wait(|cmd| {
                self.record_copies(ctx, cmd, &staging, &copies.0, &copies.1);
            })
        });
        let destroyed = staging.destroy(ctx);
        recorded.and(destroyed)
    }

    /// Writes the vertices of `installs` (the pages the page pool installed since the last
    /// fill, [`Residency::page_vertices`](caveclod_core::stream::Residency::page_vertices),
    /// each in its slot) into frame slot `frame`'s staging buffer, and the copies that
    /// [`record`](Self::record) records. The GPU must be done with the slot's previous frame
    /// (the caller's fence for that slot). Refuses more than `max_installs` and an install
    /// outside the slots.
    pub fn fill(&mut self, frame: usize, installs: &[VertexInstall<'_>]) -> Result<u32> {
        if installs.len() > self.max_installs as usize {
            return Err(Error::InvalidArgument(format!(
                "{} page installs in a frame, at most {}",
                installs.len(),
                self.max_installs
            )));
        }
        for i in installs {
            self.check_install(i, true)?;
        }
        let colours = self.vertices.colours.is_some();
        let room = u64::from(self.max_installs) * u64::from(self.layout.slot_vertices);
        let frames = self.ring.len();
        let slot = self.ring.get_mut(frame).ok_or_else(|| {
            Error::InvalidArgument(format!("frame slot {frame} of a vertex pool of {frames}"))
        })?;
        slot.copies.clear();
        slot.colour_copies.clear();
        let bytes = slot.staging.mapped_mut().ok_or_else(not_mapped)?;
        let mut copies = (
            std::mem::take(&mut slot.copies),
            std::mem::take(&mut slot.colour_copies),
        );
        stage(bytes, installs, colours, room, &mut copies);
        (slot.copies, slot.colour_copies) = copies;
        self.installed += installs.len() as u64;
        Ok(installs.len() as u32)
    }

    /// Records slot `frame`'s copies into `cmd`, outside rendering, between the two
    /// barriers (see the type's docs); nothing without installs. Returns the bytes copied.
    /// The staging buffer is reused when the slot is filled again, after its fence.
    pub fn record(&self, ctx: &Context, cmd: vk::CommandBuffer, frame: usize) -> u64 {
        let Some(slot) = self.ring.get(frame).filter(|s| !s.copies.is_empty()) else {
            return 0;
        };
        self.record_copies(ctx, cmd, &slot.staging, &slot.copies, &slot.colour_copies)
    }

    /// Destroys the buffers. The GPU must be done with them.
    pub fn destroy(self, ctx: &Context) -> Result<()> {
        let mut first_err = self.vertices.destroy(ctx).err();
        for s in self.ring {
            if let Err(e) = s.staging.destroy(ctx) {
                first_err.get_or_insert(e);
            }
        }
        first_err.map_or(Ok(()), Err)
    }

    /// Refuses an install outside the pool: a page's (`page`) past its slot, or anywhere
    /// past the pool's vertices.
    fn check_install(&self, i: &VertexInstall<'_>, page: bool) -> Result<()> {
        let first = u64::from(i.first);
        let end = first + i.vertices.len() as u64;
        let slot_vertices = u64::from(self.layout.slot_vertices);
        let slot_end = (first / slot_vertices + 1) * slot_vertices;
        let slots_end = u64::from(self.slots) * slot_vertices;
        let inside = if page {
            first < slots_end && end <= slot_end
        } else {
            first >= slots_end && end <= u64::from(self.layout.vertices)
        };
        let colours_match = i.colours.is_none_or(|c| c.len() == i.vertices.len());
        if inside && colours_match {
            return Ok(());
        }
        Err(Error::InvalidArgument(format!(
            "vertex pool: {} vertices at {first} lie outside its {}",
            i.vertices.len(),
            if page { "slots" } else { "root region" }
        )))
    }

    /// Records `copies` (and `colour_copies`) from `staging` into the pool, between the
    /// barriers; the bytes copied.
    fn record_copies(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        staging: &Buffer,
        copies: &[vk::BufferCopy],
        colour_copies: &[vk::BufferCopy],
    ) -> u64 {
        let reads = vk::PipelineStageFlags2::VERTEX_ATTRIBUTE_INPUT
            | vk::PipelineStageFlags2::VERTEX_SHADER
            | vk::PipelineStageFlags2::COMPUTE_SHADER;
        let access =
            vk::AccessFlags2::VERTEX_ATTRIBUTE_READ | vk::AccessFlags2::SHADER_STORAGE_READ;
        copies_between_barriers(ctx, cmd, (reads, access), |d| {
            // SAFETY: the buffers are alive and every region lies inside them (checked when
            // staged).
            unsafe {
                d.cmd_copy_buffer(cmd, staging.raw, self.vertices.buffer.raw, copies);
                if let (Some(c), false) = (&self.vertices.colours, colour_copies.is_empty()) {
                    d.cmd_copy_buffer(cmd, staging.raw, c.raw, colour_copies);
                }
            }
        });
        copies.iter().chain(colour_copies).map(|c| c.size).sum()
    }
}

/// Refuses a layout the page pool could not have, or a pool that installs nothing.
fn check_layout(name: &str, layout: VertexPoolLayout, slots: u32, max_installs: u32) -> Result<()> {
    let slot_total = u64::from(slots) * u64::from(layout.slot_vertices);
    if layout.slot_vertices == 0 || slot_total > u64::from(layout.vertices) || max_installs == 0 {
        return Err(Error::InvalidArgument(format!(
            "vertex pool {name}: {slots} slots of {} vertices in {} vertices, {max_installs} \
             installs a frame",
            layout.slot_vertices, layout.vertices
        )));
    }
    Ok(())
}

/// Refuses a pool the morphing vertex stage could not read: it binds the vertices as one
/// storage buffer, within the device's `maxStorageBufferRange` (2^27 bytes on many
/// devices). A pool sized within it serves a file of any size.
fn check_storage_range(ctx: &Context, name: &str, layout: VertexPoolLayout) -> Result<()> {
    // SAFETY: the context's physical device belongs to its instance.
    let props = unsafe {
        ctx.instance
            .get_physical_device_properties(ctx.physical_device)
    };
    let range = u64::from(props.limits.max_storage_buffer_range);
    if layout.bytes() <= range {
        return Ok(());
    }
    Err(Error::InvalidArgument(format!(
        "vertex pool {name}: {} bytes, past the device's maxStorageBufferRange of {range}",
        layout.bytes()
    )))
}

/// The pool's device-local vertex buffer (and colour buffer).
fn device_buffers(
    ctx: &Context,
    name: &str,
    layout: VertexPoolLayout,
    colours: bool,
) -> Result<VertexBuffer> {
    let usage = vk::BufferUsageFlags::VERTEX_BUFFER
        | vk::BufferUsageFlags::STORAGE_BUFFER
        | vk::BufferUsageFlags::TRANSFER_DST;
    let buffer = Buffer::new(
        ctx,
        &format!("{name} vertex pool"),
        BufferDesc::gpu_only(layout.bytes(), usage),
    )?;
    let colour_buffer = match colours {
        false => None,
        true => match Buffer::new(
            ctx,
            &format!("{name} vertex pool colours"),
            BufferDesc::gpu_only(u64::from(layout.vertices) * COLOUR_BYTES, usage),
        ) {
            Ok(c) => Some(c),
            Err(e) => {
                let _ = buffer.destroy(ctx);
                return Err(e);
            }
        },
    };
    Ok(VertexBuffer {
        buffer,
        count: layout.vertices,
        colours: colour_buffer,
    })
}

/// Writes `installs` into `bytes` (vertices first, then, with `colours`, a colour each
/// from `room` vertices on) and their copies into `copies`.
fn stage(
    bytes: &mut [u8],
    installs: &[VertexInstall<'_>],
    colours: bool,
    room: u64,
    copies: &mut (Vec<vk::BufferCopy>, Vec<vk::BufferCopy>),
) {
    let stride = u64::from(VERTEX_STRIDE);
    let mut at = 0u64;
    for i in installs {
        let n = i.vertices.len() as u64;
        let src: &[u8] = bytemuck::cast_slice::<Vertex, u8>(i.vertices);
        bytes[(at * stride) as usize..][..src.len()].copy_from_slice(src);
        copies.0.push(vk::BufferCopy {
            src_offset: at * stride,
            dst_offset: u64::from(i.first) * stride,
            size: n * stride,
        });
        if colours {
            let c_at = (room * stride + at * COLOUR_BYTES) as usize;
            let dst = &mut bytes[c_at..][..(n * COLOUR_BYTES) as usize];
            match i.colours {
                Some(c) => dst.copy_from_slice(bytemuck::cast_slice(c)),
                None => dst
                    .chunks_exact_mut(4)
                    .for_each(|d| d.copy_from_slice(&WHITE)),
            }
            copies.1.push(vk::BufferCopy {
                src_offset: c_at as u64,
                dst_offset: u64::from(i.first) * COLOUR_BYTES,
                size: n * COLOUR_BYTES,
            });
        }
        at += n;
    }
}

fn not_mapped() -> Error {
    Error::InvalidArgument("staging memory is not host-visible".into())
}
