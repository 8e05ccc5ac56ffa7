//! A test-only hierarchy builder: shortest-edge half-edge collapses, applied in passes of
//! independent sets (so the hierarchy stays shallow), obeying the surface-group rules and the
//! topological checks that keep the mesh manifold.
//!
//! Error bounds are deliberately crude (the distance of the removed vertex from the new
//! surface, accumulated up the hierarchy); `caveclod-bake` owns the real, quadric-based
//! builder. This one exists so the runtime can be tested before and independently of it.

use std::collections::HashMap;

use caveclod_core::format::{serialized_len, write_into};
use caveclod_core::{
    BaseFace, Creator, Hierarchy, HierarchyParts, Node, NodeId, PolyId, Polygon, Position,
    PositionClass, PositionId, Split, SplitBounds, SurfaceGroupId, SurfaceId, Vertex, VertexKey,
};

use crate::meshes::TestMesh;

const NONE: u32 = u32::MAX;

/// Owned bytes in 8-byte aligned storage, so `Hierarchy::from_bytes` can cast in place.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct AlignedBytes {
    words: Vec<u64>,
    len: usize,
}

impl AlignedBytes {
    /// `len` zero bytes.
    pub fn zeroed(len: usize) -> Self {
        Self {
            words: vec![0; len.div_ceil(8)],
            len,
        }
    }

    /// A copy of `bytes`.
    pub fn from_slice(bytes: &[u8]) -> Self {
        let mut out = Self::zeroed(bytes.len());
        out.copy_from_slice(bytes);
        out
    }
}

impl std::ops::Deref for AlignedBytes {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        &bytemuck::cast_slice(&self.words)[..self.len]
    }
}

impl std::ops::DerefMut for AlignedBytes {
    fn deref_mut(&mut self) -> &mut [u8] {
        &mut bytemuck::cast_slice_mut(&mut self.words)[..self.len]
    }
}

/// The arrays of a built hierarchy.
#[derive(Clone, Debug, Default)]
pub struct Built {
    /// Node positions (one per mesh position).
    pub positions: Vec<Position>,
    /// Nodes: splittable ones first (parents before children), then the leaves.
    pub nodes: Vec<Node>,
    /// Split records.
    pub splits: Vec<Split>,
    /// Refinement bounds.
    pub bounds: Vec<SplitBounds>,
    /// Polygons, base first.
    pub polygons: Vec<Polygon>,
    /// Roots, ascending.
    pub roots: Vec<NodeId>,
    /// Base mesh.
    pub base: Vec<BaseFace>,
    /// Vertex-table offsets per position.
    pub vertex_table_offsets: Vec<u32>,
    /// Vertex-table entries.
    pub vertex_table: Vec<VertexKey>,
    /// Vertex buffer.
    pub vertices: Vec<Vertex>,
    /// Surfaces.
    pub surface_count: u32,
    /// Surface-group ids after colouring.
    pub surface_group_count: u32,
    /// Surface groups before colouring.
    pub surface_groups: u32,
}

impl Built {
    /// Borrowed arrays.
    pub fn parts(&self) -> HierarchyParts<'_> {
        HierarchyParts {
            positions: &self.positions,
            nodes: &self.nodes,
            splits: &self.splits,
            bounds: &self.bounds,
            polygons: &self.polygons,
            roots: &self.roots,
            base: &self.base,
            vertex_table_offsets: &self.vertex_table_offsets,
            vertex_table: &self.vertex_table,
            vertices: &self.vertices,
            surface_count: self.surface_count,
            surface_group_count: self.surface_group_count,
        }
    }

    /// The validated hierarchy over these arrays.
    ///
    /// # Panics
    /// If the builder produced an invalid hierarchy (a builder bug).
    pub fn hierarchy(&self) -> Hierarchy<'_> {
        match Hierarchy::from_parts(self.parts()) {
            Ok(h) => h,
            Err(e) => panic!("test builder produced an invalid hierarchy: {e}"),
        }
    }

    /// The `.clod` file.
    ///
    /// # Panics
    /// If the builder produced an invalid hierarchy (a builder bug).
    pub fn to_bytes(&self) -> AlignedBytes {
        let parts = self.parts();
        let mut out = AlignedBytes::zeroed(serialized_len(&parts, &[]));
        if let Err(e) = write_into(&parts, &[], &mut out) {
            panic!("test builder produced an invalid hierarchy: {e}");
        }
        out
    }
}

type V3 = [f32; 3];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: V3, b: V3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn len(a: V3) -> f32 {
    dot(a, a).sqrt()
}
fn norm(a: V3) -> V3 {
    let l = len(a);
    if l > 0.0 {
        [a[0] / l, a[1] / l, a[2] / l]
    } else {
        [0.0; 3]
    }
}

struct Uf(Vec<u32>);
impl Uf {
    fn find(&mut self, mut x: u32) -> u32 {
        while self.0[x as usize] != x {
            let p = self.0[x as usize];
            self.0[x as usize] = self.0[p as usize];
            x = p;
        }
        x
    }
    fn union(&mut self, a: u32, b: u32) {
        let (a, b) = (self.find(a), self.find(b));
        if a != b {
            self.0[a.max(b) as usize] = a.min(b);
        }
    }
}

/// A collapse as recorded for its split.
#[derive(Clone, Copy)]
struct Rec {
    t: u32,
    u: u32,
    fl: u32,
    fr: u32,
    fns: [u32; 4],
    rot_l: u8,
    rot_r: u8,
}

/// The shrinking mesh during the build.
struct Work<'m> {
    mesh: &'m TestMesh,
    corners: Vec<[u32; 3]>,
    alive: Vec<bool>,
    comp: Vec<u32>,
    faces_of: Vec<Vec<u32>>,
    node_pos: Vec<u32>,
    parent: Vec<u32>,
    error: Vec<f32>,
    radius: Vec<f32>,
    cone: Vec<(V3, f32)>,
    class: Vec<PositionClass>,
    pos_comps: Vec<Vec<u32>>,
    recs: Vec<Rec>,
    stamp: Vec<u32>,
}

impl Work<'_> {
    fn p(&self, node: u32) -> V3 {
        self.mesh.positions[self.node_pos[node as usize] as usize]
    }

    fn corner(&self, f: u32, v: u32) -> Option<usize> {
        self.corners[f as usize].iter().position(|&c| c == v)
    }

    /// The alive face holding the directed edge a→b.
    fn dir_face(&self, a: u32, b: u32) -> Option<u32> {
        self.faces_of[a as usize].iter().copied().find(|&f| {
            let j = self.corner(f, a).unwrap_or(0);
            self.corners[f as usize][(j + 1) % 3] == b
        })
    }

    /// The alive face other than `f` holding both `a` and `b`.
    fn across(&self, f: u32, a: u32, b: u32) -> u32 {
        self.faces_of[a as usize]
            .iter()
            .copied()
            .find(|&g| g != f && self.corners[g as usize].contains(&b))
            .unwrap_or(NONE)
    }

    fn ring(&self, v: u32, out: &mut Vec<u32>) {
        out.clear();
        for &f in &self.faces_of[v as usize] {
            for c in self.corners[f as usize] {
                if c != v && !out.contains(&c) {
                    out.push(c);
                }
            }
        }
    }

    fn on_border(&self, v: u32) -> bool {
        self.faces_of[v as usize].iter().any(|&f| {
            let j = self.corner(f, v).unwrap_or(0);
            let c = self.corners[f as usize];
            self.across(f, v, c[(j + 1) % 3]) == NONE || self.across(f, v, c[(j + 2) % 3]) == NONE
        })
    }

    fn face_normal(&self, c: [u32; 3]) -> V3 {
        let [a, b, cc] = c.map(|n| self.p(n));
        cross(sub(b, a), sub(cc, a))
    }

    /// Checks the collapse of `u` into `t`; returns the recorded collapse and its error.
    fn check(
        &self,
        t: u32,
        u: u32,
        ring_t: &mut Vec<u32>,
        ring_u: &mut Vec<u32>,
    ) -> Option<(Rec, f32)> {
        let (pt, pu) = (self.node_pos[t as usize], self.node_pos[u as usize]);
        let class_u = self.class[pu as usize];
        if class_u == PositionClass::Rigid {
            return None;
        }
        let fl = self.dir_face(t, u)?;
        let fr = self.dir_face(u, t).unwrap_or(NONE);
        let boundary = fr == NONE || self.comp[fl as usize] != self.comp[fr as usize];
        if class_u != PositionClass::Free
            && (!boundary || self.class[pt as usize] == PositionClass::Free)
        {
            return None;
        }
        let (cu, ct) = (&self.pos_comps[pu as usize], &self.pos_comps[pt as usize]);
        if !cu.iter().all(|c| ct.contains(c)) {
            return None;
        }
        let jl = self.corner(fl, t)?;
        let l = self.corners[fl as usize][(jl + 2) % 3];
        let fn0 = self.across(fl, l, t);
        let fn1 = self.across(fl, u, l);
        if fn1 == NONE {
            return None;
        }
        let (mut r, mut fn2, mut fn3, mut jr) = (NONE, NONE, NONE, 0);
        if fr != NONE {
            jr = self.corner(fr, t)?;
            r = self.corners[fr as usize][(jr + 1) % 3];
            fn2 = self.across(fr, t, r);
            fn3 = self.across(fr, r, u);
            if fn3 == NONE {
                return None;
            }
        }
        // Link condition: t and u share exactly the neighbours l (and r).
        self.ring(t, ring_t);
        self.ring(u, ring_u);
        let shared = ring_t.iter().filter(|x| ring_u.contains(x)).count();
        if shared != 1 + usize::from(r != NONE) {
            return None;
        }
        // A border vertex t must not gain an interior edge to another border vertex: only
        // collapse along the border when both are on it.
        if fr != NONE && self.on_border(t) && self.on_border(u) {
            return None;
        }
        // Keep the opposite vertices of degree at least 3 (no doubled faces).
        for x in [l, r] {
            if x != NONE {
                self.ring(x, ring_t);
                if ring_t.len() <= 3 {
                    return None;
                }
            }
        }
        // No face may flip or collapse; the error is the removed point's distance from the
        // faces that replace its star.
        let (p_t, p_u) = (self.p(t), self.p(u));
        let mut dev = 0.0f32;
        for &f in &self.faces_of[u as usize] {
            if f == fl || f == fr {
                continue;
            }
            let before = self.face_normal(self.corners[f as usize]);
            let after_c = self.corners[f as usize].map(|c| if c == u { t } else { c });
            let after = self.face_normal(after_c);
            let (lb, la) = (len(before), len(after));
            if la <= 1e-12 * (1.0 + lb) || dot(before, after) <= 0.25 * lb * la {
                return None;
            }
            let n = norm(after);
            dev = dev.max(dot(n, sub(p_u, p_t)).abs());
        }
        let rec = Rec {
            t,
            u,
            fl,
            fr,
            fns: [fn0, fn1, fn2, fn3],
            rot_l: jl as u8,
            rot_r: jr as u8,
        };
        Some((rec, dev + 1e-3 * len(sub(p_u, p_t))))
    }

    fn apply(&mut self, rec: Rec, dev: f32) -> u32 {
        let s = self.node_pos.len() as u32;
        let (t, u) = (rec.t, rec.u);
        self.node_pos.push(self.node_pos[t as usize]);
        self.parent.push(NONE);
        self.parent[t as usize] = s;
        self.parent[u as usize] = s;
        let (p_t, p_u) = (self.p(t), self.p(u));
        self.error
            .push(self.error[t as usize].max(self.error[u as usize]) + dev);
        self.radius
            .push(self.radius[t as usize].max(len(sub(p_u, p_t)) + self.radius[u as usize]));
        self.cone
            .push(merge_cones(self.cone[t as usize], self.cone[u as usize]));
        for f in [rec.fl, rec.fr] {
            if f != NONE {
                self.alive[f as usize] = false;
                for c in self.corners[f as usize] {
                    self.faces_of[c as usize].retain(|&g| g != f);
                }
            }
        }
        let mut star = std::mem::take(&mut self.faces_of[t as usize]);
        star.append(&mut std::mem::take(&mut self.faces_of[u as usize]));
        for &f in &star {
            for c in &mut self.corners[f as usize] {
                if *c == t || *c == u {
                    *c = s;
                }
            }
        }
        self.faces_of.push(star);
        self.stamp.push(0);
        self.recs.push(rec);
        s
    }
}

/// Smallest cone containing two cones `(axis, half_angle)`.
fn merge_cones(a: (V3, f32), b: (V3, f32)) -> (V3, f32) {
    use std::f32::consts::PI;
    let phi = dot(a.0, b.0).clamp(-1.0, 1.0).acos();
    if phi + b.1 <= a.1 {
        return a;
    }
    if phi + a.1 <= b.1 {
        return b;
    }
    let theta = (phi + a.1 + b.1) / 2.0;
    if theta >= PI || phi < 1e-6 {
        return (a.0, theta.min(PI));
    }
    let alpha = theta - a.1;
    let axis = norm([
        (a.0[0] * (phi - alpha).sin() + b.0[0] * alpha.sin()) / phi.sin(),
        (a.0[1] * (phi - alpha).sin() + b.0[1] * alpha.sin()) / phi.sin(),
        (a.0[2] * (phi - alpha).sin() + b.0[2] * alpha.sin()) / phi.sin(),
    ]);
    (axis, theta)
}

/// Builds the hierarchy of `mesh`.
///
/// # Panics
/// On meshes this test builder does not support: non-manifold edges, degenerate triangles,
/// or a surface group with two different attribute sets at one position.
pub fn build(mesh: &TestMesh) -> Built {
    let np = mesh.positions.len();
    let nt = mesh.triangles.len();
    let tris = &mesh.triangles;
    let mut dir: HashMap<(u32, u32), u32> = HashMap::with_capacity(3 * nt);
    for (f, t) in tris.iter().enumerate() {
        assert!(
            t.p[0] != t.p[1] && t.p[1] != t.p[2] && t.p[0] != t.p[2],
            "degenerate triangle {f}"
        );
        for k in 0..3 {
            let prev = dir.insert((t.p[k], t.p[(k + 1) % 3]), f as u32);
            assert!(prev.is_none(), "non-manifold edge at triangle {f}");
        }
    }
    let attrs = |f: usize, p: u32| {
        let t = &tris[f];
        let k = t.p.iter().position(|&x| x == p).unwrap_or(0);
        (t.normal[k].map(f32::to_bits), t.uv[k].map(f32::to_bits))
    };
    // Surface groups: adjacent triangles of one surface with equal attributes at both ends
    // of their shared edge.
    let mut uf = Uf((0..nt as u32).collect());
    for (&(a, b), &f) in &dir {
        if let Some(&g) = dir.get(&(b, a)) {
            let (f, g) = (f as usize, g as usize);
            if f < g
                && tris[f].surface == tris[g].surface
                && attrs(f, a) == attrs(g, a)
                && attrs(f, b) == attrs(g, b)
            {
                uf.union(f as u32, g as u32);
            }
        }
    }
    let mut comp_id = HashMap::new();
    let comp: Vec<u32> = (0..nt as u32)
        .map(|f| {
            let r = uf.find(f);
            let n = comp_id.len() as u32;
            *comp_id.entry(r).or_insert(n)
        })
        .collect();
    let ncomp = comp_id.len();
    // Vertices: one per (group, position).
    let mut vkey: HashMap<(u32, u32), usize> = HashMap::new();
    let mut pos_comps: Vec<Vec<u32>> = vec![Vec::new(); np];
    for (f, t) in tris.iter().enumerate() {
        for &p in &t.p {
            let c = comp[f];
            match vkey.get(&(c, p)) {
                Some(&g) => assert_eq!(
                    attrs(g, p),
                    attrs(f, p),
                    "surface group {c} has two attribute sets at position {p}"
                ),
                None => {
                    vkey.insert((c, p), f);
                    pos_comps[p as usize].push(c);
                }
            }
        }
    }
    for v in &mut pos_comps {
        v.sort_unstable();
    }
    // Classes: boundary edges (mesh border or group change) through each position.
    let mut boundary = vec![0u32; np];
    for (&(a, b), &f) in &dir {
        let twin = dir.get(&(b, a));
        let counts = match twin {
            None => true,
            Some(&g) => f < g && comp[f as usize] != comp[g as usize],
        };
        if counts {
            boundary[a as usize] += 1;
            boundary[b as usize] += 1;
        }
    }
    let class: Vec<PositionClass> = boundary
        .iter()
        .map(|&n| match n {
            0 => PositionClass::Free,
            2 => PositionClass::Sharp,
            _ => PositionClass::Rigid,
        })
        .collect();
    // Graph colouring: groups that share a position need different ids.
    let mut colour = vec![u32::MAX; ncomp];
    let mut comp_pos: Vec<Vec<u32>> = vec![Vec::new(); ncomp];
    for (p, cs) in pos_comps.iter().enumerate() {
        for &c in cs {
            comp_pos[c as usize].push(p as u32);
        }
    }
    let mut colours = 0;
    for c in 0..ncomp {
        let mut used = Vec::new();
        for &p in &comp_pos[c] {
            for &o in &pos_comps[p as usize] {
                if colour[o as usize] != u32::MAX {
                    used.push(colour[o as usize]);
                }
            }
        }
        let k = (0..).find(|k| !used.contains(k)).unwrap_or(0);
        colour[c] = k;
        colours = colours.max(k + 1);
    }

    // The shrinking mesh. Leaves are nodes 0..np at positions 0..np.
    let mut w = Work {
        mesh,
        corners: tris.iter().map(|t| t.p).collect(),
        alive: vec![true; nt],
        comp,
        faces_of: vec![Vec::new(); np],
        node_pos: (0..np as u32).collect(),
        parent: vec![NONE; np],
        error: vec![0.0; np],
        radius: vec![0.0; np],
        cone: Vec::with_capacity(2 * np),
        class,
        pos_comps,
        recs: Vec::new(),
        stamp: vec![0; np],
    };
    for (f, t) in tris.iter().enumerate() {
        for &p in &t.p {
            w.faces_of[p as usize].push(f as u32);
        }
    }
    let mut ring = Vec::new();
    for v in 0..np as u32 {
        let normals: Vec<V3> = w.faces_of[v as usize]
            .iter()
            .map(|&f| norm(w.face_normal(w.corners[f as usize])))
            .collect();
        let axis = norm(
            normals
                .iter()
                .fold([0.0; 3], |a, n| [a[0] + n[0], a[1] + n[1], a[2] + n[2]]),
        );
        let angle = normals
            .iter()
            .map(|&n| dot(axis, n).clamp(-1.0, 1.0).acos())
            .fold(0.0f32, f32::max);
        w.cone.push(if axis == [0.0; 3] {
            ([0.0; 3], std::f32::consts::PI)
        } else {
            (axis, angle)
        });
        w.ring(v, &mut ring);
        w.radius[v as usize] = ring
            .iter()
            .map(|&o| len(sub(w.p(o), w.p(v))))
            .fold(0.0, f32::max);
    }

    // Passes of independent collapses, shortest edges first.
    let (mut ring_t, mut ring_u) = (Vec::new(), Vec::new());
    let mut pass = 0u32;
    loop {
        pass += 1;
        let mut cands: Vec<(u32, u32, u32)> = Vec::new();
        for f in 0..nt {
            if !w.alive[f] {
                continue;
            }
            let c = w.corners[f];
            for k in 0..3 {
                let (a, b) = (c[k], c[(k + 1) % 3]);
                if a < b || w.dir_face(b, a).is_none() {
                    cands.push((len(sub(w.p(a), w.p(b))).to_bits(), a, b));
                }
            }
        }
        cands.sort_unstable();
        let mut applied = 0;
        for &(_, a, b) in &cands {
            if w.stamp[a as usize] == pass || w.stamp[b as usize] == pass {
                continue;
            }
            let x = w.check(b, a, &mut ring_t, &mut ring_u);
            let y = w.check(a, b, &mut ring_t, &mut ring_u);
            let best = match (x, y) {
                (Some(x), Some(y)) => Some(if y.1 < x.1 { y } else { x }),
                (x, y) => x.or(y),
            };
            let Some((rec, dev)) = best else { continue };
            let mut touched = Vec::new();
            w.ring(rec.t, &mut ring_t);
            touched.extend_from_slice(&ring_t);
            w.ring(rec.u, &mut ring_u);
            touched.extend_from_slice(&ring_u);
            let s = w.apply(rec, dev);
            for v in touched.into_iter().chain([rec.t, rec.u, s]) {
                w.stamp[v as usize] = pass;
            }
            applied += 1;
        }
        if applied == 0 {
            break;
        }
    }
    finish(w, colour, colours, ncomp as u32, vkey)
}

/// Renumbers into the file's order and fills the records.
fn finish(
    w: Work<'_>,
    colour: Vec<u32>,
    colours: u32,
    ncomp: u32,
    vkey: HashMap<(u32, u32), usize>,
) -> Built {
    let mesh = w.mesh;
    let np = mesh.positions.len();
    let nt = mesh.triangles.len();
    let created = w.recs.len();
    // Splittable nodes in depth-first preorder, stationary child first, roots in position
    // order: a subtree is a contiguous id range and a stationary child follows its parent, so
    // the records a refinement pass reads together lie together. Then the leaves, in
    // position order.
    let mut split_new = vec![u32::MAX; created];
    let mut by_new = Vec::with_capacity(created);
    let mut stack: Vec<u32> = (0..(np + created) as u32)
        .filter(|&o| w.parent[o as usize] == NONE && o as usize >= np)
        .collect();
    stack.sort_unstable_by_key(|&o| std::cmp::Reverse(w.node_pos[o as usize]));
    while let Some(o) = stack.pop() {
        let c = o as usize - np;
        split_new[c] = by_new.len() as u32;
        by_new.push(c);
        for child in [w.recs[c].u, w.recs[c].t] {
            if child as usize >= np {
                stack.push(child);
            }
        }
    }
    let new_id = |old: u32| -> u32 {
        if (old as usize) < np {
            (created + old as usize) as u32
        } else {
            split_new[old as usize - np]
        }
    };
    let total_nodes = np + created;
    let mut nodes = vec![
        Node {
            parent: NodeId::NONE,
            position: PositionId(0)
        };
        total_nodes
    ];
    for old in 0..total_nodes as u32 {
        let p = w.parent[old as usize];
        nodes[new_id(old) as usize] = Node {
            parent: if p == NONE {
                NodeId::NONE
            } else {
                NodeId(new_id(p))
            },
            position: PositionId(w.node_pos[old as usize]),
        };
    }
    // Polygons: base first, then each split's f_l, f_r in split order.
    let mut poly_new = vec![NONE; nt];
    let mut order: Vec<(u32, u8)> = Vec::with_capacity(nt);
    for f in 0..nt {
        if w.alive[f] {
            poly_new[f] = order.len() as u32;
            order.push((f as u32, 0));
        }
    }
    let base_count = order.len();
    for &c in &by_new {
        let r = w.recs[c];
        poly_new[r.fl as usize] = order.len() as u32;
        order.push((r.fl, r.rot_l));
        if r.fr != NONE {
            poly_new[r.fr as usize] = order.len() as u32;
            order.push((r.fr, r.rot_r));
        }
    }
    let creator_of = {
        let mut v = vec![Creator::BASE; nt];
        for (c, r) in w.recs.iter().enumerate() {
            let s = NodeId(new_id((np + c) as u32));
            v[r.fl as usize] = Creator::new(s, false);
            if r.fr != NONE {
                v[r.fr as usize] = Creator::new(s, true);
            }
        }
        v
    };
    let polygons: Vec<Polygon> = order
        .iter()
        .map(|&(f, rot)| {
            let t = &mesh.triangles[f as usize];
            let k = rot as usize;
            let rotated = [t.p[k], t.p[(k + 1) % 3], t.p[(k + 2) % 3]];
            Polygon {
                nodes: rotated.map(|p| NodeId(new_id(p))),
                creator: creator_of[f as usize],
                surface: SurfaceId(t.surface),
                group: SurfaceGroupId(colour[w.comp[f as usize] as usize] as u16),
            }
        })
        .collect();
    let pid = |f: u32| {
        if f == NONE {
            PolyId::NONE
        } else {
            PolyId(poly_new[f as usize])
        }
    };
    let mut splits = vec![bytemuck::Zeroable::zeroed(); created];
    let mut bounds = vec![bytemuck::Zeroable::zeroed(); created];
    for (c, r) in w.recs.iter().enumerate() {
        let old = (np + c) as u32;
        let (axis, angle) = w.cone[old as usize];
        let sin2 = if angle >= std::f32::consts::FRAC_PI_2 {
            1.0
        } else {
            angle.sin() * angle.sin()
        };
        splits[new_id(old) as usize] = Split {
            stationary: NodeId(new_id(r.t)),
            floating: NodeId(new_id(r.u)),
            f_l: pid(r.fl),
            f_r: pid(r.fr),
            neighbours: r.fns.map(pid),
        };
        bounds[new_id(old) as usize] = SplitBounds::new(
            mesh.positions[w.node_pos[old as usize] as usize],
            w.radius[old as usize],
            if sin2 >= 1.0 { [0.0; 3] } else { axis },
            sin2,
            w.error[old as usize],
            0.0,
        );
    }
    let mut roots: Vec<NodeId> = (0..total_nodes as u32)
        .filter(|&o| w.parent[o as usize] == NONE)
        .map(|o| NodeId(new_id(o)))
        .collect();
    roots.sort_unstable();
    let base: Vec<BaseFace> = order[..base_count]
        .iter()
        .map(|&(f, _)| {
            let c = w.corners[f as usize];
            BaseFace {
                corners: c.map(|x| NodeId(new_id(x))),
                neighbours: [0, 1, 2].map(|k| pid(w.across(f, c[(k + 1) % 3], c[(k + 2) % 3]))),
            }
        })
        .collect();
    // Vertex table and vertex buffer, in position order.
    let mut vertex_table_offsets = vec![0u32];
    let mut vertex_table = Vec::new();
    let mut vertices = Vec::new();
    for p in 0..np {
        let mut keys: Vec<(u32, usize)> = w.pos_comps[p]
            .iter()
            .map(|&c| (colour[c as usize], vkey[&(c, p as u32)]))
            .collect();
        keys.sort_unstable();
        for (group, f) in keys {
            let t = &mesh.triangles[f];
            let k = t.p.iter().position(|&x| x == p as u32).unwrap_or(0);
            vertex_table.push(VertexKey {
                group: SurfaceGroupId(group as u16),
                reserved: 0,
                vertex: vertices.len() as u32,
            });
            vertices.push(Vertex {
                position: mesh.positions[p],
                normal: t.normal[k],
                uv: t.uv[k],
            });
        }
        vertex_table_offsets.push(vertex_table.len() as u32);
    }
    let positions = mesh
        .positions
        .iter()
        .zip(&w.class)
        .map(|(&xyz, &c)| Position {
            xyz,
            class: c as u32,
        })
        .collect();
    Built {
        positions,
        nodes,
        splits,
        bounds,
        polygons,
        roots,
        base,
        vertex_table_offsets,
        vertex_table,
        vertices,
        surface_count: mesh.surface_count() as u32,
        surface_group_count: colours,
        surface_groups: ncomp,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::meshes;

    #[test]
    fn builds_valid_hierarchies() {
        for m in [
            meshes::terrain(12, 10, 1),
            meshes::sphere(2),
            meshes::holed_terrain(16, 16, 2),
        ] {
            let b = build(&m);
            let h = b.hierarchy();
            assert!(
                h.base_polygon_count() < m.triangles.len() / 4,
                "{} of {}",
                h.base_polygon_count(),
                m.triangles.len()
            );
            let bytes = b.to_bytes();
            let h2 = Hierarchy::from_bytes(&bytes).expect("file validates");
            assert_eq!(h2.meta(), h.meta());
        }
    }
}
