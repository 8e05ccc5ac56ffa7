//! Edge collapse: undoing one split on the front (the walk that moves corners back to the
//! stationary record, the pair's removal and the hole it leaves filled by the last pair).

use super::OpError;
use crate::camera::index_cache::Known;
use crate::camera::records::{next, prev};
use crate::camera::records::{ActiveVertex, FREE, NONE, UNKNOWN};
use crate::camera::state::Front;
use crate::hierarchy::HierarchyRecords;
use crate::ids::{NodeId, PositionId};

impl Front<'_> {
    /// Applies the collapse into `v` given its neighbours' slots from
    /// [`collapse_slots`](Self::collapse_slots).
    pub fn apply_collapse(
        &mut self,
        h: &impl HierarchyRecords,
        v: NodeId,
        slots: [u32; 4],
    ) -> Result<(), OpError> {
        let bad = OpError::Inconsistent { node: v };
        let s = h.split(v).ok_or(OpError::Leaf { node: v })?;
        let k = self.pair_of.get(v.index()).ok_or(bad)?;
        if k == NONE || k >= self.pairs {
            return Err(OpError::NotSplit { node: v });
        }
        let fl = self.base + 2 * k;
        let fr = fl + 1;
        let [ccw, clw, rclw, rccw] = slots;
        self.prefetch_cached(clw);
        self.prefetch_cached(fl);
        let fla = *self.slot(fl, v)?;
        let (rv, ru) = (fla.corners[0], fla.corners[1]);
        if ccw != NONE {
            self.relink(ccw, fl, clw, v)?;
        }
        if rclw != NONE {
            self.relink(rclw, fr, rccw, v)?;
        }
        // Where v's record will stand, for the index cache (see `index_cache`), and its
        // indices in the groups of f_l and f_r (their corner 0, vs, stands there).
        let at_v = if self.caches_indices() {
            Self::position_of(h, v)
        } else {
            PositionId(NONE)
        };
        let mut known = Known::default();
        known.learn_from(self.triangles.get(fl as usize), 0);
        known.learn_from(self.triangles.get(fr as usize), 0);
        let mut fa = clw;
        let mut j = self.corner(fa, ru, v)?;
        let first = self.slot_mut(fa, v)?;
        first.neighbours[next(j)] = ccw;
        first.corners[j] = rv;
        self.cache_corner(h, fa, j, at_v, &mut known);
        let mut steps = 0u32;
        loop {
            if fa == rccw {
                self.slot_mut(fa, v)?.neighbours[prev(j)] = rclw;
                break;
            }
            let nx = self.slot(fa, v)?.neighbours[prev(j)];
            if nx == NONE {
                break;
            }
            self.prefetch_cached(nx);
            fa = nx;
            j = self.corner(fa, ru, v)?;
            self.slot_mut(fa, v)?.corners[j] = rv;
            self.cache_corner(h, fa, j, at_v, &mut known);
            steps += 1;
            if steps > self.active_polygons {
                return Err(bad);
            }
        }
        // The walk must end at fr_ccw, as the split's did: a border before it means the
        // connectivity contradicts the hierarchy, and corners would be left on the record
        // the collapse frees.
        if rccw != NONE && fa != rccw {
            return Err(bad);
        }
        *self.active.get_mut(rv as usize).ok_or(bad)? = ActiveVertex::of(h, v);
        self.free_record(ru);
        // The floating child's vertices are gone from the front: so is their morph.
        if self.morphs.scalars.live > 0 {
            self.end_morph_of(h, s.floating);
        }
        self.pair_of.set(v.index(), NONE).ok_or(bad)?;
        h.node_left_front(s.stationary);
        h.node_left_front(s.floating);
        h.node_entered_front(v);
        // v is active again: its parent's collapse may have become legal.
        if let Some(pp) = h.node(v).and_then(|n| self.pair_of.get(n.parent.index())) {
            self.forget_refusal(pp);
        }
        self.active_nodes = self.active_nodes.saturating_sub(1);
        self.churn = self.churn.saturating_add(1);
        for f in [s.f_l, s.f_r] {
            if let Some(p) = h.polygon(f) {
                self.active_polygons = self.active_polygons.saturating_sub(1);
                if let Some(c) = self.surface_polygons.get_mut(p.surface.index()) {
                    *c = c.saturating_sub(1);
                }
            }
        }
        self.uncache([fl, fr]);
        self.remove_pair(k, v)
    }

    /// Fills the hole of pair `k` with the last pair and patches the links to it.
    fn remove_pair(&mut self, k: u32, v: NodeId) -> Result<(), OpError> {
        let last = self.pairs - 1;
        self.pairs = last;
        self.forget_refusal(last);
        if !self.morphs.coarsening.is_empty() {
            // The last pair's coarsening bit moves with it.
            let moved = self.morphs.is_coarsening(last);
            self.morphs.set_coarsening(last, false);
            self.morphs.set_coarsening(k, moved && k != last);
        }
        if k == last {
            return Ok(());
        }
        let (old_l, new_l) = (self.base + 2 * last, self.base + 2 * k);
        let (old_r, new_r) = (old_l + 1, new_l + 1);
        let map = |x: u32| {
            if x == old_l {
                new_l
            } else if x == old_r {
                new_r
            } else {
                x
            }
        };
        // Move the pair and its ownership first, so the camera's bookkeeping (which pair
        // belongs to which split, and the counts) stays exact even if a link below turns out
        // to contradict the hierarchy.
        for (old, new) in [(old_l, new_l), (old_r, new_r)] {
            let mut moved = *self.slot(old, v)?;
            moved.neighbours = moved.neighbours.map(map);
            *self.slot_mut(new, v)? = moved;
            self.move_cached(old, new);
        }
        let owner = self.owner[last as usize];
        self.owner[k as usize] = owner;
        self.pair_of
            .set(owner.index(), k)
            .ok_or(OpError::Inconsistent { node: v })?;
        for (old, new) in [(old_l, new_l), (old_r, new_r)] {
            let nbrs = self.slot(new, v)?.neighbours;
            for m in nbrs {
                if m != NONE && m != new_l && m != new_r {
                    self.relink(m, old, new, v)?;
                }
            }
        }
        Ok(())
    }

    fn free_record(&mut self, r: u32) {
        // FREE | (FREE - 1) marks the end of the free list.
        let link = if self.free_head == NONE {
            FREE - 1
        } else {
            self.free_head
        };
        if let Some(a) = self.active.get_mut(r as usize) {
            *a = ActiveVertex {
                node: FREE | link,
                coarsen: NONE,
                own_cert: UNKNOWN,
                parent_cert: UNKNOWN,
            };
            self.free_head = r;
        }
    }
}
