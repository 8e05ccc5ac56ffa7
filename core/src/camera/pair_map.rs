//! The camera's map from split node to the face pair its split created.
//!
//! It is the one per-camera array sized by the hierarchy rather than by the front (a word per
//! splittable node), so it was half of a budgeted camera's memory. Its entries are pair
//! indices below `max_pairs`, so a camera with fewer than 65,535 pairs (every budgeted
//! camera of the demo; a quarter of a million active polygons) stores them in 16 bits, and
//! only a camera that may hold more uses 32. The width is fixed when the camera is made; the
//! branch on it is the same for every access, so the predictor takes it for free.

use super::NONE;

/// 16-bit entries' "no pair".
const NARROW_NONE: u16 = u16::MAX;

/// Pair index per split node, `NONE` where the node is not split.
#[derive(Debug)]
pub(crate) enum PairMap<'m> {
    /// 16-bit entries, for cameras with fewer than `u16::MAX` pairs.
    Narrow(&'m mut [u16]),
    /// 32-bit entries.
    Wide(&'m mut [u32]),
}

impl<'m> PairMap<'m> {
    /// Whether a camera with `max_pairs` pairs uses 16-bit entries.
    pub fn is_narrow(max_pairs: usize) -> bool {
        max_pairs < usize::from(NARROW_NONE)
    }

    /// Words for `nodes` entries with `max_pairs` pairs.
    pub fn words(nodes: usize, max_pairs: usize) -> usize {
        if Self::is_narrow(max_pairs) {
            nodes.div_ceil(2)
        } else {
            nodes
        }
    }

    /// The map over `memory` (at least [`words`](Self::words) words), `nodes` entries.
    pub fn new(memory: &'m mut [u32], nodes: usize, max_pairs: usize) -> Self {
        if Self::is_narrow(max_pairs) {
            let all: &mut [u16] = bytemuck::cast_slice_mut(memory);
            let len = nodes.min(all.len());
            Self::Narrow(&mut all[..len])
        } else {
            let len = nodes.min(memory.len());
            Self::Wide(&mut memory[..len])
        }
    }

    /// The pair of node `i` (`NONE` if not split); `None` past the end.
    #[inline]
    pub fn get(&self, i: usize) -> Option<u32> {
        match self {
            Self::Narrow(m) => m
                .get(i)
                .map(|&p| if p == NARROW_NONE { NONE } else { u32::from(p) }),
            Self::Wide(m) => m.get(i).copied(),
        }
    }

    /// Sets the pair of node `i`; `None` past the end or for a pair index the width cannot
    /// hold (which a camera's own bookkeeping never produces).
    /// Asks for entry `i`'s cache line ahead of its use (see `crate::prefetch`).
    #[inline(always)]
    pub fn prefetch(&self, i: usize) {
        match self {
            Self::Narrow(m) => m.get(i).map(crate::prefetch::line),
            Self::Wide(m) => m.get(i).map(crate::prefetch::line),
        };
    }

    #[inline]
    pub fn set(&mut self, i: usize, pair: u32) -> Option<()> {
        match self {
            Self::Narrow(m) => {
                let p = if pair == NONE {
                    NARROW_NONE
                } else {
                    u16::try_from(pair).ok().filter(|&p| p != NARROW_NONE)?
                };
                *m.get_mut(i)? = p;
            }
            Self::Wide(m) => *m.get_mut(i)? = pair,
        }
        Some(())
    }

    /// Every node unsplit.
    pub fn clear(&mut self) {
        match self {
            Self::Narrow(m) => m.fill(NARROW_NONE),
            Self::Wide(m) => m.fill(NONE),
        }
    }

    /// Bytes of the entries.
    pub fn bytes(&self) -> usize {
        match self {
            Self::Narrow(m) => core::mem::size_of_val(&**m),
            Self::Wide(m) => core::mem::size_of_val(&**m),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn narrow_and_wide_maps_agree() {
        let (mut a, mut b) = ([0u32; 3], [0u32; 5]);
        let mut n = PairMap::new(&mut a, 5, 100);
        let mut w = PairMap::new(&mut b, 5, 70_000);
        assert!(matches!(n, PairMap::Narrow(_)) && matches!(w, PairMap::Wide(_)));
        n.clear();
        w.clear();
        for (i, p) in [(0, 7), (4, 0), (2, 65_534)] {
            assert_eq!((n.set(i, p), w.set(i, p)), (Some(()), Some(())));
        }
        assert_eq!((n.set(4, NONE), w.set(4, NONE)), (Some(()), Some(())));
        for i in 0..5 {
            assert_eq!(n.get(i), w.get(i), "{i}");
        }
        assert_eq!(
            (n.get(2), n.get(4), n.get(5)),
            (Some(65_534), Some(NONE), None)
        );
        assert_eq!(n.set(1, 65_535), None, "a 16-bit map cannot hold 65,535");
        assert_eq!((n.bytes(), w.bytes()), (10, 20));
    }
}
