//! A hierarchy built on a welded store named back by the producer's positions and
//! triangles ([`crate::weld::store::Origins`]), for callers that hold the welded mesh the
//! store was made from.

use crate::hierarchy::Hierarchy;
use crate::weld::store::Origins;

const NONE: u32 = u32::MAX;

/// `h` (built on the store) with the store's positions and triangles named by their
/// origins: leaf `x` (position `x`) becomes leaf `origins.positions[x]`, triangle `f`
/// becomes `origins.triangles[f]`; the collapses' nodes keep their ids.
pub(super) fn to_origins(h: Hierarchy, origins: &Origins) -> Hierarchy {
    let np = origins.positions.len();
    let node = |v: u32| {
        if v == NONE || v as usize >= np {
            v
        } else {
            origins.positions[v as usize]
        }
    };
    let tri = |f: u32| {
        if f == NONE {
            NONE
        } else {
            origins.triangles[f as usize]
        }
    };
    let by_node = |values: &[f32]| {
        let mut out = values.to_vec();
        for (x, &v) in values[..np].iter().enumerate() {
            out[node(x as u32) as usize] = v;
        }
        out
    };
    let mut parent = h.parent.clone();
    let mut node_position = h.node_position.clone();
    let mut cone = h.cone.clone();
    for v in 0..h.parent.len() {
        let to = node(v as u32) as usize;
        parent[to] = node(h.parent[v]);
        node_position[to] = origins.positions[h.node_position[v] as usize];
        cone[to] = h.cone[v];
    }
    let mut corners = vec![[0u32; 3]; h.corners.len()];
    let mut alive = vec![false; h.alive.len()];
    for f in 0..h.corners.len() {
        let to = tri(f as u32) as usize;
        corners[to] = h.corners[f].map(node);
        alive[to] = h.alive[f];
    }
    Hierarchy {
        collapses: h
            .collapses
            .iter()
            .map(|c| crate::hierarchy::Collapse {
                t: node(c.t),
                u: node(c.u),
                fl: tri(c.fl),
                fr: tri(c.fr),
                neighbours: c.neighbours.map(tri),
                rot_l: c.rot_l,
                rot_r: c.rot_r,
            })
            .collect(),
        parent,
        node_position,
        radius: by_node(&h.radius),
        cone,
        error: by_node(&h.error),
        corners,
        alive,
        passes: h.passes,
    }
}
