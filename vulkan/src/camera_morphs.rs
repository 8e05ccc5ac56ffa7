//! Refinement geomorphs on the GPU, per camera (the design decisions are on
//! [`CameraMorphs`]).

use ash::vk;
use caveclod_core::format::Vertex;
use caveclod_core::gpu::{morph_slot_vertex, MorphSlices, MorphSlotsPush};
use caveclod_core::{CameraState, HierarchyRecords, MorphVertex};

use crate::buffer::{Buffer, BufferDesc};
use crate::device::Context;
use crate::error::{Error, Result, VkResultExt};
use crate::mesh::VertexBuffer;
use crate::pipeline::MORPHING_LOCAL_SIZE;

/// Where a camera's morphing vertices are blended each frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MorphStage {
    /// The vertex stage blends each morphing corner from its slot as it draws it.
    Vertex,
    /// A compute dispatch ([`Recorder::record_morph_blends`](crate::Recorder::record_morph_blends)) writes every slot's blended
    /// vertex into a small device-local buffer, which the vertex stage reads.
    Compute,
    /// The host blends on the CPU ([`caveclod_core::gpu::morph_slot_vertex`]) into mapped
    /// memory when it fills the slot: the reference the GPU stages are tested against, and
    /// a path for queues without compute.
    Host,
}

/// One frame slot's buffers and descriptor set.
#[derive(Debug)]
struct Slot {
    /// The camera's [`MorphVertex`] slots (host-visible, written by [`CameraMorphs::fill`]).
    slots: Buffer,
    /// The blended vertices, one per slot (written by the compute stage or the host; a
    /// one-vertex placeholder for [`MorphStage::Vertex`], which never reads it).
    blended: Buffer,
    /// Set 1 of the morphing draw, set 0 of the compute dispatch.
    set: vk::DescriptorSet,
    /// Slots filled for the frame being recorded.
    count: u32,
}

/// A frame slot's parts that a fill writes.
struct SlotParts<'a> {
    words: &'a mut [MorphVertex],
    blended: &'a mut Buffer,
    count: &'a mut u32,
}

/// A camera's morphing vertices on the GPU: a ring over the caller's frames in flight of
/// its [`MorphVertex`] slots (and, for [`MorphStage::Compute`] and [`MorphStage::Host`], the
/// blended vertices), with the descriptor sets that name them next to the persistent vertex
/// buffer.
///
/// Design decisions:
/// - **The persistent vertex buffer is never written.** Morphed emission
///   ([`CameraState::emit_indices_morphed`], through
///   [`IndexSource::MorphedCamera`](crate::IndexSource)) points a morphing corner at index
///   `vertex_count + slot`; the morphing vertex stage pulls its vertices from storage
///   buffers, so an index below `vertex_count` reads the persistent buffer and one above it
///   the camera's slot `slot`. Every camera has its own slots over the one vertex buffer, so
///   cameras morph independently.
/// - **Fixed size.** A camera's morph memory is fixed ([`CameraState::max_morphs`], two
///   vertex slots per morph), so the buffers are sized once and a frame creates nothing.
/// - **Filling is a write to mapped memory**, like the index ring: the caller fills slot `s`
///   after its fence for the frame that last used `s`, and the submission makes the writes
///   visible. The compute stage's barrier is recorded by
///   [`Recorder::record_morph_blends`](crate::Recorder::record_morph_blends).
#[derive(Debug)]
pub struct CameraMorphs {
    stage: MorphStage,
    capacity: u32,
    vertex_count: u32,
    vertex_buffer: vk::Buffer,
    has_colours: bool,
    pool: vk::DescriptorPool,
    ring: Vec<Slot>,
}

/// What camera morphs take of the recorder they are made for.
#[derive(Clone, Copy)]
pub(crate) struct MorphLayout<'a> {
    /// The morph set layout (`None`: made without `refine_morphs`).
    pub set_layout: Option<vk::DescriptorSetLayout>,
    /// The one white vertex colour, for meshes without colours.
    pub white_colour: &'a Buffer,
}

impl CameraMorphs {
    /// [`CameraMorphs::new`](crate::CameraMorphs::new) over the recorder's `parts`.
    pub(crate) fn with_layout(
        ctx: &Context,
        parts: MorphLayout<'_>,
        name: &str,
        vertices: &VertexBuffer,
        stage: MorphStage,
        max_morphs: u32,
        frames_in_flight: usize,
    ) -> Result<Self> {
        let layout = parts.set_layout.ok_or_else(|| {
            Error::InvalidArgument(format!(
                "{name}: the recorder was made without refine_morphs"
            ))
        })?;
        let capacity = max_morphs
            .checked_mul(2)
            .filter(|&c| c > 0)
            .ok_or_else(|| {
                Error::InvalidArgument(format!("{name}: {max_morphs} morphs (1 or more, < 2^31)"))
            })?;
        let frames = frames_in_flight.max(1);
        let pool = descriptor_pool(ctx, frames as u32)?;
        let mut morphs = Self {
            stage,
            capacity,
            vertex_count: vertices.count,
            vertex_buffer: vertices.buffer.raw,
            has_colours: vertices.colours.is_some(),
            pool,
            ring: Vec::with_capacity(frames),
        };
        for f in 0..frames {
            match Slot::new(ctx, name, f, stage, capacity, pool, layout) {
                Ok(slot) => morphs.ring.push(slot),
                Err(e) => {
                    let _ = morphs.destroy(ctx);
                    return Err(e);
                }
            }
        }
        for slot in &morphs.ring {
            write_set(ctx, slot, vertices, parts.white_colour);
        }
        Ok(morphs)
    }

    /// Where it blends.
    pub fn stage(&self) -> MorphStage {
        self.stage
    }

    /// Vertex slots per frame slot (twice the camera's morphs).
    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    /// Frame slots.
    pub fn frames_in_flight(&self) -> usize {
        self.ring.len()
    }

    /// Morph slots filled for frame slot `frame` (0 before the first fill).
    pub fn count(&self, frame: usize) -> u32 {
        self.ring.get(frame).map_or(0, |s| s.count)
    }

    /// The vertex count its indices may reach: the persistent vertices plus every slot.
    pub fn vertex_bound(&self) -> u64 {
        u64::from(self.vertex_count) + u64::from(self.capacity)
    }

    /// Writes `camera`'s morph slots ([`CameraState::morph_vertices`]) into frame slot
    /// `frame`, and for [`MorphStage::Host`] their blended vertices from `vertices` (the
    /// hierarchy's persistent vertices). The GPU must be done with the slot's previous
    /// contents (the caller's fence for that frame). Returns the slots written.
    pub fn fill(
        &mut self,
        frame: usize,
        vertices: &[Vertex],
        camera: &CameraState<'_>,
    ) -> Result<u32> {
        let live = camera.morph_vertices();
        if live.len() > self.capacity as usize {
            return Err(Error::InvalidArgument(format!(
                "{} morph slots for a buffer of {}",
                live.len(),
                self.capacity
            )));
        }
        let stage = self.stage;
        let slot = self.slot_words(frame)?;
        slot.words[..live.len()].copy_from_slice(live);
        if stage == MorphStage::Host {
            let out = slot.blended.mapped_mut().ok_or_else(not_mapped)?;
            let out: &mut [Vertex] = bytemuck::try_cast_slice_mut(out)
                .map_err(|e| Error::InvalidArgument(format!("blended mapping: {e}")))?;
            let inputs = MorphSlices {
                vertices,
                slots: live,
            };
            for (s, o) in (0..live.len() as u32).zip(out.iter_mut()) {
                if let Some(v) = morph_slot_vertex(&inputs, s) {
                    *o = v;
                }
            }
        }
        *slot.count = live.len() as u32;
        Ok(*slot.count)
    }

    /// Writes `camera`'s morph slots as the device reads them over `hierarchy`
    /// ([`CameraState::device_morph_vertices`]: over a streamed file, at their places in its
    /// [`VertexPool`](crate::VertexPool)) into frame slot `frame`, for
    /// [`MorphStage::Vertex`] and [`MorphStage::Compute`] (the host stage blends from a
    /// whole file's vertices: [`fill`](Self::fill)). The GPU must be done with the slot's
    /// previous contents. Returns the slots written.
    pub fn fill_device(
        &mut self,
        frame: usize,
        hierarchy: &impl HierarchyRecords,
        camera: &CameraState<'_>,
    ) -> Result<u32> {
        if self.stage == MorphStage::Host {
            return Err(Error::InvalidArgument(
                "host-blended morphs read a whole file's vertices: fill them with `fill`".into(),
            ));
        }
        let slot = self.slot_words(frame)?;
        let n = camera.device_morph_vertices(hierarchy, slot.words)?;
        *slot.count = n as u32;
        Ok(*slot.count)
    }

    /// Frame slot `frame`'s mapped morph slots, its blended buffer and its count.
    fn slot_words(&mut self, frame: usize) -> Result<SlotParts<'_>> {
        let frames = self.ring.len();
        let Slot {
            slots,
            blended,
            count,
            ..
        } = self.ring.get_mut(frame).ok_or_else(|| {
            Error::InvalidArgument(format!("frame slot {frame} of a morph ring of {frames}"))
        })?;
        let words = slots.mapped_mut().ok_or_else(not_mapped)?;
        let words: &mut [MorphVertex] = bytemuck::try_cast_slice_mut(words)
            .map_err(|e| Error::InvalidArgument(format!("morph slot mapping: {e}")))?;
        Ok(SlotParts {
            words,
            blended,
            count,
        })
    }

    /// Refuses a draw over another vertex buffer than the one it was made for.
    pub(crate) fn check(
        &self,
        vertices: &VertexBuffer,
        frame: usize,
    ) -> std::result::Result<(), String> {
        if vertices.buffer.raw != self.vertex_buffer || vertices.count != self.vertex_count {
            return Err("its morphs were made for another vertex buffer".into());
        }
        if frame >= self.ring.len() {
            return Err(format!(
                "frame slot {frame} of a morph ring of {}",
                self.ring.len()
            ));
        }
        Ok(())
    }

    /// The descriptor set of frame slot `frame` and its filled slot count.
    pub(crate) fn set(&self, frame: usize) -> Option<(vk::DescriptorSet, u32)> {
        self.ring.get(frame).map(|s| (s.set, s.count))
    }

    /// Vertex count, slot count and colours, for the morphing stage's push block.
    pub(crate) fn push_fields(&self, frame: usize) -> (u32, u32, bool) {
        (self.vertex_count, self.count(frame), self.has_colours)
    }

    /// The compute dispatch's set and push block, when this camera blends in the compute
    /// stage and has slots in `frame`.
    pub(crate) fn dispatch(&self, frame: usize) -> Option<(vk::DescriptorSet, MorphSlotsPush)> {
        let slot = self.ring.get(frame)?;
        (self.stage == MorphStage::Compute && slot.count > 0).then_some((
            slot.set,
            MorphSlotsPush {
                slot_count: slot.count,
                vertex_count: self.vertex_count,
                _pad: [0; 2],
            },
        ))
    }

    /// Destroys the buffers and the descriptor pool. The GPU must be done with them.
    pub fn destroy(self, ctx: &Context) -> Result<()> {
        // SAFETY: the caller guarantees no pending work uses the sets.
        unsafe { ctx.device.destroy_descriptor_pool(self.pool, None) };
        let mut first_err = None;
        for s in self.ring {
            for b in [s.slots, s.blended] {
                if let Err(e) = b.destroy(ctx) {
                    first_err.get_or_insert(e);
                }
            }
        }
        first_err.map_or(Ok(()), Err)
    }
}

impl Slot {
    fn new(
        ctx: &Context,
        name: &str,
        frame: usize,
        stage: MorphStage,
        capacity: u32,
        pool: vk::DescriptorPool,
        layout: vk::DescriptorSetLayout,
    ) -> Result<Self> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let slot_bytes = u64::from(capacity) * std::mem::size_of::<MorphVertex>() as u64;
        let vertex_bytes = std::mem::size_of::<Vertex>() as u64;
        let slots = Buffer::new(
            ctx,
            &format!("{name} morph slots f{frame}"),
            BufferDesc::cpu_to_gpu(slot_bytes, storage),
        )?;
        let blended_desc = match stage {
            MorphStage::Vertex => BufferDesc::gpu_only(vertex_bytes, storage),
            MorphStage::Compute => {
                BufferDesc::gpu_only(u64::from(capacity) * vertex_bytes, storage)
            }
            MorphStage::Host => BufferDesc::cpu_to_gpu(u64::from(capacity) * vertex_bytes, storage),
        };
        let blended = match Buffer::new(ctx, &format!("{name} blended f{frame}"), blended_desc) {
            Ok(b) => b,
            Err(e) => {
                let _ = slots.destroy(ctx);
                return Err(e);
            }
        };
        let layouts = [layout];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(pool)
            .set_layouts(&layouts);
        // SAFETY: the pool has room for one set per frame slot (`descriptor_pool`).
        let set = unsafe { ctx.device.allocate_descriptor_sets(&info) }
            .vk("vkAllocateDescriptorSets")
            .and_then(|sets| {
                sets.first()
                    .copied()
                    .ok_or_else(|| Error::InvalidArgument("no descriptor set allocated".into()))
            });
        match set {
            Ok(set) => Ok(Self {
                slots,
                blended,
                set,
                count: 0,
            }),
            Err(e) => {
                let _ = slots.destroy(ctx);
                let _ = blended.destroy(ctx);
                Err(e)
            }
        }
    }
}

/// A pool of `frames` morph sets (four storage buffers each).
fn descriptor_pool(ctx: &Context, frames: u32) -> Result<vk::DescriptorPool> {
    let sizes = [vk::DescriptorPoolSize {
        ty: vk::DescriptorType::STORAGE_BUFFER,
        descriptor_count: 4 * frames,
    }];
    let info = vk::DescriptorPoolCreateInfo::default()
        .max_sets(frames)
        .pool_sizes(&sizes);
    // SAFETY: valid create info.
    unsafe { ctx.device.create_descriptor_pool(&info, None) }.vk("vkCreateDescriptorPool")
}

/// Points `slot`'s set at the persistent vertices (binding 0), its morph slots (1), its
/// blended vertices (2) and the vertex colours, or one white colour (3).
fn write_set(ctx: &Context, slot: &Slot, vertices: &VertexBuffer, white: &Buffer) {
    let whole = |buffer: vk::Buffer| {
        [vk::DescriptorBufferInfo {
            buffer,
            offset: 0,
            range: vk::WHOLE_SIZE,
        }]
    };
    let colours = vertices.colours.as_ref().unwrap_or(white);
    let infos = [
        whole(vertices.buffer.raw),
        whole(slot.slots.raw),
        whole(slot.blended.raw),
        whole(colours.raw),
    ];
    let writes: Vec<vk::WriteDescriptorSet<'_>> = infos
        .iter()
        .enumerate()
        .map(|(binding, info)| {
            vk::WriteDescriptorSet::default()
                .dst_set(slot.set)
                .dst_binding(binding as u32)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(info)
        })
        .collect();
    // SAFETY: the set is not in use by pending work (just allocated); every buffer is alive
    // and has storage usage.
    unsafe { ctx.device.update_descriptor_sets(&writes, &[]) };
}

fn not_mapped() -> Error {
    Error::InvalidArgument("morph buffer is not host-visible".into())
}

/// Workgroups of the compute stage for `count` slots.
pub(crate) fn workgroups(count: u32) -> u32 {
    count.div_ceil(MORPHING_LOCAL_SIZE)
}
