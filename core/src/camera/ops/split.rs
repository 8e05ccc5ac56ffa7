//! Vertex split: applying one legal split to the front (the walk that moves corners to the
//! floating child, the new pair, the index cache's entries) and Hoppe's forced split, which
//! applies the splits that make a wanted one legal.

use super::{next, prev};
use crate::camera::index_cache::Known;
use crate::camera::OpError;
use crate::camera::{ActiveVertex, Front, PolySlot, FREE, NONE};
use crate::hierarchy::Hierarchy;
use crate::ids::{NodeId, PositionId};

impl Front<'_> {
    /// Applies the split of `v` given its neighbours' slots from
    /// [`split_slots`](Self::split_slots).
    pub fn apply_split(
        &mut self,
        h: &Hierarchy<'_>,
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
        let [ccw, clw, rclw, rccw] = slots;
        // Where the children's records stand, for the index cache (see `index_cache`); the
        // entries the walk starts and ends at, and the floating child's vertex-table row,
        // are asked for now so their misses overlap the walk's.
        let (at_stationary, at_floating) = if self.caches_indices() {
            (
                Self::position_of(h, s.stationary),
                Self::position_of(h, s.floating),
            )
        } else {
            (PositionId(NONE), PositionId(NONE))
        };
        self.prefetch_cached(clw);
        self.prefetch_cached(rccw);
        if self.caches_indices() {
            Self::prefetch_row(h, at_floating);
        }
        // The active-vertex record of v: a corner of fl_clw.
        let clw_slot = *self.slot(clw, v)?;
        let j0 = (0..3)
            .find(|&k| self.node_of(clw_slot.corners[k]) == Some(v))
            .ok_or(bad)?;
        let rv = clw_slot.corners[j0];
        let ru = self.alloc_record(h, s.floating).ok_or(bad)?;
        *self.active.get_mut(rv as usize).ok_or(bad)? = ActiveVertex::of(h, s.stationary);
        let k = self.pairs;
        let fl = self.base + 2 * k;
        let fr = fl + 1;
        // Walk from fl_clw around v to fr_ccw, moving corners to the floating child (and
        // keeping the entries of its first and last polygons as they were, for the new pair).
        let mut fa = clw;
        let mut j = j0;
        let first = self.slot_mut(fa, v)?;
        first.neighbours[next(j)] = fl;
        let vl = first.corners[prev(j)];
        first.corners[j] = ru;
        let mut known = Known::default();
        let first_before = self.cache_corner(h, fa, j, at_floating, &mut known);
        let mut last_before = first_before;
        let mut vr = NONE;
        let mut steps = 0u32;
        loop {
            if fa == rccw {
                let last = self.slot_mut(fa, v)?;
                last.neighbours[prev(j)] = fr;
                vr = last.corners[next(j)];
                break;
            }
            let nx = self.slot(fa, v)?.neighbours[prev(j)];
            if nx == NONE {
                break;
            }
            self.prefetch_cached(nx);
            fa = nx;
            j = self.corner(fa, rv, v)?;
            self.slot_mut(fa, v)?.corners[j] = ru;
            last_before = self.cache_corner(h, fa, j, at_floating, &mut known);
            steps += 1;
            if steps > self.active_polygons {
                return Err(bad);
            }
        }
        if s.f_r.is_some() && vr == NONE {
            return Err(bad);
        }
        if ccw != NONE {
            self.relink(ccw, clw, fl, v)?;
        }
        if rclw != NONE {
            self.relink(rclw, rccw, fr, v)?;
        }
        let r_link = if s.f_r.is_some() { fr } else { NONE };
        *self.slot_mut(fl, v)? = PolySlot {
            corners: [rv, ru, vl],
            neighbours: [clw, ccw, r_link],
        };
        *self.slot_mut(fr, v)? = if s.f_r.is_some() {
            PolySlot {
                corners: [rv, vr, ru],
                neighbours: [rccw, fl, rclw],
            }
        } else {
            PolySlot {
                corners: [NONE; 3],
                neighbours: [NONE; 3],
            }
        };
        if self.caches_indices() {
            // f_l = (vs, vt, vl): fl_clw's corner j0 before and after it moved, and its vl.
            let polys = h.polygons();
            let known = first_before
                .zip(self.triangles.get(clw as usize))
                .map(|(b, a)| (b.group, [b.indices[j0], a.indices[j0], b.indices[prev(j0)]]));
            let entry = self.new_entry(h, polys.get(s.f_l.index()), known, |f| {
                [at_stationary, at_floating, f.record_position(h, vl)]
            });
            self.set_cached(fl, entry);
            // f_r = (vs, vr, vt): likewise from fr_ccw, where the walk ended (corner j).
            let known = last_before
                .filter(|_| fa == rccw)
                .zip(self.triangles.get(fa as usize))
                .map(|(b, a)| (b.group, [b.indices[j], b.indices[next(j)], a.indices[j]]));
            let fr_poly = s.f_r.get().and_then(|f| polys.get(f.index()));
            let entry = self.new_entry(h, fr_poly, known, |f| {
                [at_stationary, f.record_position(h, vr), at_floating]
            });
            self.set_cached(fr, entry);
        }
        self.owner[k as usize] = v;
        self.pair_of.set(v.index(), k).ok_or(bad)?;
        self.pairs += 1;
        self.active_nodes += 1;
        self.churn = self.churn.saturating_add(1);
        for f in [s.f_l, s.f_r] {
            if let Some(p) = h.polygons().get(f.index()) {
                self.active_polygons += 1;
                if let Some(c) = self.surface_polygons.get_mut(p.surface.index()) {
                    *c += 1;
                }
            }
        }
        Ok(())
    }

    fn alloc_record(&mut self, h: &Hierarchy<'_>, node: NodeId) -> Option<u32> {
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
        h: &Hierarchy<'_>,
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
        h: &Hierarchy<'_>,
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
