//! The tiled weld's run: the band collected, the tiles welded as many at once as there are
//! threads, each with its halo, and joined in tile order.

use std::io;

use rayon::prelude::*;

use super::error::TiledWeldError;
use super::join::Joiner;
use super::sink::{WeldSink, WeldedBuilder};
use super::tile::{weld_tile, TileWeld};
use super::tiles::{TileTriangle, Tiles, SHARED};
use crate::base::fxhash::{map_with_capacity, FxHashMap};
use crate::weld::welded::{WeldError, WeldInfo, Welded};

/// Welds, repairs and groups the mesh of `tiles`, tile by tile, into memory: the result of
/// [`crate::weld::weld`] (see the module's doc for where it may differ).
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
        let welds: Vec<Result<TileWeld, WeldError>> = batch
            .par_iter()
            .map(|(core, halo)| weld_tile(mesh, core, halo))
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
