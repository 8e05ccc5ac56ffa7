//! The weld of a mesh too large to hold, tile by tile: each tile welded by [`super::weld`]
//! itself (so the repairs stay one implementation), the tiles then joined where they meet.
//!
//! The input ([`Tiles`]) has its identical positions welded already (step 1: a position per
//! distinct coordinate triple, numbered in input order as [`super::weld`] numbers them) and
//! its triangles cut into tiles, a triangle in the tile of its centroid taken over its
//! corners in position order, so that a triangle and its duplicates (the same three
//! positions) always share a tile. A position is a *border* position when triangles of two
//! tiles use it; the *band* is the triangles with a border corner, a small part of the mesh
//! on any surface whose tiles follow its layout (a border is short against a tile's area).
//!
//! Each tile is welded with a *halo*: the band's triangles of other tiles that use one of its
//! positions. Every triangle around every position the tile's own triangles use is then in
//! the tile's mesh, in input order, so every decision the weld takes at those positions is
//! the one it takes on the whole mesh: which triangles are degenerate or duplicates, which
//! edges are cut (the later triangle on an over-used edge), the fans a position splits into
//! (copies are named by the first triangle of their fan, so tiles that share a fan name its
//! copy alike), the computed normals, and whether two triangles across an edge match. Only a
//! tile's own triangles are kept from its weld. What one tile cannot see is then joined
//! (`join`):
//! - surface groups: a tile's groups are joined with the groups of the matching triangles
//!   across its border (union-find over `(tile, group)`), refusing a join that would give a
//!   group two attribute sets at one position, as the in-core growth refuses a triangle;
//! - classes of the positions where groups meet or tiles meet, counted again from the joined
//!   groups (elsewhere every edge is inside one tile's group, and the tile's class stands);
//! - attribute sets, made distinct over the whole mesh, and the colouring of the joined
//!   groups (greedy, largest first, as [`super::weld`] colours).
//!
//! On a mesh where the in-core weld takes no order-dependent choice (a group's growth never
//! refused, no chain of cut edges longer than a triangle's reach) the result is
//! [`super::weld`]'s up to the numbering of positions, attribute sets, triangles and groups;
//! elsewhere it keeps the weld's invariants (every edge at most two triangles, one fan per
//! position, no group with two attribute sets at one position).
//!
//! The tiles come from a mesh in memory ([`MeshTiles`]) or a PLY file streamed into files
//! of tiles ([`StreamTiles`]); the result goes to a [`WeldSink`] piece by piece (the welded
//! store takes it so; [`WeldedBuilder`] makes a [`Welded`] of it), so nothing the size of
//! the whole mesh's triangles is ever in memory: only per position its coordinates, tile
//! and class, the distinct attribute sets, the band, and the tiles being welded.
//! [`crate::pipeline::import_and_weld`] chooses between this and the in-core import by the
//! file.

mod join;
mod mesh_input;
mod spool;
mod store_sink;
mod stream_input;
mod tile;

use std::io;

use bytemuck::{Pod, Zeroable};

pub use mesh_input::MeshTiles;
pub use stream_input::{StreamTiles, StreamedReport};

use caveclod_core::format::PositionClass;
use rayon::prelude::*;

use super::{Attributes, Repairs, VertexLists, WeldError, WeldInfo, Welded, WeldedTri, NONE};
use crate::base::fxhash::{map_with_capacity, FxHashMap};
use crate::weld::store::StoredTri;
use join::Joiner;

/// One input triangle: its welded positions and its corners' attributes as imported.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TileTriangle {
    /// The triangle's number in the input (the order the in-core weld reads triangles in).
    pub index: u32,
    /// Welded positions, counter-clockwise.
    pub p: [u32; 3],
    /// Per corner: normal (where [`TileTriangle::has`] says so).
    pub normal: [[f32; 3]; 3],
    /// Per corner: texture coordinates.
    pub uv: [[f32; 2]; 3],
    /// Per corner: linear RGBA colour.
    pub color: [[f32; 4]; 3],
    /// Bit `k`: corner `k` has a normal; bit `3 + k` texture coordinates; bit `6 + k` a colour.
    pub has: u16,
    /// Surface.
    pub surface: u16,
}

impl TileTriangle {
    /// Whether corner `k` has a normal.
    pub fn has_normal(&self, k: usize) -> bool {
        self.has & 1 << k != 0
    }

    /// Whether corner `k` has texture coordinates.
    pub fn has_uv(&self, k: usize) -> bool {
        self.has & 1 << (3 + k) != 0
    }

    /// Whether corner `k` has a colour.
    pub fn has_color(&self, k: usize) -> bool {
        self.has & 1 << (6 + k) != 0
    }
}

/// What a tiled input tells besides its tiles.
#[derive(Clone, Debug, Default)]
pub struct TiledMesh {
    /// The welded positions.
    pub positions: Vec<[f32; 3]>,
    /// Per position: the tile whose triangles use it, [`SHARED`] when triangles of several
    /// tiles do, `u32::MAX` when none does.
    pub owner: Vec<u32>,
    /// Input points merged into an identical one (step 1).
    pub welded_positions: u64,
    /// Surfaces of the input (at least one).
    pub surface_count: u32,
    /// Whether any input triangle has a colour.
    pub has_colors: bool,
}

/// A position used by triangles of several tiles.
pub const SHARED: u32 = NONE - 1;

/// A mesh cut into tiles.
pub trait Tiles {
    /// The positions and what else the whole input tells.
    fn mesh(&self) -> &TiledMesh;
    /// Number of tiles.
    fn tile_count(&self) -> usize;
    /// The triangles of tile `tile`, in input order, into `out` (cleared first).
    fn read(&mut self, tile: usize, out: &mut Vec<TileTriangle>) -> io::Result<()>;
}

/// Why a tiled weld failed.
#[derive(Debug, thiserror::Error)]
pub enum TiledWeldError {
    /// The weld itself failed, as the in-core weld would.
    #[error(transparent)]
    Weld(#[from] WeldError),
    /// Reading a tile failed.
    #[error("reading the tiles: {0}")]
    Io(#[from] io::Error),
}

/// Receives a welded mesh piece by piece, as the welded store takes it.
pub trait WeldSink {
    /// The next position (ids in push order), its class, and its vertices: `[surface group,
    /// attribute set]` of each group with a vertex there, by group, each group once.
    fn push_position(
        &mut self,
        xyz: [f32; 3],
        class: PositionClass,
        vertices: &[[u32; 2]],
    ) -> io::Result<()>;
    /// The next attribute sets (ids in push order).
    fn push_attributes(&mut self, attributes: &[Attributes]) -> io::Result<()>;
    /// Triangles, in any order, each with its group and surface.
    fn push_triangles(&mut self, triangles: &[StoredTri]) -> io::Result<()>;
}

/// A [`WeldSink`] into a [`Welded`] in memory.
#[derive(Default)]
pub struct WeldedBuilder {
    w: Welded,
    lists: Vec<Vec<(u32, u32)>>,
}

impl WeldSink for WeldedBuilder {
    fn push_position(
        &mut self,
        xyz: [f32; 3],
        class: PositionClass,
        vertices: &[[u32; 2]],
    ) -> io::Result<()> {
        self.w.positions.push(xyz);
        self.w.classes.push(class);
        self.lists
            .push(vertices.iter().map(|&[g, a]| (g, a)).collect());
        Ok(())
    }

    fn push_attributes(&mut self, attributes: &[Attributes]) -> io::Result<()> {
        self.w.attributes.extend_from_slice(attributes);
        Ok(())
    }

    fn push_triangles(&mut self, triangles: &[StoredTri]) -> io::Result<()> {
        let w = &mut self.w;
        for t in triangles {
            let g = t.group as usize;
            if g >= w.group_surfaces.len() {
                w.group_surfaces.resize(g + 1, 0);
            }
            w.group_surfaces[g] = t.surface;
            w.triangles.push(WeldedTri {
                p: t.p,
                group: t.group,
            });
        }
        Ok(())
    }
}

impl WeldedBuilder {
    /// The welded mesh, with `summary`.
    pub fn finish(self, summary: WeldInfo) -> Welded {
        let mut w = self.w;
        w.vertices = self
            .lists
            .iter()
            .map(|l| l.iter().copied())
            .collect::<VertexLists>();
        w.group_count = summary.group_count;
        w.group_ids = summary.group_ids;
        w.group_surfaces.resize(summary.group_count as usize, 0);
        w.group_id_count = summary.group_id_count;
        w.surface_count = summary.surface_count;
        w.has_colors = summary.has_colors;
        w.repairs = summary.repairs;
        w
    }
}

/// Welds, repairs and groups the mesh of `tiles`, tile by tile, into memory: [`super::weld`]'s
/// result (see the module's doc for where it may differ).
pub fn weld_tiled(tiles: &mut dyn Tiles) -> Result<Welded, TiledWeldError> {
    let mut b = WeldedBuilder::default();
    let summary = weld_tiled_into(tiles, &mut b)?;
    Ok(b.finish(summary))
}

/// Welds, repairs and groups the mesh of `tiles`, tile by tile, into `sink`; returns what
/// else the weld tells.
pub fn weld_tiled_into(
    tiles: &mut dyn Tiles,
    sink: &mut dyn WeldSink,
) -> Result<WeldInfo, TiledWeldError> {
    let band = Band::collect(tiles)?;
    let mut joiner = Joiner::new(tiles.mesh())?;
    // As many tiles at once as there are threads, joined in tile order.
    let at_once = rayon::current_num_threads().max(1);
    let mut tile = 0;
    while tile < tiles.tile_count() {
        let mut batch: Vec<(Vec<TileTriangle>, Vec<TileTriangle>)> = Vec::new();
        while batch.len() < at_once && tile < tiles.tile_count() {
            let mut core = Vec::new();
            tiles.read(tile, &mut core)?;
            if !core.is_empty() {
                let halo = band.halo_of(tile as u32, &core, &tiles.mesh().owner);
                batch.push((core, halo));
            }
            tile += 1;
        }
        let mesh = tiles.mesh();
        let welds: Vec<Result<tile::TileWeld, WeldError>> = batch
            .par_iter()
            .map(|(core, halo)| tile::weld_tile(mesh, core, halo))
            .collect();
        drop(batch);
        for w in welds {
            joiner.add(w?)?;
        }
    }
    drop(band);
    joiner.finish(tiles.mesh(), sink)
}

/// The band: every triangle with a border corner, and the band's triangles at each border
/// position.
struct Band {
    /// `(tile, triangle)`.
    triangles: Vec<(u32, TileTriangle)>,
    /// Per border position, the band triangles (indices into `triangles`) that use it.
    at: FxHashMap<u32, Vec<u32>>,
}

impl Band {
    fn collect(tiles: &mut dyn Tiles) -> io::Result<Self> {
        let mut band = Band {
            triangles: Vec::new(),
            at: map_with_capacity(0),
        };
        let mut buf = Vec::new();
        for t in 0..tiles.tile_count() {
            tiles.read(t, &mut buf)?;
            let owner = &tiles.mesh().owner;
            for tri in &buf {
                if tri.p.iter().any(|&x| owner[x as usize] == SHARED) {
                    let i = band.triangles.len() as u32;
                    band.triangles.push((t as u32, *tri));
                    for &x in &tri.p {
                        if owner[x as usize] == SHARED {
                            let list = band.at.entry(x).or_default();
                            if list.last() != Some(&i) {
                                list.push(i);
                            }
                        }
                    }
                }
            }
        }
        Ok(band)
    }

    /// The halo of tile `tile` whose triangles are `core`: the band's triangles of other tiles
    /// at its border positions, in input order.
    fn halo_of(&self, tile: u32, core: &[TileTriangle], owner: &[u32]) -> Vec<TileTriangle> {
        let mut ids: Vec<u32> = core
            .iter()
            .flat_map(|t| t.p)
            .filter(|&x| owner[x as usize] == SHARED)
            .flat_map(|x| self.at.get(&x).into_iter().flatten().copied())
            .filter(|&i| self.triangles[i as usize].0 != tile)
            .collect();
        ids.sort_unstable();
        ids.dedup();
        let mut halo: Vec<TileTriangle> =
            ids.iter().map(|&i| self.triangles[i as usize].1).collect();
        halo.sort_unstable_by_key(|t| t.index);
        halo
    }
}

/// The repairs of the tiles' own triangles, summed.
fn add_repairs(total: &mut Repairs, r: &Repairs) {
    total.degenerate_triangles += r.degenerate_triangles;
    total.duplicate_triangles += r.duplicate_triangles;
    total.non_manifold_edges += r.non_manifold_edges;
    total.non_manifold_vertices += r.non_manifold_vertices;
    total.computed_normals += r.computed_normals;
}
