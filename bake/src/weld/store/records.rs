//! The records of the welded store: a triangle, an attribute set, where the ids came from,
//! and some positions' vertex lists.

use bytemuck::{Pod, Zeroable};
use caveclod_core::format::PositionClass;

use crate::weld::{Attributes, WeldedTri};

/// One triangle as stored: its positions (counter-clockwise), surface group and surface.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct StoredTri {
    /// Position ids.
    pub p: [u32; 3],
    /// Surface group (before colouring, as [`WeldedTri::group`]).
    pub group: u32,
    /// Surface.
    pub surface: u16,
    /// Zero.
    pub reserved: u16,
}

impl StoredTri {
    /// Welded triangle `t` of surface `surface`.
    pub fn of(t: &WeldedTri, surface: u16) -> Self {
        Self {
            p: t.p,
            group: t.group,
            surface,
            reserved: 0,
        }
    }
}

/// One attribute set as stored ([`Attributes`], its flag a word).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub(crate) struct StoredAttributes {
    normal: [f32; 3],
    uv: [f32; 2],
    color: [f32; 4],
    normal_from_geometry: u32,
}

impl From<&Attributes> for StoredAttributes {
    fn from(a: &Attributes) -> Self {
        Self {
            normal: a.normal,
            uv: a.uv,
            color: a.color,
            normal_from_geometry: u32::from(a.normal_from_geometry),
        }
    }
}

impl From<StoredAttributes> for Attributes {
    fn from(a: StoredAttributes) -> Self {
        Self {
            normal: a.normal,
            uv: a.uv,
            color: a.color,
            normal_from_geometry: a.normal_from_geometry != 0,
        }
    }
}

/// Where the store's triangles and positions came from: the producer's id of each, by
/// store id. Kept when asked ([`super::StoreWriter::finish`]), for callers that map a result back
/// to the producer's numbering.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Origins {
    /// The pushed index of each stored triangle.
    pub triangles: Vec<u32>,
    /// The pushed index of each stored position.
    pub positions: Vec<u32>,
}

/// Some positions' vertex lists: position `i`'s entries are
/// `entries[start[i]..start[i + 1]]`, `[group, attribute set]` by group.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PositionLists {
    /// Where each position's entries start, and the end.
    pub start: Vec<u32>,
    /// `[group, attribute set]`.
    pub entries: Vec<[u32; 2]>,
}

impl PositionLists {
    /// Position `i`'s entries.
    pub fn of(&self, i: usize) -> &[[u32; 2]] {
        &self.entries[self.start[i] as usize..self.start[i + 1] as usize]
    }

    /// Positions.
    pub fn len(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// No position.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The surface of each of `groups` groups, from the triangles `stored` (a group lies on one
/// surface; a group without a triangle there gets surface 0).
pub(crate) fn group_surfaces(stored: &[StoredTri], groups: u32) -> Vec<u16> {
    let mut surfaces = vec![0u16; groups as usize];
    for t in stored {
        if let Some(s) = surfaces.get_mut(t.group as usize) {
            *s = t.surface;
        }
    }
    surfaces
}

/// A stored class.
pub(super) fn class(c: u8) -> PositionClass {
    PositionClass::from_u32(u32::from(c)).unwrap_or(PositionClass::Rigid)
}
