//! A camera's index buffer on the device, edited each frame with only the places that
//! changed ([`CameraState::index_edits`]) instead of rewritten (the decisions are on
//! [`CameraIndices::edited`](crate::CameraIndices::edited)).

use ash::vk;
use caveclod_core::{CameraState, HierarchyRecords, IndexEdit, IndexEdits, SurfaceDraw};

use crate::buffer::{copies_between_barriers, reserve_host, Buffer, BufferDesc};
use crate::device::Context;
use crate::error::{Error, Result};

/// Smallest staging buffer, in edits.
const MIN_EDITS: u64 = 1024;
/// Bytes of one triangle's indices in the device buffer.
const TRIANGLE_BYTES: u64 = 12;
/// Bytes of one edit in a staging buffer: the place, then the indices.
const EDIT_BYTES: u64 = std::mem::size_of::<IndexEdit>() as u64;

/// One frame slot: its staging buffer, and the copies and draws of the frame last filled.
#[derive(Debug, Default)]
struct Slot {
    staging: Option<Buffer>,
    copies: Vec<vk::BufferCopy>,
    draws: Vec<SurfaceDraw>,
}

/// The device index buffer of one camera and a staging buffer per frame in flight.
#[derive(Debug)]
pub(crate) struct EditedBuffer {
    device: Buffer,
    slots: Vec<Slot>,
    grows: u64,
}

impl EditedBuffer {
    /// A device buffer of `places` triangles and `frames_in_flight` empty staging slots.
    pub fn new(ctx: &Context, name: &str, places: u64, frames_in_flight: usize) -> Result<Self> {
        let device = Buffer::new(
            ctx,
            &format!("{name} edited index buffer"),
            BufferDesc::gpu_only(
                (places * TRIANGLE_BYTES).max(TRIANGLE_BYTES),
                vk::BufferUsageFlags::INDEX_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            ),
        )?;
        Ok(Self {
            device,
            slots: (0..frames_in_flight.max(1))
                .map(|_| Slot::default())
                .collect(),
            grows: 0,
        })
    }

    /// Staging buffers (re)allocated so far.
    pub fn grow_count(&self) -> u64 {
        self.grows
    }

    /// Makes sure slot `frame`'s staging buffer holds `edits` edits, doubling it if not.
    fn reserve(&mut self, ctx: &Context, name: &str, frame: usize, edits: u64) -> Result<()> {
        let grew = reserve_host(
            ctx,
            &mut self.slots[frame].staging,
            || format!("{name} index edits f{frame}"),
            (EDIT_BYTES, MIN_EDITS, edits),
            vk::BufferUsageFlags::TRANSFER_SRC,
        )?;
        self.grows += u64::from(grew);
        Ok(())
    }

    /// Takes `cam`'s edits (closing at most `max_moves` holes) into slot `frame`'s staging
    /// buffer, and the copies and draws that record them. The GPU must be done with the
    /// slot's previous frame.
    pub fn fill(
        &mut self,
        ctx: &Context,
        name: &str,
        frame: usize,
        h: &impl HierarchyRecords,
        cam: &mut CameraState<'_>,
        max_moves: u32,
    ) -> Result<IndexEdits> {
        if frame >= self.slots.len() {
            return Err(Error::InvalidArgument(format!(
                "{name}: frame slot {frame} of {} slots",
                self.slots.len()
            )));
        }
        let places = self.device.desc.size / TRIANGLE_BYTES;
        if cam.index_places() as u64 > places {
            return Err(Error::InvalidArgument(format!(
                "{name}: the camera has {} index places, the buffer {places}",
                cam.index_places()
            )));
        }
        let needed = cam.index_edits_needed(max_moves) as u64;
        // One edit at least, so that a frame without edits has a staging buffer to name.
        self.reserve(ctx, name, frame, needed.max(1))?;
        let slot = &mut self.slots[frame];
        slot.draws.resize(h.surface_count(), SurfaceDraw::default());
        let bytes = slot
            .staging
            .as_mut()
            .and_then(Buffer::mapped_mut)
            .ok_or_else(|| Error::InvalidArgument(format!("{name}: staging is not mapped")))?;
        let edits: &mut [IndexEdit] = bytemuck::try_cast_slice_mut(bytes)
            .map_err(|e| Error::InvalidArgument(format!("{name}: staging mapping: {e}")))?;
        let e = cam.index_edits(h, max_moves, edits, &mut slot.draws)?;
        slot.copies.clear();
        slot.copies.extend(
            edits[..e.edits]
                .iter()
                .enumerate()
                .map(|(i, x)| vk::BufferCopy {
                    src_offset: i as u64 * EDIT_BYTES + 4,
                    dst_offset: u64::from(x.place) * TRIANGLE_BYTES,
                    size: TRIANGLE_BYTES,
                }),
        );
        Ok(e)
    }

    /// Records slot `frame`'s copies into `cmd`, outside rendering, between two barriers:
    /// earlier frames' index reads and copies before the copy (the queue's submission order
    /// makes that cover every frame in flight), and the copy before this frame's index
    /// reads. Nothing is recorded without edits. Returns the bytes copied.
    pub fn record(&self, ctx: &Context, cmd: vk::CommandBuffer, frame: usize) -> u64 {
        let Some(slot) = self.slots.get(frame) else {
            return 0;
        };
        let Some(staging) = slot.staging.as_ref().filter(|_| !slot.copies.is_empty()) else {
            return 0;
        };
        let reads = (
            vk::PipelineStageFlags2::INDEX_INPUT,
            vk::AccessFlags2::INDEX_READ,
        );
        copies_between_barriers(ctx, cmd, reads, |d| {
            // SAFETY: both buffers are alive, every region lies inside them (a staging entry
            // per edit, a place below the device buffer's places, checked at fill).
            unsafe { d.cmd_copy_buffer(cmd, staging.raw, self.device.raw, &slot.copies) };
        });
        slot.copies.len() as u64 * TRIANGLE_BYTES
    }

    /// Index bytes slot `frame`'s copies write.
    pub fn written_bytes(&self, frame: usize) -> u64 {
        self.slots
            .get(frame)
            .map_or(0, |s| s.copies.len() as u64 * TRIANGLE_BYTES)
    }

    /// The device buffer and `surface`'s first index and index count in slot `frame`'s
    /// draws; `None` when it draws nothing.
    pub fn draw_range(&self, frame: usize, surface: usize) -> Option<(vk::Buffer, u32, u32)> {
        let d = self.slots.get(frame)?.draws.get(surface)?;
        (d.index_count > 0).then_some((self.device.raw, d.first_index, d.index_count))
    }

    /// Destroys the buffers. The GPU must be done with them.
    pub fn destroy(self, ctx: &Context) -> Result<()> {
        let mut first_err = self.device.destroy(ctx).err();
        for b in self.slots.into_iter().filter_map(|s| s.staging) {
            if let Err(e) = b.destroy(ctx) {
                first_err.get_or_insert(e);
            }
        }
        first_err.map_or(Ok(()), Err)
    }
}
