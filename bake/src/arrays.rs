//! The `.clod` arrays computed from a welded mesh and its collapses, one array at a time:
//! the numbering of nodes and polygons into file order (the small tables every array needs),
//! then each array from the numbering. [`crate::baked::Baked::new`] keeps them all;
//! [`crate::streamed`] writes each as soon as it is made and drops it.
//!
//! Node ids: splittable nodes first, in depth-first preorder (stationary child first, roots
//! in position order), so a subtree is one id range and a stationary child sits next to its
//! parent — the records a refinement pass reads together lie together. Leaves follow in
//! position order. Polygons: the base mesh first, then each split's `f_l` and `f_r` in split
//! order.

use caveclod_core::format::{
    BaseFace, Creator, Meta, Node, Polygon, Position, Split, SplitBounds, Vertex, VertexKey,
};
use caveclod_core::{NodeId, PolyId, PolyKey, PositionId, SurfaceGroupId, SurfaceId};

use crate::hierarchy::Hierarchy as Collapses;
use crate::materials::encode_colour;
use crate::weld::Welded;

const NONE: u32 = u32::MAX;

/// Node ids in file order: the collapses' nodes (splittable) in depth-first preorder from
/// the roots in position order, stationary child first; then the leaves (the welded
/// positions) in position order.
pub(crate) struct NodeIds {
    /// Welded positions, the leaves.
    np: usize,
    /// The new id of each collapse's node.
    split_new: Vec<u32>,
    /// Collapses in new-id (split) order.
    by_new: Vec<usize>,
}

impl NodeIds {
    pub(crate) fn number(np: usize, h: &Collapses) -> Self {
        let created = h.collapses.len();
        let mut split_new = vec![NONE; created];
        let mut by_new = Vec::with_capacity(created);
        let mut stack: Vec<u32> = (np as u32..(np + created) as u32)
            .filter(|&o| h.parent[o as usize] == NONE)
            .collect();
        stack.sort_unstable_by_key(|&o| std::cmp::Reverse(h.node_position[o as usize]));
        while let Some(o) = stack.pop() {
            let c = o as usize - np;
            split_new[c] = by_new.len() as u32;
            by_new.push(c);
            for child in [h.collapses[c].u, h.collapses[c].t] {
                if child as usize >= np {
                    stack.push(child);
                }
            }
        }
        NodeIds {
            np,
            split_new,
            by_new,
        }
    }

    /// The new id of old node `old` (positions first, then collapses).
    fn of(&self, old: u32) -> u32 {
        if (old as usize) < self.np {
            (self.split_new.len() + old as usize) as u32
        } else {
            self.split_new[old as usize - self.np]
        }
    }

    pub(crate) fn total(&self) -> usize {
        self.np + self.split_new.len()
    }

    /// Every node with its parent and position, at its new id.
    pub(crate) fn nodes(&self, h: &Collapses) -> Vec<Node> {
        let mut nodes = vec![
            Node {
                parent: NodeId::NONE,
                position: PositionId(0)
            };
            self.total()
        ];
        for old in 0..self.total() as u32 {
            let p = h.parent[old as usize];
            nodes[self.of(old) as usize] = Node {
                parent: if p == NONE {
                    NodeId::NONE
                } else {
                    NodeId(self.of(p))
                },
                position: PositionId(h.node_position[old as usize]),
            };
        }
        nodes
    }

    /// Nodes without a parent.
    pub(crate) fn root_count(&self, h: &Collapses) -> usize {
        h.parent[..self.total()]
            .iter()
            .filter(|&&p| p == NONE)
            .count()
    }

    /// The parentless nodes, ascending.
    pub(crate) fn roots(&self, h: &Collapses) -> Vec<NodeId> {
        let mut roots: Vec<NodeId> = (0..self.total() as u32)
            .filter(|&o| h.parent[o as usize] == NONE)
            .map(|o| NodeId(self.of(o)))
            .collect();
        roots.sort_unstable();
        roots
    }
}

/// Polygon ids in file order: the base (surviving) triangles in triangle order, then each
/// split's `f_l` and `f_r` in split order, each with the corner rotation it is stored with.
pub(crate) struct PolygonOrder {
    /// The new id of each welded triangle.
    poly_new: Vec<u32>,
    /// Triangle and rotation of each new id.
    order: Vec<(u32, u8)>,
    pub(crate) base_count: usize,
    /// The split that creates each triangle (`BASE` for base triangles).
    creator: Vec<Creator>,
}

impl PolygonOrder {
    pub(crate) fn number(nt: usize, h: &Collapses, ids: &NodeIds) -> Self {
        let mut poly_new = vec![NONE; nt];
        let mut order: Vec<(u32, u8)> = Vec::with_capacity(nt);
        for f in 0..nt {
            if h.alive[f] {
                poly_new[f] = order.len() as u32;
                order.push((f as u32, 0));
            }
        }
        let base_count = order.len();
        let mut creator = vec![Creator::BASE; nt];
        for &c in &ids.by_new {
            let col = h.collapses[c];
            let s = NodeId(ids.split_new[c]);
            poly_new[col.fl as usize] = order.len() as u32;
            order.push((col.fl, col.rot_l));
            creator[col.fl as usize] = Creator::new(s, false);
            if col.fr != NONE {
                poly_new[col.fr as usize] = order.len() as u32;
                order.push((col.fr, col.rot_r));
                creator[col.fr as usize] = Creator::new(s, true);
            }
        }
        PolygonOrder {
            poly_new,
            order,
            base_count,
            creator,
        }
    }

    /// The new id of welded triangle `f` (`NONE`: none).
    fn pid(&self, f: u32) -> PolyId {
        if f == NONE {
            PolyId::NONE
        } else {
            PolyId(self.poly_new[f as usize])
        }
    }

    /// The polygons in file order, corners rotated as stored.
    pub(crate) fn polygons(&self, w: &Welded, ids: &NodeIds) -> Vec<Polygon> {
        self.order
            .iter()
            .map(|&(f, rot)| {
                let t = &w.triangles[f as usize];
                let k = rot as usize;
                Polygon {
                    nodes: [t.p[k], t.p[(k + 1) % 3], t.p[(k + 2) % 3]].map(|p| NodeId(ids.of(p))),
                    creator: self.creator[f as usize],
                    surface: SurfaceId(t.surface),
                    group: SurfaceGroupId(w.group_ids[t.group as usize]),
                }
            })
            .collect()
    }

    /// The base mesh with its adjacency, from the final corners.
    pub(crate) fn base_faces(&self, h: &Collapses, ids: &NodeIds) -> Vec<BaseFace> {
        let base = &self.order[..self.base_count];
        let mut directed = std::collections::HashMap::with_capacity(3 * self.base_count);
        for &(f, _) in base {
            let c = h.corners[f as usize];
            for k in 0..3 {
                directed.insert((c[k], c[(k + 1) % 3]), f);
            }
        }
        base.iter()
            .map(|&(f, _)| {
                let c = h.corners[f as usize];
                BaseFace {
                    corners: c.map(|x| NodeId(ids.of(x))),
                    neighbours: [0, 1, 2].map(|k| {
                        let (a, b) = (c[(k + 1) % 3], c[(k + 2) % 3]);
                        directed.get(&(b, a)).map_or(PolyId::NONE, |&g| self.pid(g))
                    }),
                }
            })
            .collect()
    }
}

/// The split record of every collapse, at its split id. Splits name their neighbours by key
/// (`PolyKey`): base polygons by id, the others by creator and side.
pub(crate) fn splits(h: &Collapses, ids: &NodeIds, polys: &PolygonOrder) -> Vec<Split> {
    let polygons_creator: Vec<Creator> = polys
        .order
        .iter()
        .map(|&(f, _)| polys.creator[f as usize])
        .collect();
    let base_keys = polys.base_count as u32;
    let key = |p: PolyId| match p.get() {
        None => PolyKey::NONE,
        Some(p) => polygons_creator[p.index()].key(base_keys, p),
    };
    let mut splits = vec![bytemuck::Zeroable::zeroed(); h.collapses.len()];
    for (c, col) in h.collapses.iter().enumerate() {
        splits[ids.split_new[c] as usize] = Split {
            stationary: NodeId(ids.of(col.t)),
            floating: NodeId(ids.of(col.u)),
            f_l: polys.pid(col.fl),
            f_r: polys.pid(col.fr),
            neighbours: col.neighbours.map(|f| key(polys.pid(f))),
        };
    }
    splits
}

/// The refinement bounds of every collapse, at its split id.
pub(crate) fn bounds(w: &Welded, h: &Collapses, ids: &NodeIds) -> Vec<SplitBounds> {
    let mut bounds = vec![bytemuck::Zeroable::zeroed(); h.collapses.len()];
    for c in 0..h.collapses.len() {
        let old = ids.np + c;
        let (axis, angle) = h.cone[old];
        let sin2 = if angle >= std::f32::consts::FRAC_PI_2 {
            1.0
        } else {
            angle.sin() * angle.sin()
        };
        bounds[ids.split_new[c] as usize] = SplitBounds::new(
            w.positions[h.node_position[old] as usize],
            h.radius[old],
            if sin2 >= 1.0 { [0.0; 3] } else { axis },
            sin2,
            h.error[old],
            0.0,
        );
    }
    bounds
}

/// Visits the vertex table in file order: per position, its vertices sorted by surface-group
/// id, each as (position, group id, attribute index).
fn each_vertex(w: &Welded, mut f: impl FnMut(usize, u16, u32)) {
    let mut keys: Vec<(u16, u32)> = Vec::new();
    for (p, vs) in w.vertices.iter().enumerate() {
        keys.clear();
        keys.extend(vs.iter().map(|&(g, a)| (w.group_ids[g as usize], a)));
        keys.sort_unstable();
        for &(group, a) in &keys {
            f(p, group, a);
        }
    }
}

/// Vertices (and vertex-table entries) of the welded mesh.
pub(crate) fn vertex_count(w: &Welded) -> usize {
    w.vertices.iter().map(<[_]>::len).sum()
}

/// Where each position's vertex-table entries start, and the end.
pub(crate) fn vertex_table_offsets(w: &Welded) -> Vec<u32> {
    let mut offsets = Vec::with_capacity(w.vertices.len() + 1);
    let mut at = 0u32;
    offsets.push(at);
    for vs in &w.vertices {
        at += vs.len() as u32;
        offsets.push(at);
    }
    offsets
}

/// The vertex table: per position, its vertices sorted by surface-group id, each a key into
/// the vertex buffer, which holds them in the same order.
pub(crate) fn vertex_table(w: &Welded) -> Vec<VertexKey> {
    let mut table = Vec::with_capacity(vertex_count(w));
    each_vertex(w, |_, group, _| {
        table.push(VertexKey {
            group: SurfaceGroupId(group),
            reserved: 0,
            vertex: table.len() as u32,
        })
    });
    table
}

/// The vertex buffer, in vertex-table order.
pub(crate) fn vertices(w: &Welded) -> Vec<Vertex> {
    let mut vertices = Vec::with_capacity(vertex_count(w));
    each_vertex(w, |p, _, a| {
        let attrs = &w.attributes[a as usize];
        vertices.push(Vertex {
            position: w.positions[p],
            normal: attrs.normal,
            uv: attrs.uv,
        })
    });
    vertices
}

/// The vertices' colours in vertex-table order; empty when the mesh has none.
pub(crate) fn vertex_colours(w: &Welded) -> Vec<[u8; 4]> {
    if !w.has_colors {
        return Vec::new();
    }
    let mut colours = Vec::with_capacity(vertex_count(w));
    each_vertex(w, |_, _, a| {
        colours.push(encode_colour(w.attributes[a as usize].color))
    });
    colours
}

/// Welded positions with their classes.
pub(crate) fn positions(w: &Welded) -> Vec<Position> {
    w.positions
        .iter()
        .zip(&w.classes)
        .map(|(&xyz, &c)| Position {
            xyz,
            class: c as u32,
        })
        .collect()
}

/// The `META` record of the arrays, from the welded mesh and the collapses (what validating
/// the arrays computes: counts, the positions' bounds, the deepest leaf).
pub(crate) fn meta(w: &Welded, h: &Collapses, ids: &NodeIds, polys: &PolygonOrder) -> Meta {
    let mut bounds_min = [f32::INFINITY; 3];
    let mut bounds_max = [f32::NEG_INFINITY; 3];
    for p in &w.positions {
        for k in 0..3 {
            bounds_min[k] = bounds_min[k].min(p[k]);
            bounds_max[k] = bounds_max[k].max(p[k]);
        }
    }
    if w.positions.is_empty() {
        (bounds_min, bounds_max) = ([0.0; 3], [0.0; 3]);
    }
    let vertices = vertex_count(w) as u32;
    Meta {
        node_count: ids.total() as u32,
        split_count: h.collapses.len() as u32,
        root_count: ids.root_count(h) as u32,
        polygon_count: polys.order.len() as u32,
        base_polygon_count: polys.base_count as u32,
        position_count: w.positions.len() as u32,
        vertex_count: vertices,
        vertex_key_count: vertices,
        surface_count: w.surface_count,
        surface_group_count: w.group_id_count,
        max_depth: max_depth(h, ids),
        flags: 0,
        bounds_min,
        bounds_max,
        reserved: [0; 4],
    }
}

/// The longest root-to-leaf path in edges. Split ids are a preorder (a parent's id below its
/// children's), so each split's depth follows from its parent's in one pass.
fn max_depth(h: &Collapses, ids: &NodeIds) -> u32 {
    let mut depth = vec![0u32; ids.by_new.len()];
    let below = |depth: &[u32], p: u32| {
        if p == NONE {
            0
        } else {
            depth[ids.of(p) as usize] + 1
        }
    };
    for (s, &c) in ids.by_new.iter().enumerate() {
        depth[s] = below(&depth, h.parent[ids.np + c]);
    }
    (0..ids.np)
        .map(|leaf| below(&depth, h.parent[leaf]))
        .max()
        .unwrap_or(0)
}
