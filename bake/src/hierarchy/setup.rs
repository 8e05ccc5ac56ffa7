//! Setting up the work: the centred points, the wedges and their quadrics (triangles' and
//! boundary planes'), the triangles with their neighbours, and the leaves' bounds.

use std::borrow::Cow;

use super::geometry::{corner_of, cross, dot, len, next, norm, prev, sub, V3};
use super::handover::Handover;
use super::records::{centred, Marks, NodeOut, PosInfo, Tri, Wedge};
use super::stars::Stars;
use super::types::{AttributeWeights, Hierarchy, NONE, PARALLEL_MIN};
use super::work::{scaled_attributes, Work};
use crate::quadric::{Layout, Quadric, Quadrics, QuadricsMut};
use crate::weld::Welded;
use rayon::prelude::*;

/// Weight of a boundary plane per squared length of its edge. Heavier than a triangle's
/// plane (weighted by its area) so that borders slide little: on a terrain tile the border
/// is where the error would otherwise be largest.
const BOUNDARY_WEIGHT: f64 = 10.0;

/// Triangle quadrics computed at a time, in one reused block of rows: enough to keep every
/// thread busy, few enough that the block stays small beside the wedges' quadrics.
const QUADRIC_BLOCK: usize = 16384;

/// What the set-up steps share.
struct Setup<'a> {
    w: &'a Welded,
    weights: &'a AttributeWeights,
    threads: usize,
    /// The bounding box's diagonal, which scales the attributes.
    diagonal: f64,
    /// The bounding box's centre.
    centre: V3,
    /// Every position relative to the centre, in f64 ([`centred`]), while setting up.
    p: Vec<V3>,
    /// Positions split into ranges, one per thread, for adding to their wedges in order.
    ranges: Vec<(usize, usize)>,
}

/// The work for a welded mesh, with the quadrics of every wedge, the triangles around every
/// position, and the leaves' rings, cones and radii.
pub(super) fn work<'w>(
    w: &'w Welded,
    weights: &AttributeWeights,
    frozen: &[bool],
    threads: usize,
) -> Work<'w> {
    let np = w.positions.len();
    let nt = w.triangles.len();
    let s = Setup::new(w, weights, threads);
    let wedges = Cow::Borrowed(w.vertices.entries());
    let wedge_start = Cow::Borrowed(w.vertices.starts());
    let layout = s.layout();
    let mut quadrics = Quadrics::zeros(layout, wedges.len());
    let faces_of = Stars::of_triangles(np, w.triangles.iter().map(|t| t.p));
    s.add_triangle_quadrics(layout, &wedges, &wedge_start, quadrics.as_mut());
    let tris = s.triangles(&faces_of);
    s.add_boundary_planes(&tris, &wedges, &wedge_start, quadrics.as_mut());
    let info = position_info(w, frozen);
    let (diagonal, centre) = (s.diagonal, s.centre);
    drop(s);
    let mut work = Work {
        w,
        weights: *weights,
        diagonal,
        centre,
        info,
        tris,
        alive: vec![true; nt],
        faces_of,
        valence: Vec::new(),
        node_pos: (0..np as u32).collect(),
        wedges,
        wedge_start,
        quadrics,
        wedges_released: 0,
        wedges_unreleased: 0,
        h: Hierarchy::default(),
        nodes: Vec::new(),
        stamp: Marks::new(np),
        shrunk: Marks::new(np),
        start_valence: vec![0; np],
        pass_start: 0,
        taken: Handover::default(),
    };
    work.add_leaves(threads);
    work.reserve_nodes();
    work
}

impl<'a> Setup<'a> {
    /// Centres the positions on their bounding box and splits them over the threads.
    fn new(w: &'a Welded, weights: &'a AttributeWeights, threads: usize) -> Self {
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
        let p: Vec<V3> = w.positions.iter().map(|&q| centred(q, centre)).collect();
        let np = w.positions.len();
        let per = if threads <= 1 || np < PARALLEL_MIN {
            np.max(1)
        } else {
            np.div_ceil(threads)
        };
        let ranges = (0..np)
            .step_by(per)
            .map(|lo| (lo, (lo + per).min(np)))
            .collect();
        Self {
            w,
            weights,
            threads,
            diagonal,
            centre,
            p,
            ranges,
        }
    }

    /// The attributes the quadrics hold: those that vary over the vertices once scaled.
    fn layout(&self) -> Layout {
        let w = self.w;
        Layout::of(
            (0..w.attributes.len() as u32)
                .map(|a| scaled_attributes(w, a, self.weights, self.diagonal)),
        )
    }

    /// Each triangle's quadric over the attributes of `layout`, added to the wedge of its
    /// group at its corners. The quadrics are computed in blocks on all threads and added in
    /// triangle order, so the sums do not depend on the threads.
    fn add_triangle_quadrics(
        &self,
        layout: Layout,
        wedges: &[Wedge],
        wedge_start: &[u32],
        mut q: QuadricsMut<'_>,
    ) {
        let (w, p) = (self.w, &self.p);
        let nt = w.triangles.len();
        let mut block = Quadrics::zeros(layout, QUADRIC_BLOCK.min(nt));
        for first in (0..nt).step_by(QUADRIC_BLOCK) {
            let n = (nt - first).min(QUADRIC_BLOCK);
            let fill = |(i, row): (usize, &mut [f64])| {
                let t = &w.triangles[first + i];
                let s = w
                    .corner_attributes(t)
                    .map(|a| layout.only(scaled_attributes(w, a, self.weights, self.diagonal)));
                Quadric::triangle(t.p.map(|x| p[x as usize]), s).write_row(layout, row);
            };
            if self.threads <= 1 || n < PARALLEL_MIN {
                block.as_mut().rows().take(n).enumerate().for_each(fill);
            } else {
                let rows = block.as_mut().par_rows().take(n).enumerate();
                rows.with_min_len(PARALLEL_MIN / 4).for_each(fill);
            }
            by_positions(
                &self.ranges,
                wedge_start,
                q.reborrow(),
                |lo, hi, mut rows| {
                    for i in 0..n {
                        let t = &w.triangles[first + i];
                        for &x in &t.p {
                            let x = x as usize;
                            if (lo..hi).contains(&x) {
                                if let Some(r) = wedge_row(wedges, wedge_start, lo, x, t.group) {
                                    rows.add_row(r, block.row(i));
                                }
                            }
                        }
                    }
                },
            );
        }
    }

    /// The triangles with, across each edge, the triangle with the reverse edge.
    fn triangles(&self, faces_of: &Stars) -> Vec<Tri> {
        let w = self.w;
        let opp = par_map(w.triangles.len(), self.threads, |f| {
            let c = w.triangles[f].p;
            [0, 1, 2].map(|k| {
                let (a, b) = (c[k], c[next(k)]);
                faces_of
                    .of(b)
                    .iter()
                    .copied()
                    .find(|&g| {
                        let d = w.triangles[g as usize].p;
                        d[next(corner_of(d, b))] == a
                    })
                    .unwrap_or(NONE)
            })
        });
        w.triangles
            .iter()
            .zip(&opp)
            .map(|(t, &o)| Tri { c: t.p, o })
            .collect()
    }

    /// Boundary planes: through each border or group-boundary edge, perpendicular to its
    /// triangle, weighted by the edge's squared length, added to the wedges of the
    /// triangle's group at the edge's ends.
    fn add_boundary_planes(
        &self,
        tris: &[Tri],
        wedges: &[Wedge],
        wedge_start: &[u32],
        q: QuadricsMut<'_>,
    ) {
        let (w, p) = (self.w, &self.p);
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
        by_positions(&self.ranges, wedge_start, q, |lo, hi, mut rows| {
            for (ends, group, q) in &planes {
                for &x in ends {
                    let x = x as usize;
                    if (lo..hi).contains(&x) {
                        if let Some(r) = wedge_row(wedges, wedge_start, lo, x, *group) {
                            rows.add(r, q);
                        }
                    }
                }
            }
        });
    }
}

/// What the surface-group rules read of every position (`frozen[x]`, absent: false).
fn position_info(w: &Welded, frozen: &[bool]) -> Vec<PosInfo> {
    w.classes
        .iter()
        .zip(&w.vertices)
        .enumerate()
        .map(|(x, (&class, vs))| PosInfo {
            class,
            frozen: frozen.get(x).copied().unwrap_or(false),
            group: match vs {
                [(g, _)] => *g,
                _ => NONE,
            },
        })
        .collect()
}

impl Work<'_> {
    /// Room for every node a build can add (a collapse per position but one), so the
    /// per-node arrays never grow by doubling past what they need.
    fn reserve_nodes(&mut self) {
        let more = self.positions().saturating_sub(1);
        self.faces_of.reserve_nodes(more);
        self.node_pos.reserve_exact(more);
        self.h.collapses.reserve_exact(more);
    }

    /// The leaves' valences, normal cones and bounding radii (to their ring), on all
    /// threads.
    fn add_leaves(&mut self, threads: usize) {
        let np = self.positions();
        let leaves = par_map(np, threads, |v| self.leaf(v as u32));
        self.valence.reserve_exact(np);
        self.nodes.reserve(2 * np);
        for (valence, cone, radius) in leaves {
            self.valence.push(valence);
            self.nodes.push(NodeOut {
                parent: NONE,
                error: 0.0,
                radius,
                cone,
            });
        }
    }

    /// A leaf's number of neighbours, normal cone and bounding radius.
    fn leaf(&self, v: u32) -> (u32, ([f32; 3], f32), f32) {
        let normals = self
            .faces_of
            .of(v)
            .iter()
            .map(|&f| norm(self.triangle_normal(self.tris[f as usize].c)));
        let axis = norm(
            normals
                .clone()
                .fold([0.0; 3], |a, n| [a[0] + n[0], a[1] + n[1], a[2] + n[2]]),
        );
        // The widest normal: the smallest cosine (one arc cosine per leaf).
        let angle = normals
            .map(|n| dot(axis, n).clamp(-1.0, 1.0))
            .fold(1.0f64, f64::min)
            .acos();
        let cone = if axis == [0.0; 3] {
            ([0.0; 3], std::f32::consts::PI)
        } else {
            (axis.map(|x| x as f32), angle as f32)
        };
        // The ring as `Work::find_ring` lists it, without collecting it.
        let pv = self.pos(v);
        let (mut valence, mut radius) = (0u32, 0.0f64);
        for &f in self.faces_of.of(v) {
            let t = &self.tris[f as usize];
            let j = corner_of(t.c, v);
            let border = t.o[prev(j)] == NONE;
            for o in [Some(t.c[next(j)]), border.then_some(t.c[prev(j)])]
                .into_iter()
                .flatten()
            {
                valence += 1;
                radius = radius.max(len(sub(self.pos(o), pv)));
            }
        }
        (valence, cone, radius as f32)
    }
}

/// `f(i)` for `i` in `0..n`, in order, computed on the rayon pool (on one thread below
/// [`PARALLEL_MIN`] items or with `threads` at most 1).
pub(super) fn par_map<T: Send>(n: usize, threads: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    if threads <= 1 || n < PARALLEL_MIN {
        return (0..n).map(f).collect();
    }
    (0..n)
        .into_par_iter()
        .with_min_len(PARALLEL_MIN)
        .map(&f)
        .collect()
}

/// Runs `f(lo, hi, rows)` for each range `lo..hi` of positions, as a rayon task each,
/// with the quadrics of those positions' wedges (the first is row 0).
pub(super) fn by_positions(
    ranges: &[(usize, usize)],
    wedge_start: &[u32],
    rows: QuadricsMut<'_>,
    f: impl Fn(usize, usize, QuadricsMut<'_>) + Sync,
) {
    if ranges.len() <= 1 {
        f(0, wedge_start.len() - 1, rows);
        return;
    }
    let mut parts = Vec::with_capacity(ranges.len());
    let mut rows = rows;
    for &(lo, hi) in ranges {
        let count = (wedge_start[hi] - wedge_start[lo]) as usize;
        let (these, others) = rows.split_at(count);
        rows = others;
        parts.push((lo, hi, these));
    }
    parts
        .into_par_iter()
        .for_each(|(lo, hi, rows)| f(lo, hi, rows));
}

/// The row of the wedge of `group` at position `x` among the quadrics of the wedges of the
/// positions from `lo` on, if `x` has one.
fn wedge_row(
    wedges: &[Wedge],
    wedge_start: &[u32],
    lo: usize,
    x: usize,
    group: u32,
) -> Option<usize> {
    (wedge_start[x] as usize..wedge_start[x + 1] as usize)
        .find(|&i| wedges[i].0 == group)
        .map(|i| i - wedge_start[lo] as usize)
}
