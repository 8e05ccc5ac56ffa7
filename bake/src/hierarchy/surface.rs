//! The surface's side of the error bounds: how far a collapse moves the surface away from
//! the surface it replaces.
//!
//! The input's points measure one direction only (every input point lies near the current
//! surface). A collapse can also lay a triangle across a gap the input does not fill (across
//! a crease, a fold or between two limbs) while every input point stays near some current
//! triangle; the symmetric (Hausdorff) distance sees it, the points do not. So a new node's
//! error is also raised to the largest distance from sample points of the triangles it moved
//! (their centroids and edge midpoints) to the surface just before the collapse: the kept
//! child's triangles, the removed child's as they were, and the two that died.

use super::bounds::Probe;
use super::geometry::{corner_of, next, prev, V3};
use super::handover::{Entry, Handover};
use super::records::Frame;

/// The sample points of a triangle with corners `c` that moved with the node at `s`: its
/// centroid and the midpoints of its two edges at `s` (the third edge did not move: it is
/// an edge of the triangle as it was).
fn samples(c: [u32; 3], s: u32, pos: impl Fn(u32) -> V3) -> [V3; 3] {
    let k = corner_of(c, s);
    let [a, b, d] = [c[k], c[next(k)], c[prev(k)]].map(pos);
    let mid = |x: V3, y: V3| {
        [
            0.5 * (x[0] + y[0]),
            0.5 * (x[1] + y[1]),
            0.5 * (x[2] + y[2]),
        ]
    };
    let third = 1.0 / 3.0;
    [
        [
            (a[0] + b[0] + d[0]) * third,
            (a[1] + b[1] + d[1]) * third,
            (a[2] + b[2] + d[2]) * third,
        ],
        mid(a, b),
        mid(a, d),
    ]
}

impl Handover {
    /// The largest distance from the samples of the triangles the new node of `e` took from
    /// its removed child to the surface before the collapse that made it, when above
    /// `floor` (which settles most samples at their own triangle as it was).
    ///
    /// The collapses of a pass have disjoint stars, so the new node's triangles and the two
    /// that died are as the collapse left them ([`Handover`]), and the points of nodes never
    /// change.
    pub(super) fn surface_error(
        &self,
        frame: Frame<'_>,
        e: &Entry,
        floor: f64,
        probes: &mut Vec<Probe>,
    ) -> f64 {
        let (kept, moved) = (self.kept(e), self.given(e));
        // The moved triangles had the removed child where the new node is.
        let before = |x: u32| frame.at(if x == e.at { e.was } else { x });
        // The surface before: the moved triangles as they were (first, in the order of
        // `moved`), then, once a sample needs them, the kept child's and the two that
        // died, which did not change.
        probes.clear();
        probes.extend(moved.iter().map(|&(_, c)| Probe::new(c, before)));
        let mut all_probed = false;
        let mut worst = floor * floor;
        for (i, &(_, c)) in moved.iter().enumerate() {
            for x in samples(c, e.at, |x| frame.at(x)) {
                // Its own triangle as it was first: most samples stay near it.
                if probes[i].d2_below(x, worst).is_some() {
                    continue;
                }
                if !all_probed {
                    probes.extend(
                        kept.iter()
                            .chain(self.dying(e))
                            .map(|&(_, c)| Probe::new(c, |x| frame.at(x))),
                    );
                    all_probed = true;
                }
                let mut best = f64::INFINITY;
                for probe in probes.iter() {
                    if let Some(d) = probe.d2_below(x, best) {
                        best = d;
                        if best <= worst {
                            break;
                        }
                    }
                }
                worst = worst.max(best);
            }
        }
        worst.sqrt()
    }
}
