//! The records a camera keeps in its words, and the values that mark them: a polygon slot
//! ([`PolySlot`]), an active-vertex record ([`ActiveVertex`]), an index-cache entry
//! ([`SlotTriangle`]).

use bytemuck::{Pod, Zeroable};

use crate::hierarchy::HierarchyRecords;
use crate::ids::NodeId;

/// Absent link / empty entry.
pub(crate) const NONE: u32 = u32::MAX;
/// Tag of a free active-vertex record; the low bits chain the free list.
pub(crate) const FREE: u32 = 1 << 31;

/// A certificate that says nothing: it holds at no odometer reading, read as either sign
/// (see `certificate`).
pub(crate) const UNKNOWN: f32 = 0.0;

/// The current state of one active polygon.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub(crate) struct PolySlot {
    /// Active-vertex records of the three corners.
    pub corners: [u32; 3],
    /// Slots of the neighbours; `neighbours[j]` lies across the edge opposite corner `j`.
    pub neighbours: [u32; 3],
}

pub(crate) const SLOT_WORDS: usize = core::mem::size_of::<PolySlot>() / 4;

/// An active-vertex record: the active node it holds and that node's coarsening parent.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub(crate) struct ActiveVertex {
    /// The node (a [`NodeId`]), or [`FREE`] with the free-list link in the low bits.
    pub node: u32,
    /// The node's parent if the node is the parent's stationary child (the collapse this
    /// node's visits may trigger), else `NONE`.
    pub coarsen: u32,
    /// Own certificate: while the camera's path odometer reads less (positive) or its sweep
    /// reads less than the magnitude (negative), the node's own split is certainly not
    /// wanted, and a visit need not read its bounds (see `certificate`); 0 when unknown.
    pub own_cert: f32,
    /// Parent certificate: while the camera's sweep reads less than the magnitude, the
    /// coarsening parent's split is certainly still wanted (positive: no collapse) or
    /// certainly not wanted (negative: collapse if legal); 0 when unknown.
    pub parent_cert: f32,
}

pub(crate) const ACTIVE_WORDS: usize = core::mem::size_of::<ActiveVertex>() / 4;

/// A slot's entry in the index cache: its polygon's vertex indices (`NONE` where a corner
/// has no vertex in the polygon's surface group), surface and surface group (`surface` is
/// [`NO_POLYGON`] for a slot without a polygon: the right side of a split on a border).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub(crate) struct SlotTriangle {
    pub indices: [u32; 3],
    pub surface: u16,
    pub group: u16,
}

/// The surface of a slot without a polygon (validation keeps surface ids below it).
pub(crate) const NO_POLYGON: u16 = u16::MAX;

pub(crate) const TRIANGLE_WORDS: usize = core::mem::size_of::<SlotTriangle>() / 4;

impl ActiveVertex {
    /// The record of `node`, with its coarsening parent read from the node records: its
    /// parent if that has a split and the two share a position.
    #[inline]
    pub fn of(h: &impl HierarchyRecords, node: NodeId) -> Self {
        let coarsen = h
            .node(node)
            .and_then(|n| {
                let p = h.node(n.parent)?;
                (p.position == n.position && h.split_bounds(n.parent).is_some())
                    .then_some(n.parent.0)
            })
            .unwrap_or(NONE);
        Self {
            node: node.0,
            coarsen,
            own_cert: UNKNOWN,
            parent_cert: UNKNOWN,
        }
    }
}

/// The next corner round a triangle.
#[inline]
pub(crate) fn next(j: usize) -> usize {
    if j == 2 {
        0
    } else {
        j + 1
    }
}

/// The previous corner round a triangle.
#[inline]
pub(crate) fn prev(j: usize) -> usize {
    if j == 0 {
        2
    } else {
        j - 1
    }
}
