//! One block of a level: its triangles as a welded mesh of their own, positions renumbered,
//! with the positions it shares with other blocks frozen.

use crate::weld::Welded;

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

/// The block of the triangles `tris` of `w` as their corners stand now (`corners`, the
/// positions of the nodes at them); `shared[x]` says that position `x` has triangles in
/// other blocks too.
pub(super) fn extract(w: &Welded, corners: &[[u32; 3]], tris: Vec<u32>, shared: &[bool]) -> Block {
    let at = |f: u32, k: usize| corners[f as usize][k];
    let mut positions: Vec<u32> = tris
        .iter()
        .flat_map(|&f| (0..3).map(move |k| at(f, k)))
        .collect();
    positions.sort_unstable();
    positions.dedup();
    let local = |x: u32| positions.binary_search(&x).unwrap_or(0) as u32;
    let mut attrs: Vec<u32> = positions
        .iter()
        .flat_map(|&x| w.vertices[x as usize].iter().map(|&(_, a)| a))
        .collect();
    attrs.sort_unstable();
    attrs.dedup();
    let attr = |a: u32| attrs.binary_search(&a).unwrap_or(0) as u32;
    let triangles = tris
        .iter()
        .map(|&f| {
            let t = w.triangles[f as usize];
            let p = [0, 1, 2].map(|k| at(f, k));
            // A corner's attributes are its position's vertex of the triangle's group.
            let a = [0, 1, 2].map(|k| {
                let vs = &w.vertices[p[k] as usize];
                let found = vs.iter().find(|&&(g, _)| g == t.group);
                attr(found.map_or(vs[0].1, |&(_, a)| a))
            });
            crate::weld::WeldedTri {
                p: p.map(local),
                a,
                surface: t.surface,
                group: t.group,
            }
        })
        .collect();
    let welded = Welded {
        positions: positions.iter().map(|&x| w.positions[x as usize]).collect(),
        classes: positions.iter().map(|&x| w.classes[x as usize]).collect(),
        attributes: attrs.iter().map(|&a| w.attributes[a as usize]).collect(),
        triangles,
        group_count: w.group_count,
        group_ids: w.group_ids.clone(),
        group_id_count: w.group_id_count,
        surface_count: w.surface_count,
        has_colors: w.has_colors,
        vertices: positions
            .iter()
            .map(|&x| w.vertices[x as usize].iter().map(|&(g, a)| (g, attr(a))))
            .collect(),
        repairs: Default::default(),
    };
    Block {
        frozen: positions.iter().map(|&x| shared[x as usize]).collect(),
        tris,
        positions,
        welded,
    }
}
