//! The index cache: each polygon slot's vertex indices, surface and group, kept exact by the
//! operations so that emission copies them.
//!
//! A polygon's indices are the end of a chain of reads at unrelated addresses: the slot's
//! polygon (for a split's pair, the split record), the polygon record (surface and group),
//! per corner the active-vertex record (the node), the node record (the position), and the
//! vertex table's row for the position and its entry for the group. They change only when a
//! corner of the slot moves to another active-vertex record, since a record keeps its
//! position for life. A split moves corners only onto its floating child and a collapse
//! only back onto its node, so an operation rewrites each moved corner from the group its
//! slot's entry keeps and one position (one vertex-table row for all the moved corners): the
//! indices of a position in a group are learned once per operation (`Known`), and a
//! collapse knows its node's from the pair it removes (corner 0 of `f_l` and `f_r`). The
//! pair a split creates shares its corners with the first and last polygons of that walk
//! (`f_l` has `vs`, `vt` and `vl` as `fl_clw` has them, `f_r` likewise with `fr_ccw`), so
//! its entries come from theirs where the surface groups agree (validation guarantees that
//! a stationary child stands at its parent's position), and through the vertex table where
//! they do not.
//!
//! Without the cache, emission follows the chain itself ([`Front::gather`], then
//! [`Gathered::entry`] while it hands out the triangles), [`BATCH`] slots at a time, one link
//! for all of them before the next, so the misses of a link are independent and the core
//! overlaps them instead of waiting for each in turn. 32 slots per batch keep the batch's
//! arrays under 1 KB of stack, which a small target can afford; a larger batch gains little
//! for twice the stack. A reset fills the base slots' entries the same way; compaction moves
//! each pair's entries with the pair.

use super::records::{SlotTriangle, NONE, NO_POLYGON};
use super::state::Front;
use crate::format::Polygon;
use crate::hierarchy::HierarchyRecords;
use crate::ids::{NodeId, PolyId, PositionId, SurfaceGroupId};

/// Slots per batch of [`Front::gather`]: enough independent reads per link to keep the
/// core's miss queue busy, few enough that a batch's gathered links stay in the first-level
/// cache.
pub(crate) const BATCH: usize = 32;

/// An entry for a slot without a polygon.
pub(crate) const EMPTY: SlotTriangle = SlotTriangle {
    indices: [NONE; 3],
    surface: NO_POLYGON,
    group: 0,
};

/// The vertex indices of one position in the surface groups an operation met so far (at
/// most two are kept: an operation's polygons rarely span more).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Known {
    entries: [(u16, u32); 2],
    len: usize,
}

impl Known {
    /// The index in `group`, if known.
    #[inline]
    pub fn get(&self, group: u16) -> Option<u32> {
        self.entries[..self.len.min(2)]
            .iter()
            .find(|e| e.0 == group)
            .map(|e| e.1)
    }

    /// Remembers the index in `group` (while there is room).
    #[inline]
    pub fn learn(&mut self, group: u16, index: u32) {
        if let Some(e) = self.entries.get_mut(self.len) {
            *e = (group, index);
            self.len += 1;
        }
    }

    /// The index of a polygon's corner, as its slot's entry `t` has it (nothing for a slot
    /// without a polygon).
    #[inline]
    pub fn learn_from(&mut self, t: Option<&SlotTriangle>, corner: usize) {
        if let Some(t) = t.filter(|t| t.surface != NO_POLYGON) {
            if let (None, Some(&i)) = (self.get(t.group), t.indices.get(corner)) {
                self.learn(t.group, i);
            }
        }
    }
}

impl SlotTriangle {
    /// The entry of `poly` with its corners at `positions`.
    #[inline]
    fn of(h: &impl HierarchyRecords, poly: Option<&Polygon>, positions: [PositionId; 3]) -> Self {
        match poly {
            Some(p) => Self {
                indices: positions.map(|pos| h.vertex_index(p.group, pos).unwrap_or(NONE)),
                surface: p.surface.0,
                group: p.group.0,
            },
            None => EMPTY,
        }
    }
}

impl Front<'_> {
    /// Whether the camera keeps an index cache.
    #[inline]
    pub fn caches_indices(&self) -> bool {
        !self.triangles.is_empty()
    }

    /// The position of `node` (`NONE` for an absent node, which no group has a vertex at).
    #[inline]
    pub fn position_of(h: &impl HierarchyRecords, node: NodeId) -> PositionId {
        h.node(node).map_or(PositionId(NONE), |n| n.position)
    }

    /// The position of the node active-vertex record `record` holds.
    #[inline]
    pub fn record_position(&self, h: &impl HierarchyRecords, record: u32) -> PositionId {
        self.node_of(record)
            .map_or(PositionId(NONE), |n| Self::position_of(h, n))
    }

    /// Corner `corner` of `slot` moved to a record at `position`: rewrites its index, from
    /// `known` when it holds the slot's group, else through the vertex table (and then
    /// `known` learns it). Returns the entry as it was, if the slot holds a polygon.
    #[inline]
    pub fn cache_corner(
        &mut self,
        h: &impl HierarchyRecords,
        slot: u32,
        corner: usize,
        position: PositionId,
        known: &mut Known,
    ) -> Option<SlotTriangle> {
        let t = self.triangles.get_mut(slot as usize)?;
        let before = *t;
        if t.surface == NO_POLYGON {
            return None;
        }
        let index = known.get(t.group).unwrap_or_else(|| {
            let i = h
                .vertex_index(SurfaceGroupId(t.group), position)
                .unwrap_or(NONE);
            known.learn(t.group, i);
            i
        });
        *t.indices.get_mut(corner)? = index;
        self.placement.mark_slot(slot);
        Some(before)
    }

    /// The entry of a slot that now holds `poly` (or nothing). `known` is the polygon's
    /// indices as a neighbour in surface group `known.0` has them: taken when the groups
    /// agree (a vertex is one per group and position); otherwise the indices are looked up
    /// at `positions(self)`.
    #[inline]
    pub fn new_entry(
        &self,
        h: &impl HierarchyRecords,
        poly: Option<&Polygon>,
        known: Option<(u16, [u32; 3])>,
        positions: impl FnOnce(&Self) -> [PositionId; 3],
    ) -> SlotTriangle {
        match (poly, known) {
            (Some(p), Some((group, indices))) if p.group.0 == group => SlotTriangle {
                indices,
                surface: p.surface.0,
                group,
            },
            _ => SlotTriangle::of(h, poly, positions(self)),
        }
    }

    /// Writes the entry of `slot`, which now holds a new polygon (or nothing), and gives the
    /// polygon its place in the index buffer.
    #[inline]
    pub fn set_cached(&mut self, slot: u32, entry: SlotTriangle) {
        if let Some(t) = self.triangles.get_mut(slot as usize) {
            *t = entry;
            self.placement.unplace(slot);
            if entry.surface != NO_POLYGON {
                self.placement.place_new(slot, entry.surface);
            }
        }
    }

    /// The polygons of `slots` leave the front: their places are freed.
    #[inline]
    pub fn uncache(&mut self, slots: [u32; 2]) {
        for s in slots {
            self.placement.unplace(s);
        }
    }

    /// Places the base polygons (a reset; the placement starts over).
    pub fn place_base_slots(&mut self) {
        if !self.placement.is_on() {
            return;
        }
        self.placement.clear();
        for slot in 0..(self.base as usize).min(self.triangles.len()) {
            let surface = self.triangles[slot].surface;
            if surface != NO_POLYGON {
                self.placement.place_new(slot as u32, surface);
            }
        }
    }

    /// Asks for the vertex-table row of `position` ahead of an operation's first lookup.
    #[inline]
    pub fn prefetch_row(h: &impl HierarchyRecords, position: PositionId) {
        h.prefetch_vertex_keys(position);
    }

    /// Asks for `slot`'s entry ahead of an operation's write to it: it is not on the line
    /// of the slot the operation reads first, so the two misses overlap.
    #[inline]
    pub fn prefetch_cached(&self, slot: u32) {
        if let Some(t) = self.triangles.get(slot as usize) {
            crate::prefetch::line(t);
        }
    }

    /// Moves slot `from`'s entry to slot `to` (a pair filling a hole); its polygon keeps its
    /// place.
    #[inline]
    pub fn move_cached(&mut self, from: u32, to: u32) {
        if let Some(&t) = self.triangles.get(from as usize) {
            if let Some(dst) = self.triangles.get_mut(to as usize) {
                *dst = t;
                self.placement.move_slot(from, to);
            }
        }
    }

    /// Swaps the entries of slots `a` and `b` (compaction swapping pairs); their polygons
    /// keep their places.
    #[inline]
    pub fn swap_cached(&mut self, a: u32, b: u32) {
        if self.caches_indices()
            && (a as usize) < self.triangles.len()
            && (b as usize) < self.triangles.len()
        {
            self.triangles.swap(a as usize, b as usize);
            self.placement.swap_slots(a, b);
        }
    }

    /// Fills the entries of slots `from..to` through the hierarchy (the base slots, at a
    /// reset).
    pub fn cache_slots(&mut self, h: &impl HierarchyRecords, from: usize, to: usize) {
        let to = to.min(self.triangles.len());
        let mut start = from;
        while start < to {
            let n = (to - start).min(BATCH);
            let g = self.gather(h, start as u32, n);
            for k in 0..n {
                self.triangles[start + k] = g.entry(h, k);
            }
            start += n;
        }
    }

    /// The first links of the chain for slots `start..start + n` (`n` at most [`BATCH`]),
    /// one link for every slot before the next (see the module docs); the vertex table is
    /// left to [`Gathered::entry`], so a caller can look it up while it hands out each
    /// triangle.
    pub fn gather<'h>(&self, h: &'h impl HierarchyRecords, start: u32, n: usize) -> Gathered<'h> {
        let n = n.min(BATCH);
        let mut g = Gathered {
            records: [None; BATCH],
            positions: [[NONE; 3]; BATCH],
        };
        // Link 1: the polygon each slot holds (a base polygon, or one side of the split that
        // owns the pair: the split record) and the node each corner's record holds.
        let mut ids = [PolyId::NONE; BATCH];
        for k in 0..n {
            let slot = start + k as u32;
            ids[k] = self.poly_at(h, slot).unwrap_or(PolyId::NONE);
            let held = self
                .slots
                .get(slot as usize)
                .map_or([NONE; 3], |s| s.corners);
            for (c, r) in g.positions[k].iter_mut().zip(held) {
                *c = self.node_of(r).map_or(NONE, |n| n.0);
            }
        }
        // Link 2: the polygon records, and each corner's position.
        for k in 0..n {
            g.records[k] = h.polygon(ids[k]);
            for c in &mut g.positions[k] {
                *c = h.node(NodeId(*c)).map_or(NONE, |n| n.position.0);
            }
        }
        g
    }
}

/// A batch of slots' polygon records and corner positions (see [`Front::gather`]).
pub(crate) struct Gathered<'h> {
    records: [Option<&'h Polygon>; BATCH],
    positions: [[u32; 3]; BATCH],
}

impl Gathered<'_> {
    /// Slot `k`'s entry: links 3 and 4 of the chain, the vertex table's row of each
    /// position and the group's entry in it.
    #[inline]
    pub fn entry(&self, h: &impl HierarchyRecords, k: usize) -> SlotTriangle {
        match (self.records.get(k), self.positions.get(k)) {
            (Some(&poly), Some(p)) => SlotTriangle::of(h, poly, p.map(PositionId)),
            _ => EMPTY,
        }
    }
}
