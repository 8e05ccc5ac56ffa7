//! Reading the welded store: its arrays by range or by ids, its blocks, and the whole
//! welded mesh back into memory.

use std::ops::Range;

use caveclod_core::format::PositionClass;

use super::column::Column;
use super::records::{class, group_surfaces, Origins, PositionLists, StoredAttributes, StoredTri};
use crate::weld::{Attributes, VertexLists, WeldInfo, Welded, WeldedTri};

/// A welded mesh on disk in block order (see the module's doc).
#[derive(Debug)]
pub struct WeldedStore {
    pub(super) positions: Column<[f32; 3]>,
    pub(super) classes: Column<u8>,
    /// `vertex_start[p]..vertex_start[p + 1]`: position `p`'s range of `vertices`.
    pub(super) vertex_start: Column<u32>,
    pub(super) vertices: Column<[u32; 2]>,
    pub(super) attributes: Column<StoredAttributes>,
    pub(super) triangles: Column<StoredTri>,
    pub(super) info: WeldInfo,
    pub(super) bounds: ([f32; 3], [f32; 3]),
    /// First-level tiles along each axis (a power of two).
    pub(super) side: u32,
    /// The first triangle of each first-level tile in Z order, and the end.
    pub(super) tile_start: Vec<u32>,
    pub(super) origins: Option<Origins>,
}

impl WeldedStore {
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
