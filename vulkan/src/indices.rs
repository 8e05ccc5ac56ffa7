//! Index buffers of one camera (the design decisions are on [`CameraIndices`]).

use ash::vk;
use caveclod_core::{CameraState, Hierarchy};

use crate::buffer::{Buffer, BufferDesc};
use crate::device::Context;
use crate::error::{Error, Result};

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
        }
    }

    /// Surfaces (index lists per frame).
    pub fn surface_count(&self) -> usize {
        self.slots.first().map_or(0, Vec::len)
    }

    /// Frame slots.
    pub fn frames_in_flight(&self) -> usize {
        self.slots.len()
    }

    /// Buffers (re)allocated so far, all surfaces and slots together.
    pub fn grow_count(&self) -> u64 {
        self.grows
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

    /// Index bytes `frame`'s buffers hold as last filled, all surfaces (what a draw of the
    /// slot reads).
    pub fn index_bytes(&self, frame: usize) -> u64 {
        self.slots
            .get(frame)
            .map_or(0, |f| f.iter().map(|s| 4 * u64::from(s.count)).sum())
    }

    /// The buffer and index count (32-bit indices, from offset 0) of `surface` in `frame`,
    /// as last filled; `None` when empty. For hosts that draw with their own pipelines.
    pub fn draw_range(&self, frame: usize, surface: usize) -> Option<(vk::Buffer, u32)> {
        let s = self.slots.get(frame)?.get(surface)?;
        match (&s.buffer, s.count) {
            (Some(b), n) if n > 0 => Some((b.raw, n)),
            _ => None,
        }
    }

    /// Makes sure `surface` in `frame` holds `needed` indices, doubling its buffer if not.
    /// The frame's previous GPU work must be complete.
    fn reserve(&mut self, ctx: &Context, frame: usize, surface: usize, needed: u64) -> Result<()> {
        let cap = self.capacity(frame, surface);
        if needed <= cap {
            return Ok(());
        }
        let mut new_cap = cap.max(MIN_INDICES);
        while new_cap < needed {
            new_cap *= 2;
        }
        let name = format!("{} index buffer f{frame} s{surface}", self.name);
        let buffer = Buffer::new(
            ctx,
            &name,
            BufferDesc::cpu_to_gpu(new_cap * 4, vk::BufferUsageFlags::INDEX_BUFFER),
        )?;
        let slot = self
            .slots
            .get_mut(frame)
            .and_then(|f| f.get_mut(surface))
            .ok_or_else(|| Error::InvalidArgument(format!("no slot {frame}/{surface}")))?;
        if let Some(old) = slot.buffer.replace(buffer) {
            old.destroy(ctx)?;
        }
        self.grows += 1;
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
            IndexSource::Lists(lists) => {
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
                let slots = cam.morph_vertices().len();
                u32::try_from(hierarchy.vertices().len() + slots).unwrap_or(u32::MAX)
            }
            IndexSource::Lists(lists) => {
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
        self.morphed[frame] = matches!(source, IndexSource::MorphedCamera { .. });
        let mut bytes = 0u64;
        for (slot, &n) in slots.iter_mut().zip(&written) {
            slot.count = n;
            bytes += 4 * u64::from(n);
        }
        Ok(bytes)
    }

    /// Destroys every buffer. The GPU must be done with them.
    pub fn destroy(self, ctx: &Context) -> Result<()> {
        let mut first_err = None;
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
