//! Building the vertex hierarchy by half-edge collapses.
//!
//! - **Half-edge collapses** only: the parent keeps the stationary child's position, so no
//!   vertex is ever created and the vertex buffer is the full-resolution one.
//! - **Batches of independent collapses** (as g-mesh builds its levels): each pass sorts the
//!   legal collapses by cost and applies those whose neighbourhoods do not overlap, so the
//!   hierarchy is balanced and shallow (depth grows with the logarithm of the size). A pass
//!   goes only through the cheapest half of its ranked collapses ([`PASS_SHARE`]): applying
//!   every independent one lets dear collapses take neighbourhoods that cheaper ones of the
//!   next pass would have used (measured on lucy and St. Helens against meshoptimizer, this
//!   ordering is a large part of the difference; it costs passes, not depth).
//! - **Cost**: the attribute-aware quadric of the removed position's wedges (one per surface
//!   group there) evaluated at the kept position with that group's attributes there
//!   ([`crate::quadric`]), plus boundary planes that hold mesh borders and surface-group
//!   boundaries in place, weighted [`BOUNDARY_WEIGHT`] times a triangle's (sliding borders
//!   were the largest errors on terrain). A normal that follows from the geometry
//!   ([`crate::weld::Attributes::normal_from_geometry`]: computed, or an importer's smooth
//!   one) gets no weight: it would only make curved regions dearer, which the distance
//!   term already does, at the expense of geometric accuracy.
//! - **Legality**: the surface-group rules (a RIGID position never floats; a SHARP one floats
//!   only along a boundary edge onto a non-FREE position; every group at the removed position
//!   must have a vertex at the kept one), the link condition, no doubled faces, no face
//!   flipped or collapsed, and Hoppe's requirement that `fl_clw` (and `fr_ccw` when `f_r`
//!   exists) are present.
//! - **Bounds for refinement**: the bounding-sphere radius and normal cone of everything
//!   below a node, and its error (`uni_error`) from the residuals of the input, as Hoppe's
//!   view-dependent progressive meshes (1997) measure it: every input position belongs to
//!   a current triangle near it; a collapse hands the positions of the removed node's
//!   triangles to the nearest of the triangles that replace them, and the node's error is
//!   the largest of those distances and its children's errors. It measures what a cut
//!   through the node loses, including borders that slide, where the planes' distances
//!   alone miss it. The hand-over runs after each pass on all threads (the collapses of a
//!   pass have disjoint stars); it takes about a sixth of a lucy bake's instructions and
//!   a fifth of St. Helens'.
//!
//! A pass is built for speed without changing its outcome: every edge is ranked by the cost
//! of its cheaper allowed direction (a ranking stands while the edge's ends are the same
//! nodes, and ranking runs on all threads), and the legality checks run only for the
//! collapses the pass reaches with both ends free, as they stood at the start of the pass.
//! The result is the same as checking every edge first and sorting the legal collapses
//! stably by cost.

use caveclod_core::format::PositionClass;

use crate::quadric::{Quadric, M};
use crate::weld::Welded;

const NONE: u32 = u32::MAX;

type V3 = [f64; 3];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn len(a: V3) -> f64 {
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

/// Weights of the attribute kinds, relative to the mesh's bounding-box diagonal: an
/// attribute difference of 1 costs as much as a distance of `weight × diagonal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AttributeWeights {
    /// Unit normals.
    pub normal: f64,
    /// Texture coordinates.
    pub uv: f64,
    /// Colours (0..1 per channel).
    pub color: f64,
}

impl Default for AttributeWeights {
    fn default() -> Self {
        Self {
            normal: 0.01,
            uv: 0.02,
            color: 0.01,
        }
    }
}

/// One collapse, as its split will replay it.
#[derive(Clone, Copy, Debug)]
pub struct Collapse {
    /// The stationary child (kept).
    pub t: u32,
    /// The floating child (removed).
    pub u: u32,
    /// Triangle left of the edge `t→u` (dies).
    pub fl: u32,
    /// Triangle right of it, or `NONE` on a border (dies).
    pub fr: u32,
    /// `[fl_ccw, fl_clw, fr_clw, fr_ccw]`, triangle ids or `NONE`.
    pub neighbours: [u32; 4],
    /// Corner of `fl` holding `t` (the polygon's rotation).
    pub rot_l: u8,
    /// Corner of `fr` holding `t`.
    pub rot_r: u8,
}

/// The result: nodes `0..positions` are the leaves; collapse `c` creates node
/// `positions + c`.
#[derive(Clone, Debug, Default)]
pub struct Hierarchy {
    /// Collapses in the order applied.
    pub collapses: Vec<Collapse>,
    /// Parent of every node, `NONE` for roots.
    pub parent: Vec<u32>,
    /// Position of every node.
    pub node_position: Vec<u32>,
    /// Radius of the sphere around the node's position bounding its descendants' triangles.
    pub radius: Vec<f32>,
    /// Normal cone `(axis, half angle)` of every node.
    pub cone: Vec<([f32; 3], f32)>,
    /// Error bound of every node (world units; zero for leaves).
    pub error: Vec<f32>,
    /// Current corners of every triangle at the end (the base mesh's for those alive).
    pub corners: Vec<[u32; 3]>,
    /// Which triangles are in the base mesh.
    pub alive: Vec<bool>,
    /// Number of batches (passes).
    pub passes: u32,
}

/// Progress of a build: `(collapses so far, at most collapsible)`.
pub type Progress<'a> = &'a mut dyn FnMut(u64, u64);

struct Wedge {
    group: u32,
    attrs: [f64; M],
    q: Quadric,
}

/// A collapse as a pass ranks it: `(cost, t, u)`.
type Candidate = (f64, u32, u32);

/// The ranking of one edge slot (3 per triangle) in the current pass.
#[derive(Clone, Copy)]
struct Slot {
    /// The edge's ends, first and second corner of the slot, at the start of the pass.
    ends: [u32; 2],
    /// Quadric costs of the two directions for these ends (direction 1 moves the first end
    /// onto the second, direction 2 the reverse), infinite where not allowed.
    costs: [f64; 2],
    /// The cheaper allowed direction (the first on a tie), 0 for none.
    dir: u8,
}

impl Slot {
    /// The cheaper allowed direction's cost.
    fn cost(&self) -> f64 {
        self.costs[self.dir as usize - 1]
    }

    /// The other direction's cost, infinite where not allowed.
    fn other(&self) -> f64 {
        self.costs[2 - self.dir as usize]
    }
}

impl Default for Slot {
    fn default() -> Self {
        Self {
            ends: [NONE; 2],
            costs: [f64::INFINITY; 2],
            dir: 0,
        }
    }
}

/// What [`Work::verdict`] found.
enum Verdict {
    /// Not legal at the start of the pass.
    Illegal,
    /// Legal at the start of the pass but no longer.
    Lapsed,
    /// Legal: the collapse.
    Legal(Collapse),
}

/// A triangle of the mesh being simplified, in one cache line.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Tri {
    /// Current corners (nodes), counter-clockwise.
    c: [u32; 3],
    /// `o[k]`: the triangle across the edge `c[k] → c[k + 1]`, or `NONE`. The mesh stays
    /// an oriented manifold, so that triangle holds the edge the other way round.
    o: [u32; 3],
    /// Surface group.
    group: u32,
    /// Unnormalised normal at the current corners.
    n: V3,
    /// Its length.
    len: f64,
}

/// What the hierarchy records of a node.
#[derive(Clone, Copy)]
struct NodeOut {
    parent: u32,
    error: f32,
    radius: f32,
    cone: ([f32; 3], f32),
}

/// What the surface-group rules read of a position.
#[derive(Clone, Copy)]
struct PosInfo {
    class: PositionClass,
    /// The position's one surface group, or `NONE` when it has several.
    group: u32,
}

/// The mesh being simplified, with per node its triangles.
struct Work<'w> {
    w: &'w Welded,
    /// Point of every position.
    p: Vec<V3>,
    info: Vec<PosInfo>,
    tris: Vec<Tri>,
    alive: Vec<bool>,
    /// Point of every node (its position's).
    pos: Vec<V3>,
    /// Triangles around every node.
    faces_of: Vec<Vec<u32>>,
    /// Number of distinct neighbours of every live node.
    valence: Vec<u32>,
    node_pos: Vec<u32>,
    /// Wedges of position `x`: `wedges[wedge_start[x]..wedge_start[x + 1]]`.
    wedges: Vec<Wedge>,
    wedge_start: Vec<u32>,
    h: Hierarchy,
    /// Per node: parent, and the bounds of [`Hierarchy`] (kept together here).
    nodes: Vec<NodeOut>,
    /// Pass in which a node's neighbourhood was last taken by a collapse.
    stamp: Vec<u32>,
    /// Pass in which a node last lost a neighbour.
    shrunk: Vec<u32>,
    /// A node's number of neighbours at the start of the pass it last lost one in.
    start_valence: Vec<u32>,
    /// The input's positions each triangle stands for (nearest to it when it last
    /// changed), which the error bounds measure; relative to the centre.
    pts_of: Vec<Vec<P3>>,
    /// Points the pass's collapses moved, waiting for [`Work::settle`], each with the new
    /// node whose triangles it goes to (those of one node in a row).
    moved: Vec<(P3, u32)>,
    /// Per collapse of the pass, in order: how many of its new node's triangles came from
    /// the kept child (they are listed first; the removed child's follow).
    from_kept: Vec<u32>,
}

/// A point the error bounds measure (single precision is ample for an error bound).
type P3 = [f32; 3];

impl Work<'_> {
    #[inline]
    fn wedges_at(&self, pos: usize) -> &[Wedge] {
        &self.wedges[self.wedge_start[pos] as usize..self.wedge_start[pos + 1] as usize]
    }

    /// The triangle with the directed edge `a → b` and the corner of `a` in it.
    #[inline]
    fn dir_face(&self, a: u32, b: u32) -> Option<(u32, usize)> {
        for &f in &self.faces_of[a as usize] {
            let c = self.tris[f as usize].c;
            let j = corner_of(c, a);
            if c[next(j)] == b {
                return Some((f, j));
            }
        }
        None
    }

    /// The distinct neighbours of `v` into `out`; returns whether `v` is on a border.
    ///
    /// Every neighbour `x` is reached once: through the triangle with the edge `v → x`, or,
    /// when there is none, through the border triangle with `x → v`.
    fn find_ring(&self, v: u32, out: &mut Vec<u32>) -> bool {
        out.clear();
        let mut border = false;
        for &f in &self.faces_of[v as usize] {
            let t = &self.tris[f as usize];
            let j = corner_of(t.c, v);
            out.push(t.c[next(j)]);
            if t.o[prev(j)] == NONE {
                out.push(t.c[prev(j)]);
                border = true;
            }
            border |= t.o[j] == NONE;
        }
        border
    }

    #[inline]
    fn triangle_normal(&self, c: [u32; 3]) -> V3 {
        let (a, b, d) = (
            self.pos[c[0] as usize],
            self.pos[c[1] as usize],
            self.pos[c[2] as usize],
        );
        cross(sub(b, a), sub(d, a))
    }

    /// Quadric cost of moving `u`'s wedges onto `t`.
    fn cost(&self, t: u32, u: u32) -> f64 {
        let (pt, pu) = (
            self.node_pos[t as usize] as usize,
            self.node_pos[u as usize] as usize,
        );
        let at = self.wedges_at(pt);
        self.wedges_at(pu)
            .iter()
            .map(|wu| match at.iter().find(|wt| wt.group == wu.group) {
                Some(wt) => wu.q.eval(self.p[pt], &wt.attrs),
                None => f64::INFINITY,
            })
            .sum()
    }

    /// The link condition on the edge `a`–`b` (the ends share exactly the neighbours that
    /// are the third corners of the triangles on the edge, `r` being the second's or
    /// `NONE` on a border), and no interior edge between two border nodes.
    fn link_ok(ra: &[u32], border_a: bool, rb: &[u32], border_b: bool, r: u32) -> bool {
        if r != NONE && border_a && border_b {
            return false;
        }
        let shared = if rb.len() <= 8 {
            // No node is NONE, so the padding matches nothing.
            let mut pad = [NONE; 8];
            pad[..rb.len()].copy_from_slice(rb);
            ra.iter()
                .map(|&x| pad.iter().map(|&y| usize::from(x == y)).sum::<usize>())
                .sum::<usize>()
        } else {
            ra.iter().filter(|x| rb.contains(x)).count()
        };
        shared == 1 + usize::from(r != NONE)
    }

    /// Number of neighbours of `x` at the start of pass `pass`.
    #[inline]
    fn valence_at_start(&self, x: u32, pass: u32) -> usize {
        if self.shrunk[x as usize] == pass {
            self.start_valence[x as usize] as usize
        } else {
            self.valence[x as usize] as usize
        }
    }

    /// The surface-group rules for moving `u` onto `t` across an edge with the triangles
    /// `fl` and `fr` (`NONE` on a border): a RIGID position never floats; a SHARP one
    /// floats only along a boundary onto a non-FREE one; every group at `u` has a vertex
    /// at `t`.
    #[inline]
    fn groups_ok(&self, t: u32, u: u32, fl: u32, fr: u32) -> bool {
        let (pt, pu) = (
            self.node_pos[t as usize] as usize,
            self.node_pos[u as usize] as usize,
        );
        let (it, iu) = (self.info[pt], self.info[pu]);
        match iu.class {
            PositionClass::Rigid => return false,
            PositionClass::Sharp => {
                let group = |f: u32| self.tris[f as usize].group;
                let boundary = fr == NONE || group(fl) != group(fr);
                if !boundary || it.class == PositionClass::Free {
                    return false;
                }
            }
            PositionClass::Free => {}
        }
        if iu.group != NONE && it.group != NONE {
            return iu.group == it.group;
        }
        let (vu, vt) = (&self.w.vertices[pu], &self.w.vertices[pt]);
        vu.iter().all(|(g, _)| vt.iter().any(|(h, _)| h == g))
    }

    /// The checks of the collapse of `u` into `t` that look at `u`'s triangles, `fl` being
    /// the triangle with the edge `t → u` (`t` at its corner `jl`) and `fr` the one across
    /// or `NONE`: Hoppe's neighbours exist, no triangle flips or collapses.
    fn moves(&self, t: u32, u: u32, fl: u32, jl: usize, fr: u32) -> Option<Collapse> {
        let ol = self.tris[fl as usize].o;
        let fn0 = ol[prev(jl)];
        let fn1 = ol[next(jl)];
        if fn1 == NONE {
            return None;
        }
        let (mut fn2, mut fn3, mut jr) = (NONE, NONE, 0);
        if fr != NONE {
            let r = &self.tris[fr as usize];
            jr = corner_of(r.c, t);
            fn2 = r.o[jr];
            fn3 = r.o[next(jr)];
            if fn3 == NONE {
                return None;
            }
        }
        let p_t = self.pos[t as usize];
        for &f in &self.faces_of[u as usize] {
            if f == fl || f == fr {
                continue;
            }
            let tri = &self.tris[f as usize];
            let c = tri.c;
            let mut q = [
                self.pos[c[0] as usize],
                self.pos[c[1] as usize],
                self.pos[c[2] as usize],
            ];
            q[corner_of(c, u)] = p_t;
            let after = cross(sub(q[1], q[0]), sub(q[2], q[0]));
            let (before, lb) = (tri.n, tri.len);
            let la = len(after);
            if la <= 1e-12 * (1.0 + lb) || dot(before, after) <= 0.2 * lb * la {
                return None;
            }
        }
        let c = Collapse {
            t,
            u,
            fl,
            fr,
            neighbours: [fn0, fn1, fn2, fn3],
            rot_l: jl as u8,
            rot_r: jr as u8,
        };
        Some(c)
    }

    /// The corner of triangle `f` after `v` (for a triangle on the edge `u → v`, its third
    /// corner), or `NONE` for no triangle.
    #[inline]
    fn third(&self, f: u32, v: u32) -> u32 {
        if f == NONE {
            return NONE;
        }
        let c = self.tris[f as usize].c;
        c[next(corner_of(c, v))]
    }

    /// Ranks the edge in slot `k` of triangle `f` if the slot stands for its edge (the
    /// lower-numbered end first, or a border edge): the quadric costs of the directions
    /// the surface-group rules allow, the cheaper first (the first on a tie).
    ///
    /// A ranking stands while the edge's ends are the same nodes: it reads their quadrics
    /// and positions (a node's never change), the groups of the triangles on the edge, and
    /// which those are (they change only by a collapse that also changes an end).
    fn rank(&self, f: u32, k: usize, slot: &mut Slot) {
        let tri = &self.tris[f as usize];
        let (a, b, g) = (tri.c[k], tri.c[next(k)], tri.o[k]);
        if slot.ends == [a, b] {
            return;
        }
        *slot = Slot {
            ends: [a, b],
            ..Slot::default()
        };
        if !(a < b || g == NONE) {
            return;
        }
        // Direction 1 moves a onto b across g (t = b, u = a); direction 2 the reverse.
        let cx = if g != NONE && self.groups_ok(b, a, g, f) {
            self.cost(b, a)
        } else {
            f64::INFINITY
        };
        let cy = if self.groups_ok(a, b, f, g) {
            self.cost(a, b)
        } else {
            f64::INFINITY
        };
        slot.costs = [cx, cy];
        let (cost, dir) = if cy < cx { (cy, 2) } else { (cx, 1) };
        if cost.is_finite() {
            slot.dir = dir;
        }
    }

    /// The checks of the collapse of `u` into `t` (which the surface-group rules allow, at
    /// a finite cost) as they stood at the start of pass `pass`, and as they stand now;
    /// the rings of `t` and `u` go to `rings`. Neither end was touched since (callers skip
    /// stamped ends), so their stars, rings and borders are as they were; only a third
    /// corner of the edge may have lost a neighbour since.
    fn verdict(&self, t: u32, u: u32, pass: u32, rings: &mut [Vec<u32>; 2]) -> Verdict {
        let Some((fl, jl)) = self.dir_face(t, u) else {
            return Verdict::Illegal;
        };
        let fr = self.tris[fl as usize].o[jl];
        let l = self.tris[fl as usize].c[prev(jl)];
        let r = self.third(fr, t);
        let opposite = [l, r];
        if !opposite
            .iter()
            .all(|&x| x == NONE || self.valence_at_start(x, pass) > 3)
        {
            return Verdict::Illegal;
        }
        let [ring_t, ring_u] = rings;
        let border_t = self.find_ring(t, ring_t);
        let border_u = self.find_ring(u, ring_u);
        if !Self::link_ok(ring_t, border_t, ring_u, border_u, r) {
            return Verdict::Illegal;
        }
        let Some(c) = self.moves(t, u, fl, jl, fr) else {
            return Verdict::Illegal;
        };
        if opposite
            .iter()
            .all(|&x| x == NONE || self.valence[x as usize] > 3)
        {
            Verdict::Legal(c)
        } else {
            Verdict::Lapsed
        }
    }

    /// Applies a checked collapse; returns the new node. The points of `u`'s triangles
    /// (those dying included) wait for [`Work::settle`] to find their nearest triangle
    /// around the new node.
    fn apply(&mut self, c: Collapse) -> u32 {
        let s = self.node_pos.len() as u32;
        let (t, u) = (c.t, c.u);
        for &f in &self.faces_of[u as usize] {
            self.moved
                .extend(self.pts_of[f as usize].drain(..).map(|x| (x, s)));
        }
        let (pt, pu) = (self.node_pos[t as usize], self.node_pos[u as usize]);
        self.node_pos.push(pt);
        self.nodes[t as usize].parent = s;
        self.nodes[u as usize].parent = s;
        let (nt, nu) = (self.nodes[t as usize], self.nodes[u as usize]);
        let (p_t, p_u) = (self.pos[t as usize], self.pos[u as usize]);
        self.pos.push(p_t);
        self.nodes.push(NodeOut {
            parent: NONE,
            error: nt.error.max(nu.error),
            radius: (nt.radius as f64).max(len(sub(p_u, p_t)) + nu.radius as f64) as f32,
            cone: merge_cones(nt.cone, nu.cone),
        });
        // The removed position's wedges merge into the kept position's.
        let (st, et) = (
            self.wedge_start[pt as usize] as usize,
            self.wedge_start[pt as usize + 1] as usize,
        );
        for i in self.wedge_start[pu as usize] as usize..self.wedge_start[pu as usize + 1] as usize
        {
            let g = self.wedges[i].group;
            if let Some(j) = (st..et).find(|&j| self.wedges[j].group == g) {
                let q = self.wedges[i].q;
                self.wedges[j].q.add(&q);
            }
        }
        // The triangles across each dying one's two other edges become neighbours.
        for f in [c.fl, c.fr] {
            if f == NONE {
                continue;
            }
            self.alive[f as usize] = false;
            let Tri { c: fc, o, .. } = self.tris[f as usize];
            let j = corner_of(fc, t);
            // The edge t–u is slot j of f_l and slot prev(j) of f_r.
            let on_edge = if f == c.fl { j } else { prev(j) };
            let (x, y) = (o[next(on_edge)], o[prev(on_edge)]);
            for (a, b) in [(x, y), (y, x)] {
                if a != NONE {
                    let oa = &mut self.tris[a as usize].o;
                    if let Some(k) = oa.iter().position(|&g| g == f) {
                        oa[k] = b;
                    }
                }
            }
            for x in fc {
                self.faces_of[x as usize].retain(|&g| g != f);
            }
        }
        let mut star = std::mem::take(&mut self.faces_of[t as usize]);
        self.from_kept.push(star.len() as u32);
        star.append(&mut std::mem::take(&mut self.faces_of[u as usize]));
        for &f in &star {
            let mut tri = self.tris[f as usize];
            for x in tri.c.iter_mut() {
                if *x == t || *x == u {
                    *x = s;
                }
            }
            tri.n = self.triangle_normal(tri.c);
            tri.len = len(tri.n);
            self.tris[f as usize] = tri;
        }
        self.faces_of.push(star);
        self.stamp.push(0);
        self.shrunk.push(0);
        self.start_valence.push(0);
        // The ends' rings share just l and r (the link condition): the new node has the
        // other neighbours of both, and l and r lose one.
        let (l, r) = (
            self.tris[c.fl as usize].c[prev(c.rot_l as usize)],
            self.third(c.fr, t),
        );
        let shared = 1 + u32::from(r != NONE);
        self.valence
            .push(self.valence[t as usize] + self.valence[u as usize] - 2 - shared);
        for x in [l, r] {
            if x != NONE {
                self.valence[x as usize] -= 1;
            }
        }
        #[cfg(debug_assertions)]
        {
            let mut ring = Vec::new();
            self.find_ring(s, &mut ring);
            let mut around = Vec::new();
            for x in std::iter::once(s).chain(ring.iter().copied()) {
                self.find_ring(x, &mut around);
                debug_assert_eq!(self.valence[x as usize] as usize, around.len(), "{x}");
            }
        }
        self.h.collapses.push(c);
        s
    }

    /// The points of the error bounds, the input's positions, each given to a triangle it
    /// is a corner of (its first).
    fn place_points(&mut self) {
        self.pts_of = vec![Vec::new(); self.tris.len()];
        for (x, faces) in self.faces_of[..self.p.len()].iter().enumerate() {
            if let Some(&f) = faces.first() {
                self.pts_of[f as usize].push(self.p[x].map(|c| c as f32));
            }
        }
    }

    /// The nearest triangle of `star` to each of `points` and the squared distance, into
    /// `out`; `tris` is scratch space.
    fn nearest(
        &self,
        star: &[u32],
        points: &[(P3, u32)],
        tris: &mut Vec<([V3; 3], V3, f64)>,
        out: &mut Vec<(f64, u32)>,
    ) {
        // The triangles' corners and plane normals, gathered once for all the points.
        tris.clear();
        tris.extend(star.iter().map(|&f| {
            let tri = &self.tris[f as usize];
            (
                tri.c.map(|v| self.pos[v as usize]),
                tri.n,
                tri.len * tri.len,
            )
        }));
        for &(x, _) in points {
            let x = x.map(f64::from);
            let mut best = (f64::INFINITY, NONE);
            for (&f, &([a, b, c], n, len2)) in star.iter().zip(tris.iter()) {
                // The distance to the plane is a lower bound.
                let h = dot(sub(x, a), n);
                if len2 > 0.0 && h * h >= best.0 * len2 {
                    continue;
                }
                let d = point_triangle_d2(x, a, b, c);
                if d < best.0 {
                    best = (d, f);
                }
            }
            out.push(best);
        }
    }

    /// Gives each point a collapse of the pass moved to the nearest of the triangles that
    /// replace the removed child's (its ring fanned from the kept child: the same stretch
    /// of surface; a nearer triangle elsewhere would only lower the distance, so this is an
    /// upper bound at half the work of searching the whole star), and raises the new
    /// node's error to the largest such distance. The collapses of a pass have disjoint
    /// stars, which no later collapse of the pass changes, so this runs after the pass, on
    /// all threads.
    fn settle(&mut self, threads: usize) {
        let moved = std::mem::take(&mut self.moved);
        // Runs of points going to one node, split over the threads at run boundaries.
        let per = moved.len().div_ceil(threads.max(1)).max(PARALLEL_MIN);
        let mut parts = Vec::new();
        let mut lo = 0;
        while lo < moved.len() {
            let mut hi = (lo + per).min(moved.len());
            while hi < moved.len() && moved[hi].1 == moved[hi - 1].1 {
                hi += 1;
            }
            parts.push(&moved[lo..hi]);
            lo = hi;
        }
        let this = &*self;
        let first_node = self.nodes.len() - self.from_kept.len();
        let run = |part: &[(P3, u32)]| {
            let (mut out, mut tris) = (Vec::with_capacity(part.len()), Vec::new());
            for points in part.chunk_by(|a, b| a.1 == b.1) {
                let s = points[0].1 as usize;
                let star = &this.faces_of[s];
                let from_kept = this.from_kept[s - first_node] as usize;
                let moved_ones = if from_kept < star.len() {
                    &star[from_kept..]
                } else {
                    star
                };
                this.nearest(moved_ones, points, &mut tris, &mut out);
            }
            out
        };
        let found: Vec<Vec<(f64, u32)>> = if parts.len() <= 1 {
            parts.iter().map(|part| run(part)).collect()
        } else {
            std::thread::scope(|scope| {
                let handles: Vec<_> = parts
                    .iter()
                    .map(|part| {
                        let run = &run;
                        scope.spawn(move || run(part))
                    })
                    .collect();
                handles
                    .into_iter()
                    .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
                    .collect()
            })
        };
        for (&(x, s), &(d, f)) in moved.iter().zip(found.iter().flatten()) {
            if f != NONE {
                self.pts_of[f as usize].push(x);
                let error = &mut self.nodes[s as usize].error;
                *error = error.max(d.sqrt() as f32);
            }
        }
        self.moved = moved;
        self.moved.clear();
        self.from_kept.clear();
    }
}

/// Squared distance from `x` to the triangle `a b c` (Ericson, "Real-Time Collision
/// Detection", 5.1.5: the closest point by the Voronoi region of `x`).
fn point_triangle_d2(x: V3, a: V3, b: V3, c: V3) -> f64 {
    let d2 = |y: V3| dot(sub(x, y), sub(x, y));
    let along = |p: V3, s: f64, d: V3| [p[0] + s * d[0], p[1] + s * d[1], p[2] + s * d[2]];
    let (ab, ac, ax) = (sub(b, a), sub(c, a), sub(x, a));
    let (d1, d2_) = (dot(ab, ax), dot(ac, ax));
    if d1 <= 0.0 && d2_ <= 0.0 {
        return d2(a);
    }
    let bx = sub(x, b);
    let (d3, d4) = (dot(ab, bx), dot(ac, bx));
    if d3 >= 0.0 && d4 <= d3 {
        return d2(b);
    }
    let vc = d1 * d4 - d3 * d2_;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return d2(along(a, d1 / (d1 - d3), ab));
    }
    let cx = sub(x, c);
    let (d5, d6) = (dot(ab, cx), dot(ac, cx));
    if d6 >= 0.0 && d5 <= d6 {
        return d2(c);
    }
    let vb = d5 * d2_ - d1 * d6;
    if vb <= 0.0 && d2_ >= 0.0 && d6 <= 0.0 {
        return d2(along(a, d2_ / (d2_ - d6), ac));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return d2(along(b, w, sub(c, b)));
    }
    let denom = va + vb + vc;
    if denom <= 0.0 {
        // Degenerate: the nearest corner.
        return d2(a).min(d2(b)).min(d2(c));
    }
    let (v, w) = (vb / denom, vc / denom);
    d2(along(along(a, v, ab), w, ac))
}

#[inline]
fn next(k: usize) -> usize {
    if k == 2 {
        0
    } else {
        k + 1
    }
}

#[inline]
fn prev(k: usize) -> usize {
    if k == 0 {
        2
    } else {
        k - 1
    }
}

/// The corner of `c` holding `v` (which it must hold).
#[inline]
fn corner_of(c: [u32; 3], v: u32) -> usize {
    if c[0] == v {
        0
    } else if c[1] == v {
        1
    } else {
        debug_assert_eq!(c[2], v);
        2
    }
}

/// The bits of `x` as an unsigned number ordered as [`f64::total_cmp`] orders floats.
#[inline]
fn order_key(x: f64) -> u64 {
    let bits = x.to_bits();
    // Negative numbers: all bits flipped; others: the sign bit set.
    bits ^ (((bits as i64 >> 63) as u64) | (1 << 63))
}

/// The ranked collapses of a pass, handed out by cost, equal costs in the order they were
/// ranked. They are bucketed by the top bits of their cost first, and a bucket is sorted
/// only when reached, after dropping those whose ends are taken by then (which the pass
/// would skip wherever they stood).
#[derive(Default)]
struct Ranked {
    /// The candidates, bucket after bucket, each in ranking order.
    by_bucket: Vec<Candidate>,
    /// Where each bucket starts in `by_bucket`, and the end.
    bounds: Vec<u32>,
    /// The next bucket.
    bucket: usize,
    /// The current bucket's remaining candidates, sorted.
    chunk: Vec<Candidate>,
    /// The next one in `chunk`.
    pos: usize,
}

/// Bits of [`order_key`] that pick a bucket: sign, exponent and 4 bits of mantissa.
const BUCKET_BITS: u32 = 16;

/// Candidates below which a pass sorts them all at once.
const BUCKET_MIN: usize = 4096;

impl Ranked {
    /// Takes a pass's candidates, of which the pass means to apply the cheapest `share`;
    /// returns the [`order_key`] of the dearest cost in that share (for many candidates,
    /// rounded up to the end of its bucket). Only candidates up to it are handed out.
    fn start(&mut self, cands: &[Candidate], share: f64) -> u64 {
        self.chunk.clear();
        self.pos = 0;
        let want = ((cands.len() as f64 * share).ceil() as usize).clamp(1, cands.len().max(1));
        if cands.len() < BUCKET_MIN {
            self.chunk.extend_from_slice(cands);
            self.chunk.sort_by(|a, b| a.0.total_cmp(&b.0));
            self.bucket = self.bounds.len().saturating_sub(1);
            return match self.chunk.get(want - 1) {
                Some(c) if want < cands.len() => order_key(c.0),
                _ => u64::MAX,
            };
        }
        let bucket = |c: &Candidate| (order_key(c.0) >> (64 - BUCKET_BITS)) as usize;
        self.bounds.clear();
        self.bounds.resize((1 << BUCKET_BITS) + 1, 0);
        for c in cands {
            self.bounds[bucket(c) + 1] += 1;
        }
        for i in 0..1 << BUCKET_BITS {
            self.bounds[i + 1] += self.bounds[i];
        }
        // The bucket holding the `want`-th cheapest; those after it are left out.
        let last = self.bounds[1..].partition_point(|&n| (n as usize) < want);
        let limit = if last + 1 >= 1 << BUCKET_BITS {
            u64::MAX
        } else {
            (((last + 1) as u64) << (64 - BUCKET_BITS)) - 1
        };
        let kept = self.bounds[last + 1] as usize;
        self.bounds.truncate(last + 2);
        self.by_bucket.clear();
        self.by_bucket.resize(kept, (0.0, 0, 0));
        let mut fill = self.bounds.clone();
        for c in cands {
            let b = bucket(c);
            if b <= last {
                self.by_bucket[fill[b] as usize] = *c;
                fill[b] += 1;
            }
        }
        self.bucket = 0;
        limit
    }

    /// The next candidate whose ends were free when its bucket was reached.
    fn peek(&mut self, stamp: &[u32], pass: u32) -> Option<Candidate> {
        while self.pos == self.chunk.len() {
            if self.bucket + 1 >= self.bounds.len() {
                return None;
            }
            let (a, b) = (
                self.bounds[self.bucket] as usize,
                self.bounds[self.bucket + 1] as usize,
            );
            self.bucket += 1;
            if a == b {
                continue;
            }
            self.chunk.clear();
            self.pos = 0;
            self.chunk.extend(
                self.by_bucket[a..b]
                    .iter()
                    .filter(|c| stamp[c.1 as usize] != pass && stamp[c.2 as usize] != pass),
            );
            self.chunk.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        Some(self.chunk[self.pos])
    }

    fn advance(&mut self) {
        self.pos += 1;
    }
}

/// Smallest cone containing two cones `(axis, half angle)`.
fn merge_cones(a: ([f32; 3], f32), b: ([f32; 3], f32)) -> ([f32; 3], f32) {
    use std::f32::consts::PI;
    let d = (a.0[0] * b.0[0] + a.0[1] * b.0[1] + a.0[2] * b.0[2]).clamp(-1.0, 1.0);
    let phi = d.acos();
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
    let (wa, wb) = ((phi - alpha).sin() / phi.sin(), alpha.sin() / phi.sin());
    let axis = [
        a.0[0] * wa + b.0[0] * wb,
        a.0[1] * wa + b.0[1] * wb,
        a.0[2] * wa + b.0[2] * wb,
    ];
    let l = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    if l > 0.0 {
        ([axis[0] / l, axis[1] / l, axis[2] / l], theta)
    } else {
        (a.0, PI)
    }
}

fn scaled_attributes(w: &Welded, attr: u32, weights: &AttributeWeights, scale: f64) -> [f64; M] {
    let a = &w.attributes[attr as usize];
    let normal = if a.normal_from_geometry {
        0.0
    } else {
        weights.normal
    };
    let (wn, wu, wc) = (normal * scale, weights.uv * scale, weights.color * scale);
    [
        a.normal[0] as f64 * wn,
        a.normal[1] as f64 * wn,
        a.normal[2] as f64 * wn,
        a.uv[0] as f64 * wu,
        a.uv[1] as f64 * wu,
        a.color[0] as f64 * wc,
        a.color[1] as f64 * wc,
        a.color[2] as f64 * wc,
    ]
}

/// Builds the hierarchy of a welded mesh.
pub fn build(w: &Welded, weights: &AttributeWeights, progress: Progress<'_>) -> Hierarchy {
    let np = w.positions.len();
    let nt = w.triangles.len();
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(MAX_THREADS);
    // Work relative to the bounding box's centre, in f64.
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in &w.positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k] as f64);
            hi[k] = hi[k].max(p[k] as f64);
        }
    }
    let centre = [
        (lo[0] + hi[0]) / 2.0,
        (lo[1] + hi[1]) / 2.0,
        (lo[2] + hi[2]) / 2.0,
    ];
    let diagonal = len(sub(hi, lo)).max(f64::MIN_POSITIVE);
    let p: Vec<V3> = w
        .positions
        .iter()
        .map(|q| sub(q.map(f64::from), centre))
        .collect();
    let mut wedge_start = Vec::with_capacity(np + 1);
    let mut wedges = Vec::with_capacity(np);
    wedge_start.push(0u32);
    for vs in &w.vertices {
        wedges.extend(vs.iter().map(|&(group, a)| Wedge {
            group,
            attrs: scaled_attributes(w, a, weights, diagonal),
            q: Quadric::default(),
        }));
        wedge_start.push(wedges.len() as u32);
    }
    // Positions split into ranges, one per thread, for adding to their wedges in order.
    let per = if threads <= 1 || np < PARALLEL_MIN {
        np.max(1)
    } else {
        np.div_ceil(threads)
    };
    let ranges: Vec<(usize, usize)> = (0..np)
        .step_by(per)
        .map(|lo| (lo, (lo + per).min(np)))
        .collect();
    let mut faces_of: Vec<Vec<u32>> = vec![Vec::new(); np];
    // Triangle quadrics, computed in blocks on all threads and added in triangle order.
    for first in (0..nt).step_by(QUADRIC_BLOCK) {
        let n = (nt - first).min(QUADRIC_BLOCK);
        let block = par_map(n, threads, |i| {
            let t = &w.triangles[first + i];
            let s = t.a.map(|a| scaled_attributes(w, a, weights, diagonal));
            Quadric::triangle(t.p.map(|x| p[x as usize]), s)
        });
        by_positions(
            &ranges,
            &mut faces_of,
            &mut wedges,
            &wedge_start,
            |lo, hi, faces_of, wedges| {
                for (i, q) in block.iter().enumerate() {
                    let t = &w.triangles[first + i];
                    for &x in &t.p {
                        let x = x as usize;
                        if (lo..hi).contains(&x) {
                            faces_of[x - lo].push((first + i) as u32);
                            add_to_wedge(wedges, &wedge_start, lo, x, t.group, q);
                        }
                    }
                }
            },
        );
    }
    // The triangle across each edge: the one with the reverse edge.
    let opp = par_map(nt, threads, |f| {
        let c = w.triangles[f].p;
        [0, 1, 2].map(|k| {
            let (a, b) = (c[k], c[next(k)]);
            faces_of[b as usize]
                .iter()
                .copied()
                .find(|&g| {
                    let d = w.triangles[g as usize].p;
                    d[next(corner_of(d, b))] == a
                })
                .unwrap_or(NONE)
        })
    });
    let tris: Vec<Tri> = w
        .triangles
        .iter()
        .zip(&opp)
        .map(|(t, &o)| {
            let [a, b, d] = t.p.map(|x| p[x as usize]);
            let n = cross(sub(b, a), sub(d, a));
            Tri {
                c: t.p,
                o,
                group: t.group,
                n,
                len: len(n),
            }
        })
        .collect();
    drop(opp);
    // Boundary planes: through each border or group-boundary edge, perpendicular to its
    // triangle, weighted by the edge's squared length.
    let mut planes = Vec::new();
    for (f, t) in w.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t.p[k], t.p[next(k)]);
            let twin = tris[f].o[k];
            if twin != NONE && w.triangles[twin as usize].group == t.group {
                continue;
            }
            let (pa, pb, pc) = (p[a as usize], p[b as usize], p[t.p[prev(k)] as usize]);
            let e = sub(pb, pa);
            let n = norm(cross(e, cross(sub(pc, pa), e)));
            let weight = BOUNDARY_WEIGHT * dot(e, e);
            planes.push(([a, b], t.group, Quadric::plane(n, -dot(n, pa), weight)));
        }
    }
    by_positions(
        &ranges,
        &mut faces_of,
        &mut wedges,
        &wedge_start,
        |lo, hi, _, wedges| {
            for (ends, group, q) in &planes {
                for &x in ends {
                    let x = x as usize;
                    if (lo..hi).contains(&x) {
                        add_to_wedge(wedges, &wedge_start, lo, x, *group, q);
                    }
                }
            }
        },
    );
    drop(planes);
    let info = w
        .classes
        .iter()
        .zip(&w.vertices)
        .map(|(&class, vs)| PosInfo {
            class,
            group: match vs.as_slice() {
                [(g, _)] => *g,
                _ => NONE,
            },
        })
        .collect();
    let pos = p.clone();
    let mut work = Work {
        w,
        p,
        info,
        tris,
        alive: vec![true; nt],
        pos,
        faces_of,
        valence: Vec::new(),
        node_pos: (0..np as u32).collect(),
        wedges,
        wedge_start,
        h: Hierarchy::default(),
        nodes: Vec::new(),
        stamp: vec![0; np],
        shrunk: vec![0; np],
        start_valence: vec![0; np],
        pts_of: Vec::new(),
        moved: Vec::new(),
        from_kept: Vec::new(),
    };
    work.place_points();
    // Rings, borders, normal cones and bounding radii of the leaves.
    let leaves = par_map(np, threads, |v| {
        let v = v as u32;
        let mut ring = Vec::new();
        work.find_ring(v, &mut ring);
        let normals = work.faces_of[v as usize]
            .iter()
            .map(|&f| norm(work.tris[f as usize].n));
        let axis = norm(
            normals
                .clone()
                .fold([0.0; 3], |a, n| [a[0] + n[0], a[1] + n[1], a[2] + n[2]]),
        );
        let angle = normals
            .map(|n| dot(axis, n).clamp(-1.0, 1.0).acos())
            .fold(0.0f64, f64::max);
        let cone = if axis == [0.0; 3] {
            ([0.0; 3], std::f32::consts::PI)
        } else {
            (axis.map(|x| x as f32), angle as f32)
        };
        let pv = work.pos[v as usize];
        let radius = ring
            .iter()
            .map(|&o| len(sub(work.pos[o as usize], pv)))
            .fold(0.0, f64::max) as f32;
        (ring.len() as u32, cone, radius)
    });
    work.valence.reserve(2 * np);
    work.nodes.reserve(2 * np);
    for (valence, cone, radius) in leaves {
        work.valence.push(valence);
        work.nodes.push(NodeOut {
            parent: NONE,
            error: 0.0,
            radius,
            cone,
        });
    }

    // The live triangles and, for each, the ranking of its three edge slots.
    let mut live: Vec<u32> = (0..nt as u32).collect();
    let mut slots = vec![[Slot::default(); 3]; nt];
    let mut cands: Vec<Candidate> = Vec::new();
    let mut ranked = Ranked::default();
    let mut later: std::collections::BinaryHeap<std::cmp::Reverse<(u64, usize)>> =
        std::collections::BinaryHeap::new();
    let mut rings = [Vec::new(), Vec::new()];
    let most = np.saturating_sub(1) as u64;
    // Whether this pass may apply every ranked collapse (after one that applied none of
    // its cheapest share).
    let mut full = false;
    loop {
        work.h.passes += 1;
        let pass = work.h.passes;
        // Drop the triangles the last pass removed (keeping the order).
        live.retain(|&f| work.alive[f as usize]);
        // Each edge's cheaper allowed direction, by cost; equal costs in slot order (three
        // slots per triangle, in order).
        rank_all(&work, &live, &mut slots, &mut cands, threads);
        // The pass stops at the first collapse dearer than its cheapest share.
        let limit = ranked.start(&cands, if full { 1.0 } else { PASS_SHARE });
        let mut cut = false;
        // The pass applies, in that order, each edge's cheapest legal direction unless an
        // earlier collapse of the pass took a neighbourhood its ends are in (stamped), or
        // it lapsed since the start of the pass. A direction is checked only when reached
        // with both ends free; when it was illegal at the start of the pass, the edge's
        // other direction queues at its own cost (in the same order as if it had been
        // ranked with the others).
        let stamped = |work: &Work<'_>, t: u32, u: u32| {
            work.stamp[t as usize] == pass || work.stamp[u as usize] == pass
        };
        // The number of the slot standing for the edge of free ends t, u.
        let slot_of = |work: &Work<'_>, t: u32, u: u32| -> usize {
            let (fl, jl) = work.dir_face(t, u).unwrap_or((0, 0));
            let fr = work.tris[fl as usize].o[jl];
            let (f, k) = if fr == NONE || t < u {
                (fl, jl)
            } else {
                (fr, corner_of(work.tris[fr as usize].c, u))
            };
            3 * f as usize + k
        };
        let mut applied = 0u64;
        later.clear();
        loop {
            let next_cand = ranked.peek(&work.stamp, pass);
            let later_first = match (next_cand, later.peek()) {
                (None, None) => break,
                (None, Some(_)) => true,
                (Some(_), None) => false,
                (Some((c, t, u)), Some(&std::cmp::Reverse((key, i)))) => {
                    let own = order_key(c);
                    key < own || (key == own && !stamped(&work, t, u) && i < slot_of(&work, t, u))
                }
            };
            let key = if later_first {
                later.peek().map(|r| r.0 .0)
            } else {
                next_cand.map(|c| order_key(c.0))
            };
            if key.is_some_and(|k| k > limit) {
                cut = true;
                break;
            }
            let (t, u, from_later) = if later_first {
                let Some(std::cmp::Reverse((_, i))) = later.pop() else {
                    break;
                };
                let slot = &slots[i / 3][i % 3];
                let [a, b] = slot.ends;
                if slot.dir == 1 {
                    (a, b, true)
                } else {
                    (b, a, true)
                }
            } else {
                let Some((_, t, u)) = next_cand else {
                    break;
                };
                ranked.advance();
                (t, u, false)
            };
            if stamped(&work, t, u) {
                continue;
            }
            let col = match work.verdict(t, u, pass, &mut rings) {
                Verdict::Legal(col) => col,
                Verdict::Lapsed => continue,
                Verdict::Illegal => {
                    if !from_later {
                        let i = slot_of(&work, t, u);
                        let other = slots[i / 3][i % 3].other();
                        if other.is_finite() {
                            later.push(std::cmp::Reverse((order_key(other), i)));
                        }
                    }
                    continue;
                }
            };
            let l = work.tris[col.fl as usize].c[prev(col.rot_l as usize)];
            let r = work.third(col.fr, t);
            for x in [l, r] {
                if x != NONE && work.shrunk[x as usize] != pass {
                    work.shrunk[x as usize] = pass;
                    work.start_valence[x as usize] = work.valence[x as usize];
                }
            }
            let s = work.apply(col);
            for &v in rings.iter().flatten().chain(&[t, u, s]) {
                work.stamp[v as usize] = pass;
            }
            applied += 1;
        }
        work.settle(threads);
        progress(work.h.collapses.len() as u64, most);
        if applied == 0 && !cut {
            break;
        }
        full = applied == 0;
    }
    work.h.parent = work.nodes.iter().map(|n| n.parent).collect();
    work.h.error = work.nodes.iter().map(|n| n.error).collect();
    work.h.radius = work.nodes.iter().map(|n| n.radius).collect();
    work.h.cone = work.nodes.iter().map(|n| n.cone).collect();
    work.h.node_position = work.node_pos;
    work.h.corners = work.tris.iter().map(|t| t.c).collect();
    work.h.alive = work.alive;
    work.h
}

/// `f(i)` for `i` in `0..n`, in order, computed on up to `threads` threads.
fn par_map<T: Send>(n: usize, threads: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    if threads <= 1 || n < PARALLEL_MIN {
        return (0..n).map(f).collect();
    }
    let per = n.div_ceil(threads);
    std::thread::scope(|scope| {
        let parts: Vec<_> = (0..n)
            .step_by(per)
            .map(|lo| {
                let f = &f;
                scope.spawn(move || (lo..(lo + per).min(n)).map(f).collect::<Vec<T>>())
            })
            .collect();
        parts
            .into_iter()
            .flat_map(|part| part.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    })
}

/// Runs `f(lo, hi, faces_of, wedges)` for each range `lo..hi` of positions, on a thread
/// each, with the triangle lists and the wedges of those positions.
fn by_positions(
    ranges: &[(usize, usize)],
    faces_of: &mut [Vec<u32>],
    wedges: &mut [Wedge],
    wedge_start: &[u32],
    f: impl Fn(usize, usize, &mut [Vec<u32>], &mut [Wedge]) + Sync,
) {
    if ranges.len() <= 1 {
        f(0, faces_of.len(), faces_of, wedges);
        return;
    }
    std::thread::scope(|scope| {
        let (mut faces_of, mut wedges) = (faces_of, wedges);
        for &(lo, hi) in ranges {
            let (these_faces, other_faces) = faces_of.split_at_mut(hi - lo);
            let count = (wedge_start[hi] - wedge_start[lo]) as usize;
            let (these_wedges, other_wedges) = wedges.split_at_mut(count);
            (faces_of, wedges) = (other_faces, other_wedges);
            let f = &f;
            scope.spawn(move || f(lo, hi, these_faces, these_wedges));
        }
    });
}

/// Adds `q` to the wedge of `group` at position `x`, in the wedges of the positions from
/// `lo` on.
fn add_to_wedge(
    wedges: &mut [Wedge],
    wedge_start: &[u32],
    lo: usize,
    x: usize,
    group: u32,
    q: &Quadric,
) {
    let base = wedge_start[lo] as usize;
    let range = wedge_start[x] as usize - base..wedge_start[x + 1] as usize - base;
    if let Some(wd) = wedges[range].iter_mut().find(|wd| wd.group == group) {
        wd.q.add(q);
    }
}

/// Weight of a boundary plane per squared length of its edge. Heavier than a triangle's
/// plane (weighted by its area) so that borders slide little: on a terrain tile the border
/// is where the error would otherwise be largest.
const BOUNDARY_WEIGHT: f64 = 10.0;

/// Share of a pass's ranked collapses it may apply: the cheapest half. Applying every
/// independent collapse lets an expensive one take a neighbourhood that a cheaper one of
/// the next pass would have used; the cut costs passes, not depth to speak of.
const PASS_SHARE: f64 = 0.5;

/// Threads evaluating edges.
const MAX_THREADS: usize = 8;

/// Triangles below which work stays on one thread.
const PARALLEL_MIN: usize = 4096;

/// Triangle quadrics computed at a time (a block's take about 5 MB).
const QUADRIC_BLOCK: usize = 16384;

/// Ranks every slot of the live triangles, split over the threads by ranges of triangles
/// (each slot's ranking depends on the mesh alone, so the split does not change it), and
/// lists each edge's cheaper allowed direction in `cands`, in slot order.
fn rank_all(
    work: &Work<'_>,
    live: &[u32],
    slots: &mut [[Slot; 3]],
    cands: &mut Vec<Candidate>,
    threads: usize,
) {
    // `slots` from triangle `first` on.
    let run = |live: &[u32], first: usize, slots: &mut [[Slot; 3]], cands: &mut Vec<Candidate>| {
        for &f in live {
            for (k, slot) in slots[f as usize - first].iter_mut().enumerate() {
                work.rank(f, k, slot);
                let [a, b] = slot.ends;
                match slot.dir {
                    1 => cands.push((slot.cost(), b, a)),
                    2 => cands.push((slot.cost(), a, b)),
                    _ => {}
                }
            }
        }
    };
    cands.clear();
    if threads <= 1 || live.len() < PARALLEL_MIN {
        run(live, 0, slots, cands);
        return;
    }
    let per = live.len().div_ceil(threads);
    let parts: Vec<Vec<Candidate>> = std::thread::scope(|scope| {
        let mut rest = slots;
        let mut first = 0;
        let mut handles = Vec::new();
        for (i, part) in live.chunks(per).enumerate() {
            // This thread's triangles run up to the next part's first.
            let end = live
                .get((i + 1) * per)
                .map_or(first + rest.len(), |&f| f as usize);
            let (mine, others) = rest.split_at_mut(end - first);
            rest = others;
            let run = &run;
            let start = first;
            handles.push(scope.spawn(move || {
                let mut found = Vec::with_capacity(part.len() * 3 / 2);
                run(part, start, mine, &mut found);
                found
            }));
            first = end;
        }
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    });
    for part in parts {
        cands.extend_from_slice(&part);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Mesh, Surface, Triangle, NO_ATTRIBUTE};

    #[test]
    fn point_triangle_distance_in_every_region() {
        let (a, b, c) = ([0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]);
        let d = |x: V3| point_triangle_d2(x, a, b, c).sqrt();
        let close = |x: f64, y: f64| (x - y).abs() < 1e-12;
        assert!(close(d([0.5, 0.5, 3.0]), 3.0)); // inside, above
        assert!(close(d([-1.0, -1.0, 0.0]), 2f64.sqrt())); // corner a
        assert!(close(d([3.0, 0.0, 0.0]), 1.0)); // corner b
        assert!(close(d([0.0, 3.0, 4.0]), 17f64.sqrt())); // corner c
        assert!(close(d([1.0, -2.0, 0.0]), 2.0)); // edge ab
        assert!(close(d([-2.0, 1.0, 0.0]), 2.0)); // edge ac
        assert!(close(d([2.0, 2.0, 0.0]), 2f64.sqrt())); // edge bc
                                                         // Degenerate (a segment): the nearest corner at worst.
        assert!(point_triangle_d2([1.0, 1.0, 0.0], a, b, b) <= 2.0 + 1e-12);
    }

    /// A bumpy height field of `n × n` posts with a border.
    fn terrain(n: u32) -> Mesh {
        let mut m = Mesh {
            surfaces: vec![Surface::default()],
            ..Mesh::default()
        };
        for row in 0..n {
            for col in 0..n {
                let (x, z) = (col as f32, row as f32);
                let h = (x * 0.7).sin() * (z * 0.4).cos() * 2.0 + ((x * z) * 0.37).sin() * 0.3;
                m.positions.push([x, h, z]);
            }
        }
        for row in 0..n - 1 {
            for col in 0..n - 1 {
                let i = row * n + col;
                for position in [[i, i + n, i + n + 1], [i, i + n + 1, i + 1]] {
                    m.triangles.push(Triangle {
                        position,
                        normal: [NO_ATTRIBUTE; 3],
                        uv: [NO_ATTRIBUTE; 3],
                        color: [NO_ATTRIBUTE; 3],
                        surface: 0,
                    });
                }
            }
        }
        m
    }

    #[test]
    fn every_input_position_is_within_the_roots_error_of_the_base_mesh() {
        let w = crate::weld::weld(&terrain(24)).expect("weld");
        let h = build(&w, &AttributeWeights::default(), &mut |_, _| {});
        let point = |node: u32| w.positions[h.node_position[node as usize] as usize].map(f64::from);
        let base: Vec<[V3; 3]> = h
            .corners
            .iter()
            .zip(&h.alive)
            .filter(|(_, &alive)| alive)
            .map(|(c, _)| c.map(point))
            .collect();
        assert!(
            base.len() < w.triangles.len() / 10,
            "{} base triangles",
            base.len()
        );
        let root_error = h
            .parent
            .iter()
            .zip(&h.error)
            .filter(|(&p, _)| p == NONE)
            .map(|(_, &e)| e as f64)
            .fold(0.0, f64::max);
        let worst = w
            .positions
            .iter()
            .map(|p| {
                let x = p.map(f64::from);
                base.iter()
                    .map(|&[a, b, c]| point_triangle_d2(x, a, b, c))
                    .fold(f64::INFINITY, f64::min)
                    .sqrt()
            })
            .fold(0.0, f64::max);
        assert!(worst > 0.1, "the base mesh should not be exact: {worst}");
        assert!(worst <= root_error * (1.0 + 1e-5), "{worst} > {root_error}");
        // A parent's error is at least its children's.
        for (v, &p) in h.parent.iter().enumerate() {
            if p != NONE {
                assert!(h.error[p as usize] >= h.error[v]);
            }
        }
    }
}
