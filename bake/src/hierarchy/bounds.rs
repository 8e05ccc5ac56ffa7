//! The error bounds: every input position belongs to a current triangle near it; a
//! collapse hands the positions of the removed node's triangles to the nearest of the
//! triangles that replace them, and raises the new node's error to the largest distance.

use super::geometry::{dot, point_triangle_d2, sub, V3};
use super::work::Work;
use super::{NONE, PARALLEL_MIN};
use rayon::prelude::*;

impl Work<'_> {
    /// The points of the error bounds, the input's positions, each given to a triangle it
    /// is a corner of (its first).
    pub(super) fn place_points(&mut self) {
        self.pts_head = vec![NONE; self.tris.len()];
        self.pts_next = vec![NONE; self.p.len()];
        for (x, faces) in self.faces_of[..self.p.len()].iter().enumerate() {
            if let Some(&f) = faces.first() {
                self.pts_next[x] = std::mem::replace(&mut self.pts_head[f as usize], x as u32);
            }
        }
    }

    /// The point of the error bounds standing for position `x`: in single precision
    /// (ample for an error bound), relative to the centre.
    #[inline]
    fn point(&self, x: u32) -> V3 {
        self.p[x as usize].map(|c| c as f32 as f64)
    }

    /// The nearest triangle of `star` to each of `points` and the squared distance, into
    /// `out`; `tris` is scratch space.
    pub(super) fn nearest(
        &self,
        star: &[u32],
        points: &[(u32, u32)],
        tris: &mut Vec<([V3; 3], V3, f64)>,
        out: &mut Vec<(f64, u32)>,
    ) {
        // The triangles' corners and plane normals, gathered once for all the points.
        tris.clear();
        tris.extend(star.iter().map(|&f| {
            let tri = &self.tris[f as usize];
            (
                tri.c.map(|v| self.pos(v)),
                tri.n,
                tri.len * tri.len,
            )
        }));
        for &(x, _) in points {
            let x = self.point(x);
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
            parts.par_iter().map(|part| run(part)).collect()
        };
        for (&(x, s), &(d, f)) in moved.iter().zip(found.iter().flatten()) {
            if f != NONE {
                self.pts_next[x as usize] =
                    std::mem::replace(&mut self.pts_head[f as usize], x);
                let error = &mut self.nodes[s as usize].error;
                *error = error.max(d.sqrt() as f32);
            }
        }
        self.moved = moved;
        self.moved.clear();
        self.from_kept.clear();
    }
}
