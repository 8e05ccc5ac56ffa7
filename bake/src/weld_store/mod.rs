//! A welded mesh on disk: the arrays of a [`Welded`] in unlinked temporary files, ordered so
//! that each block of a blocked build ([`crate::blocked`]) is read with a few positioned
//! reads, and only small indexes in memory.
//!
//! The order (made by [`StoreWriter::finish`] from pieces pushed in any order):
//! - triangles by the tile of their centroid in the Z (Morton) order of the first level's
//!   `side × side` tiles, in push order within a tile. A tile of the next level is four
//!   consecutive tiles of this one, so every block of every level is one range of triangle
//!   ids ([`WeldedStore::block`]);
//! - positions by first use in that triangle order (corners in order), positions no triangle
//!   uses last: a block's positions are mostly one range, its border's in a few runs;
//! - attribute sets by first use in the positions' vertex lists in that position order;
//! - each position's vertex list `(surface group, attribute set)`, by group.
//!
//! A corner's attributes are its position's vertex of the triangle's group, so triangles
//! store no attribute ids ([`StoredTri`]).

mod column;
mod writer;

pub use writer::StoreWriter;

use std::ops::Range;

use bytemuck::{Pod, Zeroable};
use caveclod_core::format::PositionClass;

use crate::weld::{Attributes, VertexLists, WeldInfo, Welded, WeldedTri};
use column::Column;

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
/// store id. Kept when asked ([`StoreWriter::finish`]), for callers that map a result back
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

/// A welded mesh on disk in block order (see the module's doc).
#[derive(Debug)]
pub struct WeldedStore {
    positions: Column<[f32; 3]>,
    classes: Column<u8>,
    /// `vertex_start[p]..vertex_start[p + 1]`: position `p`'s range of `vertices`.
    vertex_start: Column<u32>,
    vertices: Column<[u32; 2]>,
    attributes: Column<StoredAttributes>,
    triangles: Column<StoredTri>,
    info: WeldInfo,
    bounds: ([f32; 3], [f32; 3]),
    /// First-level tiles along each axis (a power of two).
    side: u32,
    /// The first triangle of each first-level tile in Z order, and the end.
    tile_start: Vec<u32>,
    origins: Option<Origins>,
}

impl WeldedStore {
    /// Stores `w` in block order for first-level tiles of about `block_triangles` triangles
    /// (keeping the [`Origins`] when `keep_origins`), freeing each of its arrays once
    /// stored.
    pub fn from_welded(
        w: Welded,
        block_triangles: usize,
        keep_origins: bool,
    ) -> std::io::Result<Self> {
        let info = WeldInfo::of(&w);
        let Welded {
            positions,
            classes,
            attributes,
            triangles,
            vertices,
            group_surfaces,
            ..
        } = w;
        let mut out = StoreWriter::new()?;
        for (x, (p, c)) in positions.iter().zip(&classes).enumerate() {
            let list: Vec<[u32; 2]> = vertices[x].iter().map(|&(g, a)| [g, a]).collect();
            out.push_position(*p, *c, &list)?;
        }
        drop((positions, classes, vertices));
        for a in attributes.chunks(1 << 16) {
            out.push_attributes(a)?;
        }
        drop(attributes);
        let mut stored = Vec::with_capacity(1 << 16);
        for chunk in triangles.chunks(1 << 16) {
            stored.clear();
            stored.extend(
                chunk
                    .iter()
                    .map(|t| StoredTri::of(t, group_surfaces[t.group as usize])),
            );
            out.push_triangles(&stored)?;
        }
        drop(triangles);
        out.finish(info, block_triangles, keep_origins)
    }

    /// Positions.
    pub fn positions(&self) -> usize {
        self.positions.len()
    }

    /// Triangles.
    pub fn triangles(&self) -> usize {
        self.triangles.len()
    }

    /// Attribute sets.
    pub fn attribute_sets(&self) -> usize {
        self.attributes.len()
    }

    /// Vertices (vertex-list entries) in all.
    pub fn vertices(&self) -> usize {
        self.vertices.len()
    }

    /// The small fields.
    pub fn info(&self) -> &WeldInfo {
        &self.info
    }

    /// The positions' bounding box `(min, max)` (zero when there is none).
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        self.bounds
    }

    /// First-level tiles along each axis.
    pub fn side(&self) -> u32 {
        self.side
    }

    /// Where the ids came from, if kept.
    pub fn origins(&self) -> Option<&Origins> {
        self.origins.as_ref()
    }

    /// The triangles of block `code` (Z order) of level `level`, whose blocks are tiles of
    /// `2^level × 2^level` first-level tiles.
    pub fn block(&self, level: u32, code: u32) -> Range<u32> {
        let tiles = self.tile_start.len() - 1;
        let first = ((code as usize) << (2 * level)).min(tiles);
        let end = ((code as usize + 1) << (2 * level)).min(tiles);
        self.tile_start[first]..self.tile_start[end]
    }

    /// Blocks of level `level`.
    pub fn blocks(&self, level: u32) -> u32 {
        let side = (self.side >> level).max(1);
        side * side
    }

    /// Triangles `range`.
    pub fn read_triangles(&self, range: Range<u32>) -> std::io::Result<Vec<StoredTri>> {
        self.triangles
            .read(range.start as usize..range.end as usize)
    }

    /// Positions `range`.
    pub fn read_positions(&self, range: Range<u32>) -> std::io::Result<Vec<[f32; 3]>> {
        self.positions
            .read(range.start as usize..range.end as usize)
    }

    /// The positions `ids` (ascending, each once).
    pub fn gather_positions(&self, ids: &[u32]) -> std::io::Result<Vec<[f32; 3]>> {
        self.positions.gather(ids)
    }

    /// The triangles `ids` (ascending, each once).
    pub fn gather_triangles(&self, ids: &[u32]) -> std::io::Result<Vec<StoredTri>> {
        self.triangles.gather(ids)
    }

    /// The classes of positions `ids` (ascending, each once).
    pub fn gather_classes(&self, ids: &[u32]) -> std::io::Result<Vec<PositionClass>> {
        Ok(self.classes.gather(ids)?.into_iter().map(class).collect())
    }

    /// The classes of positions `range`.
    pub fn read_classes(&self, range: Range<u32>) -> std::io::Result<Vec<PositionClass>> {
        let stored = self
            .classes
            .read(range.start as usize..range.end as usize)?;
        Ok(stored.into_iter().map(class).collect())
    }

    /// The vertex lists of positions `ids` (ascending, each once).
    pub fn gather_vertex_lists(&self, ids: &[u32]) -> std::io::Result<PositionLists> {
        let mut starts = Vec::with_capacity(2 * ids.len());
        for &x in ids {
            starts.extend([x, x + 1]);
        }
        starts.dedup();
        let at = self.vertex_start.gather(&starts)?;
        let mut wanted = Vec::new();
        let mut start = Vec::with_capacity(ids.len() + 1);
        start.push(0u32);
        let mut k = 0;
        for &x in ids {
            while starts[k] != x {
                k += 1;
            }
            wanted.extend(at[k]..at[k + 1]);
            start.push(wanted.len() as u32);
        }
        let entries = self.vertices.gather(&wanted)?;
        Ok(PositionLists { start, entries })
    }

    /// The vertex lists of positions `range`.
    pub fn read_vertex_lists(&self, range: Range<u32>) -> std::io::Result<PositionLists> {
        let at = self
            .vertex_start
            .read(range.start as usize..range.end as usize + 1)?;
        let entries = self
            .vertices
            .read(at[0] as usize..at[at.len() - 1] as usize)?;
        let start = at.iter().map(|&s| s - at[0]).collect();
        Ok(PositionLists { start, entries })
    }

    /// Where the vertex lists of positions `range` start in the store's list of all
    /// vertices (entry `p` of `0..=positions`: the vertex lists' ends before position `p`).
    pub fn read_vertex_starts(&self, range: Range<u32>) -> std::io::Result<Vec<u32>> {
        self.vertex_start
            .read(range.start as usize..range.end as usize)
    }

    /// The attribute sets `ids` (ascending, each once).
    pub fn gather_attributes(&self, ids: &[u32]) -> std::io::Result<Vec<Attributes>> {
        let stored = self.attributes.gather(ids)?;
        Ok(stored.into_iter().map(Attributes::from).collect())
    }

    /// The whole welded mesh in memory, in the store's order; each corner's attributes are
    /// its position's vertex of the triangle's group.
    pub fn into_welded(self) -> std::io::Result<Welded> {
        let np = self.positions() as u32;
        let lists = self.read_vertex_lists(0..np)?;
        let stored = self.triangles.read_all()?;
        let group_surfaces = group_surfaces(&stored, self.info.group_count);
        let triangles = stored
            .iter()
            .map(|t| WeldedTri {
                p: t.p,
                group: t.group,
            })
            .collect();
        drop(stored);
        let vertices: VertexLists = (0..lists.len())
            .map(|x| lists.of(x).iter().map(|&[g, a]| (g, a)))
            .collect();
        Ok(Welded {
            positions: self.positions.read_all()?,
            classes: self.read_classes(0..np)?,
            attributes: self
                .attributes
                .read_all()?
                .into_iter()
                .map(Attributes::from)
                .collect(),
            triangles,
            group_count: self.info.group_count,
            group_ids: self.info.group_ids,
            group_surfaces,
            group_id_count: self.info.group_id_count,
            surface_count: self.info.surface_count,
            has_colors: self.info.has_colors,
            vertices,
            repairs: self.info.repairs,
        })
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
fn class(c: u8) -> PositionClass {
    PositionClass::from_u32(u32::from(c)).unwrap_or(PositionClass::Rigid)
}
