//! The `.clod` arrays computed from a welded mesh and its collapses, one array at a time:
//! the numbering of nodes and polygons into file order (the small tables every array needs,
//! `u32` per node, split or triangle, and the vertex table's order), then each array's
//! records from the numbering, each record from its index alone, so an array is made on
//! all cores and comes out the same whatever the threads. [`crate::baked::Baked::new`] collects
//! each into a `Vec`; [`crate::streamed`] writes the records in bounded chunks as they are
//! made, so no array is ever whole in memory.
//!
//! Node ids: splittable nodes first, in depth-first preorder (stationary child first, roots
//! in position order), so a subtree is one id range and a stationary child sits next to its
//! parent — the records a refinement pass reads together lie together. Leaves follow in
//! position order. Polygons: the base mesh first, then each split's `f_l` and `f_r` in split
//! order.

use caveclod_core::format::{BaseFace, Creator, Meta, Node, Polygon, Position, Split, SplitBounds};
use caveclod_core::{NodeId, PolyId, PolyKey, PositionId, SurfaceGroupId, SurfaceId};

use crate::hierarchy::{Collapse, Hierarchy as Collapses};
use crate::weld::Welded;

mod indexed;
mod vertices;

use indexed::collect_indexed;

pub(crate) use vertices::{
    vertex_colours, vertex_count, vertex_table, vertex_table_offset_records, vertex_table_offsets,
    vertices, VertexOrder,
};

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
    by_new: Vec<u32>,
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
            by_new.push(c as u32);
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

    /// The collapses (indices into `h.collapses`) in split order.
    pub(crate) fn collapses_in_order(&self) -> impl Iterator<Item = usize> + '_ {
        self.by_new.iter().map(|&c| c as usize)
    }

    /// Node `id` (new ids: the splits' nodes, then the leaves) with its parent and position.
    pub(crate) fn node(&self, h: &Collapses, id: usize) -> Node {
        let old = match self.by_new.get(id) {
            Some(&c) => self.np + c as usize,
            None => id - self.by_new.len(),
        };
        let p = h.parent[old];
        Node {
            parent: if p == NONE {
                NodeId::NONE
            } else {
                NodeId(self.of(p))
            },
            position: PositionId(h.node_position[old]),
        }
    }

    /// Every [`node`](Self::node) in new-id order, made on all cores.
    pub(crate) fn nodes(&self, h: &Collapses) -> Vec<Node> {
        collect_indexed(self.total(), |id| self.node(h, id))
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
/// split's `f_l` and `f_r` in split order, each with the corner rotation it is stored with
/// (none for a base triangle, the collapse's `rot_l` / `rot_r` for the others). Only the
/// base triangles are listed; the created ones follow from the split order.
pub(crate) struct PolygonOrder {
    /// The new id of each welded triangle.
    poly_new: Vec<u32>,
    /// The base triangles, in triangle order (their new ids).
    base: Vec<u32>,
    pub(crate) base_count: usize,
    /// Polygons in all.
    pub(crate) count: usize,
    /// The split that creates each triangle (`BASE` for base triangles).
    creator: Vec<Creator>,
}

impl PolygonOrder {
    pub(crate) fn number(nt: usize, h: &Collapses, ids: &NodeIds) -> Self {
        let mut order = Self::base(&h.alive);
        for c in ids.collapses_in_order() {
            order.add_split(NodeId(ids.split_new[c]), &h.collapses[c]);
        }
        debug_assert_eq!(order.poly_new.len(), nt);
        order
    }

    /// The base polygons: the triangles alive at the end, in triangle order.
    pub(crate) fn base(alive: &[bool]) -> Self {
        let nt = alive.len();
        let mut poly_new = vec![NONE; nt];
        let base: Vec<u32> = (0..nt as u32).filter(|&f| alive[f as usize]).collect();
        for (i, &f) in base.iter().enumerate() {
            poly_new[f as usize] = i as u32;
        }
        PolygonOrder {
            poly_new,
            base_count: base.len(),
            count: base.len(),
            base,
            creator: vec![Creator::BASE; nt],
        }
    }

    /// Numbers the polygons of the next split in split order, `s`, which collapse `col`
    /// undoes: its `f_l`, then its `f_r` if it has one.
    pub(crate) fn add_split(&mut self, s: NodeId, col: &Collapse) {
        self.poly_new[col.fl as usize] = self.count as u32;
        self.creator[col.fl as usize] = Creator::new(s, false);
        self.count += 1;
        if col.fr != NONE {
            self.poly_new[col.fr as usize] = self.count as u32;
            self.creator[col.fr as usize] = Creator::new(s, true);
            self.count += 1;
        }
    }

    /// The base triangles, in triangle order.
    pub(crate) fn base_triangles(&self) -> &[u32] {
        &self.base
    }

    /// The new id of welded triangle `f` (`NONE`: none).
    pub(crate) fn pid(&self, f: u32) -> PolyId {
        if f == NONE {
            PolyId::NONE
        } else {
            PolyId(self.poly_new[f as usize])
        }
    }

    /// The welded triangle of each polygon, in new-id order (the inverse of the numbering),
    /// so that any polygon's record can be made on its own ([`Polygons`]).
    pub(crate) fn triangles_in_order(&self) -> Vec<u32> {
        let mut by_polygon = vec![NONE; self.count];
        for (f, &p) in self.poly_new.iter().enumerate() {
            if p != NONE {
                by_polygon[p as usize] = f as u32;
            }
        }
        by_polygon
    }

    /// The rotation welded triangle `f` is stored with: none for a base polygon, its
    /// creator's collapse's `rot_l` or `rot_r` for the others.
    fn rotation(&self, h: &Collapses, ids: &NodeIds, f: u32) -> u8 {
        let creator = self.creator[f as usize];
        match creator.node() {
            None => 0,
            Some(s) => {
                let col = &h.collapses[ids.by_new[s.index()] as usize];
                if creator.is_right() {
                    col.rot_r
                } else {
                    col.rot_l
                }
            }
        }
    }

    /// The polygon of welded triangle `f`, its corners rotated by `rot` and named by the
    /// new ids `of` their leaves.
    pub(crate) fn polygon(&self, w: &Welded, f: u32, rot: u8, of: impl Fn(u32) -> u32) -> Polygon {
        let t = &w.triangles[f as usize];
        let group = SurfaceGroupId(w.group_ids[t.group as usize]);
        self.polygon_of(f, t.p, SurfaceId(w.surface_of(t)), group, rot, of)
    }

    /// The polygon of welded triangle `f` with positions `p`, `surface` and `group`, its
    /// corners rotated by `rot` and named by the new ids `of` their leaves.
    pub(crate) fn polygon_of(
        &self,
        f: u32,
        p: [u32; 3],
        surface: SurfaceId,
        group: SurfaceGroupId,
        rot: u8,
        of: impl Fn(u32) -> u32,
    ) -> Polygon {
        let k = rot as usize;
        Polygon {
            nodes: [p[k], p[(k + 1) % 3], p[(k + 2) % 3]].map(|p| NodeId(of(p))),
            creator: self.creator[f as usize],
            surface,
            group,
        }
    }

    /// The key a split names welded triangle `f` by (`PolyKey`): a base polygon by its id,
    /// the others by creator and side.
    fn key(&self, f: u32) -> PolyKey {
        match self.pid(f).get() {
            None => PolyKey::NONE,
            Some(p) => self.creator[f as usize].key(self.base_count as u32, p),
        }
    }

    /// The split record of collapse `col`, its nodes named by their new ids `of`.
    pub(crate) fn split(&self, col: &Collapse, of: impl Fn(u32) -> u32) -> Split {
        Split {
            stationary: NodeId(of(col.t)),
            floating: NodeId(of(col.u)),
            f_l: self.pid(col.fl),
            f_r: self.pid(col.fr),
            neighbours: col.neighbours.map(|f| self.key(f)),
        }
    }

    /// The polygons in file order, corners rotated as stored, made on all cores.
    pub(crate) fn polygons(&self, w: &Welded, h: &Collapses, ids: &NodeIds) -> Vec<Polygon> {
        let order = Polygons::new(self, w, h, ids);
        collect_indexed(self.count, |id| order.polygon(id))
    }

    /// The base mesh with its adjacency, from the final corners.
    pub(crate) fn base_faces(&self, h: &Collapses, ids: &NodeIds) -> Vec<BaseFace> {
        self.base_faces_by(|f| h.corners[f as usize], |x| ids.of(x))
    }

    /// The base mesh with its adjacency, from the final corners `corners` of each base
    /// triangle (nodes), named by their new ids `of`.
    pub(crate) fn base_faces_by(
        &self,
        corners: impl Fn(u32) -> [u32; 3],
        of: impl Fn(u32) -> u32,
    ) -> Vec<BaseFace> {
        let base = &self.base;
        let mut directed = std::collections::HashMap::with_capacity(3 * self.base_count);
        for &f in base {
            let c = corners(f);
            for k in 0..3 {
                directed.insert((c[k], c[(k + 1) % 3]), f);
            }
        }
        base.iter()
            .map(|&f| {
                let c = corners(f);
                BaseFace {
                    corners: c.map(|x| NodeId(of(x))),
                    neighbours: [0, 1, 2].map(|k| {
                        let (a, b) = (c[(k + 1) % 3], c[(k + 2) % 3]);
                        directed.get(&(b, a)).map_or(PolyId::NONE, |&g| self.pid(g))
                    }),
                }
            })
            .collect()
    }
}

/// The polygons' records by id: the welded triangle of each ([`PolygonOrder::triangles_in_order`])
/// and what names their corners.
pub(crate) struct Polygons<'a> {
    order: &'a PolygonOrder,
    by_polygon: Vec<u32>,
    w: &'a Welded,
    h: &'a Collapses,
    ids: &'a NodeIds,
}

impl<'a> Polygons<'a> {
    pub(crate) fn new(
        order: &'a PolygonOrder,
        w: &'a Welded,
        h: &'a Collapses,
        ids: &'a NodeIds,
    ) -> Self {
        Self {
            order,
            by_polygon: order.triangles_in_order(),
            w,
            h,
            ids,
        }
    }

    /// Polygon `id`, corners rotated as stored.
    pub(crate) fn polygon(&self, id: usize) -> Polygon {
        let f = self.by_polygon[id];
        let rot = self.order.rotation(self.h, self.ids, f);
        self.order.polygon(self.w, f, rot, |p| self.ids.of(p))
    }
}

/// The split record of split `s` (in split order). Splits name their neighbours by key
/// (`PolyKey`): base polygons by id, the others by creator and side.
pub(crate) fn split(h: &Collapses, ids: &NodeIds, polys: &PolygonOrder, s: usize) -> Split {
    polys.split(&h.collapses[ids.by_new[s] as usize], |x| ids.of(x))
}

/// Every [`split`] in split order, made on all cores.
pub(crate) fn splits(h: &Collapses, ids: &NodeIds, polys: &PolygonOrder) -> Vec<Split> {
    collect_indexed(ids.by_new.len(), |s| split(h, ids, polys, s))
}

/// The refinement bounds of split `s` (in split order).
pub(crate) fn bound(w: &Welded, h: &Collapses, ids: &NodeIds, s: usize) -> SplitBounds {
    let old = ids.np + ids.by_new[s] as usize;
    split_bounds(
        w.positions[h.node_position[old] as usize],
        h.radius[old],
        h.cone[old],
        h.error[old],
    )
}

/// The refinement bounds of a split whose node stands at `position` with sphere `radius`,
/// normal cone `(axis, half angle)` and `error`.
pub(crate) fn split_bounds(
    position: [f32; 3],
    radius: f32,
    (axis, angle): ([f32; 3], f32),
    error: f32,
) -> SplitBounds {
    let sin2 = if angle >= std::f32::consts::FRAC_PI_2 {
        1.0
    } else {
        angle.sin() * angle.sin()
    };
    SplitBounds::new(
        position,
        radius,
        if sin2 >= 1.0 { [0.0; 3] } else { axis },
        sin2,
        error,
        0.0,
    )
}

/// Every [`bound`] in split order, made on all cores.
pub(crate) fn bounds(w: &Welded, h: &Collapses, ids: &NodeIds) -> Vec<SplitBounds> {
    collect_indexed(ids.by_new.len(), |s| bound(w, h, ids, s))
}

/// Welded position `p` with its class.
pub(crate) fn position(w: &Welded, p: usize) -> Position {
    Position {
        xyz: w.positions[p],
        class: w.classes[p] as u32,
    }
}

/// Every [`position`], made on all cores.
pub(crate) fn positions(w: &Welded) -> Vec<Position> {
    collect_indexed(w.positions.len(), |p| position(w, p))
}

/// The `META` record of the arrays, from the welded mesh and the collapses (what validating
/// the arrays computes: counts, the positions' bounds, the deepest leaf).
pub(crate) fn meta(w: &Welded, h: &Collapses, ids: &NodeIds, polys: &PolygonOrder) -> Meta {
    let counts = Counts {
        nodes: ids.total(),
        splits: h.collapses.len(),
        roots: ids.root_count(h),
        max_depth: max_depth(h, ids),
    };
    meta_of(w, &counts, polys)
}

/// What the `META` record counts of the hierarchy.
pub(crate) struct Counts {
    pub(crate) nodes: usize,
    pub(crate) splits: usize,
    pub(crate) roots: usize,
    /// The longest root-to-leaf path in edges.
    pub(crate) max_depth: u32,
}

/// What the `META` record counts of the welded mesh.
pub(crate) struct MeshCounts {
    /// The positions' bounding box (zero when there is none).
    pub(crate) bounds: ([f32; 3], [f32; 3]),
    pub(crate) positions: usize,
    pub(crate) vertices: usize,
    pub(crate) surfaces: u32,
    pub(crate) group_ids: u32,
}

impl MeshCounts {
    /// The counts of `w`.
    fn of(w: &Welded) -> Self {
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
        Self {
            bounds: (bounds_min, bounds_max),
            positions: w.positions.len(),
            vertices: vertex_count(w),
            surfaces: w.surface_count,
            group_ids: w.group_id_count,
        }
    }
}

/// The `META` record of the welded mesh `w` with a hierarchy of `counts` and the polygons
/// `polys`.
pub(crate) fn meta_of(w: &Welded, counts: &Counts, polys: &PolygonOrder) -> Meta {
    meta_from(&MeshCounts::of(w), counts, polys)
}

/// The `META` record of a welded mesh of `mesh` with a hierarchy of `counts` and the
/// polygons `polys`.
pub(crate) fn meta_from(mesh: &MeshCounts, counts: &Counts, polys: &PolygonOrder) -> Meta {
    let vertices = mesh.vertices as u32;
    Meta {
        node_count: counts.nodes as u32,
        split_count: counts.splits as u32,
        root_count: counts.roots as u32,
        polygon_count: polys.count as u32,
        base_polygon_count: polys.base_count as u32,
        position_count: mesh.positions as u32,
        vertex_count: vertices,
        vertex_key_count: vertices,
        surface_count: mesh.surfaces,
        surface_group_count: mesh.group_ids,
        max_depth: counts.max_depth,
        flags: 0,
        bounds_min: mesh.bounds.0,
        bounds_max: mesh.bounds.1,
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
    for (s, c) in ids.collapses_in_order().enumerate() {
        depth[s] = below(&depth, h.parent[ids.np + c]);
    }
    (0..ids.np)
        .map(|leaf| below(&depth, h.parent[leaf]))
        .max()
        .unwrap_or(0)
}
