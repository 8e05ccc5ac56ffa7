//! The error bounds: every input position belongs to a current triangle near it; a
//! collapse hands the positions of the removed node's triangles to the nearest of the
//! triangles that replace them, and raises the new node's error to the largest distance.

use super::geometry::{cross, dot, len, point_triangle_d2, sub, V3};
use super::work::{Tri, Work};
use super::{NONE, PARALLEL_MIN};
use rayon::prelude::*;

/// A triangle as the nearest-triangle search reads it: corners, edges from the first,
/// unnormalised normal and the Gram entries of the edges.
#[derive(Clone, Copy)]
pub(super) struct Probe {
    a: V3,
    b: V3,
    c: V3,
    ab: V3,
    ac: V3,
    n: V3,
    /// `|n|²`, which is `d00 d11 - d01²`.
    len2: f64,
    d00: f64,
    d01: f64,
    d11: f64,
}

impl Probe {
    pub(super) fn new(tri: &Tri, pos: impl Fn(u32) -> V3) -> Self {
        let [a, b, c] = tri.c.map(pos);
        let (ab, ac) = (sub(b, a), sub(c, a));
        let n = cross(ab, ac);
        let l = len(n);
        Self {
            a,
            b,
            c,
            ab,
            ac,
            n,
            len2: l * l,
            d00: dot(ab, ab),
            d01: dot(ab, ac),
            d11: dot(ac, ac),
        }
    }

    /// The squared distance from `x` to the triangle if it is below `best`.
    ///
    /// The distance to the plane is a lower bound; when `x` projects inside the triangle
    /// it is the distance, and only a projection outside takes the general case.
    #[inline]
    pub(super) fn d2_below(&self, x: V3, best: f64) -> Option<f64> {
        let ax = sub(x, self.a);
        let h = dot(ax, self.n);
        if self.len2 > 0.0 {
            if h * h >= best * self.len2 {
                return None;
            }
            let (d20, d21) = (dot(ax, self.ab), dot(ax, self.ac));
            // Barycentric coordinates of the projection, times `len2`.
            let v = self.d11 * d20 - self.d01 * d21;
            let w = self.d00 * d21 - self.d01 * d20;
            if v >= 0.0 && w >= 0.0 && v + w <= self.len2 {
                let d = h * h / self.len2;
                return (d < best).then_some(d);
            }
        }
        let d = point_triangle_d2(x, self.a, self.b, self.c);
        (d < best).then_some(d)
    }
}

impl Work<'_> {
    /// The points of the error bounds, the input's positions, each given to a triangle it
    /// is a corner of (its first).
    pub(super) fn place_points(&mut self) {
        self.pts_head = vec![NONE; self.tris.len()];
        self.pts_next = vec![NONE; self.positions()];
        for x in 0..self.positions() {
            if let Some(&f) = self.faces_of.of(x as u32).first() {
                self.pts_next[x] = std::mem::replace(&mut self.pts_head[f as usize], x as u32);
            }
        }
    }

    /// The point of the error bounds standing for position `x`: in single precision
    /// (ample for an error bound), relative to the centre.
    #[inline]
    fn point(&self, x: u32) -> V3 {
        self.at(x as usize).map(|c| c as f32 as f64)
    }

    /// The nearest triangle of `star` to each of `points` and the squared distance, into
    /// `out`; `probes` is scratch space.
    pub(super) fn nearest(
        &self,
        star: &[u32],
        points: &[(u32, u32)],
        probes: &mut Vec<Probe>,
        out: &mut Vec<(f64, u32)>,
    ) {
        // What the distances read of the triangles, gathered once for all the points.
        probes.clear();
        probes.extend(
            star.iter()
                .map(|&f| Probe::new(&self.tris[f as usize], |v| self.pos(v))),
        );
        for &(x, _) in points {
            let x = self.point(x);
            let mut best = (f64::INFINITY, NONE);
            for (&f, probe) in star.iter().zip(probes.iter()) {
                if let Some(d) = probe.d2_below(x, best.0) {
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
    pub(super) fn settle(&mut self, threads: usize) {
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
        let run = |part: &[(u32, u32)]| {
            let (mut out, mut probes) = (Vec::with_capacity(part.len()), Vec::new());
            for points in part.chunk_by(|a, b| a.1 == b.1) {
                let s = points[0].1 as usize;
                let star = this.faces_of.of(s as u32);
                let from_kept = this.from_kept[s - first_node] as usize;
                let moved_ones = if from_kept < star.len() {
                    &star[from_kept..]
                } else {
                    star
                };
                this.nearest(moved_ones, points, &mut probes, &mut out);
            }
            out
        };
        let found: Vec<Vec<(f64, u32)>> = if parts.len() <= 1 {
            parts.iter().map(|part| run(part)).collect()
        } else {
            parts.par_iter().map(|part| run(part)).collect()
        };
        for (&(x, s), &(d, f)) in moved.iter().zip(found.iter().flatten()) {
            if f != NONE {
                self.pts_next[x as usize] = std::mem::replace(&mut self.pts_head[f as usize], x);
                let error = &mut self.nodes[s as usize].error;
                *error = error.max(d.sqrt() as f32);
            }
        }
        self.raise_to_surface(first_node, threads);
        self.moved = moved;
        self.moved.clear();
        self.from_kept.clear();
    }

    /// Raises the error of each node the pass made (from `first_node` on) to the distance
    /// its collapse moved the surface ([`Work::surface_error`]), on all threads.
    fn raise_to_surface(&mut self, first_node: usize, threads: usize) {
        let this = &*self;
        let nodes = first_node..self.nodes.len();
        let raise = |probes: &mut Vec<Probe>, s: usize| {
            let floor = f64::from(this.nodes[s].error);
            let from_kept = this.from_kept[s - first_node] as usize;
            this.surface_error(s as u32, from_kept, floor, probes) as f32
        };
        let errors: Vec<f32> = if threads <= 1 || nodes.len() < PARALLEL_MIN {
            let mut probes = Vec::new();
            nodes.clone().map(|s| raise(&mut probes, s)).collect()
        } else {
            nodes
                .clone()
                .into_par_iter()
                .map_init(Vec::new, raise)
                .collect()
        };
        for (s, e) in nodes.zip(errors) {
            let error = &mut self.nodes[s].error;
            *error = error.max(e);
        }
    }
}
