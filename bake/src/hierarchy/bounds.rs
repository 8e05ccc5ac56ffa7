//! The error bounds: every input position belongs to a current triangle near it; a
//! collapse hands the positions of the removed node's triangles to the nearest of the
//! triangles that replace them, and raises the new node's error to the largest distance.

use super::geometry::{cross, dot, len, point_triangle_d2, sub, V3};
use super::work::{Tri, Work};
use super::NONE;
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
    /// `out`; `probes` and `coords` are scratch space.
    pub(super) fn nearest(
        &self,
        star: &[u32],
        points: &[u32],
        probes: &mut Vec<Probe>,
        coords: &mut Vec<V3>,
        out: &mut Vec<(f64, u32)>,
    ) {
        // What the distances read of the triangles, gathered once for all the points.
        probes.clear();
        probes.extend(
            star.iter()
                .map(|&f| Probe::new(&self.tris[f as usize], |v| self.pos(v))),
        );
        // The points' coordinates in a loop of their own, whose loads overlap.
        coords.clear();
        coords.extend(points.iter().map(|&x| self.point(x)));
        for &x in coords.iter() {
            let mut best = (f64::INFINITY, NONE);
            for (&f, probe) in star.iter().zip(probes.iter()) {
                if let Some(d) = probe.d2_below(x, best.0) {
                    best = (d, f);
                }
            }
            out.push(best);
        }
    }

    /// The triangles the removed child of the pass's collapse `i` had: those it gave the
    /// new node (listed after the kept child's), then the dying ones; and the triangles
    /// their points go to, the given ones (the whole star when it gave none).
    fn handed_over(&self, i: usize) -> (impl Iterator<Item = u32> + '_, &[u32]) {
        let count = self.from_kept.len();
        let c = &self.h.collapses[self.h.collapses.len() - count + i];
        let s = (self.nodes.len() - count + i) as u32;
        let star = self.faces_of.of(s);
        let from_kept = self.from_kept[i] as usize;
        let given = star.get(from_kept..).unwrap_or(&[]);
        let dying = [c.fl, c.fr].into_iter().filter(|&f| f != NONE);
        let to = if given.is_empty() { star } else { given };
        (given.iter().copied().chain(dying), to)
    }

    /// The points of the lists that start at `heads` (the lists' heads, changed), into
    /// `points`: the lists are walked side by side, so that their cache misses overlap, and
    /// their points are interleaved (which no result depends on).
    fn walk_lists(&self, heads: &mut Vec<u32>, points: &mut Vec<u32>) {
        points.clear();
        heads.retain(|&x| x != NONE);
        while !heads.is_empty() {
            for x in heads.iter_mut() {
                points.push(*x);
                *x = self.pts_next[*x as usize];
            }
            heads.retain(|&x| x != NONE);
        }
    }

    /// The points of the pass's collapses `range`, each moved to the nearest of the
    /// triangles its collapse's removed child gave the new node (that child's ring fanned
    /// from the kept child: the same stretch of surface; a nearer triangle elsewhere would
    /// only lower the distance, so this is an upper bound at half the work of searching the
    /// whole star): each point with its triangle, and per collapse its number of points and
    /// its new node's error, raised to the largest distance and to how far the collapse
    /// moved the surface ([`Work::surface_error`]).
    fn settle_part(&self, range: std::ops::Range<usize>) -> Settled {
        let first_node = self.nodes.len() - self.from_kept.len();
        let mut part = Settled::default();
        let (mut points, mut found, mut probes) = (Vec::new(), Vec::new(), Vec::new());
        let (mut walks, mut coords) = (Vec::new(), Vec::new());
        for i in range {
            let (from, to) = self.handed_over(i);
            walks.clear();
            walks.extend(from.map(|f| self.pts_head[f as usize]));
            self.walk_lists(&mut walks, &mut points);
            found.clear();
            self.nearest(to, &points, &mut probes, &mut coords, &mut found);
            let mut error = self.nodes[first_node + i].error;
            let before = part.points.len();
            for (&x, &(d, f)) in points.iter().zip(&found) {
                if f != NONE {
                    part.points.push((x, f));
                    error = error.max(d.sqrt() as f32);
                }
            }
            let s = (first_node + i) as u32;
            let moved =
                self.surface_error(s, self.from_kept[i] as usize, error.into(), &mut probes);
            error = error.max(moved as f32);
            part.nodes
                .push(((part.points.len() - before) as u32, error));
        }
        part
    }

    /// Hands the points of the pass's collapses over ([`Work::settle_part`]), on all
    /// threads: the collapses of a pass have disjoint stars, which no later collapse of the
    /// pass changes, and each collapse's points are handed over on their own, so the split
    /// does not change the result. The lists are then rebuilt in collapse order.
    pub(super) fn settle(&mut self, threads: usize) {
        let count = self.from_kept.len();
        // Several parts a thread: the last passes' few collapses carry most points each.
        let per = count.div_ceil(SETTLE_PARTS * threads.max(1)).max(1);
        let ranges: Vec<_> = (0..count)
            .step_by(per.max(1))
            .map(|lo| lo..(lo + per).min(count))
            .collect();
        let this = &*self;
        let parts: Vec<Settled> = if threads <= 1 || ranges.len() <= 1 {
            ranges.into_iter().map(|r| this.settle_part(r)).collect()
        } else {
            ranges
                .into_par_iter()
                .map(|r| this.settle_part(r))
                .collect()
        };
        let first_node = self.nodes.len() - count;
        let (mut i, mut from) = (0, Vec::new());
        for part in parts {
            let mut points = part.points.iter();
            for &(n, error) in &part.nodes {
                from.clear();
                from.extend(self.handed_over(i).0);
                for &f in &from {
                    self.pts_head[f as usize] = NONE;
                }
                for &(x, f) in points.by_ref().take(n as usize) {
                    self.pts_next[x as usize] =
                        std::mem::replace(&mut self.pts_head[f as usize], x);
                }
                self.nodes[first_node + i].error = error;
                i += 1;
            }
        }
        self.from_kept.clear();
    }
}

/// Parts per thread that [`Work::settle`] splits a pass's collapses into.
const SETTLE_PARTS: usize = 8;

/// What [`Work::settle_part`] found.
#[derive(Default)]
struct Settled {
    /// The points handed over, each with its new triangle, collapse after collapse.
    points: Vec<(u32, u32)>,
    /// Per collapse: its number of points there, and its new node's error.
    nodes: Vec<(u32, f32)>,
}
