//! Incremental compaction: [`CameraState::compact`]'s order reached a bounded amount of work
//! per call, whatever refinement does between calls.
//!
//! The full compaction permutes the records and the pairs through states refinement must not
//! see; this one only ever applies steps after which the camera is whole:
//! - **Squeeze.** A free record is filled with the last record of the list, which shortens
//!   the list by one (as a collapse fills its pair's hole with the last pair). Free records
//!   left past the list's end stay on the free list; a split taking a record from the list
//!   drops them.
//! - **Sort.** The records by node, then the pairs by their owning split, each by Shell sort
//!   (Ciura's gaps): an insertion sort over ever smaller gaps, whose progress is three
//!   numbers the camera keeps. Shell sort moves an element far in few steps, so a record a
//!   split appended at the end of a sorted list reaches its place in about one step per gap,
//!   and it needs no memory besides those numbers.
//!
//! A step is a comparison or a swap. Swapping two pairs moves their slots and index-cache
//! entries and patches the at most twelve links into them, as a collapse's `remove_pair`
//! does. Swapping two records rewrites the corners that name them; those polygons are the
//! fan around each record's vertex, found from one of them: a vertex created by a split is a
//! corner of the polygon its split created on the left (a split hands the record of its node
//! to the stationary child, and a collapse takes it back), a root is a corner of a base
//! polygon. The fans are walked once to check them before anything is written, so data that
//! contradicts the front leaves it as it was (the record stays where it is).
//!
//! Refinement between steps may split, collapse, free and append records: a comparison
//! with a free record or past the list's end is skipped, so a cycle that the front changed
//! under ends less than sorted, and the next cycle sorts further. A cycle run while the front
//! holds still ends in exactly the order of [`CameraState::compact`].

use super::compact_progress::{Progress, GAPS, IDLE, PAIRS, RECORDS, SQUEEZE};
use super::fan::FanStart;
use super::records::{next, prev, FREE, NONE};
use super::state::{CameraState, Front};
use crate::hierarchy::HierarchyRecords;

/// A corner or link value no record or slot has: the middle of a three-way rename.
const PARKED: u32 = NONE - 1;

/// What one [`CameraState::compact_step`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CompactProgress {
    /// Work done: comparisons, plus the records, slots and links each move read or wrote.
    pub work: u32,
    /// The call ended a compaction cycle: a cycle the front did not change under leaves the
    /// camera in [`CameraState::compact`]'s order.
    pub finished: bool,
}

impl Front<'_> {
    /// At most about `budget` work of the compaction under way, or of a new one.
    pub(crate) fn compact_step(
        &mut self,
        h: &impl HierarchyRecords,
        budget: u32,
    ) -> CompactProgress {
        let mut done = CompactProgress::default();
        if self.compaction.phase == IDLE {
            self.compaction.phase = SQUEEZE;
            self.churn = 0;
        }
        while done.work < budget {
            let work = match self.compaction.phase {
                SQUEEZE => self.squeeze_one(h),
                RECORDS => self.sort_records_step(h),
                PAIRS => self.sort_pairs_step(),
                _ => None,
            };
            match work {
                Some(w) => done.work = done.work.saturating_add(w.max(1)),
                None => {
                    done.work = done.work.saturating_add(1);
                    self.compaction = match self.compaction.phase {
                        SQUEEZE => Progress::sort(RECORDS, self.active_len),
                        RECORDS => Progress::sort(PAIRS, self.pairs),
                        _ => Progress::IDLE,
                    };
                    if self.compaction.phase == IDLE {
                        done.finished = true;
                        break;
                    }
                }
            }
        }
        done
    }

    /// One squeeze step: drop a free record at the list's end, or fill the free list's first
    /// record with the list's last; `None` when the free list is empty (or the last record
    /// cannot move: then the holes stay, and the sort skips them).
    fn squeeze_one(&mut self, h: &impl HierarchyRecords) -> Option<u32> {
        let len = self.active_len as usize;
        if len > 0 && self.active.get(len - 1)?.node & FREE != 0 {
            self.active_len -= 1;
            return Some(1);
        }
        if self.free_head == NONE {
            return None;
        }
        let hole = self.free_head;
        let link = self.active.get(hole as usize)?.node & !FREE;
        let rest = if link == FREE - 1 { NONE } else { link };
        if hole >= self.active_len {
            self.free_head = rest;
            return Some(1);
        }
        let last = self.active_len - 1;
        let (fan, looked) = self.fan_start(h, last)?;
        let work = self.check_fan(fan, last)?;
        self.free_head = rest;
        self.rename_fan(fan, last, hole);
        self.active[hole as usize] = self.active[last as usize];
        self.active_len = last;
        Some(looked + 2 * work + 2)
    }

    /// One step of the records' Shell sort by node; `None` when it is done.
    fn sort_records_step(&mut self, h: &impl HierarchyRecords) -> Option<u32> {
        let n = self.active_len;
        let key = |f: &Self, k: u32| {
            let node = f.active.get(k as usize)?.node;
            (node & FREE == 0).then_some(node)
        };
        self.shell_step(n, key, |f, a, b| f.swap_records(h, a, b))
    }

    /// One step of the pairs' Shell sort by owner; `None` when it is done.
    fn sort_pairs_step(&mut self) -> Option<u32> {
        let n = self.pairs.min(self.owner.len() as u32);
        let key = |f: &Self, k: u32| f.owner.get(k as usize).map(|o| o.0);
        self.shell_step(n, key, |f, a, b| f.swap_pairs(a, b))
    }

    /// One comparison (and swap, if out of order) of a Shell sort of `n` elements with `key`
    /// (`None`: the element does not take part) and `swap` (its work, `None` if it could not
    /// swap); `None` when the sort is done.
    fn shell_step(
        &mut self,
        n: u32,
        key: impl Fn(&Self, u32) -> Option<u32>,
        swap: impl FnOnce(&mut Self, u32, u32) -> Option<u32>,
    ) -> Option<u32> {
        let p = self.compaction;
        let gap = *GAPS.get(p.gap as usize)?;
        if p.i >= n {
            let smaller = p.gap.checked_sub(1)?;
            let first = *GAPS.get(smaller as usize)?;
            self.compaction = Progress {
                gap: smaller,
                i: first,
                j: first,
                ..p
            };
            return Some(1);
        }
        if p.j >= gap && p.j < n {
            let (a, b) = (p.j - gap, p.j);
            if let (Some(ka), Some(kb)) = (key(self, a), key(self, b)) {
                if ka > kb {
                    if let Some(work) = swap(self, a, b) {
                        self.compaction.j = a;
                        return Some(work + 1);
                    }
                }
            }
        }
        self.compaction.i = p.i + 1;
        self.compaction.j = p.i + 1;
        Some(1)
    }

    /// Swaps records `a` and `b` (both live) and renames them in every corner; its work, or
    /// `None` (nothing changed) if a fan contradicts the front.
    fn swap_records(&mut self, h: &impl HierarchyRecords, a: u32, b: u32) -> Option<u32> {
        let ((fa, looked_a), (fb, looked_b)) = (self.fan_start(h, a)?, self.fan_start(h, b)?);
        let work = self.check_fan(fa, a)? + self.check_fan(fb, b)?;
        self.rename_fan(fa, a, PARKED);
        self.rename_fan(fb, b, a);
        self.rename_fan(fa, PARKED, b);
        self.active.swap(a as usize, b as usize);
        Some(looked_a + looked_b + 3 * work + 2)
    }

    /// Walks the fan of record `r` from `start`: its slots each name `r` once and the walk
    /// closes or ends at two borders; the number of slots, or `None`.
    fn check_fan(&self, start: FanStart, r: u32) -> Option<u32> {
        let FanStart::At(s0) = start else {
            return Some(0);
        };
        let mut count = 0u32;
        let ok = self.walk_fan(s0, r, |s, j| {
            let once = s.corners.iter().filter(|&&c| c == r).count() == 1;
            count += 1;
            once && s.corners[j] == r
        });
        ok.then_some(count)
    }

    /// Renames record `from` to `to` in the corners of the fan from `start` (checked).
    fn rename_fan(&mut self, start: FanStart, from: u32, to: u32) {
        let FanStart::At(s0) = start else {
            return;
        };
        // The walk reads links only, which a rename leaves alone, so the slots are listed by
        // a read-only walk and renamed after it, one at a time.
        let mut s = s0;
        let mut back = false;
        for _ in 0..=self.active_polygons.saturating_add(1) {
            let Some(slot) = self.slots.get_mut(s as usize) else {
                return;
            };
            let Some(j) = slot.corners.iter().position(|&c| c == from) else {
                return;
            };
            let link = if back {
                slot.neighbours[next(j)]
            } else {
                slot.neighbours[prev(j)]
            };
            slot.corners[j] = to;
            if let Some(pair) = s.checked_sub(self.base) {
                self.forget_refusal(pair / 2);
            }
            if link == s0 {
                return;
            }
            if link == NONE {
                if back {
                    return;
                }
                // A border: the rest of the fan lies the other way round from the start.
                back = true;
                let Some(first) = self.slots.get(s0 as usize) else {
                    return;
                };
                let Some(j0) = first.corners.iter().position(|&c| c == to) else {
                    return;
                };
                s = first.neighbours[next(j0)];
                if s == NONE {
                    return;
                }
                continue;
            }
            s = link;
        }
    }

    /// Swaps pairs `a` and `b` (both live): their slots, index-cache entries, owners, the
    /// map's entries, their refusal and coarsening bits, and the links into them.
    fn swap_pairs(&mut self, a: u32, b: u32) -> Option<u32> {
        let (la, lb) = (self.base + 2 * a, self.base + 2 * b);
        let moved = [la, la + 1, lb, lb + 1];
        let partner = |x: u32| match x {
            _ if x == la => lb,
            _ if x == la + 1 => lb + 1,
            _ if x == lb => la,
            _ if x == lb + 1 => la + 1,
            _ => x,
        };
        let last = self.base as usize + 2 * self.pairs as usize;
        if moved
            .iter()
            .any(|&s| s as usize >= last.min(self.slots.len()))
        {
            return None;
        }
        let outside = |m: u32| m != NONE && !moved.contains(&m);
        // Nothing is written unless every write below can be made.
        let links_live = moved.iter().all(|&x| {
            self.slots[x as usize]
                .neighbours
                .iter()
                .all(|&m| !outside(m) || (m as usize) < last.min(self.slots.len()))
        });
        let owned = [a, b].iter().all(|&k| {
            self.owner
                .get(k as usize)
                .is_some_and(|o| self.pair_of.get(o.index()) == Some(k))
        });
        if !links_live || !owned {
            return None;
        }
        // Links from outside into the four slots: parked first, each under its slot's own
        // mark, then pointed at the partner, so a slot next to two of them is patched once
        // per link.
        let mut work = 0;
        for (k, &x) in moved.iter().enumerate() {
            for m in self.slots[x as usize].neighbours {
                if outside(m) {
                    let links = &mut self.slots[m as usize].neighbours;
                    for l in links.iter_mut().filter(|l| **l == x) {
                        *l = PARKED - 1 - k as u32;
                    }
                    work += 1;
                }
            }
        }
        for (k, &x) in moved.iter().enumerate() {
            for m in self.slots[x as usize].neighbours {
                if outside(m) {
                    let links = &mut self.slots[m as usize].neighbours;
                    for l in links.iter_mut().filter(|l| **l == PARKED - 1 - k as u32) {
                        *l = partner(x);
                    }
                }
            }
        }
        for side in 0..2 {
            self.slots.swap((la + side) as usize, (lb + side) as usize);
            self.swap_cached(la + side, lb + side);
        }
        for &x in &moved {
            let s = &mut self.slots[x as usize];
            s.neighbours = s.neighbours.map(|l| if l == NONE { l } else { partner(l) });
        }
        self.owner.swap(a as usize, b as usize);
        let (oa, ob) = (self.owner[a as usize], self.owner[b as usize]);
        let _ = self.pair_of.set(oa.index(), a);
        let _ = self.pair_of.set(ob.index(), b);
        let (ra, rb) = (self.refusal_remembered(a), self.refusal_remembered(b));
        for (k, on) in [(a, rb), (b, ra)] {
            if on {
                self.remember_refusal(k);
            } else {
                self.forget_refusal(k);
            }
        }
        if !self.morphs.coarsening.is_empty() {
            let (ca, cb) = (self.morphs.is_coarsening(a), self.morphs.is_coarsening(b));
            self.morphs.set_coarsening(a, cb);
            self.morphs.set_coarsening(b, ca);
        }
        Some(work + 8)
    }
}

impl CameraState<'_> {
    /// At most about `budget` work towards [`compact`](Self::compact)'s order (a unit is a
    /// comparison, or a record, slot or link a move reads or writes), continuing the
    /// compaction cycle under way or starting one. Every call leaves a whole camera: the
    /// front and what it emits are those before the call, only the order of records and
    /// pairs changes, and refinement, operations and emission may run between calls. A cycle
    /// the front holds still during ends in [`compact`](Self::compact)'s order; one it
    /// changes under ends less sorted, and the next sorts further. A cycle over `n` records
    /// and pairs costs about `n` comparisons per gap (a dozen gaps for 50,000), plus the
    /// moves, which are few when the order is close to sorted and dominate after heavy
    /// churn: a front half replaced since the last cycle costs tens of times
    /// [`compact`](Self::compact)'s work in all, spread over the steps. Never called by
    /// [`refine`](Self::refine); [`churn`](Self::churn) counts from a cycle's start.
    pub fn compact_step(&mut self, h: &impl HierarchyRecords, budget: u32) -> CompactProgress {
        if !self.is_for(h) {
            return CompactProgress::default();
        }
        self.front.compact_step(h, budget)
    }

    /// `true` while a compaction cycle of [`compact_step`](Self::compact_step) is under way.
    pub fn compacting(&self) -> bool {
        self.front.compaction.phase != IDLE
    }

    /// A frame loop's compaction, called once a frame: a step of
    /// [`compact_budget(most)`](Self::compact_budget) work while a cycle is under way, or the
    /// first step of a new one once the splits and collapses since the last began
    /// ([`churn`](Self::churn)) reach a quarter of the active nodes; else nothing. Bounded
    /// per frame, unlike [`compact`](Self::compact), whose spike grows with the front.
    pub fn compact_as_needed(&mut self, h: &impl HierarchyRecords, most: u32) -> CompactProgress {
        if self.compacting() || self.churn() >= (self.active_node_count() / 4).max(1) {
            let budget = self.compact_budget(most);
            return self.compact_step(h, budget);
        }
        CompactProgress::default()
    }

    /// One frame's step of incremental compaction for this camera's front: an eighth of
    /// its active nodes' worth of work, at least 256 and at most `most` ([`COMPACT_STEP`]
    /// suits most). A step sized by the front keeps its cost a small share of a pass over
    /// that front, small fronts included, while a cycle still ends in a few dozen frames.
    pub fn compact_budget(&self, most: u32) -> u32 {
        (self.active_node_count() / 8).max(256).min(most)
    }
}

/// The most work of one frame's incremental compaction
/// ([`CameraState::compact_budget`]): 5,000 comparisons and moves, the step of a front of
/// 40,000 nodes (80,000 polygons), small beside a refinement pass over it.
pub const COMPACT_STEP: u32 = 5000;
