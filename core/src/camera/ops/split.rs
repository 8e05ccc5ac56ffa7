//! Vertex split: applying one legal split to the front (the walk that moves corners to the
//! floating child, the new pair, the index cache's entries) and Hoppe's forced split, which
//! applies the splits that make a wanted one legal.

use super::OpError;
use crate::camera::index_cache::Known;
use crate::camera::records::{next, prev, ActiveVertex, PolySlot, SlotTriangle, FREE, NONE};
use crate::camera::state::Front;
use crate::format::Split;
use crate::hierarchy::HierarchyRecords;
use crate::ids::{NodeId, PositionId};

/// The new pair's two slots and the records of the split's children: what the walk
/// around `vs` and the pair's links need.
#[derive(Clone, Copy)]
struct NewPair {
    /// Slots of `f_l` and `f_r`.
    fl: u32,
    fr: u32,
    /// The record of `vs`, which the stationary child takes, and the floating child's.
    rv: u32,
    ru: u32,
}

/// What the walk from `fl_clw` round `vs` found: where it ended, the pair's outer corners,
/// and the cache entries of its first and last polygons before their corners moved.
struct Walked {
    /// The last slot walked and the corner of `vs` there.
    fa: u32,
    j: usize,
    /// `f_l`'s third corner (from `fl_clw`) and `f_r`'s (from `fr_ccw`; `NONE` without one).
    vl: u32,
    vr: u32,
    first_before: Option<SlotTriangle>,
    last_before: Option<SlotTriangle>,
}

impl Front<'_> {
    /// Applies the split of `v` given its neighbours' slots from
    /// [`split_slots`](Self::split_slots): the floating child takes a new record, the
    /// corners round `vs` from `fl_clw` to `fr_ccw` move to it, and the new pair is linked
    /// in, cached and counted.
    pub fn apply_split(
        &mut self,
        h: &impl HierarchyRecords,
        v: NodeId,
        slots: [u32; 4],
    ) -> Result<(), OpError> {
        let bad = OpError::Inconsistent { node: v };
        let s = h.split(v).ok_or(OpError::Leaf { node: v })?;
        if self.pairs as usize >= self.owner.len() {
            return Err(OpError::CapacityFull {
                max_pairs: self.owner.len() as u32,
            });
        }
        let [_, clw, _, rccw] = slots;
        let at = self.split_positions(h, s, clw, rccw);
        // The active-vertex record of v: a corner of fl_clw.
        let clw_slot = *self.slot(clw, v)?;
        let j0 = (0..3)
            .find(|&k| self.node_of(clw_slot.corners[k]) == Some(v))
            .ok_or(bad)?;
        let rv = clw_slot.corners[j0];
        let ru = self.alloc_record(h, s.floating).ok_or(bad)?;
        *self.active.get_mut(rv as usize).ok_or(bad)? = ActiveVertex::of(h, s.stationary);
        let fl = self.base + 2 * self.pairs;
        let pair = NewPair {
            fl,
            fr: fl + 1,
            rv,
            ru,
        };
        let walked = self.move_corners(h, v, slots, &pair, j0, at[1])?;
        if s.f_r.is_some() && walked.vr == NONE {
            return Err(bad);
        }
        self.link_pair(v, s, slots, &pair, &walked)?;
        if self.caches_indices() {
            self.cache_pair(h, s, slots, &pair, &walked, j0, at);
        }
        h.node_left_front(v);
        h.node_entered_front(s.stationary);
        h.node_entered_front(s.floating);
        self.count_split(h, v, s)
    }

    /// The positions of the split's stationary and floating children, for the index cache
    /// (see `index_cache`); the entries the walk starts and ends at, and the floating
    /// child's vertex-table row, are asked for now so their misses overlap the walk's.
    #[inline]
    fn split_positions(
        &self,
        h: &impl HierarchyRecords,
        s: &Split,
        clw: u32,
        rccw: u32,
    ) -> [PositionId; 2] {
        let at = if self.caches_indices() {
            [
                Self::position_of(h, s.stationary),
                Self::position_of(h, s.floating),
            ]
        } else {
            [PositionId(NONE); 2]
        };
        self.prefetch_cached(clw);
        self.prefetch_cached(rccw);
        if self.caches_indices() {
            Self::prefetch_row(h, at[1]);
        }
        at
    }

    /// Walks from `fl_clw` (corner `j0` holds `vs`) around `vs` to `fr_ccw`, moving corners
    /// to the floating child at `at_floating` and linking the first and last polygons to
    /// the new pair (keeping their cache entries as they were, for the new pair's).
    #[inline]
    fn move_corners(
        &mut self,
        h: &impl HierarchyRecords,
        v: NodeId,
        [_, clw, _, rccw]: [u32; 4],
        pair: &NewPair,
        j0: usize,
        at_floating: PositionId,
    ) -> Result<Walked, OpError> {
        let bad = OpError::Inconsistent { node: v };
        let (mut fa, mut j) = (clw, j0);
        let first = self.slot_mut(fa, v)?;
        first.neighbours[next(j)] = pair.fl;
        let vl = first.corners[prev(j)];
        first.corners[j] = pair.ru;
        let mut known = Known::default();
        let first_before = self.cache_corner(h, fa, j, at_floating, &mut known);
        let mut last_before = first_before;
        let mut vr = NONE;
        let mut steps = 0u32;
        loop {
            if fa == rccw {
                let last = self.slot_mut(fa, v)?;
                last.neighbours[prev(j)] = pair.fr;
                vr = last.corners[next(j)];
                break;
            }
            let nx = self.slot(fa, v)?.neighbours[prev(j)];
            if nx == NONE {
                break;
            }
            self.prefetch_cached(nx);
            fa = nx;
            j = self.corner(fa, pair.rv, v)?;
            self.slot_mut(fa, v)?.corners[j] = pair.ru;
            last_before = self.cache_corner(h, fa, j, at_floating, &mut known);
            steps += 1;
            if steps > self.active_polygons {
                return Err(bad);
            }
        }
        Ok(Walked {
            fa,
            j,
            vl,
            vr,
            first_before,
            last_before,
        })
    }

    /// Links the new pair in: its outer neighbours point at it, and its slots hold
    /// `f_l = (vs, vt, vl)` and `f_r = (vs, vr, vt)` (an empty slot without `f_r`).
    #[inline]
    fn link_pair(
        &mut self,
        v: NodeId,
        s: &Split,
        [ccw, clw, rclw, rccw]: [u32; 4],
        pair: &NewPair,
        walked: &Walked,
    ) -> Result<(), OpError> {
        let NewPair { fl, fr, rv, ru } = *pair;
        if ccw != NONE {
            self.relink(ccw, clw, fl, v)?;
        }
        if rclw != NONE {
            self.relink(rclw, rccw, fr, v)?;
        }
        let r_link = if s.f_r.is_some() { fr } else { NONE };
        *self.slot_mut(fl, v)? = PolySlot {
            corners: [rv, ru, walked.vl],
            neighbours: [clw, ccw, r_link],
        };
        *self.slot_mut(fr, v)? = if s.f_r.is_some() {
            PolySlot {
                corners: [rv, walked.vr, ru],
                neighbours: [rccw, fl, rclw],
            }
        } else {
            PolySlot {
                corners: [NONE; 3],
                neighbours: [NONE; 3],
            }
        };
        Ok(())
    }

    /// The new pair's cache entries, from those of the first and last polygons the walk
    /// moved where the surface groups agree, through the vertex table where they do not.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn cache_pair(
        &mut self,
        h: &impl HierarchyRecords,
        s: &Split,
        [_, clw, _, rccw]: [u32; 4],
        pair: &NewPair,
        walked: &Walked,
        j0: usize,
        [at_stationary, at_floating]: [PositionId; 2],
    ) {
        let (vl, vr, j) = (walked.vl, walked.vr, walked.j);
        // f_l = (vs, vt, vl): fl_clw's corner j0 before and after it moved, and its vl.
        let known = walked
            .first_before
            .zip(self.triangles.get(clw as usize))
            .map(|(b, a)| (b.group, [b.indices[j0], a.indices[j0], b.indices[prev(j0)]]));
        let entry = self.new_entry(h, h.polygon(s.f_l), known, |f| {
            [at_stationary, at_floating, f.record_position(h, vl)]
        });
        self.set_cached(pair.fl, entry);
        // f_r = (vs, vr, vt): likewise from fr_ccw, where the walk ended (corner j).
        let known = walked
            .last_before
            .filter(|_| walked.fa == rccw)
            .zip(self.triangles.get(walked.fa as usize))
            .map(|(b, a)| (b.group, [b.indices[j], b.indices[next(j)], a.indices[j]]));
        let fr_poly = s.f_r.get().and_then(|f| h.polygon(f));
        let entry = self.new_entry(h, fr_poly, known, |f| {
            [at_stationary, f.record_position(h, vr), at_floating]
        });
        self.set_cached(pair.fr, entry);
    }

    /// Records the split of `v` as pair `pairs` and counts its node and polygons.
    #[inline]
    fn count_split(
        &mut self,
        h: &impl HierarchyRecords,
        v: NodeId,
        s: &Split,
    ) -> Result<(), OpError> {
        let k = self.pairs;
        self.owner[k as usize] = v;
        self.pair_of
            .set(v.index(), k)
            .ok_or(OpError::Inconsistent { node: v })?;
        self.pairs += 1;
        self.active_nodes += 1;
        self.churn = self.churn.saturating_add(1);
        for f in [s.f_l, s.f_r] {
            if let Some(p) = h.polygon(f) {
                self.active_polygons += 1;
                if let Some(c) = self.surface_polygons.get_mut(p.surface.index()) {
                    *c += 1;
                }
            }
        }
        Ok(())
    }

    fn alloc_record(&mut self, h: &impl HierarchyRecords, node: NodeId) -> Option<u32> {
        // A free record at or past the high-water mark was dropped by an incremental
        // compaction (see `compact_step`): it is taken off the list and not used.
        let mut reused = NONE;
        while self.free_head != NONE {
            let r = self.free_head;
            let link = self.active.get(r as usize)?.node & !FREE;
            self.free_head = if link == FREE - 1 { NONE } else { link };
            if r < self.active_len {
                reused = r;
                break;
            }
        }
        let r = if reused != NONE {
            reused
        } else {
            let r = self.active_len;
            if r as usize >= self.active.len() {
                return None;
            }
            self.active_len += 1;
            r
        };
        self.active[r as usize] = ActiveVertex::of(h, node);
        Some(r)
    }

    /// Hoppe's `force_vsplit`, iteratively with the caller's stack, applying at most `budget`
    /// splits. Returns the number applied (if `v` is split, the last one was `v`'s).
    pub fn force_split(
        &mut self,
        h: &impl HierarchyRecords,
        v: NodeId,
        stack: &mut [NodeId],
        budget: u32,
    ) -> Result<u32, OpError> {
        let mut applied = 0;
        self.force_split_counted(h, v, stack, budget, &mut applied, |_, _| {})
            .map(|()| applied)
    }

    /// [`force_split`](Self::force_split) that counts the splits it applies in `applied`,
    /// also when it stops with an error (the splits applied before the error stay), and
    /// calls `after_split` with each node it split (refinement starts morphs there).
    pub fn force_split_counted(
        &mut self,
        h: &impl HierarchyRecords,
        v: NodeId,
        stack: &mut [NodeId],
        budget: u32,
        applied: &mut u32,
        mut after_split: impl FnMut(&mut Self, NodeId),
    ) -> Result<(), OpError> {
        if h.split(v).is_none() {
            return Err(OpError::Leaf { node: v });
        }
        let len = stack.len() as u32;
        let full = OpError::StackFull { len };
        let mut top = 0usize;
        *stack.first_mut().ok_or(full)? = v;
        top += 1;
        let start = *applied;
        while top > 0 {
            let u = stack[top - 1];
            if self.is_split(u) {
                top -= 1;
                continue;
            }
            // Every node on the stack is split before `v` is: one whose records (or its
            // children's) are absent defers the chain here, before it reads them.
            if let Err(a) = h.split_ready(u) {
                return Err(OpError::Absent {
                    node: a.node,
                    page: a.page,
                });
            }
            if !self.is_created(h, u) {
                let p = h
                    .node(u)
                    .map(|n| n.parent)
                    .ok_or(OpError::Inconsistent { node: v })?;
                *stack.get_mut(top).ok_or(full)? = p;
                top += 1;
                continue;
            }
            let s = h.split(u).ok_or(OpError::Inconsistent { node: v })?;
            let mut pushed = false;
            let mut slots = [NONE; 4];
            for (k, &f) in s.neighbours.iter().enumerate() {
                if f.is_none() {
                    continue;
                }
                match self.slot_of_key(f) {
                    Some(slot) => slots[k] = slot,
                    None => {
                        // Inactive: its creator is not split yet (a base polygon is
                        // always active).
                        let (creator, _) = f
                            .creator(self.base)
                            .ok_or(OpError::Inconsistent { node: v })?;
                        *stack.get_mut(top).ok_or(full)? = creator;
                        top += 1;
                        pushed = true;
                    }
                }
            }
            if !pushed {
                if *applied - start == budget {
                    return Ok(());
                }
                top -= 1;
                self.apply_split(h, u, slots)?;
                *applied += 1;
                after_split(self, u);
            }
        }
        Ok(())
    }
}
