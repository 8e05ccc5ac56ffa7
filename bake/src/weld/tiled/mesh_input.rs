//! A mesh in memory cut into tiles: the tiled weld's input for a mesh that fits, and the
//! reference its streamed input is tested against.

use std::io;

use super::tiles::{TileTriangle, TiledMesh, Tiles, SHARED};
use crate::mesh::{Mesh, NO_ATTRIBUTE};
use crate::weld::in_core::check_weldable;
use crate::weld::repair;
use crate::weld::welded::{Repairs, WeldError, NONE};

/// A [`Mesh`] cut into `side × side` tiles over its bounding box's two widest axes.
pub struct MeshTiles {
    mesh: TiledMesh,
    tiles: Vec<Vec<TileTriangle>>,
}

impl MeshTiles {
    /// Welds the positions of `mesh` (step 1 of [`super::super::weld`]) and cuts its
    /// triangles into `side × side` tiles.
    pub fn new(mesh: &Mesh, side: u32) -> Result<Self, WeldError> {
        check_weldable(mesh)?;
        let mut repairs = Repairs::default();
        let (positions, remap) = repair::weld_positions(mesh, &mut repairs);
        let grid = TileGrid::new(&positions, side);
        let mut tiles = vec![Vec::new(); (side * side) as usize];
        let mut owner = vec![NONE; positions.len()];
        let get = |v: &[[f32; 3]], i: u32| v.get(i as usize).copied();
        for (i, t) in mesh.triangles.iter().enumerate() {
            let p = t.position.map(|x| remap[x as usize]);
            let mut tri = TileTriangle {
                index: i as u32,
                p,
                surface: t.surface,
                ..TileTriangle::default()
            };
            for k in 0..3 {
                if let Some(n) =
                    get(&mesh.normals, t.normal[k]).filter(|_| t.normal[k] != NO_ATTRIBUTE)
                {
                    tri.normal[k] = n;
                    tri.has |= 1 << k;
                }
                if let Some(uv) = mesh.uvs.get(t.uv[k] as usize) {
                    tri.uv[k] = *uv;
                    tri.has |= 1 << (3 + k);
                }
                if let Some(c) = mesh.colors.get(t.color[k] as usize) {
                    tri.color[k] = *c;
                    tri.has |= 1 << (6 + k);
                }
            }
            let tile = grid.tile_of(&positions, p);
            for &x in &p {
                let o = &mut owner[x as usize];
                if *o == NONE {
                    *o = tile;
                } else if *o != tile {
                    *o = SHARED;
                }
            }
            tiles[tile as usize].push(tri);
        }
        let has_colors = mesh.triangles.iter().any(|t| {
            t.color
                .iter()
                .any(|&c| c != NO_ATTRIBUTE && (c as usize) < mesh.colors.len())
        });
        Ok(Self {
            mesh: TiledMesh {
                positions,
                owner,
                welded_positions: repairs.welded_positions,
                surface_count: mesh.surfaces.len().max(1) as u32,
                has_colors,
            },
            tiles,
        })
    }
}

impl Tiles for MeshTiles {
    fn mesh(&self) -> &TiledMesh {
        &self.mesh
    }

    fn tile_count(&self) -> usize {
        self.tiles.len()
    }

    fn read(&mut self, tile: usize, out: &mut Vec<TileTriangle>) -> io::Result<()> {
        out.clear();
        out.extend_from_slice(&self.tiles[tile]);
        Ok(())
    }
}

/// Square tiles over the plane of a bounding box's two widest axes; a triangle in the tile
/// of its centroid, summed over its corners in position order (so a triangle and its
/// duplicates, however turned, share a tile).
#[derive(Clone, Copy, Debug)]
pub(crate) struct TileGrid {
    side: u32,
    axes: [usize; 2],
    lo: [f64; 2],
    size: [f64; 2],
}

impl TileGrid {
    /// The grid of `side × side` tiles over the box around `positions`.
    pub(crate) fn new(positions: &[[f32; 3]], side: u32) -> Self {
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for p in positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        Self::around(lo, hi, side)
    }

    /// The grid of `side × side` tiles over the box `lo..hi`.
    pub(crate) fn around(lo: [f32; 3], hi: [f32; 3], side: u32) -> Self {
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| (hi[b] - lo[b]).total_cmp(&(hi[a] - lo[a])));
        let axes = [order[0], order[1]];
        Self {
            side: side.max(1),
            axes,
            lo: axes.map(|a| f64::from(lo[a])),
            size: axes.map(|a| f64::from(hi[a] - lo[a]).max(f64::MIN_POSITIVE)),
        }
    }

    /// The tile of the triangle of welded positions `p`.
    pub(crate) fn tile_of(&self, positions: &[[f32; 3]], p: [u32; 3]) -> u32 {
        let mut sorted = p;
        sorted.sort_unstable();
        let c = sorted.map(|x| positions.get(x as usize).copied().unwrap_or_default());
        let cell = |k: usize| {
            let a = self.axes[k];
            let centroid = (f64::from(c[0][a]) + f64::from(c[1][a]) + f64::from(c[2][a])) / 3.0;
            let t = ((centroid - self.lo[k]) / self.size[k] * f64::from(self.side)).floor();
            (t.max(0.0) as u32).min(self.side - 1)
        };
        cell(0) + cell(1) * self.side
    }
}
