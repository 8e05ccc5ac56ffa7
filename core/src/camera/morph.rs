//! Geomorphs of view-dependent refinement (Hoppe's `SrVertexMorph`), in the camera's memory,
//! for the GPU to blend.
//!
//! Only a split's floating child moves: the hierarchy keeps every node at an original
//! position (half-edge collapses), so the stationary child already stands where its parent
//! stood. A *morph* is the floating child's vertices travelling between the parent's vertex
//! (`t = 0`) and their own (`t = 1`):
//! - a **refine morph** starts at `t = 0` when refinement splits a visible node, and rises at
//!   `1 / refine_morph_s` per second of the caller's clock; at 1 it ends;
//! - a **coarsen morph** starts when refinement wants a legal collapse of a visible parent:
//!   `t` falls from where it stands (1, or a refine morph's value) at `1 / coarsen_morph_s`
//!   per second, and at 0 the collapse is applied;
//! - a coarsen morph is **aborted** when the parent's split is wanted again or the collapse
//!   became illegal (a neighbouring split, or a child split): it turns into a refine morph
//!   from where it stands, back to the fine position, and then ends.
//!
//! A split or collapse of a node outside the view (the frustum and the normal cone, as
//! refinement tests them), whose position does not morph, happens at once, and a collapse that happens at once ends its
//! floating child's morph. `t` moves at a constant speed (a full morph takes its duration;
//! Hoppe's morphs take the whole duration again from wherever the vertex stands).
//!
//! Each pass first steps every morph ([`Front::sweep_morphs`]): a coarsen morph's parent is
//! asked again whether its split is wanted and its collapse legal before it moves, so an
//! abort happens on the pass after the change, before the vertex has moved on. The sweep is
//! O(morphs); a camera without morph memory never runs it, and the walk over the active nodes
//! looks at morphs only where it applies a split or would collapse. A pair whose coarsen
//! morph runs has a bit set (`coarsening`, a bit per pair): the walk leaves such a pair to the
//! sweep without asking whether its collapse is legal. The sweep asks cheaply too: the
//! camera's bit per pair that remembers a refused collapse until either slot changes (see the
//! [`CameraState`] docs) remembers, for a coarsening pair, that its collapse was found legal
//! and nothing it depends on changed since, besides a child's split, which the sweep reads.
//!
//! A morph has two vertex slots: a floating child is FREE (one surface group at its
//! position) or SHARP (two), so two vertices cover every position a floating child may
//! have; a position with more, or without a vertex, moves at once (counted as dropped). Slot
//! `k` of morph `m` is vertex slot `2m + k`; its [`MorphVertex`] names the two persistent
//! vertices (the parent's in the same surface group, or any of the parent's where that
//! group has none) and the current `t`. Morphed emission writes `vertex_count + slot` for a
//! corner whose vertex morphs ([`CameraState::emit_indices_morphed`]), found through a bit
//! per vertex and a small map from vertex to slot (`morph_map`); the persistent vertex
//! buffer is never written.
//!
//! A split of a vertex that is still morphing leaves its morph running (the stationary child
//! keeps the position, so the vertex keeps its morph), and the new floating child starts
//! where that vertex is drawn, as Hoppe's do: its slot's `from` names the slot of the
//! vertex it leaves (`vertex_count + slot`), so it moves with it until that morph ends, and
//! from then on blends from the persistent vertex (see [`MorphVertex::from`]). The GPU still
//! blends every slot from persistent vertices, in any order: a slot's blend walks its chain
//! ([`gpu::morph_slot_vertex`](crate::gpu::morph_slot_vertex)).
//!
//! A morph can also be held to a screen speed ([`RefineParams::morph_speed_px_s`], off by
//! default): a floating child far from its parent on the screen then takes longer than the
//! duration, so no vertex slides far in one frame however coarse the node that splits.

use super::criterion::Criterion;
use super::morph_pool::{MorphState, COARSENING, REFINING, VERTICES_PER_MORPH};
use super::ops::OpError;
use super::records::NONE;
use super::state::{CameraState, Front};
use super::stats::RefineStats;
use crate::format::Split;
use crate::gpu::{MorphVertex, MAX_MORPH_CHAIN};
use crate::hierarchy::HierarchyRecords;
use crate::ids::NodeId;
use crate::params::RefineParams;
use glam::Vec3;

/// How far `t` moves in `dt` seconds of a morph lasting `duration` seconds: all the way for
/// a duration that is zero, negative or not a number (morphs off).
#[inline]
fn step(dt: f32, duration: f32) -> f32 {
    if duration > 0.0 {
        (dt / duration).min(1.0)
    } else {
        1.0
    }
}

impl Front<'_> {
    /// Sets morph `m` (of `parent`'s floating child) coarsening or refining, and its pair's
    /// bit with it. A pair that starts to coarsen-morph had its collapse found legal just
    /// now: its remembered-refusal bit remembers that (see the module docs); one that stops
    /// for any reason but an illegal collapse forgets it.
    fn set_phase(&mut self, m: u32, parent: NodeId, phase: u32) {
        if let Some(state) = self.morphs.states.get_mut(m as usize) {
            let was = state.phase;
            state.phase = phase;
            let s = &mut self.morphs.scalars;
            if was != COARSENING && phase == COARSENING {
                s.coarsening += 1;
            } else if was == COARSENING && phase != COARSENING {
                s.coarsening = s.coarsening.saturating_sub(1);
            }
        }
        if let Some(pair) = self.pair_of.get(parent.index()).filter(|&p| p != NONE) {
            let on = phase == COARSENING;
            self.morphs.set_coarsening(pair, on);
            if on {
                self.remember_refusal(pair);
            } else {
                self.forget_refusal(pair);
            }
        }
    }

    /// Ends morph `m`; a coarsening pair's bits go with it, and the polygons round its
    /// vertex are marked for the index edits (their corners stop pointing at its slots).
    fn free_morph(&mut self, h: &impl HierarchyRecords, m: u32) {
        if let Some(state) = self.morphs.state(m) {
            if state.phase == COARSENING {
                self.set_phase(m, NodeId(state.parent), REFINING);
            }
            self.morphs.free(m);
            // The morphs that start at its vertex start at the persistent vertex now, and
            // its polygons' corners stop pointing at its slots: one walk down the line.
            let base = h.vertex_id_bound() as u32;
            let parent = NodeId(state.parent);
            let end = self.walk_stationary_line(h, parent, |f, s| f.link_morph_of(h, base, s));
            if let Some((made_by, holder)) = end {
                self.mark_fan_of(made_by, holder);
            }
        }
    }

    /// Every coarsening pair's bit again, from the morphs (after compaction moved pairs).
    pub fn mark_coarsening_pairs(&mut self) {
        self.morphs.coarsening.fill(0);
        let len = (self.morphs.scalars.len as usize).min(self.morphs.capacity());
        for m in 0..len as u32 {
            if let Some(state) = self.morphs.state(m).filter(|s| s.phase == COARSENING) {
                if let Some(pair) = self.pair_of.get(state.parent as usize) {
                    self.morphs.set_coarsening(pair, true);
                }
            }
        }
    }

    /// The morph of the vertices at `floating`'s position, if any.
    fn morph_of(&self, h: &impl HierarchyRecords, floating: NodeId) -> Option<u32> {
        let first = h.vertex_keys(Self::position_of(h, floating)).first()?;
        self.morphs.of_slot(self.morphs.map.get(first.vertex)?)
    }

    /// Starts (or restarts) the morph of `parent`'s floating child at `t`, in `phase`;
    /// `false` if there is no room or the positions' vertices cannot morph.
    fn start_morph(
        &mut self,
        h: &impl HierarchyRecords,
        parent: NodeId,
        t: f32,
        phase: u32,
    ) -> bool {
        let Some(s) = h.split(parent) else {
            return false;
        };
        let at = Self::position_of(h, parent);
        let fine = h.vertex_keys(Self::position_of(h, s.floating));
        let Some(any_coarse) = h.vertex_keys(at).first() else {
            return false;
        };
        if fine.is_empty() || fine.len() > VERTICES_PER_MORPH {
            return false;
        }
        let m = match self.morph_of(h, s.floating) {
            Some(m) => {
                self.morphs.unmap(m);
                m
            }
            None => match self.morphs.alloc() {
                Some(m) => m,
                None => return false,
            },
        };
        let base = h.vertex_id_bound() as u32;
        let mut mapped = true;
        for k in 0..VERTICES_PER_MORPH {
            let slot = m * VERTICES_PER_MORPH as u32 + k as u32;
            let v = match fine.get(k) {
                Some(key) => {
                    mapped &= self.morphs.map.insert(key.vertex, slot).is_some();
                    let coarse = h.vertex_index(key.group, at).unwrap_or(any_coarse.vertex);
                    MorphVertex {
                        from: self.chained_from(base, coarse, slot),
                        to: key.vertex,
                        t,
                        coarse,
                    }
                }
                None => MorphVertex::IDLE,
            };
            if let Some(dst) = self.morphs.vertices.get_mut(slot as usize) {
                *dst = v;
            }
        }
        if let Some(state) = self.morphs.states.get_mut(m as usize) {
            *state = MorphState {
                parent: parent.0,
                phase: REFINING,
            };
        }
        if !mapped {
            // The map has room for every slot (see `morph_map`); a camera whose own
            // bookkeeping says otherwise moves this vertex at once.
            self.free_morph(h, m);
            return false;
        }
        // No morph starts at the new morph's position yet (see `link_morph_of`).
        if phase == COARSENING {
            self.set_phase(m, parent, COARSENING);
            // The vertex starts to morph: its polygons' corners now point at the slots. A
            // refine morph starts on the split that just wrote every polygon round its
            // vertex, which marked them already.
            self.mark_floating_fan(h, parent);
        }
        true
    }

    /// Whether `node`'s position is drawn elsewhere than at its point: its vertex morphs.
    #[inline]
    fn position_morphs(&self, h: &impl HierarchyRecords, node: NodeId) -> bool {
        h.vertex_keys(Self::position_of(h, node))
            .first()
            .is_some_and(|k| self.morphs.map.bit(k.vertex) != 0)
    }

    /// Whether a split or collapse of `node` may show: its bounds are visible, or its
    /// position morphs. A morphing position is drawn on its way from another place, which
    /// the bounds (of the hierarchy's geometry) do not hold and which may be in view (a
    /// chain of slow morphs near the eye can stand far from the node's sphere), so its
    /// operations morph too.
    fn drawn_visible(&self, h: &impl HierarchyRecords, c: &Criterion, node: NodeId) -> bool {
        h.split_bounds(node).is_some_and(|b| c.visible(b)) || self.position_morphs(h, node)
    }

    /// Ends the morph of the vertices at `floating`'s position, if any (its pair collapsed).
    pub fn end_morph_of(&mut self, h: &impl HierarchyRecords, floating: NodeId) {
        if let Some(m) = self.morph_of(h, floating) {
            self.free_morph(h, m);
        }
    }

    /// After refinement applied the split of `node`: a refine morph of its floating child,
    /// if the node is visible and refine morphs are on.
    pub(super) fn morph_split(
        &mut self,
        h: &impl HierarchyRecords,
        c: &Criterion,
        p: &RefineParams,
        node: NodeId,
        st: &mut RefineStats,
    ) {
        // Zero, negative and NaN durations all mean "at once".
        let on = p.refine_morph_s > 0.0;
        if !on || !self.drawn_visible(h, c, node) {
            return;
        }
        if self.start_morph(h, node, 0.0, REFINING) {
            st.morphs_started += 1;
        } else {
            st.morphs_dropped += 1;
        }
    }

    /// Whether refinement, wanting the legal collapse of `parent` (whose pair does not
    /// coarsen-morph yet), waits for a coarsen morph instead: a refine morph turned around,
    /// or one started now. `false` (collapse at once, ending any morph of the floating child)
    /// for a parent outside the view, coarsen morphs off, or no room.
    pub(super) fn defers_collapse(
        &mut self,
        h: &impl HierarchyRecords,
        c: &Criterion,
        p: &RefineParams,
        parent: NodeId,
        st: &mut RefineStats,
    ) -> bool {
        let (Some(b), Some(s)) = (h.split_bounds(parent), h.split(parent)) else {
            return false;
        };
        let running = self.morph_of(h, s.floating);
        if p.coarsen_morph_s > 0.0 && (c.visible(b) || self.position_morphs(h, parent)) {
            if let Some(m) = running {
                if self.morphs.state(m).is_some_and(|s| s.phase != COARSENING) {
                    st.morphs_started += 1;
                }
                self.set_phase(m, parent, COARSENING);
                return true;
            }
            if self.start_morph(h, parent, 1.0, COARSENING) {
                st.morphs_started += 1;
                return true;
            }
            st.morphs_dropped += 1;
        } else if let Some(m) = running {
            self.free_morph(h, m);
            st.morphs_finished += 1;
        }
        false
    }

    /// Whether the collapse into `parent`, whose pair coarsen-morphs, is still legal: its
    /// children unsplit, and its slots as they were when it was found legal (the pair's
    /// remembered bit, see the module docs) or found legal now.
    fn coarsening_legal(&mut self, h: &impl HierarchyRecords, parent: NodeId) -> bool {
        let (Some(s), Some(pair)) = (h.split(parent), self.pair_of.get(parent.index())) else {
            return false;
        };
        if pair == NONE || self.is_split(s.stationary) || self.is_split(s.floating) {
            return false;
        }
        if self.refusal_remembered(pair) {
            return true;
        }
        let legal = self.collapse_slots(h, parent).is_some();
        if legal {
            self.remember_refusal(pair);
        }
        legal
    }

    /// The largest step of morph `m`'s `t` that keeps its vertex within `max_px` pixels
    /// of screen motion per pass, as a share of that bound: a vertex whose morph starts
    /// from another morphing vertex (a chain, see [`MorphVertex::from`]) moves with it too,
    /// so each link further down a chain takes half its parent's share (a chain's moves
    /// then sum to less than twice the first link's), and the path it may cover is the sum
    /// of the chain's paths, each at the larger magnification of its two ends. 1 (no limit)
    /// for paths of no length, wholly behind the eye, or a morph without vertices.
    fn screen_limit(&self, h: &impl HierarchyRecords, c: &Criterion, m: u32, max_px: f32) -> f32 {
        let base = h.vertex_id_bound() as u32;
        let mut slot = self
            .morphs
            .vertices
            .get(m as usize * VERTICES_PER_MORPH)
            .copied();
        let (mut px, mut share) = (0.0f32, max_px);
        let mut links = 0;
        while let Some(v) = slot.filter(|v| !v.is_idle()) {
            if let (Some(a), Some(b)) = (h.vertex(v.coarse), h.vertex(v.to)) {
                let (pa, pb) = (Vec3::from_array(a.position), Vec3::from_array(b.position));
                px += (pb - pa).length() * c.magnification(pa).max(c.magnification(pb));
            }
            links += 1;
            if v.from < base || links >= MAX_MORPH_CHAIN {
                break;
            }
            share *= 0.5;
            slot = self.morphs.vertices.get((v.from - base) as usize).copied();
        }
        if px > 0.0 && px.is_finite() {
            (share / px).min(1.0)
        } else if px > 0.0 {
            0.0 // the eye stands on the path: hold the vertex until it moves on
        } else {
            1.0 // a path of no length, or wholly behind the eye
        }
    }

    /// Where a slot `slot` whose blend starts at persistent vertex `coarse` starts: the slot
    /// of `coarse` while that vertex morphs, else `coarse` (see [`MorphVertex::from`]).
    #[inline]
    fn chained_from(&self, base: u32, coarse: u32, slot: u32) -> u32 {
        match self.morphs.map.get(coarse) {
            Some(k) if k != slot => base.saturating_add(k),
            _ => coarse,
        }
    }

    /// Links again the morph of `split`'s floating child, if it morphs: a split along the
    /// stationary line of a vertex whose morph ended (see `free_morph`), whose morph starts
    /// at that vertex. A morph start needs no such walk: its floating child was just made
    /// (a refine morph) or is a leaf (a coarsen morph), so no morph starts at it yet. Each
    /// link is then exact after every change, between passes too.
    fn link_morph_of(&mut self, h: &impl HierarchyRecords, base: u32, split: &Split) {
        let Some(m) = self.morph_of(h, split.floating) else {
            return;
        };
        for k in 0..VERTICES_PER_MORPH as u32 {
            let slot = m * VERTICES_PER_MORPH as u32 + k;
            let Some(v) = self.morphs.vertices.get(slot as usize).copied() else {
                continue;
            };
            if v.is_idle() {
                continue;
            }
            let from = self.chained_from(base, v.coarse, slot);
            if let Some(dst) = self.morphs.vertices.get_mut(slot as usize) {
                dst.from = from;
            }
        }
    }

    /// Steps every morph by `p.dt_s` (see the module docs): a coarsen morph whose parent's
    /// split is wanted again or whose collapse is illegal turns back; one whose parent left
    /// the view, or that reached 0, collapses (while the pass has operations left); a refine
    /// morph that reached 1 ends.
    pub(super) fn sweep_morphs(
        &mut self,
        h: &impl HierarchyRecords,
        c: &Criterion,
        p: &RefineParams,
        st: &mut RefineStats,
        max_ops: u32,
    ) -> Result<(), OpError> {
        let dt = if p.dt_s > 0.0 && p.dt_s.is_finite() {
            p.dt_s
        } else {
            0.0
        };
        let (up, down) = (step(dt, p.refine_morph_s), step(dt, p.coarsen_morph_s));
        let max_px = p.morph_speed_px_s * dt;
        let limited = p.morph_speed_px_s > 0.0 && p.morph_speed_px_s.is_finite();
        let len = (self.morphs.scalars.len as usize).min(self.morphs.capacity()) as u32;
        for m in 0..len {
            let Some(state) = self.morphs.state(m) else {
                continue;
            };
            let (up, down) = if limited {
                let most = self.screen_limit(h, c, m, max_px);
                (up.min(most), down.min(most))
            } else {
                (up, down)
            };
            // A collapse ends its floating child's morph, so the parent is split (and were it
            // not, a coarsen morph would find the collapse illegal and turn back).
            let parent = NodeId(state.parent);
            let t = self.morphs.t(m);
            if state.phase == COARSENING {
                let bounds = h.split_bounds(parent);
                let wanted = bounds.is_some_and(|b| c.wants_split(b));
                let legal = !wanted && self.coarsening_legal(h, parent);
                if legal {
                    let visible = self.drawn_visible(h, c, parent);
                    let t = if visible { (t - down).max(0.0) } else { 0.0 };
                    if t <= 0.0 && st.operations() < max_ops {
                        if let Some(slots) = self.collapse_slots(h, parent) {
                            self.apply_collapse(h, parent, slots)?;
                            self.free_morph(h, m);
                            st.collapses += 1;
                            st.morphs_finished += 1;
                            continue;
                        }
                    }
                    self.morphs.set_t(m, t);
                    continue;
                }
                self.set_phase(m, parent, REFINING);
                if !wanted {
                    // Refused: remembered as any refusal is, until something changes.
                    if let Some(pair) = self.pair_of.get(parent.index()).filter(|&k| k != NONE) {
                        self.remember_refusal(pair);
                    }
                }
                st.morphs_aborted += 1;
            }
            let t = (t + up).min(1.0);
            if t >= 1.0 {
                self.free_morph(h, m);
                st.morphs_finished += 1;
            } else {
                self.morphs.set_t(m, t);
            }
        }
        Ok(())
    }
}

impl CameraState<'_> {
    /// The morph vertex slots up to the highest in use, for the GPU to blend each frame
    /// (slot `s` is `morph_vertices()[s]`; idle ones are [`MorphVertex::IDLE`]): the
    /// persistent indices and `t` of every vertex that morphs. Empty when nothing morphs.
    pub fn morph_vertices(&self) -> &[MorphVertex] {
        self.front.morphs.live_vertices()
    }

    /// Morphs in progress (each moves one or two of [`morph_vertices`](Self::morph_vertices)).
    pub fn morph_count(&self) -> u32 {
        self.front.morphs.scalars.live
    }

    /// Coarsen morphs in progress: visible collapses refinement wants that wait for their
    /// floating child to glide back. Each holds the pair's polygons on the screen until it
    /// ends, so a front that coarsens shows its count that many collapses late; a
    /// [`Regulator`](crate::Regulator) is given the count the front settles at,
    /// [`settled_polygon_count`](Self::settled_polygon_count).
    pub fn coarsening_count(&self) -> u32 {
        self.front.morphs.scalars.coarsening
    }

    /// The active polygons once the coarsen morphs in progress have collapsed: two fewer
    /// for each (see [`coarsening_count`](Self::coarsening_count); a collapse on the mesh's
    /// border removes one, so there the figure is one low).
    pub fn settled_polygon_count(&self) -> u32 {
        self.front
            .active_polygons
            .saturating_sub(self.coarsening_count().saturating_mul(2))
    }

    /// Most morphs this camera holds at once ([`CameraConfig::max_morphs`](crate::CameraConfig));
    /// its vertex slots are twice as many.
    pub fn max_morphs(&self) -> u32 {
        self.front.morphs.capacity() as u32
    }

    /// Ends every morph at once: refine morphs snap to the fine position, coarsen morphs back
    /// to it too (their collapses wait for refinement to want them again). The front is
    /// unchanged.
    pub fn finish_morphs(&mut self) {
        let f = &mut self.front;
        if f.morphs.scalars.live > 0 {
            // A coarsening pair's remembered bit says "legal"; without the morph it would read
            // as a refusal.
            f.refused.fill(0);
            // Every morphed corner points at its vertex again: the index edits rewrite all.
            f.placement.mark_everything();
        }
        f.morphs.clear();
    }
}
