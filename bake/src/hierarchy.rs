//! Building the vertex hierarchy by half-edge collapses.
//!
//! - **Half-edge collapses** only: the parent keeps the stationary child's position, so no
//!   vertex is ever created and the vertex buffer is the full-resolution one.
//! - **Batches of independent collapses** (as g-mesh builds its levels): each pass sorts the
//!   legal collapses by cost and applies those whose neighbourhoods do not overlap, so the
//!   hierarchy is balanced and shallow (depth grows with the logarithm of the size).
//! - **Cost**: the attribute-aware quadric of the removed position's wedges (one per surface
//!   group there) evaluated at the kept position with that group's attributes there
//!   ([`crate::quadric`]), plus boundary planes that hold mesh borders and surface-group
//!   boundaries in place.
//! - **Legality**: the surface-group rules (a RIGID position never floats; a SHARP one floats
//!   only along a boundary edge onto a non-FREE position; every group at the removed position
//!   must have a vertex at the kept one), the link condition, no doubled faces, no face
//!   flipped or collapsed, and Hoppe's requirement that `fl_clw` (and `fr_ccw` when `f_r`
//!   exists) are present.
//! - **Bounds for refinement**: the bounding-sphere radius and normal cone of everything
//!   below a node, and an error bound that grows with the removed positions' distances from
//!   the surface that replaces them.

use caveclod_core::PositionClass;

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

struct Work<'w> {
    w: &'w Welded,
    p: Vec<V3>,
    corners: Vec<[u32; 3]>,
    alive: Vec<bool>,
    faces_of: Vec<Vec<u32>>,
    node_pos: Vec<u32>,
    wedges: Vec<Vec<Wedge>>,
    h: Hierarchy,
    stamp: Vec<u32>,
}

impl Work<'_> {
    #[inline]
    fn pt(&self, node: u32) -> V3 {
        self.p[self.node_pos[node as usize] as usize]
    }

    fn corner(&self, f: u32, v: u32) -> Option<usize> {
        self.corners[f as usize].iter().position(|&c| c == v)
    }

    fn dir_face(&self, a: u32, b: u32) -> Option<u32> {
        self.faces_of[a as usize].iter().copied().find(|&f| {
            let c = self.corners[f as usize];
            (0..3).any(|j| c[j] == a && c[(j + 1) % 3] == b)
        })
    }

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
            let c = self.corners[f as usize];
            let j = c.iter().position(|&x| x == v).unwrap_or(0);
            self.across(f, v, c[(j + 1) % 3]) == NONE || self.across(f, v, c[(j + 2) % 3]) == NONE
        })
    }

    fn normal(&self, c: [u32; 3]) -> V3 {
        let [a, b, d] = c.map(|n| self.pt(n));
        cross(sub(b, a), sub(d, a))
    }

    /// Quadric cost of moving `u`'s wedges onto `t`.
    fn cost(&self, t: u32, u: u32) -> f64 {
        let (pt, pu) = (
            self.node_pos[t as usize] as usize,
            self.node_pos[u as usize] as usize,
        );
        let at = &self.wedges[pt];
        self.wedges[pu]
            .iter()
            .map(|wu| match at.iter().find(|wt| wt.group == wu.group) {
                Some(wt) => wu.q.eval(self.p[pt], &wt.attrs),
                None => f64::INFINITY,
            })
            .sum()
    }

    /// Checks the collapse of `u` into `t`; returns it with its cost and error increment.
    fn check(
        &self,
        t: u32,
        u: u32,
        ring_t: &mut Vec<u32>,
        ring_u: &mut Vec<u32>,
    ) -> Option<(Collapse, f64, f64)> {
        let (pt, pu) = (
            self.node_pos[t as usize] as usize,
            self.node_pos[u as usize] as usize,
        );
        let class_u = self.w.classes[pu];
        if class_u == PositionClass::Rigid {
            return None;
        }
        let fl = self.dir_face(t, u)?;
        let fr = self.dir_face(u, t).unwrap_or(NONE);
        let group = |f: u32| self.w.triangles[f as usize].group;
        let boundary = fr == NONE || group(fl) != group(fr);
        if class_u != PositionClass::Free
            && (!boundary || self.w.classes[pt] == PositionClass::Free)
        {
            return None;
        }
        let (vu, vt) = (&self.w.vertices[pu], &self.w.vertices[pt]);
        if !vu.iter().all(|(g, _)| vt.iter().any(|(h, _)| h == g)) {
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
        self.ring(t, ring_t);
        self.ring(u, ring_u);
        let shared = ring_t.iter().filter(|x| ring_u.contains(x)).count();
        if shared != 1 + usize::from(r != NONE) {
            return None;
        }
        if fr != NONE && self.on_border(t) && self.on_border(u) {
            return None;
        }
        for x in [l, r] {
            if x != NONE {
                self.ring(x, ring_t);
                if ring_t.len() <= 3 {
                    return None;
                }
            }
        }
        let (p_t, p_u) = (self.pt(t), self.pt(u));
        let mut dev = 0.0f64;
        for &f in &self.faces_of[u as usize] {
            if f == fl || f == fr {
                continue;
            }
            let before = self.normal(self.corners[f as usize]);
            let after = self.normal(self.corners[f as usize].map(|c| if c == u { t } else { c }));
            let (lb, la) = (len(before), len(after));
            if la <= 1e-12 * (1.0 + lb) || dot(before, after) <= 0.2 * lb * la {
                return None;
            }
            dev = dev.max(dot(norm(after), sub(p_u, p_t)).abs());
        }
        let cost = self.cost(t, u);
        if !cost.is_finite() {
            return None;
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
        Some((c, cost, dev))
    }

    fn apply(&mut self, c: Collapse, dev: f64) -> u32 {
        let s = self.node_pos.len() as u32;
        let (t, u) = (c.t, c.u);
        let (pt, pu) = (self.node_pos[t as usize], self.node_pos[u as usize]);
        self.node_pos.push(pt);
        self.h.parent.push(NONE);
        self.h.parent[t as usize] = s;
        self.h.parent[u as usize] = s;
        let (p_t, p_u) = (self.pt(t), self.pt(u));
        let e = (self.h.error[t as usize] as f64).max(self.h.error[u as usize] as f64 + dev);
        self.h.error.push(e as f32);
        let r = (self.h.radius[t as usize] as f64)
            .max(len(sub(p_u, p_t)) + self.h.radius[u as usize] as f64);
        self.h.radius.push(r as f32);
        self.h.cone.push(merge_cones(
            self.h.cone[t as usize],
            self.h.cone[u as usize],
        ));
        // The removed position's wedges merge into the kept position's.
        let moved = std::mem::take(&mut self.wedges[pu as usize]);
        for wu in moved {
            if let Some(wt) = self.wedges[pt as usize]
                .iter_mut()
                .find(|wt| wt.group == wu.group)
            {
                wt.q.add(&wu.q);
            }
        }
        for f in [c.fl, c.fr] {
            if f != NONE {
                self.alive[f as usize] = false;
                for x in self.corners[f as usize] {
                    self.faces_of[x as usize].retain(|&g| g != f);
                }
            }
        }
        let mut star = std::mem::take(&mut self.faces_of[t as usize]);
        star.append(&mut std::mem::take(&mut self.faces_of[u as usize]));
        for &f in &star {
            for x in &mut self.corners[f as usize] {
                if *x == t || *x == u {
                    *x = s;
                }
            }
        }
        self.faces_of.push(star);
        self.stamp.push(0);
        self.h.collapses.push(c);
        s
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
    let (wn, wu, wc) = (
        weights.normal * scale,
        weights.uv * scale,
        weights.color * scale,
    );
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
    let mut wedges: Vec<Vec<Wedge>> = w
        .vertices
        .iter()
        .map(|vs| {
            vs.iter()
                .map(|&(group, a)| Wedge {
                    group,
                    attrs: scaled_attributes(w, a, weights, diagonal),
                    q: Quadric::default(),
                })
                .collect()
        })
        .collect();
    let mut faces_of: Vec<Vec<u32>> = vec![Vec::new(); np];
    for (f, t) in w.triangles.iter().enumerate() {
        let s = t.a.map(|a| scaled_attributes(w, a, weights, diagonal));
        let q = Quadric::triangle(t.p.map(|x| p[x as usize]), s);
        for &x in &t.p {
            faces_of[x as usize].push(f as u32);
            if let Some(wd) = wedges[x as usize].iter_mut().find(|wd| wd.group == t.group) {
                wd.q.add(&q);
            }
        }
    }
    // Boundary planes: through each border or group-boundary edge, perpendicular to its
    // triangle, weighted by the edge's squared length.
    let mut directed = std::collections::HashMap::with_capacity(3 * nt);
    for (f, t) in w.triangles.iter().enumerate() {
        for k in 0..3 {
            directed.insert((t.p[k], t.p[(k + 1) % 3]), f as u32);
        }
    }
    for (f, t) in w.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t.p[k], t.p[(k + 1) % 3]);
            let twin = directed.get(&(b, a)).copied();
            if twin.is_some_and(|g| w.triangles[g as usize].group == t.group) {
                continue;
            }
            let (pa, pb, pc) = (p[a as usize], p[b as usize], p[t.p[(k + 2) % 3] as usize]);
            let e = sub(pb, pa);
            let n = norm(cross(e, cross(sub(pc, pa), e)));
            let q = Quadric::plane(n, -dot(n, pa), dot(e, e));
            for x in [a, b] {
                if let Some(wd) = wedges[x as usize].iter_mut().find(|wd| wd.group == t.group) {
                    wd.q.add(&q);
                }
            }
            let _ = f;
        }
    }
    drop(directed);
    let mut work = Work {
        w,
        p,
        corners: w.triangles.iter().map(|t| t.p).collect(),
        alive: vec![true; nt],
        faces_of,
        node_pos: (0..np as u32).collect(),
        wedges,
        h: Hierarchy {
            parent: vec![NONE; np],
            radius: vec![0.0; np],
            cone: Vec::with_capacity(2 * np),
            error: vec![0.0; np],
            ..Hierarchy::default()
        },
        stamp: vec![0; np],
    };
    let mut ring = Vec::new();
    for v in 0..np as u32 {
        let normals: Vec<V3> = work.faces_of[v as usize]
            .iter()
            .map(|&f| norm(work.normal(work.corners[f as usize])))
            .collect();
        let axis = norm(
            normals
                .iter()
                .fold([0.0; 3], |a, n| [a[0] + n[0], a[1] + n[1], a[2] + n[2]]),
        );
        let angle = normals
            .iter()
            .map(|&n| dot(axis, n).clamp(-1.0, 1.0).acos())
            .fold(0.0f64, f64::max);
        let cone = if axis == [0.0; 3] {
            ([0.0; 3], std::f32::consts::PI)
        } else {
            (axis.map(|x| x as f32), angle as f32)
        };
        work.h.cone.push(cone);
        work.ring(v, &mut ring);
        work.h.radius[v as usize] = ring
            .iter()
            .map(|&o| len(sub(work.pt(o), work.pt(v))))
            .fold(0.0, f64::max) as f32;
    }

    let (mut ring_t, mut ring_u) = (Vec::new(), Vec::new());
    let mut touched = Vec::new();
    let most = np.saturating_sub(1) as u64;
    loop {
        work.h.passes += 1;
        let pass = work.h.passes;
        let mut cands: Vec<(f64, Collapse, f64)> = Vec::new();
        for f in 0..nt {
            if !work.alive[f] {
                continue;
            }
            let c = work.corners[f];
            for k in 0..3 {
                let (a, b) = (c[k], c[(k + 1) % 3]);
                if a < b || work.dir_face(b, a).is_none() {
                    let x = work.check(b, a, &mut ring_t, &mut ring_u);
                    let y = work.check(a, b, &mut ring_t, &mut ring_u);
                    let best = match (x, y) {
                        (Some(x), Some(y)) => Some(if y.1 < x.1 { y } else { x }),
                        (x, y) => x.or(y),
                    };
                    if let Some((col, cost, dev)) = best {
                        cands.push((cost, col, dev));
                    }
                }
            }
        }
        cands.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let mut applied = 0u64;
        for &(_, col, _) in &cands {
            if work.stamp[col.t as usize] == pass || work.stamp[col.u as usize] == pass {
                continue;
            }
            // Neighbourhoods of earlier collapses in this pass are stamped, so this one's
            // check at the start of the pass still holds; check again all the same, since a
            // shared neighbour's degree may have changed.
            let Some((col, _, dev)) = work.check(col.t, col.u, &mut ring_t, &mut ring_u) else {
                continue;
            };
            touched.clear();
            work.ring(col.t, &mut ring_t);
            touched.extend_from_slice(&ring_t);
            work.ring(col.u, &mut ring_u);
            touched.extend_from_slice(&ring_u);
            let s = work.apply(col, dev);
            for &v in touched.iter().chain(&[col.t, col.u, s]) {
                work.stamp[v as usize] = pass;
            }
            applied += 1;
        }
        progress(work.h.collapses.len() as u64, most);
        if applied == 0 {
            break;
        }
    }
    work.h.node_position = work.node_pos;
    work.h.corners = work.corners;
    work.h.alive = work.alive;
    work.h
}
