//! One block of a level: its triangles as a welded mesh of their own, positions renumbered,
//! with the positions it shares with other blocks frozen, read from the welded store.

use crate::weld::store::WeldedStore;
use crate::weld::{VertexLists, Welded, WeldedTri};

/// A block's mesh and how it maps to the whole.
pub(super) struct Block {
    /// The whole mesh's id of each of the block's triangles.
    pub(super) tris: Vec<u32>,
    /// The whole mesh's position of each of the block's positions (ascending).
    pub(super) positions: Vec<u32>,
    /// The block's mesh.
    pub(super) welded: Welded,
    /// Per block position: on the border with another block.
    pub(super) frozen: Vec<bool>,
}

/// The block of the triangles `tris` (ascending) of `store` as their corners stand now
/// (`corners`, the positions of the nodes at them); `shared[x]` says that position `x` has
/// triangles in other blocks too. Its triangles, positions and attribute sets are read from
/// the store, near ids in one read.
pub(super) fn extract(
    store: &WeldedStore,
    corners: &[[u32; 3]],
    tris: Vec<u32>,
    shared: &[bool],
) -> std::io::Result<Block> {
    let at = |f: u32, k: usize| corners[f as usize][k];
    let mut positions: Vec<u32> = tris
        .iter()
        .flat_map(|&f| (0..3).map(move |k| at(f, k)))
        .collect();
    positions.sort_unstable();
    positions.dedup();
    let local = |x: u32| positions.binary_search(&x).unwrap_or(0) as u32;
    let lists = store.gather_vertex_lists(&positions)?;
    let mut attrs: Vec<u32> = lists.entries.iter().map(|&[_, a]| a).collect();
    attrs.sort_unstable();
    attrs.dedup();
    let attr = |a: u32| attrs.binary_search(&a).unwrap_or(0) as u32;
    let stored = store.gather_triangles(&tris)?;
    let triangles = tris
        .iter()
        .zip(&stored)
        .map(|(&f, t)| {
            let p = [0, 1, 2].map(|k| at(f, k));
            WeldedTri {
                p: p.map(local),
                group: t.group,
            }
        })
        .collect();
    let info = store.info();
    let group_surfaces = crate::weld::store::group_surfaces(&stored, info.group_count);
    let vertices: VertexLists = (0..lists.len())
        .map(|x| lists.of(x).iter().map(|&[g, a]| (g, attr(a))))
        .collect();
    let welded = Welded {
        positions: store.gather_positions(&positions)?,
        classes: store.gather_classes(&positions)?,
        attributes: store.gather_attributes(&attrs)?,
        triangles,
        group_count: info.group_count,
        group_ids: info.group_ids.clone(),
        group_surfaces,
        group_id_count: info.group_id_count,
        surface_count: info.surface_count,
        has_colors: info.has_colors,
        vertices,
        repairs: Default::default(),
    };
    Ok(Block {
        frozen: positions.iter().map(|&x| shared[x as usize]).collect(),
        tris,
        positions,
        welded,
    })
}
