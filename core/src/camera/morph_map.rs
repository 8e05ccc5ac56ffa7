//! The camera's map from a morphing vertex (its persistent vertex-buffer index) to its morph
//! slot, which morphed emission asks for every corner.
//!
//! Two parts: a bit per vertex of the hierarchy, set while the vertex morphs, and an
//! open-addressed table of `4 × max_morphs + 1` entries from vertex to slot (a morph has at
//! most two vertices, so the table is never more than half full and never full): linear
//! probing from a multiplicative hash, deletion by shifting the rest of the run back, as in
//! the hashed pair map. Emission reads the bit of every corner, in the order the polygons
//! name their vertices, which keeps those reads close together; only a morphing corner
//! probes the table, whose scattered reads would otherwise cost every corner a cache miss
//! once thousands of vertices morph. The bits cost one per vertex, an eighth of a byte,
//! against the pair map's two bytes per splittable node.

use super::records::NONE;
use bytemuck::{Pod, Zeroable};

/// One entry: a vertex index (`NONE` when empty) and its morph slot.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub(crate) struct Entry {
    vertex: u32,
    slot: u32,
}

const EMPTY: Entry = Entry {
    vertex: NONE,
    slot: NONE,
};

const ENTRY_WORDS: usize = core::mem::size_of::<Entry>() / 4;

/// Entries for `max_morphs` morphs: none without morphs.
fn capacity(max_morphs: usize) -> usize {
    if max_morphs == 0 {
        0
    } else {
        max_morphs.saturating_mul(4).saturating_add(1)
    }
}

/// Words of the bits for `vertices` vertices: none without morphs.
fn bit_words(max_morphs: usize, vertices: usize) -> usize {
    if max_morphs == 0 {
        0
    } else {
        vertices.div_ceil(32)
    }
}

/// The entry a vertex's probe starts at (multiply and shift onto `len` entries).
#[inline(always)]
fn home(vertex: u32, len: usize) -> usize {
    let h = vertex.wrapping_mul(0x9E37_79B1);
    ((u64::from(h) * len as u64) >> 32) as usize
}

/// Morph slot by vertex index, over caller memory.
#[derive(Debug)]
pub(crate) struct MorphMap<'m> {
    /// Bit `v % 32` of word `v / 32`: vertex `v` morphs.
    bits: &'m mut [u32],
    table: &'m mut [Entry],
}

impl<'m> MorphMap<'m> {
    /// Words for `max_morphs` morphs over `vertices` vertices.
    pub fn words(max_morphs: usize, vertices: usize) -> usize {
        capacity(max_morphs)
            .saturating_mul(ENTRY_WORDS)
            .saturating_add(bit_words(max_morphs, vertices))
    }

    /// The map over `memory` (at least [`words`](Self::words) words).
    pub fn new(memory: &'m mut [u32], max_morphs: usize, vertices: usize) -> Self {
        let table_words = capacity(max_morphs).saturating_mul(ENTRY_WORDS);
        let (table, bits) = memory.split_at_mut(table_words.min(memory.len()));
        let bits_len = bit_words(max_morphs, vertices).min(bits.len());
        Self {
            bits: &mut bits[..bits_len],
            table: bytemuck::cast_slice_mut(table),
        }
    }

    /// Whether `vertex` morphs (non-zero) or not (zero): one read of its bit, or a probe of
    /// the table where the camera keeps no bits (a hierarchy with sparse vertex ids).
    #[inline(always)]
    pub fn bit(&self, vertex: u32) -> u32 {
        if self.bits.is_empty() {
            return u32::from(self.get(vertex).is_some());
        }
        self.bits
            .get(vertex as usize / 32)
            .map_or(0, |w| w & (1 << (vertex % 32)))
    }

    fn set_bit(&mut self, vertex: u32, on: bool) {
        if let Some(w) = self.bits.get_mut(vertex as usize / 32) {
            if on {
                *w |= 1 << (vertex % 32);
            } else {
                *w &= !(1 << (vertex % 32));
            }
        }
    }

    /// Where `vertex` is, or the empty entry its probe ends at.
    #[inline]
    fn find(&self, vertex: u32) -> Result<usize, usize> {
        let len = self.table.len();
        if len == 0 {
            return Err(0);
        }
        let mut at = home(vertex, len);
        for _ in 0..len {
            let e = self.table.get(at).copied().unwrap_or(EMPTY);
            if e.vertex == vertex {
                return Ok(at);
            }
            if e.vertex == NONE {
                return Err(at);
            }
            at = if at + 1 == len { 0 } else { at + 1 };
        }
        Err(len)
    }

    /// The slot of `vertex`, if it morphs: a vertex that does not is answered by its bit,
    /// without a probe (most asked are not: a collapse's floating child long settled, a
    /// morph's coarse vertex).
    #[inline]
    pub fn get(&self, vertex: u32) -> Option<u32> {
        if vertex == NONE || (!self.bits.is_empty() && self.bit(vertex) == 0) {
            return None;
        }
        let at = self.find(vertex).ok()?;
        self.table.get(at).map(|e| e.slot)
    }

    /// Maps `vertex` to `slot` (replacing any slot it had); `None` if the table has no room,
    /// which its capacity rules out for a camera's own bookkeeping.
    pub fn insert(&mut self, vertex: u32, slot: u32) -> Option<()> {
        if vertex == NONE {
            return None;
        }
        let at = match self.find(vertex) {
            Ok(at) | Err(at) => at,
        };
        *self.table.get_mut(at)? = Entry { vertex, slot };
        self.set_bit(vertex, true);
        Some(())
    }

    /// Forgets `vertex` if it maps to `slot`.
    pub fn remove(&mut self, vertex: u32, slot: u32) {
        if let Ok(at) = self.find(vertex) {
            if self.table.get(at).is_some_and(|e| e.slot == slot) {
                self.remove_at(at);
                self.set_bit(vertex, false);
            }
        }
    }

    /// Empties entry `at` and shifts back the entries after it in its run that may stand
    /// closer to their home, so every probe still finds its vertex.
    fn remove_at(&mut self, mut at: usize) {
        let len = self.table.len();
        let mut next = at;
        for _ in 0..len {
            next = if next + 1 == len { 0 } else { next + 1 };
            let Some(&e) = self.table.get(next) else {
                return;
            };
            if e.vertex == NONE {
                break;
            }
            // The entry at `next` stays unless its home lies cyclically outside (at, next].
            let h = home(e.vertex, len);
            let stays = if at <= next {
                at < h && h <= next
            } else {
                at < h || h <= next
            };
            if !stays {
                if let Some(slot) = self.table.get_mut(at) {
                    *slot = e;
                }
                at = next;
            }
        }
        if let Some(slot) = self.table.get_mut(at) {
            *slot = EMPTY;
        }
    }

    /// No vertex morphs.
    pub fn clear(&mut self) {
        self.table.fill(EMPTY);
        self.bits.fill(0);
    }

    pub fn bytes(&self) -> usize {
        core::mem::size_of_val(&*self.table) + core::mem::size_of_val(&*self.bits)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Insertions and removals in any order leave every vertex findable, as a plain array
    /// answers, whatever runs and wrap-arounds the probes make.
    #[test]
    fn the_map_answers_as_an_array_does() {
        const VERTICES: usize = 300;
        const MORPHS: usize = 8;
        let steps = if cfg!(miri) { 300 } else { 20_000 };
        let mut memory = [0u32; 2 * 33 + 10];
        assert_eq!(MorphMap::words(MORPHS, VERTICES), memory.len());
        let mut map = MorphMap::new(&mut memory, MORPHS, VERTICES);
        map.clear();
        let mut direct = [NONE; VERTICES];
        let mut live = 0usize;
        let mut state = 0x2545_F491u32;
        for _ in 0..steps {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            let v = state as usize % VERTICES;
            if direct[v] != NONE {
                map.remove(v as u32, direct[v] + u32::from(state & 256 != 0));
                if state & 256 == 0 {
                    direct[v] = NONE;
                    live -= 1;
                }
            } else if live < 2 * MORPHS {
                let slot = (state >> 9) % (2 * MORPHS as u32);
                assert_eq!(map.insert(v as u32, slot), Some(()));
                direct[v] = slot;
                live += 1;
            }
            for (i, &d) in direct.iter().enumerate() {
                assert_eq!(map.get(i as u32), (d != NONE).then_some(d), "vertex {i}");
                assert_eq!(map.bit(i as u32) != 0, d != NONE, "vertex {i}");
            }
        }
        assert_eq!(map.get(NONE), None);
        assert_eq!(map.bit(NONE), 0);
        assert_eq!(map.bytes(), 33 * 8 + 40);
        assert_eq!(MorphMap::words(0, VERTICES), 0);
        // Without bits (sparse vertex ids), the table answers alone.
        let mut memory = [0u32; 2 * 33];
        let mut sparse = MorphMap::new(&mut memory, MORPHS, 0);
        sparse.clear();
        assert_eq!(sparse.insert(1 << 30, 5), Some(()));
        assert_ne!(sparse.bit(1 << 30), 0);
        assert_eq!(sparse.bit(7), 0);
        sparse.remove(1 << 30, 5);
        assert_eq!(sparse.bit(1 << 30), 0);
        assert_eq!(MorphMap::new(&mut [], 0, VERTICES).get(3), None);
    }
}
