//! The camera's map from split node to the face pair its split created.
//!
//! Every other per-camera array is sized by the front the camera may hold (`max_pairs`); this
//! map is asked about any splittable node, so as a plain array it is sized by the hierarchy: a
//! word per splittable node, half of a budgeted camera's memory before 16-bit entries. Three
//! layouts, fixed when the camera is made (the branch on it is the same for every access, so
//! the predictor takes it for free):
//! - **Narrow**, an array of 16-bit pair indices by node, for a camera with fewer than 65,535
//!   pairs (a budget of up to about a quarter of a million active polygons).
//! - **Wide**, an array of 32-bit pair indices by node, for cameras with more pairs.
//! - **Hashed**, when [`CameraConfig::hashed_pair_map`](crate::CameraConfig) asks for it and
//!   it is smaller than the narrow array (a `max_pairs` below about a sixth of the splittable
//!   nodes): only the split nodes, in an open-addressed table of `2 × max_pairs + 1` entries of
//!   6 bytes (the node, and the pair in 16 bits), never more than half full. Linear probing
//!   from a multiplicative hash, and deletion by shifting the rest of the run back (no
//!   tombstones), keep lookups short: at half load, linear probing expects about 1.5 entries
//!   read for a split node and 2.5 for an unsplit one (Knuth's estimates; not counted here).
//!   It shrinks the map for a small budget, but refinement is slower with it: node ids are
//!   numbered depth-first, so the array keeps the entries a pass and its operations read
//!   together in a few lines, and the hash scatters them (hashing blocks of consecutive nodes
//!   together does not win that locality back). So the array is the default, and the table
//!   is for a runtime that counts bytes. A camera with 65,535 pairs or more hashes into
//!   8-byte entries (the pair in 32 bits).
//!
//! A hierarchy with sparse ids (a paged file's page-major ids) always hashes: an array by
//! node would be sized by the id space, not by what the camera holds.

use super::records::NONE;
use bytemuck::{Pod, Zeroable};

/// 16-bit entries' "no pair".
const NARROW_NONE: u16 = u16::MAX;

/// One entry of the hashed map: the node (`NONE` when the entry is empty), in two halves so
/// that the entry takes 6 bytes, and its pair.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub(crate) struct Entry {
    node_lo: u16,
    node_hi: u16,
    pair: u16,
}

/// One entry of the hashed map with 32-bit pairs, for cameras of 65,535 pairs or more.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub(crate) struct WideEntry {
    node: u32,
    pair: u32,
}

/// What the hashed table's probes need of an entry.
trait HashEntry: Copy {
    const EMPTY: Self;
    fn node(&self) -> u32;
    fn pair(&self) -> u32;
    /// The entry of `node` and `pair`; `None` for a pair the entry cannot hold.
    fn of(node: u32, pair: u32) -> Option<Self>;
}

impl HashEntry for Entry {
    const EMPTY: Self = Self {
        node_lo: u16::MAX,
        node_hi: u16::MAX,
        pair: NARROW_NONE,
    };

    #[inline(always)]
    fn node(&self) -> u32 {
        u32::from(self.node_lo) | (u32::from(self.node_hi) << 16)
    }

    #[inline(always)]
    fn pair(&self) -> u32 {
        u32::from(self.pair)
    }

    #[inline(always)]
    fn of(node: u32, pair: u32) -> Option<Self> {
        Some(Self {
            node_lo: node as u16,
            node_hi: (node >> 16) as u16,
            pair: PairMap::narrow(pair)?,
        })
    }
}

impl HashEntry for WideEntry {
    const EMPTY: Self = Self {
        node: NONE,
        pair: NONE,
    };

    #[inline(always)]
    fn node(&self) -> u32 {
        self.node
    }

    #[inline(always)]
    fn pair(&self) -> u32 {
        self.pair
    }

    #[inline(always)]
    fn of(node: u32, pair: u32) -> Option<Self> {
        (pair != NONE).then_some(Self { node, pair })
    }
}

/// Pair index per split node, `NONE` where the node is not split.
#[derive(Debug)]
pub(crate) enum PairMap<'m> {
    /// The split nodes only, hashed (see the module docs); `nodes` bounds the node indices.
    Hashed {
        table: &'m mut [Entry],
        nodes: usize,
    },
    /// The same with 32-bit pairs.
    HashedWide {
        table: &'m mut [WideEntry],
        nodes: usize,
    },
    /// 16-bit entries by node, for cameras with fewer than `u16::MAX` pairs.
    Narrow(&'m mut [u16]),
    /// 32-bit entries by node.
    Wide(&'m mut [u32]),
}

/// The layout a camera with `max_pairs` pairs over `nodes` splittable nodes uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Layout {
    Hashed,
    HashedWide,
    Narrow,
    Wide,
}

impl Layout {
    fn of(nodes: usize, max_pairs: usize, hashed: bool) -> Self {
        if max_pairs >= usize::from(NARROW_NONE) {
            let wide_hashed = capacity(max_pairs).saturating_mul(size_of::<WideEntry>());
            if hashed && wide_hashed < nodes.saturating_mul(4) {
                Self::HashedWide
            } else {
                Self::Wide
            }
        } else if hashed && hashed_bytes(max_pairs) < nodes.saturating_mul(2) {
            Self::Hashed
        } else {
            Self::Narrow
        }
    }
}

/// Entries of the hashed table for `max_pairs` pairs: never more than half full, and never
/// full, so every probe ends at an empty entry.
fn capacity(max_pairs: usize) -> usize {
    max_pairs.saturating_mul(2).saturating_add(1)
}

fn hashed_bytes(max_pairs: usize) -> usize {
    capacity(max_pairs).saturating_mul(size_of::<Entry>())
}

use core::mem::size_of;

/// The entry a node's probe starts at: a multiplicative hash, mapped onto `len` entries by
/// its high bits (multiply and shift, no division).
#[inline(always)]
fn home(node: u32, len: usize) -> usize {
    let h = node.wrapping_mul(0x9E37_79B1);
    ((u64::from(h) * len as u64) >> 32) as usize
}

impl<'m> PairMap<'m> {
    /// Words for `nodes` splittable nodes and `max_pairs` pairs (`hashed`: hash them where
    /// that is smaller).
    pub fn words(nodes: usize, max_pairs: usize, hashed: bool) -> usize {
        match Layout::of(nodes, max_pairs, hashed) {
            Layout::Hashed => hashed_bytes(max_pairs).div_ceil(4),
            Layout::HashedWide => capacity(max_pairs).saturating_mul(2),
            Layout::Narrow => nodes.div_ceil(2),
            Layout::Wide => nodes,
        }
    }

    /// The map over `memory` (at least [`words`](Self::words) words), `nodes` nodes.
    pub fn new(memory: &'m mut [u32], nodes: usize, max_pairs: usize, hashed: bool) -> Self {
        match Layout::of(nodes, max_pairs, hashed) {
            Layout::Hashed => {
                let halves: &mut [u16] = bytemuck::cast_slice_mut(memory);
                let len = capacity(max_pairs).min(halves.len() / 3);
                Self::Hashed {
                    table: bytemuck::cast_slice_mut(&mut halves[..3 * len]),
                    nodes,
                }
            }
            Layout::HashedWide => {
                let len = capacity(max_pairs).min(memory.len() / 2);
                Self::HashedWide {
                    table: bytemuck::cast_slice_mut(&mut memory[..2 * len]),
                    nodes,
                }
            }
            Layout::Narrow => {
                let all: &mut [u16] = bytemuck::cast_slice_mut(memory);
                let len = nodes.min(all.len());
                Self::Narrow(&mut all[..len])
            }
            Layout::Wide => {
                let len = nodes.min(memory.len());
                Self::Wide(&mut memory[..len])
            }
        }
    }

    /// Where node `i` is in the hashed table, or the empty entry its probe ends at.
    #[inline]
    fn find<E: HashEntry>(table: &[E], i: u32) -> Result<usize, usize> {
        let len = table.len();
        let mut at = home(i, len);
        for _ in 0..len {
            let e = table.get(at).copied().unwrap_or(E::EMPTY);
            if e.node() == i {
                return Ok(at);
            }
            if e.node() == NONE {
                return Err(at);
            }
            at = if at + 1 == len { 0 } else { at + 1 };
        }
        Err(len)
    }

    /// The pair of node `i` (`NONE` if not split); `None` past the end.
    #[inline]
    pub fn get(&self, i: usize) -> Option<u32> {
        match self {
            Self::Hashed { table, nodes } => Self::hashed_get(table, *nodes, i),
            Self::HashedWide { table, nodes } => Self::hashed_get(table, *nodes, i),
            Self::Narrow(m) => m
                .get(i)
                .map(|&p| if p == NARROW_NONE { NONE } else { u32::from(p) }),
            Self::Wide(m) => m.get(i).copied(),
        }
    }

    /// Asks for entry `i`'s cache line ahead of its use (see `crate::prefetch`).
    #[inline(always)]
    pub fn prefetch(&self, i: usize) {
        match self {
            Self::Hashed { table, nodes } => {
                if i < *nodes {
                    table
                        .get(home(i as u32, table.len()))
                        .map(crate::prefetch::line);
                }
            }
            Self::HashedWide { table, nodes } => {
                if i < *nodes {
                    table
                        .get(home(i as u32, table.len()))
                        .map(crate::prefetch::line);
                }
            }
            Self::Narrow(m) => {
                m.get(i).map(crate::prefetch::line);
            }
            Self::Wide(m) => {
                m.get(i).map(crate::prefetch::line);
            }
        }
    }

    /// Sets the pair of node `i` (`NONE`: not split); `None` past the end, for a pair index
    /// the layout cannot hold, or with the hashed table full (a camera's own bookkeeping
    /// produces none of these).
    #[inline]
    pub fn set(&mut self, i: usize, pair: u32) -> Option<()> {
        match self {
            Self::Hashed { table, nodes } => Self::hashed_set(table, *nodes, i, pair),
            Self::HashedWide { table, nodes } => Self::hashed_set(table, *nodes, i, pair),
            Self::Narrow(m) => {
                let p = if pair == NONE {
                    NARROW_NONE
                } else {
                    Self::narrow(pair)?
                };
                *m.get_mut(i)? = p;
                Some(())
            }
            Self::Wide(m) => {
                *m.get_mut(i)? = pair;
                Some(())
            }
        }
    }

    #[inline]
    fn hashed_get<E: HashEntry>(table: &[E], nodes: usize, i: usize) -> Option<u32> {
        if i >= nodes {
            return None;
        }
        Some(match Self::find(table, i as u32) {
            Ok(at) => table.get(at).map_or(NONE, HashEntry::pair),
            Err(_) => NONE,
        })
    }

    #[inline]
    fn hashed_set<E: HashEntry>(table: &mut [E], nodes: usize, i: usize, pair: u32) -> Option<()> {
        if i >= nodes {
            return None;
        }
        let node = u32::try_from(i).ok().filter(|&n| n != NONE)?;
        match (Self::find(table, node), pair == NONE) {
            (Ok(at), true) => Self::remove_at(table, at),
            (Ok(at), false) => *table.get_mut(at)? = E::of(node, pair)?,
            (Err(_), true) => {}
            // `at` is `len` (no entry) only if the table were full, which the capacity rules
            // out: at most `max_pairs` nodes are split at once.
            (Err(at), false) => *table.get_mut(at)? = E::of(node, pair)?,
        }
        Some(())
    }

    /// A pair index in 16 bits, if it fits (and is not the empty value).
    #[inline]
    fn narrow(pair: u32) -> Option<u16> {
        u16::try_from(pair).ok().filter(|&p| p != NARROW_NONE)
    }

    /// Empties entry `at` and shifts back the entries after it in its run that may stand
    /// closer to their home, so every probe still finds its node (deletion without
    /// tombstones for linear probing).
    fn remove_at<E: HashEntry>(table: &mut [E], mut at: usize) {
        let len = table.len();
        let mut next = at;
        for _ in 0..len {
            next = if next + 1 == len { 0 } else { next + 1 };
            let Some(&e) = table.get(next) else {
                return;
            };
            if e.node() == NONE {
                break;
            }
            // The entry at `next` may move to `at` unless its home lies cyclically in
            // (at, next]: then its probe never passes `at`.
            let h = home(e.node(), len);
            let stays = if at <= next {
                at < h && h <= next
            } else {
                at < h || h <= next
            };
            if !stays {
                if let Some(slot) = table.get_mut(at) {
                    *slot = e;
                }
                at = next;
            }
        }
        if let Some(slot) = table.get_mut(at) {
            *slot = E::EMPTY;
        }
    }

    /// Every node unsplit.
    pub fn clear(&mut self) {
        match self {
            Self::Hashed { table, .. } => table.fill(Entry::EMPTY),
            Self::HashedWide { table, .. } => table.fill(WideEntry::EMPTY),
            Self::Narrow(m) => m.fill(NARROW_NONE),
            Self::Wide(m) => m.fill(NONE),
        }
    }

    /// Bytes of the entries.
    pub fn bytes(&self) -> usize {
        match self {
            Self::Hashed { table, .. } => core::mem::size_of_val(&**table),
            Self::HashedWide { table, .. } => core::mem::size_of_val(&**table),
            Self::Narrow(m) => core::mem::size_of_val(&**m),
            Self::Wide(m) => core::mem::size_of_val(&**m),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_three_layouts_agree() {
        // 40 nodes: 4 pairs hash (9 entries of 6 bytes, against 80 bytes of 16-bit entries),
        // 20 pairs do not (41 entries).
        assert_eq!(Layout::of(40, 4, true), Layout::Hashed);
        assert_eq!(Layout::of(40, 4, false), Layout::Narrow);
        assert_eq!(Layout::of(40, 20, true), Layout::Narrow);
        assert_eq!(Layout::of(40, 70_000, true), Layout::Wide);
        assert_eq!(Layout::of(1 << 30, 70_000, true), Layout::HashedWide);
        assert_eq!(Layout::of(1 << 30, 70_000, false), Layout::Wide);
        assert_eq!(
            (
                PairMap::words(40, 4, true),
                PairMap::words(40, 20, true),
                PairMap::words(40, 70_000, true)
            ),
            (14, 20, 40)
        );
        let (mut a, mut b, mut c) = ([0u32; 14], [0u32; 20], [0u32; 40]);
        let mut hashed = PairMap::new(&mut a, 40, 4, true);
        let mut n = PairMap::new(&mut b, 40, 20, true);
        let mut w = PairMap::new(&mut c, 40, 70_000, true);
        assert!(matches!(hashed, PairMap::Hashed { .. }));
        assert!(matches!(n, PairMap::Narrow(_)) && matches!(w, PairMap::Wide(_)));
        for m in [&mut hashed, &mut n, &mut w] {
            m.clear();
        }
        // Splits and collapses in an order that makes runs, then removes from their middle.
        let steps = [
            (0, 3),
            (7, 0),
            (11, 1),
            (4, 2),
            (7, NONE),
            (2, 0),
            (0, NONE),
            (9, 3),
        ];
        for (i, p) in steps {
            for m in [&mut hashed, &mut n, &mut w] {
                assert_eq!(m.set(i, p), Some(()));
            }
            for node in 0..41 {
                assert_eq!(hashed.get(node), n.get(node), "node {node}");
                assert_eq!(n.get(node), w.get(node), "node {node}");
            }
        }
        assert_eq!((hashed.get(40), hashed.set(40, 1)), (None, None));
        assert_eq!(n.set(1, 65_535), None, "a 16-bit map cannot hold 65,535");
        assert_eq!(hashed.set(1, 65_535), None, "nor can the hashed table");
        assert_eq!((hashed.bytes(), n.bytes(), w.bytes()), (54, 80, 160));
    }

    /// Every sequence of splits and collapses leaves the hashed table answering as the
    /// array does, whatever runs and wrap-arounds the probes make.
    #[test]
    fn hashed_deletion_keeps_every_run_findable() {
        const NODES: usize = 256;
        const PAIRS: usize = 16;
        let mut mem = [0u32; 50];
        let map = PairMap::new(&mut mem, NODES, PAIRS, true);
        assert!(matches!(map, PairMap::Hashed { .. }));
        answers_as_an_array(map, NODES, PAIRS);
        // The 8-byte entries of a camera with 65,535 pairs or more, in a small table.
        let mut wide = [WideEntry::EMPTY; 2 * PAIRS + 1];
        let map = PairMap::HashedWide {
            table: &mut wide,
            nodes: NODES,
        };
        answers_as_an_array(map, NODES, PAIRS);
    }

    fn answers_as_an_array(mut map: PairMap<'_>, nodes: usize, pairs: usize) {
        let steps = if cfg!(miri) { 300 } else { 20_000 };
        let mut direct = [NONE; 256];
        map.clear();
        let mut state = 0x2545_F491u32;
        let mut split = 0usize;
        for _ in 0..steps {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            let node = state as usize % nodes;
            let p = if direct[node] != NONE {
                split -= 1;
                NONE
            } else if split < pairs {
                split += 1;
                (state >> 8) % pairs as u32 + 70_000
            } else {
                continue;
            };
            direct[node] = p;
            let fits = p == NONE || matches!(map, PairMap::HashedWide { .. });
            let p = if fits { p } else { p - 70_000 };
            direct[node] = p;
            assert_eq!(map.set(node, p), Some(()));
            for (i, &d) in direct.iter().enumerate().take(nodes) {
                assert_eq!(map.get(i), Some(d), "node {i}");
            }
        }
    }
}
