//! Re-ordering a camera's arrays for locality.
//!
//! Splits append active-vertex records and polygon pairs in the order they happen, so after
//! many frames the active list and the pairs are in no useful order and every visit is a
//! cache miss. Node ids are numbered depth-first (subtrees contiguous, a stationary child
//! next to its parent), so sorting the active records by node id, and the pairs by the node
//! that owns them, makes a refinement pass and an emission sweep the static arrays nearly in
//! order.
//!
//! It needs no scratch memory and reads the hierarchy only to restore each record's
//! coarsening parent, in node order:
//! - **Records.** Each record's `coarsen` field (which the record's node determines, so it
//!   can be read again afterwards) first holds the record's own index; the records are
//!   sorted by node, and the field, now the old index of the record at each place, is
//!   inverted in place by following the permutation's cycles, so that it holds the new
//!   place of each old record. A corner then moves to its record's new place with one read,
//!   and the field is restored from the node records, visited in node order.
//! - **Pairs.** Links into pairs are first rewritten into the owning split and side (from
//!   the camera's `owner`, without the hierarchy). The owners alone are sorted; the pair map
//!   still gives each owner's old pair, so the permutation is known, and each pair's two
//!   slots (with their index-cache entries) move once along its cycles, the map taking each
//!   pair's new place as the pair arrives. Links are then mapped back through the map.
//!
//! Sorting only the owners and moving each pair once along the permutation's cycles avoids
//! moving both slots at every swap of a sort, mapping ids back by binary search, and looking
//! every moved pair's index-cache entries up again in the hierarchy.
//!
//! [`CameraState::compact`] is never called by refinement on its own (no hidden frame
//! spikes): call it where a frame can afford it, for example when [`CameraState::churn`]
//! exceeds the active node count, or reach the same order by bounded steps with
//! [`CameraState::compact_step`] (see `compact_step`).

use super::compact_progress::Progress;
use super::index_cache::EMPTY;
use super::records::{ActiveVertex, PolySlot, SlotTriangle, FREE, NONE};
use super::state::{CameraState, Front};
use crate::hierarchy::HierarchyRecords;
use crate::ids::NodeId;

/// Marks an entry of the permutation that the in-place inversion has written.
const DONE: u32 = 1 << 31;

impl Front<'_> {
    pub(crate) fn compact(&mut self, h: &impl HierarchyRecords) {
        let live = self.base as usize + 2 * self.pairs as usize;
        let len = self.active_len as usize;
        // Encoded links (`base + 2 * owner + side`) must stay below `NONE`, and record
        // indices below `DONE`; no hierarchy that fits in memory comes near either, and a
        // camera that could is left as it is (compaction changes no result, only speed).
        let encodable =
            u64::from(self.base) + 2 * u64::from(h.meta().split_count) + 2 < u64::from(NONE);
        if !encodable
            || live > self.slots.len()
            || (self.caches_indices() && live > self.triangles.len())
            || len > self.active.len()
            || len >= DONE as usize
        {
            return;
        }
        self.links_to_owners(live);
        self.sort_records(h, live, len);
        self.sort_pairs();
        self.links_to_slots(live);
        self.refused.fill(0);
        if self.morphs.scalars.live > 0 {
            self.mark_coarsening_pairs();
        }
        self.churn = 0;
        self.visit_cursor = 0;
        self.compaction = Progress::IDLE;
    }

    /// Rewrites every link into a pair's slot as `base + 2 * owner + side`, which survives
    /// the pairs' re-ordering (links into base slots, below `base`, stay as they are).
    fn links_to_owners(&mut self, live: usize) {
        let (owner, pairs) = (&*self.owner, self.pairs);
        let owner_of = |k: u32| owner.get(k as usize).filter(|_| k < pairs).map(|o| o.0);
        map_pair_links(&mut self.slots[..live], self.base, owner_of);
    }

    /// Maps the encoded links back to the slots their pairs now occupy.
    fn links_to_slots(&mut self, live: usize) {
        let (pair_of, pairs) = (&self.pair_of, self.pairs);
        let pair_now = |owner: u32| pair_of.get(owner as usize).filter(|&k| k < pairs);
        map_pair_links(&mut self.slots[..live], self.base, pair_now);
    }

    /// Sorts the active records by node (free records, tagged with the top bit, sort last
    /// and are dropped), moves every corner to its record's new place and restores the
    /// records' coarsening parents.
    fn sort_records(&mut self, h: &impl HierarchyRecords, live: usize, len: usize) {
        let records = &mut self.active[..len];
        for (i, r) in records.iter_mut().enumerate() {
            r.coarsen = i as u32;
        }
        records.sort_unstable_by_key(|a| a.node);
        // `coarsen` of place j is the old index of the record now there; invert it in place,
        // cycle by cycle, so that `coarsen` of old index i is the new place of record i.
        for start in 0..len {
            if records[start].coarsen & DONE != 0 {
                continue;
            }
            let (mut prev, mut cur) = (start as u32, records[start].coarsen);
            let mut steps = 0;
            while cur != start as u32 && steps < len {
                let Some(r) = records.get_mut(cur as usize) else {
                    break;
                };
                let next = r.coarsen;
                r.coarsen = prev | DONE;
                (prev, cur) = (cur, next);
                steps += 1;
            }
            records[start].coarsen = prev | DONE;
        }
        let kept = records.iter().take_while(|a| a.node & FREE == 0).count();
        for s in &mut self.slots[..live] {
            for c in &mut s.corners {
                *c = match records.get(*c as usize) {
                    Some(r) if ((r.coarsen & !DONE) as usize) < kept => r.coarsen & !DONE,
                    _ => NONE,
                };
            }
        }
        for r in &mut records[..kept] {
            r.coarsen = ActiveVertex::of(h, NodeId(r.node)).coarsen;
        }
        self.active_len = kept as u32;
        self.free_head = NONE;
    }

    /// Sorts the pairs by owner: the owners alone, then each pair's slots and index-cache
    /// entries along the permutation's cycles, the pair map following (see the module docs).
    fn sort_pairs(&mut self) {
        let n = (self.pairs as usize).min(self.owner.len());
        let base = self.base as usize;
        self.owner[..n].sort_unstable();
        let cached = self.caches_indices();
        // A pair's two slots and two cache entries (`live` bounds every index: `compact`
        // checked it against both arrays).
        // A pair's places in the index buffer go with it (see `placement`).
        let take = |f: &Self, k: usize| -> ([PolySlot; 2], [SlotTriangle; 2], [u32; 2]) {
            let s = [f.slots[base + 2 * k], f.slots[base + 2 * k + 1]];
            let t = if cached {
                [f.triangles[base + 2 * k], f.triangles[base + 2 * k + 1]]
            } else {
                [EMPTY; 2]
            };
            let place = |i: usize| f.placement.place.get(i).copied().unwrap_or(NONE);
            (s, t, [place(base + 2 * k), place(base + 2 * k + 1)])
        };
        let put =
            |f: &mut Self, k: usize, (s, t, p): ([PolySlot; 2], [SlotTriangle; 2], [u32; 2])| {
                f.slots[base + 2 * k] = s[0];
                f.slots[base + 2 * k + 1] = s[1];
                if cached {
                    f.triangles[base + 2 * k] = t[0];
                    f.triangles[base + 2 * k + 1] = t[1];
                }
                for side in 0..2 {
                    let slot = base + 2 * k + side;
                    f.placement.put(slot as u32, p[side]);
                }
            };
        for start in 0..n {
            // The pair now owned by `owner[start]` was at `pair_of`'s entry until moved.
            let Some(src) = self.old_place(start, n) else {
                continue;
            };
            if src == start {
                continue;
            }
            let first = take(self, start);
            let mut k = start;
            for _ in 0..n {
                let Some(src) = self.old_place(k, n) else {
                    break;
                };
                let _ = self.pair_of.set(self.owner[k].index(), k as u32);
                if src == start {
                    break;
                }
                let moved = take(self, src);
                put(self, k, moved);
                k = src;
            }
            put(self, k, first);
        }
    }

    /// Where the pair of sorted owner `k` was before this sort (`pair_of` has not yet been
    /// set to its new place), if below `n`.
    fn old_place(&self, k: usize, n: usize) -> Option<usize> {
        let owner = self.owner.get(k)?;
        let p = self.pair_of.get(owner.index())? as usize;
        (p < n).then_some(p)
    }
}

/// Rewrites every link at or above `base` (into a pair's slot, `base + 2 * x + side`) to
/// `base + 2 * to(x) + side`, and to `NONE` where `to` has no answer or the sum would not fit;
/// links into base slots and absent links stay as they are.
fn map_pair_links(slots: &mut [PolySlot], base: u32, to: impl Fn(u32) -> Option<u32>) {
    for s in slots {
        for l in &mut s.neighbours {
            if *l == NONE || *l < base {
                continue;
            }
            let rel = *l - base;
            *l = to(rel / 2)
                .and_then(|x| x.checked_mul(2))
                .and_then(|x| x.checked_add(base + rel % 2))
                .unwrap_or(NONE);
        }
    }
}

impl CameraState<'_> {
    /// Splits and collapses applied since the camera was created, reset or compacted.
    pub fn churn(&self) -> u32 {
        self.front.churn
    }

    /// Re-orders the active list by node id and the polygon pairs by split, for locality
    /// (sorting the records by node and the pairs by their owning split). The front is
    /// unchanged; only the emission order of polygons changes. Costs O(n_a log n_a + p_a log
    /// p_a) at once, a spike on a large front (see [`compact_step`](Self::compact_step) for
    /// bounded steps), and ends any incremental cycle
    /// under way; never called by [`refine`](Self::refine).
    pub fn compact(&mut self, h: &impl HierarchyRecords) {
        if self.is_for(h) {
            self.front.compact(h);
        }
    }
}
