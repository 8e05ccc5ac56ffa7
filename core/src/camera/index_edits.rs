//! Index edits: what a host writes to a camera's device index buffer this frame, instead of
//! the whole of [`emit_indices_packed_morphed`](CameraState::emit_indices_packed_morphed).
//!
//! With [`CameraConfig::edit_list`](crate::CameraConfig::edit_list) each active polygon keeps
//! a place in one index buffer of [`index_places`](CameraState::index_places) triangles, a
//! region per surface (see `placement`). [`index_edits`](CameraState::index_edits) hands out
//! the places that changed since the last call, each with the three indices it must now
//! hold (morphed emission's, so a morphing corner points at `vertex_count + slot`), or a
//! degenerate triangle for a hole, and each surface's draw range. A host copies the edits
//! into the buffer before the draws that read it; the triangles drawn are then exactly
//! those of morphed emission, in another order, with holes that draw nothing. A bounded
//! number of moves per call closes holes, so the draws stay near the polygons' count.

use bytemuck::{Pod, Zeroable};

use super::device_space::{on_device, MorphRemap};
use super::emit::EmitError;
use super::index_cache::BATCH;
use super::records::{NONE, NO_POLYGON};
use super::state::CameraState;
use crate::hierarchy::HierarchyRecords;

/// One place of a camera's index buffer and the triangle it now holds: indices
/// `3 × place .. 3 × place + 3`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct IndexEdit {
    /// The place (a triangle of the buffer).
    pub place: u32,
    /// Its three vertex indices; a hole holds three equal ones, which draw nothing.
    pub indices: [u32; 3],
}

/// One surface's draw over a camera's index buffer (in indices, as `vkCmdDrawIndexed` takes
/// them).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct SurfaceDraw {
    /// The first index.
    pub first_index: u32,
    /// Indices to draw: three per place in use or hole.
    pub index_count: u32,
}

/// What one [`index_edits`](CameraState::index_edits) handed out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct IndexEdits {
    /// Edits written.
    pub edits: usize,
    /// Every drawn place was written: the front was rebuilt (a reset, a new camera) or more
    /// places changed than the list holds.
    pub everything: bool,
    /// Polygons moved into holes.
    pub moves: u32,
    /// Holes drawn (as nothing) after the moves.
    pub holes: u32,
}

/// The triangle a hole holds: three equal indices, which rasterize nothing.
pub(crate) const HOLE: [u32; 3] = [0; 3];

impl CameraState<'_> {
    /// Triangles of the camera's device index buffer (three indices each): a region of
    /// polygon slots per surface; 0 without index edits.
    pub fn index_places(&self) -> usize {
        self.front.placement.slot_of.len()
    }

    /// Most edits the next [`index_edits`](Self::index_edits) with `max_moves` writes: the
    /// places marked (every drawn place when everything is to be written) and the moves
    /// (at most one per hole).
    pub fn index_edits_needed(&self, max_moves: u32) -> usize {
        let p = &self.front.placement;
        let marked = if p.scalars.everything {
            p.regions.iter().map(|g| g.len as usize).sum()
        } else {
            p.scalars.listed as usize
        };
        marked + self.hole_moves(max_moves) as usize
    }

    /// Moves the next edits make of at most `max_moves`: one per hole at most, and no more
    /// than the list has room to mark (edits never grow past what was asked for room).
    fn hole_moves(&self, max_moves: u32) -> u32 {
        let p = &self.front.placement;
        let holes: u32 = p.regions.iter().map(|g| g.holes).sum();
        let room = if p.scalars.everything {
            u32::MAX
        } else {
            p.list.len() as u32 - p.scalars.listed
        };
        holes.min(max_moves).min(room)
    }

    /// Moves at most `max_moves` polygons into holes, then writes to `out` every place that
    /// changed since the last call with what it must hold, and to `draws` (one per surface)
    /// each surface's range; the marks are cleared. The edits are in the order the places
    /// changed, each place once; `out` needs [`index_edits_needed`](Self::index_edits_needed)
    /// entries, checked before anything changes. [`EmitError::NoDeviceVertex`] (a camera
    /// inconsistent with its streamed pool) comes after the marks were cleared: reset the
    /// camera, whose next edits rewrite everything.
    pub fn index_edits(
        &mut self,
        h: &impl HierarchyRecords,
        max_moves: u32,
        out: &mut [IndexEdit],
        draws: &mut [SurfaceDraw],
    ) -> Result<IndexEdits, EmitError> {
        if !self.is_for(h) {
            return Err(EmitError::WrongHierarchy);
        }
        let ns = h.surface_count();
        if !self.front.placement.is_on() {
            return Err(EmitError::NoIndexEdits);
        }
        if draws.len() < ns {
            return Err(EmitError::TooFewOutputs {
                needed: ns,
                given: draws.len(),
            });
        }
        let needed = self.index_edits_needed(max_moves);
        if out.len() < needed {
            return Err(EmitError::OutputTooSmall {
                surface: None,
                needed,
                given: out.len(),
            });
        }
        let moves = self.front.placement.close_holes(self.hole_moves(max_moves));
        let f = &self.front;
        let remap = MorphRemap::of(&f.morphs, h.device_vertex_bound() as u32);
        let mut placeless = None;
        let p = &f.placement;
        let mut n = 0;
        let mut write = |places: &[u32]| {
            // Two links per place, its slot and the slot's cache entry, each taken for a
            // batch before the next so that their misses overlap.
            let mut slots = [NONE; BATCH];
            for (s, &place) in slots.iter_mut().zip(places) {
                *s = p.slot_of.get(place as usize).copied().unwrap_or(NONE);
            }
            for (&place, &slot) in places.iter().zip(&slots) {
                if !p.drawn(place) {
                    continue;
                }
                let indices = match f.triangles.get(slot as usize) {
                    Some(t) if t.surface != NO_POLYGON => match &remap {
                        Some(m) => m.triangle(h, t.indices),
                        None => on_device(h, t.indices),
                    }
                    .unwrap_or_else(|v| {
                        placeless.get_or_insert(v);
                        HOLE
                    }),
                    _ => HOLE,
                };
                if let Some(e) = out.get_mut(n) {
                    *e = IndexEdit { place, indices };
                    n += 1;
                }
            }
        };
        if p.scalars.everything {
            let mut batch = [0u32; BATCH];
            for r in 0..p.regions.len() {
                let (mut at, end) = (p.drawn_range(r).start, p.drawn_range(r).end);
                while at < end {
                    let k = (end - at).min(BATCH as u32) as usize;
                    for (i, b) in batch[..k].iter_mut().enumerate() {
                        *b = at + i as u32;
                    }
                    write(&batch[..k]);
                    at += k as u32;
                }
            }
        } else {
            p.list[..p.scalars.listed as usize]
                .chunks(BATCH)
                .for_each(&mut write);
        }
        let everything = p.scalars.everything;
        let mut holes = 0;
        for (r, (d, g)) in draws.iter_mut().zip(p.regions.iter()).enumerate() {
            let range = p.drawn_range(r);
            *d = SurfaceDraw {
                first_index: 3 * range.start,
                index_count: 3 * (range.end - range.start),
            };
            holes += g.holes;
        }
        self.front.placement.clear_marks();
        if let Some(vertex) = placeless {
            return Err(EmitError::NoDeviceVertex { vertex });
        }
        Ok(IndexEdits {
            edits: n,
            everything,
            moves,
            holes,
        })
    }
}
