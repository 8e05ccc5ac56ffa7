//! The fan of an active vertex: the polygons round one active-vertex record, found from one
//! of them and walked over the slots' neighbour links.
//!
//! A vertex created by a split is a corner of a polygon of the pair its split created (a
//! split hands the record of its node to the stationary child, and a collapse takes it
//! back, so the latest split in a record's line of stationary children made a pair naming
//! it); a root is a corner of a base polygon. Compaction renames records along fans, and the
//! index edits mark the polygons round a vertex whose morph starts or ends.

use super::records::{next, prev, PolySlot, FREE, NONE};
use super::state::Front;
use crate::format::Split;
use crate::hierarchy::HierarchyRecords;
use crate::ids::NodeId;

/// Where a record's fan starts: a slot naming it, or no polygon at all.
#[derive(Clone, Copy)]
pub(crate) enum FanStart {
    At(u32),
    Empty,
}

/// Visits the fan of record `r` from slot `s0` (each slot's index, the slot, and its corner
/// naming `r`), round one way and, from a border, the other way; `false` as soon as `visit`
/// says so, a slot does not name `r`, or the walk runs longer than `bound` slots.
pub(crate) fn walk(
    slots: &[PolySlot],
    s0: u32,
    r: u32,
    bound: u32,
    mut visit: impl FnMut(u32, &PolySlot, usize) -> bool,
) -> bool {
    for back in [false, true] {
        let mut s = s0;
        let mut steps = 0u32;
        loop {
            let Some(slot) = slots.get(s as usize) else {
                return false;
            };
            let Some(j) = slot.corners.iter().position(|&c| c == r) else {
                return false;
            };
            // The way back starts at the first slot, which the way out visited.
            let first_again = back && s == s0;
            if !first_again && !visit(s, slot, j) {
                return false;
            }
            let link = if back {
                slot.neighbours[next(j)]
            } else {
                slot.neighbours[prev(j)]
            };
            if link == s0 {
                // Closed: every slot was visited going one way.
                return !back;
            }
            if link == NONE {
                break;
            }
            s = link;
            steps += 1;
            if steps > bound {
                return false;
            }
        }
    }
    true
}

impl Front<'_> {
    /// Visits the fan of record `r` from slot `s0` (see [`walk`]), bounded by the front's
    /// polygons.
    pub fn walk_fan(
        &self,
        s0: u32,
        r: u32,
        mut visit: impl FnMut(&PolySlot, usize) -> bool,
    ) -> bool {
        walk(
            self.slots,
            s0,
            r,
            self.active_polygons.saturating_add(1),
            |_, s, j| visit(s, j),
        )
    }

    /// A slot naming live record `r`, or `Empty` for a root no base polygon names (a vertex
    /// without polygons), with the slots looked at to find it; `None` if the front
    /// contradicts the hierarchy.
    pub fn fan_start(&self, h: &impl HierarchyRecords, r: u32) -> Option<(FanStart, u32)> {
        let node = self.active.get(r as usize)?.node;
        if node & FREE != 0 {
            return None;
        }
        let n = h.node(NodeId(node))?;
        let names = |s: u32| {
            self.slots
                .get(s as usize)
                .is_some_and(|p| p.corners.contains(&r))
        };
        if h.node(n.parent).is_none() {
            let found = (0..self.base).find(|&s| names(s));
            let looked = found.map_or(self.base, |s| s + 1);
            return Some((found.map_or(FanStart::Empty, FanStart::At), looked));
        }
        let pair = self.pair_of.get(n.parent.index())?;
        if pair >= self.pairs {
            return None;
        }
        let left = self.base + 2 * pair;
        [left, left + 1]
            .into_iter()
            .find(|&s| names(s))
            .map(|s| (FanStart::At(s), 2))
    }

    /// The live pair of `node`'s split, if it is split.
    #[inline]
    fn live_pair(&self, node: NodeId) -> Option<u32> {
        self.pair_of
            .get(node.index())
            .filter(|&k| k != NONE && k < self.pairs)
    }

    /// Walks down the stationary line of `parent`'s floating child: that child, then its
    /// stationary child, and so on while this camera has them split; `visit` sees each split
    /// node's split record. Returns the last split node (`parent` where the child is not
    /// split) and the node after it, which holds the floating child's position now. These
    /// are the nodes that have held that position, so the splits that made pairs naming it
    /// and every morph that starts at it. `None` for a leaf `parent`. Bounded by the
    /// hierarchy's depth, whatever the records say.
    pub(super) fn walk_stationary_line(
        &mut self,
        h: &impl HierarchyRecords,
        parent: NodeId,
        mut visit: impl FnMut(&mut Self, &Split),
    ) -> Option<(NodeId, NodeId)> {
        let s = h.split(parent)?;
        let (mut made_by, mut holder) = (parent, s.floating);
        for _ in 0..=h.meta().max_depth {
            if self.live_pair(holder).is_none() {
                break;
            }
            let x = h.split(holder)?;
            visit(self, x);
            made_by = holder;
            holder = x.stationary;
        }
        Some((made_by, holder))
    }

    /// Marks, for the index edits, the places of the polygons round the vertex that
    /// `parent`'s split brought (its floating child's position): its morph starts or ends,
    /// so their morphed corners change. The record holding that position is the floating
    /// child's, handed down its stationary children while they split; the latest of those
    /// splits made a pair naming it.
    pub fn mark_floating_fan(&mut self, h: &impl HierarchyRecords, parent: NodeId) {
        if !self.placement.is_on() {
            return;
        }
        if let Some((made_by, holder)) = self.walk_stationary_line(h, parent, |_, _| {}) {
            self.mark_fan_of(made_by, holder);
        }
    }

    /// Marks the fan round the record of `holder`, found in the pair of `made_by`'s split
    /// (the end of a stationary line, see [`walk_stationary_line`](Self::walk_stationary_line)).
    pub(super) fn mark_fan_of(&mut self, made_by: NodeId, holder: NodeId) {
        if !self.placement.is_on() {
            return;
        }
        let Some(k) = self.live_pair(made_by) else {
            return;
        };
        let left = self.base + 2 * k;
        let found = [left, left + 1].into_iter().find_map(|slot| {
            let corners = self.slots.get(slot as usize)?.corners;
            let r = corners
                .into_iter()
                .find(|&c| self.node_of(c) == Some(holder))?;
            Some((slot, r))
        });
        let Some((s0, r)) = found else {
            return;
        };
        let bound = self.active_polygons.saturating_add(1);
        let placement = &mut self.placement;
        walk(self.slots, s0, r, bound, |slot, _, _| {
            placement.mark_slot(slot);
            true
        });
    }
}
