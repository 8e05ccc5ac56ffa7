//! The morph pool of a camera: its morphs' vertex slots, states and free bits in the
//! camera's words (see `morph` for what the morphs do).

use bytemuck::{Pod, Zeroable};

use super::morph_map::MorphMap;
use super::records::FREE;
use crate::gpu::MorphVertex;

/// Vertex slots per morph.
pub(crate) const VERTICES_PER_MORPH: usize = 2;

pub(crate) const MORPH_VERTEX_WORDS: usize = core::mem::size_of::<MorphVertex>() / 4;

/// A morph's state besides its vertices.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub(crate) struct MorphState {
    /// The node whose split made the floating child that morphs, or [`FREE`].
    pub parent: u32,
    /// [`REFINING`] or [`COARSENING`].
    pub phase: u32,
}

pub(crate) const STATE_WORDS: usize = core::mem::size_of::<MorphState>() / 4;

/// Towards the fine position, then end.
pub(crate) const REFINING: u32 = 0;
/// Towards the parent's position, then collapse.
pub(crate) const COARSENING: u32 = 1;

/// The morph pool of one camera: its vertex slots (what the GPU reads), its states, the
/// map from vertex to slot, a bit per pair that coarsen-morphs, and a bit per free morph.
#[derive(Debug)]
pub(crate) struct Morphs<'m> {
    /// Two per morph.
    pub vertices: &'m mut [MorphVertex],
    pub states: &'m mut [MorphState],
    pub map: MorphMap<'m>,
    /// Bit `k % 32` of word `k / 32`: pair `k`'s floating child coarsen-morphs.
    pub coarsening: &'m mut [u32],
    /// Bit `m % 32` of word `m / 32`: morph `m` is free. A new morph takes the lowest free
    /// one, so the morphs in progress stay at the bottom of the pool and the slots the GPU
    /// reads (up to the highest in progress) stay few.
    pub free: &'m mut [u32],
    pub scalars: MorphScalars,
}

/// The pool's state besides its arrays.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MorphScalars {
    /// One past the highest morph in progress.
    pub len: u32,
    /// No word of `free` below this one has a bit set.
    pub low: u32,
    /// Morphs in progress.
    pub live: u32,
    /// Of them, coarsen morphs: collapses that wait for their morph.
    pub coarsening: u32,
}

impl MorphScalars {
    pub const EMPTY: Self = Self {
        len: 0,
        low: 0,
        live: 0,
        coarsening: 0,
    };
}

impl Morphs<'_> {
    /// Most morphs at once.
    #[inline]
    pub fn capacity(&self) -> usize {
        self.states.len()
    }

    /// No morph.
    pub fn clear(&mut self) {
        self.vertices.fill(MorphVertex::IDLE);
        self.map.clear();
        self.coarsening.fill(0);
        self.states.fill(MorphState {
            parent: FREE,
            phase: REFINING,
        });
        self.free.fill(u32::MAX);
        // The bits past the last morph stay clear, so no search ever finds them.
        let n = self.states.len();
        if let Some(last) = self.free.last_mut().filter(|_| n % 32 != 0) {
            *last = (1 << (n % 32)) - 1;
        }
        self.scalars = MorphScalars::EMPTY;
    }

    /// Whether pair `pair`'s floating child coarsen-morphs.
    #[inline]
    pub fn is_coarsening(&self, pair: u32) -> bool {
        self.coarsening
            .get(pair as usize / 32)
            .is_some_and(|w| w & (1 << (pair % 32)) != 0)
    }

    pub fn set_coarsening(&mut self, pair: u32, on: bool) {
        if let Some(w) = self.coarsening.get_mut(pair as usize / 32) {
            if on {
                *w |= 1 << (pair % 32);
            } else {
                *w &= !(1 << (pair % 32));
            }
        }
    }

    /// The vertex slots up to the high-water mark.
    pub fn live_vertices(&self) -> &[MorphVertex] {
        let n = (self.scalars.len as usize).saturating_mul(VERTICES_PER_MORPH);
        &self.vertices[..n.min(self.vertices.len())]
    }

    pub fn state(&self, m: u32) -> Option<MorphState> {
        self.states
            .get(m as usize)
            .copied()
            .filter(|s| s.parent & FREE == 0)
    }

    /// The morph whose vertex slot `slot` is, if live.
    pub fn of_slot(&self, slot: u32) -> Option<u32> {
        let m = slot / VERTICES_PER_MORPH as u32;
        self.state(m).map(|_| m)
    }

    /// The lowest free morph, taken.
    pub fn alloc(&mut self) -> Option<u32> {
        let s = &mut self.scalars;
        let low = s.low as usize;
        let (k, w) = self
            .free
            .iter_mut()
            .enumerate()
            .skip(low)
            .find(|(_, w)| **w != 0)?;
        let m = (k * 32) as u32 + w.trailing_zeros();
        *w &= *w - 1;
        s.low = k as u32;
        s.len = s.len.max(m + 1);
        s.live += 1;
        Some(m)
    }

    /// Ends morph `m`: its slots go idle and it is free again; the high-water mark drops
    /// below the free morphs at the top.
    pub fn free(&mut self, m: u32) {
        if self.state(m).is_none() {
            return;
        }
        self.unmap(m);
        if let Some(state) = self.states.get_mut(m as usize) {
            state.parent = FREE;
        }
        let s = &mut self.scalars;
        if let Some(w) = self.free.get_mut(m as usize / 32) {
            *w |= 1 << (m % 32);
            s.low = s.low.min(m / 32);
        }
        s.live = s.live.saturating_sub(1);
        while s.len > 0
            && self
                .states
                .get(s.len as usize - 1)
                .is_none_or(|x| x.parent & FREE != 0)
        {
            s.len -= 1;
        }
    }

    /// Idles morph `m`'s vertex slots and takes them out of the map.
    pub fn unmap(&mut self, m: u32) {
        for k in 0..VERTICES_PER_MORPH as u32 {
            let slot = m * VERTICES_PER_MORPH as u32 + k;
            if let Some(v) = self.vertices.get_mut(slot as usize) {
                if !v.is_idle() {
                    self.map.remove(v.to, slot);
                }
                *v = MorphVertex::IDLE;
            }
        }
    }

    pub fn set_t(&mut self, m: u32, t: f32) {
        let start = m as usize * VERTICES_PER_MORPH;
        for v in self
            .vertices
            .iter_mut()
            .skip(start)
            .take(VERTICES_PER_MORPH)
        {
            v.t = t;
        }
    }

    pub fn t(&self, m: u32) -> f32 {
        self.vertices
            .get(m as usize * VERTICES_PER_MORPH)
            .map_or(1.0, |v| v.t)
    }
}

/// Word count of the morph arrays for `max_morphs` morphs over `vertices` vertices and
/// `max_pairs` pairs: vertex slots, states, map, coarsening bits, free bits.
pub(crate) fn words(max_morphs: usize, vertices: usize, max_pairs: usize) -> [usize; 5] {
    [
        max_morphs.saturating_mul(VERTICES_PER_MORPH * MORPH_VERTEX_WORDS),
        max_morphs.saturating_mul(STATE_WORDS),
        MorphMap::words(max_morphs, vertices),
        if max_morphs == 0 {
            0
        } else {
            max_pairs.div_ceil(32)
        },
        max_morphs.div_ceil(32),
    ]
}
