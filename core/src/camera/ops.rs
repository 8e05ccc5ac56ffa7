//! Vertex split and edge collapse on one camera's front, with Hoppe's preconditions, and the
//! iterative forced split.
//!
//! The rules (SIGGRAPH 97; `libHh/SrMesh.cpp`): a split of active `vs` is legal iff every
//! present neighbour `fn0..fn3` is active; a collapse back into `vs` is legal iff both children
//! are active and `f_l`, `f_r` still have exactly the neighbours the split gave them. Applying
//! a split hands `vs`'s active-vertex record to the stationary child, walks from `fl_clw`
//! around it to `fr_ccw` moving those corners to the floating child, and links `f_l`, `f_r`
//! in; a collapse undoes exactly that. Every walk is bounded, and every slot read is checked,
//! so a hierarchy that passed validation but has contradictory connectivity produces
//! [`OpError::Inconsistent`], never a panic or an endless loop.

use super::index_cache::Known;
use super::{ActiveVertex, CameraState, Front, PolySlot, FREE, NONE};
use crate::hierarchy::Hierarchy;
use crate::ids::{NodeId, PolyKey, PositionId};

/// Why an operation was not applied.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OpError {
    /// The camera was made for another hierarchy.
    WrongHierarchy,
    /// The node is not on the camera's active front (or is out of range).
    NotActive {
        /// The node.
        node: NodeId,
    },
    /// The node is a leaf: it has no split.
    Leaf {
        /// The node.
        node: NodeId,
    },
    /// Collapse of a node whose split is not applied.
    NotSplit {
        /// The node.
        node: NodeId,
    },
    /// Hoppe's preconditions do not hold (use a forced split, or wait for the collapse).
    Illegal {
        /// The node.
        node: NodeId,
    },
    /// The camera holds `max_pairs` splits already.
    CapacityFull {
        /// Its capacity.
        max_pairs: u32,
    },
    /// The forced-split stack is full.
    StackFull {
        /// Its length.
        len: u32,
    },
    /// The hierarchy's connectivity contradicts the camera's state: the data is corrupt in a
    /// way validation cannot see. The camera should be [`reset`](CameraState::reset).
    Inconsistent {
        /// The node being split or collapsed.
        node: NodeId,
    },
}

impl core::fmt::Display for OpError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::WrongHierarchy => write!(f, "camera state belongs to another hierarchy"),
            Self::NotActive { node } => write!(f, "node {} is not active", node.0),
            Self::Leaf { node } => write!(f, "node {} is a leaf and cannot be split", node.0),
            Self::NotSplit { node } => write!(f, "node {} is not split", node.0),
            Self::Illegal { node } => write!(f, "preconditions for node {} do not hold", node.0),
            Self::CapacityFull { max_pairs } => {
                write!(f, "camera full: {max_pairs} splits applied")
            }
            Self::StackFull { len } => write!(f, "forced-split stack of {len} entries is full"),
            Self::Inconsistent { node } => {
                write!(
                    f,
                    "hierarchy connectivity contradicts the camera at node {} (corrupt data)",
                    node.0
                )
            }
        }
    }
}

impl core::error::Error for OpError {}

#[inline]
fn next(j: usize) -> usize {
    if j == 2 {
        0
    } else {
        j + 1
    }
}

#[inline]
fn prev(j: usize) -> usize {
    if j == 0 {
        2
    } else {
        j - 1
    }
}

impl Front<'_> {
    /// Slot of a neighbour that must be active, or `NONE` for an absent one; `None` if a
    /// present neighbour is inactive.
    #[inline]
    fn want(&self, f: PolyKey) -> Option<u32> {
        if f.is_none() {
            Some(NONE)
        } else {
            self.slot_of_key(f)
        }
    }

    #[inline]
    fn slot(&self, slot: u32, node: NodeId) -> Result<&PolySlot, OpError> {
        self.slots
            .get(slot as usize)
            .ok_or(OpError::Inconsistent { node })
    }

    /// The slot for writing. Every write to a pair's slot can change whether the pair's
    /// collapse is legal, so it forgets a refusal remembered for that pair.
    #[inline]
    fn slot_mut(&mut self, slot: u32, node: NodeId) -> Result<&mut PolySlot, OpError> {
        if let Some(pair) = slot.checked_sub(self.base) {
            self.forget_refusal(pair / 2);
        }
        self.slots
            .get_mut(slot as usize)
            .ok_or(OpError::Inconsistent { node })
    }

    /// Corner index of active-vertex record `record` in `slot`.
    #[inline]
    fn corner(&self, slot: u32, record: u32, node: NodeId) -> Result<usize, OpError> {
        let s = self.slot(slot, node)?;
        s.corners
            .iter()
            .position(|&c| c == record)
            .ok_or(OpError::Inconsistent { node })
    }

    /// Replaces the link of `slot` that points to `from` with `to`.
    #[inline]
    fn relink(&mut self, slot: u32, from: u32, to: u32, node: NodeId) -> Result<(), OpError> {
        let s = self.slot_mut(slot, node)?;
        let j = s
            .neighbours
            .iter()
            .position(|&n| n == from)
            .ok_or(OpError::Inconsistent { node })?;
        s.neighbours[j] = to;
        Ok(())
    }

    /// The slots of `v`'s present neighbours (`NONE` for absent ones) if its split is legal.
    #[inline]
    pub fn split_slots(&self, h: &Hierarchy<'_>, v: NodeId) -> Option<[u32; 4]> {
        let s = h.split(v)?;
        if !self.is_node_active(h, v) {
            return None;
        }
        let n = &s.neighbours;
        Some([
            self.want(n[0])?,
            self.want(n[1])?,
            self.want(n[2])?,
            self.want(n[3])?,
        ])
    }

    pub fn can_split(&self, h: &Hierarchy<'_>, v: NodeId) -> bool {
        self.split_slots(h, v).is_some()
    }

    /// The slots of `v`'s neighbours (`NONE` for absent ones) if the collapse into `v` is
    /// legal: both children active and `f_l`, `f_r` linked exactly as the split left them.
    #[inline]
    pub fn collapse_slots(&self, h: &Hierarchy<'_>, v: NodeId) -> Option<[u32; 4]> {
        let s = h.split(v)?;
        let pair = self.pair_of.get(v.index())?;
        if pair == NONE || self.is_split(s.stationary) || self.is_split(s.floating) {
            return None;
        }
        let fl = self.base + 2 * pair;
        let fla = self.slots.get(fl as usize)?;
        let fra = self.slots.get(fl as usize + 1)?;
        let n = &s.neighbours;
        // Refinement asks this of every stationary child whose parent could collapse, and
        // most are refused because a neighbour is finer than the split left it: each link is
        // compared as soon as its neighbour's slot is known, so a refusal stops early.
        let mut slots = [NONE; 4];
        slots[0] = self.want(n[0])?;
        if fla.neighbours[1] != slots[0] {
            return None;
        }
        slots[1] = self.want(n[1])?;
        if fla.neighbours[0] != slots[1] {
            return None;
        }
        slots[2] = self.want(n[2])?;
        if s.f_r.is_some() && fra.neighbours[2] != slots[2] {
            return None;
        }
        slots[3] = self.want(n[3])?;
        if s.f_r.is_some() && fra.neighbours[0] != slots[3] {
            return None;
        }
        Some(slots)
    }

    pub fn can_collapse(&self, h: &Hierarchy<'_>, v: NodeId) -> bool {
        self.collapse_slots(h, v).is_some()
    }

    /// Whether pair `pair`'s collapse was refused and nothing it depends on changed since.
    #[inline]
    pub fn refusal_remembered(&self, pair: u32) -> bool {
        self.refused
            .get(pair as usize / 32)
            .is_some_and(|w| w & (1 << (pair % 32)) != 0)
    }

    /// Remembers that pair `pair`'s collapse is refused.
    #[inline]
    pub fn remember_refusal(&mut self, pair: u32) {
        if let Some(w) = self.refused.get_mut(pair as usize / 32) {
            *w |= 1 << (pair % 32);
        }
    }

    /// Forgets a refusal remembered for pair `pair`.
    #[inline]
    pub fn forget_refusal(&mut self, pair: u32) {
        if let Some(w) = self.refused.get_mut(pair as usize / 32) {
            *w &= !(1 << (pair % 32));
        }
    }

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

    /// Applies the collapse into `v` given its neighbours' slots from
    /// [`collapse_slots`](Self::collapse_slots).
    pub fn apply_collapse(
        &mut self,
        h: &Hierarchy<'_>,
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
        // v is active again: its parent's collapse may have become legal.
        if let Some(pp) = h.node(v).and_then(|n| self.pair_of.get(n.parent.index())) {
            self.forget_refusal(pp);
        }
        self.active_nodes = self.active_nodes.saturating_sub(1);
        self.churn = self.churn.saturating_add(1);
        for f in [s.f_l, s.f_r] {
            if let Some(p) = h.polygons().get(f.index()) {
                self.active_polygons = self.active_polygons.saturating_sub(1);
                if let Some(c) = self.surface_polygons.get_mut(p.surface.index()) {
                    *c = c.saturating_sub(1);
                }
            }
        }
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
                own_cert: super::UNKNOWN,
                parent_cert: super::UNKNOWN,
            };
            self.free_head = r;
        }
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

impl CameraState<'_> {
    fn check(&self, h: &Hierarchy<'_>) -> Result<(), OpError> {
        if self.is_for(h) {
            Ok(())
        } else {
            Err(OpError::WrongHierarchy)
        }
    }

    /// `true` if `node` is active, can be split, and every present `fn0..fn3` is active.
    pub fn can_split(&self, h: &Hierarchy<'_>, node: NodeId) -> bool {
        self.is_for(h) && self.front.can_split(h, node)
    }

    /// Forgets every collapse refusal that refinement remembers, so the next
    /// [`refine`](Self::refine) checks every wanted collapse again. Refinement never needs
    /// this (a refusal is forgotten as soon as anything it depends on changes); it exists so
    /// tests can compare refinement with and without the memory.
    #[doc(hidden)]
    pub fn forget_refused_collapses(&mut self) {
        self.front.refused.fill(0);
    }

    /// Forgets every certificate (see [`RefineStats::certified`](crate::RefineStats)), so
    /// the next [`refine`](Self::refine) reads every bound it asks about. Refinement never
    /// needs this (a certificate lapses as soon as the view may have changed its answer);
    /// it exists so tests and benchmarks can compare refinement with and without them.
    #[doc(hidden)]
    pub fn forget_certificates(&mut self) {
        self.front.odometer = super::certificate::Odometer::new();
    }

    /// `true` if `node` is split, both children are active, and `f_l`, `f_r` have exactly
    /// the neighbours the split gave them.
    pub fn can_collapse(&self, h: &Hierarchy<'_>, node: NodeId) -> bool {
        self.is_for(h) && self.front.can_collapse(h, node)
    }

    /// Splits active `node` if [`can_split`](Self::can_split).
    pub fn split(&mut self, h: &Hierarchy<'_>, node: NodeId) -> Result<(), OpError> {
        self.check(h)?;
        if h.split(node).is_none() {
            return Err(if h.node(node).is_some() {
                OpError::Leaf { node }
            } else {
                OpError::NotActive { node }
            });
        }
        if !self.front.is_node_active(h, node) {
            return Err(OpError::NotActive { node });
        }
        let slots = self
            .front
            .split_slots(h, node)
            .ok_or(OpError::Illegal { node })?;
        self.front.apply_split(h, node, slots)
    }

    /// Collapses the children of `node` back into it if [`can_collapse`](Self::can_collapse).
    pub fn collapse(&mut self, h: &Hierarchy<'_>, node: NodeId) -> Result<(), OpError> {
        self.check(h)?;
        if h.split(node).is_none() {
            return Err(OpError::Leaf { node });
        }
        if !self.front.is_split(node) {
            return Err(OpError::NotSplit { node });
        }
        let slots = self
            .front
            .collapse_slots(h, node)
            .ok_or(OpError::Illegal { node })?;
        self.front.apply_collapse(h, node, slots)
    }

    /// Splits `node`, first forcing the splits that create it (if it is not yet on the
    /// front) and that activate its missing neighbours (Hoppe's `force_vsplit`), with an
    /// explicit stack in `stack`. Returns the number of
    /// splits applied; 0 if `node` was already split. On error the splits already applied
    /// stay (the front is valid, just not yet refined at `node`).
    pub fn force_split(
        &mut self,
        h: &Hierarchy<'_>,
        node: NodeId,
        stack: &mut [NodeId],
    ) -> Result<u32, OpError> {
        self.check(h)?;
        self.front.force_split(h, node, stack, u32::MAX)
    }

    /// [`force_split`](Self::force_split) with the camera's own stack.
    pub fn force_split_own_stack(
        &mut self,
        h: &Hierarchy<'_>,
        node: NodeId,
    ) -> Result<u32, OpError> {
        self.check(h)?;
        self.front.force_split(h, node, self.stack, u32::MAX)
    }
}
