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
//!
//! This module holds the preconditions, the remembered refusals and the camera's public
//! operations; applying a split (and the forced split) is in `split`, applying a collapse in
//! `collapse`.

mod collapse;
mod split;

use super::certificate::Odometer;
use super::records::{PolySlot, NONE};
use super::state::{CameraState, Front};
use crate::hierarchy::HierarchyRecords;
use crate::ids::{NodeId, PolyKey};
use crate::params::ParamsError;

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
    /// A split needs records of a page that is not resident (a streamed hierarchy): the
    /// split waits, and the page is wanted. Splits forced before it stay: each was legal.
    Absent {
        /// The node whose split waits.
        node: NodeId,
        /// The page its records lie in.
        page: crate::stream::PageKey,
    },
    /// Refinement parameters out of range ([`RefineParams::validate`](crate::RefineParams::validate)):
    /// the pass did nothing.
    InvalidParams(ParamsError),
}

impl From<ParamsError> for OpError {
    fn from(e: ParamsError) -> Self {
        Self::InvalidParams(e)
    }
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
            Self::Absent { node, page } => write!(
                f,
                "the split of node {} waits for page {} of file {}",
                node.0, page.page, page.file
            ),
            Self::InvalidParams(e) => write!(f, "refinement parameters refused: {e}"),
        }
    }
}

impl core::error::Error for OpError {}

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
    pub fn split_slots(&self, h: &impl HierarchyRecords, v: NodeId) -> Option<[u32; 4]> {
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

    pub fn can_split(&self, h: &impl HierarchyRecords, v: NodeId) -> bool {
        self.split_slots(h, v).is_some()
    }

    /// The slots of `v`'s neighbours (`NONE` for absent ones) if the collapse into `v` is
    /// legal: both children active and `f_l`, `f_r` linked exactly as the split left them.
    #[inline]
    pub fn collapse_slots(&self, h: &impl HierarchyRecords, v: NodeId) -> Option<[u32; 4]> {
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

    pub fn can_collapse(&self, h: &impl HierarchyRecords, v: NodeId) -> bool {
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
}

impl CameraState<'_> {
    fn check(&self, h: &impl HierarchyRecords) -> Result<(), OpError> {
        if self.is_for(h) {
            Ok(())
        } else {
            Err(OpError::WrongHierarchy)
        }
    }

    /// `true` if `node` is active, can be split, and every present `fn0..fn3` is active.
    pub fn can_split(&self, h: &impl HierarchyRecords, node: NodeId) -> bool {
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
        self.front.odometer = Odometer::new();
    }

    /// `true` if `node` is split, both children are active, and `f_l`, `f_r` have exactly
    /// the neighbours the split gave them.
    pub fn can_collapse(&self, h: &impl HierarchyRecords, node: NodeId) -> bool {
        self.is_for(h) && self.front.can_collapse(h, node)
    }

    /// Splits active `node` if [`can_split`](Self::can_split); [`OpError::Absent`] if its
    /// records lie in a page that is not resident (a streamed hierarchy).
    pub fn split(&mut self, h: &impl HierarchyRecords, node: NodeId) -> Result<(), OpError> {
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
        h.split_ready(node).map_err(|a| OpError::Absent {
            node: a.node,
            page: a.page,
        })?;
        let slots = self
            .front
            .split_slots(h, node)
            .ok_or(OpError::Illegal { node })?;
        self.front.apply_split(h, node, slots)
    }

    /// Collapses the children of `node` back into it if [`can_collapse`](Self::can_collapse).
    pub fn collapse(&mut self, h: &impl HierarchyRecords, node: NodeId) -> Result<(), OpError> {
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
        h: &impl HierarchyRecords,
        node: NodeId,
        stack: &mut [NodeId],
    ) -> Result<u32, OpError> {
        self.check(h)?;
        self.front.force_split(h, node, stack, u32::MAX)
    }

    /// [`force_split`](Self::force_split) with the camera's own stack.
    pub fn force_split_own_stack(
        &mut self,
        h: &impl HierarchyRecords,
        node: NodeId,
    ) -> Result<u32, OpError> {
        self.check(h)?;
        self.front.force_split(h, node, self.stack, u32::MAX)
    }
}
