//! The error bounds: every input position belongs to a current triangle near it; a
//! collapse hands the positions of the removed node's triangles to the nearest of the
//! triangles that replace them, and raises the new node's error to the largest distance.
//!
//! The settling reads a pass's collapses from a [`Handover`] (what it needs of them, taken
//! once they are applied) and the points' lists, never the mesh being simplified, so it runs
//! while the pass goes on with its next collapses ([`super::pass`]).

use super::geometry::{cross, dot, len, point_triangle_d2_from, sub, V3};
use super::handover::Handover;
use super::prefetch::prefetch;
use super::records::Frame;
use super::types::NONE;
use super::work::Work;
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
    pub(super) fn new(corners: [u32; 3], pos: impl Fn(u32) -> V3) -> Self {
        let [a, b, c] = corners.map(pos);
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
        if self.len2 > 0.0 && h * h >= best * self.len2 {
            return None;
        }
        let (d20, d21) = (dot(self.ab, ax), dot(self.ac, ax));
        if self.len2 > 0.0 {
            // Barycentric coordinates of the projection, times `len2`.
            let v = self.d11 * d20 - self.d01 * d21;
            let w = self.d00 * d21 - self.d01 * d20;
            if v >= 0.0 && w >= 0.0 && v + w <= self.len2 {
                let d = h * h / self.len2;
                return (d < best).then_some(d);
            }
        }
        let d = point_triangle_d2_from(x, [self.a, self.b, self.c], [self.ab, self.ac], [d20, d21]);
        (d < best).then_some(d)
    }
}

/// The points of the error bounds, the input's positions, as a list per triangle.
#[derive(Default)]
pub(super) struct Points {
    /// Each triangle's first position, or `NONE`...
    head: Vec<u32>,
    /// ...and each position's next one in its triangle's list, or `NONE`.
    next: Vec<u32>,
}

impl Points {
    /// Each position given to a triangle it is a corner of (its first).
    pub(super) fn place(work: &Work<'_>) -> Self {
        let mut p = Self {
            head: vec![NONE; work.tris.len()],
            next: vec![NONE; work.positions()],
        };
        for x in 0..work.positions() {
            if let Some(&f) = work.faces_of.of(x as u32).first() {
                p.next[x] = std::mem::replace(&mut p.head[f as usize], x as u32);
            }
        }
        p
    }

    /// The points of the lists that start at `heads` (the lists' heads, changed), into
    /// `points`: the lists are walked side by side, so that their cache misses overlap, and
    /// their points are interleaved (which no result depends on); their coordinates in
    /// `frame` start loading on the way.
    fn walk(&self, frame: Frame<'_>, heads: &mut Vec<u32>, points: &mut Vec<u32>) {
        points.clear();
        heads.retain(|&x| x != NONE);
        while !heads.is_empty() {
            for x in heads.iter_mut() {
                points.push(*x);
                // The point's coordinates, read once the walk is done.
                prefetch(&frame.positions[*x as usize]);
                *x = self.next[*x as usize];
            }
            heads.retain(|&x| x != NONE);
        }
    }

    /// Settles the points of `handover`'s collapses: finds the triangles they go to
    /// ([`Handover::settle`], on up to `threads` threads), then moves them, collapse after
    /// collapse, and gives each new node's error to `errors` (`(node, error)`, for
    /// [`Work::record_errors`]).
    pub(super) fn settle(
        &mut self,
        handover: &Handover,
        frame: Frame<'_>,
        threads: usize,
        errors: &mut Vec<(u32, f32)>,
    ) {
        let parts = handover.settle(frame, self, threads);
        self.hand_over(handover, parts, errors);
    }

    /// Moves the points of `handover`'s collapses to the triangles `parts` found for them
    /// and gives the new nodes' errors to `errors`, collapse after collapse.
    fn hand_over(
        &mut self,
        handover: &Handover,
        parts: Vec<Settled>,
        errors: &mut Vec<(u32, f32)>,
    ) {
        let mut entries = handover.entries().iter();
        for part in parts {
            let mut points = part.points.iter();
            for (&(n, error), e) in part.nodes.iter().zip(entries.by_ref()) {
                for (f, _) in handover.given(e).iter().chain(handover.dying(e)) {
                    self.head[*f as usize] = NONE;
                }
                for &(x, f) in points.by_ref().take(n as usize) {
                    self.next[x as usize] = std::mem::replace(&mut self.head[f as usize], x);
                }
                errors.push((e.node, error));
            }
        }
    }
}

impl Work<'_> {
    /// Records the new nodes' errors the settling gave (`(node, error)`), emptying `errors`.
    pub(super) fn record_errors(&mut self, errors: &mut Vec<(u32, f32)>) {
        for (node, error) in errors.drain(..) {
            self.nodes[node as usize].error = error;
        }
    }
}

/// The nearest triangle of `star` (each with its corners' positions) to each of `points`
/// and the squared distance, into `out`; `probes` and `coords` are scratch space.
fn nearest(
    frame: Frame<'_>,
    star: &[(u32, [u32; 3])],
    points: &[u32],
    (probes, coords): (&mut Vec<Probe>, &mut Vec<V3>),
    out: &mut Vec<(f64, u32)>,
) {
    // What the distances read of the triangles, gathered once for all the points.
    probes.clear();
    probes.extend(star.iter().map(|&(_, c)| Probe::new(c, |x| frame.at(x))));
    // The points' coordinates in a loop of their own, whose loads overlap.
    coords.clear();
    coords.extend(points.iter().map(|&x| frame.point(x)));
    for &x in coords.iter() {
        let mut best = (f64::INFINITY, NONE);
        for (&(f, _), probe) in star.iter().zip(probes.iter()) {
            if let Some(d) = probe.d2_below(x, best.0) {
                best = (d, f);
            }
        }
        out.push(best);
    }
}

impl Handover {
    /// Finds where the points of the handover's collapses go ([`Handover::settle_part`]),
    /// on up to `threads` threads: the collapses of a pass have disjoint stars, which no
    /// later collapse of the pass changes, and each collapse's points are handed over on
    /// their own, so the split does not change the result. [`Points::settle`] then moves
    /// them.
    pub(super) fn settle(&self, frame: Frame<'_>, points: &Points, threads: usize) -> Vec<Settled> {
        let count = self.entries().len();
        // Several parts a thread: the last passes' few collapses carry most points each.
        let per = count.div_ceil(SETTLE_PARTS * threads.max(1)).max(1);
        let ranges: Vec<_> = (0..count)
            .step_by(per)
            .map(|lo| lo..(lo + per).min(count))
            .collect();
        if threads <= 1 || ranges.len() <= 1 {
            ranges
                .into_iter()
                .map(|r| self.settle_part(frame, points, r))
                .collect()
        } else {
            ranges
                .into_par_iter()
                .map(|r| self.settle_part(frame, points, r))
                .collect()
        }
    }

    /// The points of the collapses `range`, each moved to the nearest of the triangles its
    /// collapse's removed child gave the new node (that child's ring fanned from the kept
    /// child: the same stretch of surface; a nearer triangle elsewhere would only lower the
    /// distance, so this is an upper bound at half the work of searching the whole star),
    /// or of the whole star when it gave none: each point with its triangle, and per
    /// collapse its number of points and its new node's error, raised to the largest
    /// distance and to how far the collapse moved the surface
    /// ([`Handover::surface_error`]).
    fn settle_part(
        &self,
        frame: Frame<'_>,
        points: &Points,
        range: std::ops::Range<usize>,
    ) -> Settled {
        let mut part = Settled::default();
        let (mut list, mut found, mut probes) = (Vec::new(), Vec::new(), Vec::new());
        let (mut walks, mut coords) = (Vec::new(), Vec::new());
        for e in &self.entries()[range] {
            let given = self.given(e);
            walks.clear();
            walks.extend(
                given
                    .iter()
                    .chain(self.dying(e))
                    .map(|&(f, _)| points.head[f as usize]),
            );
            points.walk(frame, &mut walks, &mut list);
            let to = if given.is_empty() {
                self.star(e)
            } else {
                given
            };
            found.clear();
            nearest(frame, to, &list, (&mut probes, &mut coords), &mut found);
            let mut error = e.error;
            let before = part.points.len();
            for (&x, &(d, f)) in list.iter().zip(&found) {
                if f != NONE {
                    part.points.push((x, f));
                    error = error.max(d.sqrt() as f32);
                }
            }
            let moved = self.surface_error(frame, e, error.into(), &mut probes);
            error = error.max(moved as f32);
            part.nodes
                .push(((part.points.len() - before) as u32, error));
        }
        part
    }
}

/// Parts per thread that [`Handover::settle`] splits its collapses into.
const SETTLE_PARTS: usize = 8;

/// What [`Handover::settle_part`] found.
#[derive(Default)]
pub(super) struct Settled {
    /// The points handed over, each with its new triangle, collapse after collapse.
    points: Vec<(u32, u32)>,
    /// Per collapse: its number of points there, and its new node's error.
    nodes: Vec<(u32, f32)>,
}
