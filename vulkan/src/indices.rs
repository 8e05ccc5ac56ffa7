//! Index buffers of one camera (the design decisions are on [`CameraIndices`]).

use ash::vk;
use caveclod_core::{CameraState, Hierarchy, HierarchyRecords, IndexEdits};

use crate::buffer::{reserve_host, Buffer};
use crate::device::Context;
use crate::error::{Error, Result};
use crate::index_edits::EditedBuffer;

/// Smallest index buffer, in indices.
const MIN_INDICES: u64 = 1024;

/// One surface's index buffer in one frame slot.
#[derive(Debug, Default)]
struct Slot {
    buffer: Option<Buffer>,
    /// Indices written for the frame being recorded.
    count: u32,
}

/// Where a camera's indices come from this frame.
#[derive(Clone, Copy, Debug)]
pub enum IndexSource<'a, 'c> {
    /// Emitted by a refined camera over its hierarchy.
    Camera {
        /// The shared hierarchy.
        hierarchy: &'a Hierarchy<'a>,
        /// The camera's front.
        camera: &'a CameraState<'c>,
    },
    /// Emitted by a refined camera with its morphing corners pointing at its morph slots
    /// ([`CameraState::emit_indices_morphed`]), for a draw with the camera's
    /// [`CameraMorphs`](crate::CameraMorphs).
    MorphedCamera {
        /// The shared hierarchy.
        hierarchy: &'a Hierarchy<'a>,
        /// The camera's front.
        camera: &'a CameraState<'c>,
    },
    /// Given lists, one per surface (e.g. an unbaked mesh drawn directly).
    Lists(&'a [&'a [u32]]),
    /// Given lists whose morphing corners point at a camera's morph slots, as morphed
    /// emission writes them (a host that emits on its own threads, or reorders), for a
    /// draw with the camera's [`CameraMorphs`](crate::CameraMorphs).
    MorphedLists(&'a [&'a [u32]]),
}

impl<'a, 'c> IndexSource<'a, 'c> {
    /// The indices `camera` emits over `hierarchy`.
    pub fn camera(hierarchy: &'a Hierarchy<'a>, camera: &'a CameraState<'c>) -> Self {
        Self::Camera { hierarchy, camera }
    }
}

/// The index buffers of one camera, `[frame slot][surface]`: one host-visible buffer per
/// surface and per frame in flight.
///
/// Design decisions:
/// - **Emission writes straight into mapped memory.** caveclod-core's
///   [`CameraState::emit_indices`] takes one output slice per surface, so the mapped buffers
///   of the frame being recorded are those slices: no intermediate copy.
/// - **One buffer per frame in flight**, so the CPU fills frame `n + 1`'s lists while the
///   GPU still reads frame `n`'s. A slot is written only after its frame's fence signalled.
/// - **Growth by doubling, only when needed**: a surface's buffer is replaced by one at
///   least twice as large when its list no longer fits, so a camera flying towards more
///   detail reallocates O(log n) times, never per frame.
///
/// **Edited** ([`edited`](Self::edited)): one device-local buffer that a camera keeping
/// index edits ([`CameraConfig::edit_list`](caveclod_core::CameraConfig::edit_list)) patches
/// each frame with only the places that changed: [`fill_edits`](Self::fill_edits) takes the
/// edits into a host-visible staging buffer per frame in flight, and
/// [`record_edits`](Self::record_edits) records their copies, outside rendering, before the
/// frame's draws. Each copy is 12 bytes at its place; a hole holds a degenerate triangle,
/// which draws nothing. One device buffer serves every frame in flight: the copies of frame
/// `n + 1` wait, by a barrier, for the index reads of every earlier submission on the queue,
/// so a frame still drawing never sees the next one's edits (the caller submits the frames
/// on one queue, in order).
///
/// The record path ([`Recorder`](crate::Recorder)) leaves the ring to the caller: it
/// [`fill`](Self::fill)s slot `s` for the frame it records into slot `s` (after that
/// frame's previous use of the slot completed on the GPU), then records with the same
/// slot. Host writes to the mapped memory need no barrier: a queue submission makes every
/// host write made before it visible to the commands it submits.
#[derive(Debug)]
pub struct CameraIndices {
    name: String,
    slots: Vec<Vec<Slot>>,
    /// Per frame slot: the vertex count the slot's indices may reference (the hierarchy's
    /// vertex count, or one more than the largest listed index).
    vertex_bounds: Vec<u32>,
    /// Per frame slot: filled by morphed emission ([`IndexSource::MorphedCamera`]).
    morphed: Vec<bool>,
    grows: u64,
    /// The edited device buffer, for buffers made by [`edited`](Self::edited).
    edited: Option<EditedBuffer>,
}

impl CameraIndices {
    /// Index buffers for `surfaces` surfaces and `frames_in_flight` frame slots; buffers are
    /// created on first use.
    pub fn new(name: &str, surfaces: usize, frames_in_flight: usize) -> Self {
        Self {
            name: name.to_string(),
            slots: (0..frames_in_flight.max(1))
                .map(|_| (0..surfaces).map(|_| Slot::default()).collect())
                .collect(),
            vertex_bounds: vec![0; frames_in_flight.max(1)],
            morphed: vec![false; frames_in_flight.max(1)],
            grows: 0,
            edited: None,
        }
    }

    /// An edited index buffer (see the type's docs) for a camera of `places` index places
    /// ([`CameraState::index_places`]) over `surfaces` surfaces, and its staging for
    /// `frames_in_flight` frame slots.
    pub fn edited(
        ctx: &Context,
        name: &str,
        surfaces: usize,
        places: usize,
        frames_in_flight: usize,
    ) -> Result<Self> {
        let mut made = Self::new(name, surfaces, frames_in_flight);
        made.edited = Some(EditedBuffer::new(
            ctx,
            name,
            places as u64,
            frames_in_flight,
        )?);
        Ok(made)
    }

    /// Whether the buffer is edited in place ([`edited`](Self::edited)).
    pub fn is_edited(&self) -> bool {
        self.edited.is_some()
    }

    /// Takes `camera`'s index edits for frame slot `frame`, closing at most `max_moves`
    /// holes (see [`CameraState::index_edits`]); [`record_edits`](Self::record_edits) then
    /// records them. The GPU must be done with the slot's previous frame (the caller's
    /// fence for that slot). The indices are morphed emission's when the camera has morph
    /// memory, for a draw with its [`CameraMorphs`](crate::CameraMorphs). The edits taken
    /// leave the camera: record them before the next `fill_edits`, or the device buffer
    /// misses them (after a dropped frame, `reset` the camera so the next edits rewrite
    /// every place).
    pub fn fill_edits(
        &mut self,
        ctx: &Context,
        frame: usize,
        hierarchy: &impl HierarchyRecords,
        camera: &mut CameraState<'_>,
        max_moves: u32,
    ) -> Result<IndexEdits> {
        if hierarchy.surface_count() != self.surface_count() {
            return Err(Error::InvalidArgument(format!(
                "{}: the hierarchy has {} surfaces, the index buffers {}",
                self.name,
                hierarchy.surface_count(),
                self.surface_count()
            )));
        }
        let Some(edited) = self.edited.as_mut() else {
            return Err(Error::InvalidArgument(format!(
                "{}: index edits into buffers not made by CameraIndices::edited",
                self.name
            )));
        };
        let e = edited.fill(ctx, &self.name, frame, hierarchy, camera, max_moves)?;
        self.vertex_bounds[frame] = morphed_bound(hierarchy.device_vertex_bound(), camera);
        self.morphed[frame] = camera.max_morphs() > 0;
        Ok(e)
    }

    /// Records the copies [`fill_edits`](Self::fill_edits) took for `frame` into `cmd`,
    /// which must be recording outside rendering, before the frame's draws; returns the index
    /// bytes they write (0, recording nothing, for buffers that are not edited or a frame
    /// without edits). The staging buffer must stay alive until the GPU has executed `cmd`.
    pub fn record_edits(&self, ctx: &Context, cmd: vk::CommandBuffer, frame: usize) -> u64 {
        self.edited
            .as_ref()
            .map_or(0, |e| e.record(ctx, cmd, frame))
    }

    /// Surfaces (index lists per frame).
    pub fn surface_count(&self) -> usize {
        self.slots.first().map_or(0, Vec::len)
    }

    /// Frame slots.
    pub fn frames_in_flight(&self) -> usize {
        self.slots.len()
    }

    /// Buffers (re)allocated so far, all surfaces and slots together (staging buffers, for
    /// edited ones).
    pub fn grow_count(&self) -> u64 {
        self.grows + self.edited.as_ref().map_or(0, EditedBuffer::grow_count)
    }

    /// Capacity of surface `surface`'s buffer in `frame`, in indices (0 before first use).
    pub fn capacity(&self, frame: usize, surface: usize) -> u64 {
        self.slots
            .get(frame)
            .and_then(|f| f.get(surface))
            .and_then(|s| s.buffer.as_ref())
            .map_or(0, |b| b.desc.size / 4)
    }

    /// The vertices `frame`'s indices may reference: a vertex buffer with at least this many
    /// vertices can draw them (0 before the slot is filled).
    pub fn vertex_bound(&self, frame: usize) -> u32 {
        self.vertex_bounds.get(frame).copied().unwrap_or(0)
    }

    /// Whether `frame` was last filled by morphed emission ([`IndexSource::MorphedCamera`]),
    /// whose indices point at a camera's morph slots.
    pub fn morphed(&self, frame: usize) -> bool {
        self.morphed.get(frame).copied().unwrap_or(false)
    }

    /// Index bytes `frame`'s fill wrote, all surfaces: every index of emitted lists, the
    /// copies of edited buffers.
    pub fn index_bytes(&self, frame: usize) -> u64 {
        if let Some(e) = &self.edited {
            return e.written_bytes(frame);
        }
        self.slots
            .get(frame)
            .map_or(0, |f| f.iter().map(|s| 4 * u64::from(s.count)).sum())
    }

    /// The buffer, first index and index count (32-bit indices) of `surface` in `frame`,
    /// as last filled; `None` when empty. For hosts that draw with their own pipelines.
    pub fn draw_range(&self, frame: usize, surface: usize) -> Option<(vk::Buffer, u32, u32)> {
        if let Some(e) = &self.edited {
            return e.draw_range(frame, surface);
        }
        let s = self.slots.get(frame)?.get(surface)?;
        match (&s.buffer, s.count) {
            (Some(b), n) if n > 0 => Some((b.raw, 0, n)),
            _ => None,
        }
    }

    /// Makes sure `surface` in `frame` holds `needed` indices, doubling its buffer if not.
    /// The frame's previous GPU work must be complete.
    fn reserve(&mut self, ctx: &Context, frame: usize, surface: usize, needed: u64) -> Result<()> {
        let name = &self.name;
        let slot = self
            .slots
            .get_mut(frame)
            .and_then(|f| f.get_mut(surface))
            .ok_or_else(|| Error::InvalidArgument(format!("no slot {frame}/{surface}")))?;
        let grew = reserve_host(
            ctx,
            &mut slot.buffer,
            || format!("{name} index buffer f{frame} s{surface}"),
            (4, MIN_INDICES, needed),
            vk::BufferUsageFlags::INDEX_BUFFER,
        )?;
        self.grows += u64::from(grew);
        Ok(())
    }

    /// Fills slot `frame`'s buffers from `source` (writing mapped memory; a buffer too small
    /// is replaced by one twice as large); returns the index bytes written. The GPU must be
    /// done with the slot's previous contents (the caller's frame fence for that slot).
    pub fn fill(
        &mut self,
        ctx: &Context,
        frame: usize,
        source: IndexSource<'_, '_>,
    ) -> Result<u64> {
        if self.edited.is_some() {
            return Err(Error::InvalidArgument(format!(
                "{}: edited index buffers take the camera's edits (fill_edits)",
                self.name
            )));
        }
        if frame >= self.slots.len() {
            return Err(Error::InvalidArgument(format!(
                "frame slot {frame} of {} slots",
                self.slots.len()
            )));
        }
        let surfaces = self.surface_count();
        let needed: Vec<u64> = match source {
            IndexSource::Camera {
                hierarchy,
                camera: state,
            }
            | IndexSource::MorphedCamera {
                hierarchy,
                camera: state,
            } => {
                if hierarchy.surface_count() != surfaces {
                    return Err(Error::InvalidArgument(format!(
                        "{}: the hierarchy has {} surfaces, the index buffers {surfaces}",
                        self.name,
                        hierarchy.surface_count()
                    )));
                }
                (0..surfaces).map(|s| state.index_count(s) as u64).collect()
            }
            IndexSource::Lists(lists) | IndexSource::MorphedLists(lists) => {
                if lists.len() != surfaces {
                    return Err(Error::InvalidArgument(format!(
                        "{}: {} index lists given for {surfaces} surfaces",
                        self.name,
                        lists.len()
                    )));
                }
                lists.iter().map(|l| l.len() as u64).collect()
            }
        };
        for (s, &n) in needed.iter().enumerate() {
            self.reserve(ctx, frame, s, n)?;
        }
        let slots = &mut self.slots[frame];
        let mut outs: Vec<&mut [u32]> = Vec::with_capacity(surfaces);
        for slot in slots.iter_mut() {
            match slot.buffer.as_mut().and_then(Buffer::mapped_mut) {
                Some(bytes) => {
                    outs.push(bytemuck::try_cast_slice_mut(bytes).map_err(|e| {
                        Error::InvalidArgument(format!("index buffer mapping: {e}"))
                    })?)
                }
                None => outs.push(&mut []),
            }
        }
        let mut written = vec![0u32; surfaces];
        let vertex_bound = match source {
            IndexSource::Camera {
                hierarchy,
                camera: cam,
            } => {
                cam.emit_indices(hierarchy, &mut outs, &mut written)?;
                u32::try_from(hierarchy.vertices().len()).unwrap_or(u32::MAX)
            }
            IndexSource::MorphedCamera {
                hierarchy,
                camera: cam,
            } => {
                cam.emit_indices_morphed(hierarchy, &mut outs, &mut written)?;
                morphed_bound(hierarchy.vertices().len(), cam)
            }
            IndexSource::Lists(lists) | IndexSource::MorphedLists(lists) => {
                let mut bound = 0u32;
                for (s, list) in lists.iter().enumerate() {
                    outs[s][..list.len()].copy_from_slice(list);
                    written[s] = list.len() as u32;
                    if let Some(&max) = list.iter().max() {
                        bound = bound.max(max.saturating_add(1));
                    }
                }
                bound
            }
        };
        drop(outs);
        self.vertex_bounds[frame] = vertex_bound;
        self.morphed[frame] = matches!(
            source,
            IndexSource::MorphedCamera { .. } | IndexSource::MorphedLists(_)
        );
        let mut bytes = 0u64;
        for (slot, &n) in slots.iter_mut().zip(&written) {
            slot.count = n;
            bytes += 4 * u64::from(n);
        }
        Ok(bytes)
    }

    /// Destroys every buffer. The GPU must be done with them.
    pub fn destroy(self, ctx: &Context) -> Result<()> {
        let mut first_err = self.edited.map(|e| e.destroy(ctx)).and_then(Result::err);
        for slot in self.slots.into_iter().flatten() {
            if let Some(b) = slot.buffer {
                if let Err(e) = b.destroy(ctx) {
                    first_err.get_or_insert(e);
                }
            }
        }
        first_err.map_or(Ok(()), Err)
    }
}

/// The vertices morphed indices of `camera` may name: `vertices` persistent ones, then its
/// morph slots in use (none without morph memory).
fn morphed_bound(vertices: usize, camera: &CameraState<'_>) -> u32 {
    u32::try_from(vertices + camera.morph_vertices().len()).unwrap_or(u32::MAX)
}
