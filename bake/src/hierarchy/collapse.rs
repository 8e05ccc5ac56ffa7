//! Applying a checked collapse: the new node and its bounds, the merged wedges, the dying
//! triangles' neighbours, the star moved onto the new node, and the valences.

use super::geometry::{corner_of, len, merge_cones, next, prev, sub};
use super::records::{NodeOut, Tri, Wedge};
use super::setup::by_positions;
use super::types::{Collapse, NONE, PARALLEL_MIN};
use super::work::Work;
use crate::quadric::QuadricsMut;

impl Work<'_> {
    /// Applies a checked collapse of the pass and stamps the neighbourhood it took (the
    /// rings of `t` and `u` in `rings`, the ends and the new node), so that no later
    /// collapse of the pass overlaps it. The third corners of the edge remember their
    /// number of neighbours at the start of the pass before they lose one. Returns the new
    /// node.
    pub(super) fn apply_in_pass(&mut self, c: Collapse, rings: &[Vec<u32>; 2]) -> u32 {
        let l = self.tris[c.fl as usize].c[prev(c.rot_l as usize)];
        let r = self.third(c.fr, c.t);
        for x in [l, r] {
            if x != NONE && !self.shrunk.get(self.at_node(x)) {
                let px = self.at_node(x);
                self.shrunk.set(px);
                self.start_valence[px] = self.valence[px];
            }
        }
        let s = self.apply(c);
        for &v in rings.iter().flatten().chain(&[c.t, c.u, s]) {
            let pv = self.at_node(v);
            self.stamp.set(pv);
        }
        s
    }

    /// Applies a checked collapse; returns the new node. The points of `u`'s triangles
    /// (those dying included) stay in their lists for the settling ([`super::bounds`]) to
    /// hand to their nearest triangle around the new node, from what the collapse adds to
    /// the handover ([`Work::take_over`]), and `u`'s wedges wait for
    /// [`Work::merge_wedges`].
    pub(super) fn apply(&mut self, c: Collapse) -> u32 {
        let s = self.node_pos.len() as u32;
        self.push_node(c);
        for f in [c.fl, c.fr] {
            if f != NONE {
                self.remove_dying(c, f);
            }
        }
        let kept = self.move_star(c, s);
        self.update_valences(c);
        #[cfg(debug_assertions)]
        self.check_valences(s);
        self.h.collapses.push(c);
        self.take_over(c, s, kept);
        s
    }

    /// The new node, parent of `t` and `u`, at `t`'s position: its error is at least its
    /// children's, its sphere holds both children's, its cone both cones.
    fn push_node(&mut self, c: Collapse) {
        let (t, u) = (c.t as usize, c.u as usize);
        let s = self.node_pos.len() as u32;
        self.node_pos.push(self.node_pos[t]);
        self.nodes[t].parent = s;
        self.nodes[u].parent = s;
        let (nt, nu) = (self.nodes[t], self.nodes[u]);
        let (p_t, p_u) = (self.pos(c.t), self.pos(c.u));
        self.nodes.push(NodeOut {
            parent: NONE,
            error: nt.error.max(nu.error),
            radius: (nt.radius as f64).max(len(sub(p_u, p_t)) + nu.radius as f64) as f32,
            cone: merge_cones(nt.cone, nu.cone),
        });
    }

    /// Merges the wedges of the pass's collapses: the removed position's into the kept
    /// position's (those of its groups; the surface-group rules made sure every group at
    /// `u` has a wedge at `t`). Nothing in a pass reads them: its costs are those of ends
    /// no collapse of the pass took. The positions are split into ranges, a rayon task
    /// each merging the collapses within its range; those across two ranges follow on one
    /// thread. Each kept position takes one collapse's wedges, so the sums do not depend
    /// on the split.
    pub(super) fn merge_wedges(&mut self, threads: usize) {
        let count = self.h.collapses.len() - self.pass_start;
        let pairs: Vec<(usize, usize)> = self.h.collapses[self.pass_start..]
            .iter()
            .map(|c| {
                let at = |v: u32| self.node_pos[v as usize] as usize;
                (at(c.t), at(c.u))
            })
            .collect();
        let np = self.positions();
        let per = if threads <= 1 || count < PARALLEL_MIN {
            np.max(1)
        } else {
            np.div_ceil(threads)
        };
        let ranges: Vec<(usize, usize)> = (0..np)
            .step_by(per)
            .map(|lo| (lo, (lo + per).min(np)))
            .collect();
        let (wedges, wedge_start) = (&self.wedges, &self.wedge_start);
        by_positions(
            &ranges,
            wedge_start,
            self.quadrics.as_mut(),
            |lo, hi, mut rows| {
                let base = wedge_start[lo] as usize;
                for &(pt, pu) in &pairs {
                    if (lo..hi).contains(&pt) && (lo..hi).contains(&pu) {
                        merge_at(wedges, wedge_start, &mut rows, base, pt, pu);
                    }
                }
            },
        );
        let range_of = |p: usize| p / per;
        let mut rows = self.quadrics.as_mut();
        for &(pt, pu) in &pairs {
            if range_of(pt) != range_of(pu) {
                merge_at(wedges, wedge_start, &mut rows, 0, pt, pu);
            }
        }
    }

    /// Removes the dying triangle `f` (`f_l` or `f_r` of `c`): the triangles across its two
    /// other edges become neighbours, and its third corner forgets it.
    fn remove_dying(&mut self, c: Collapse, f: u32) {
        self.alive[f as usize] = false;
        let Tri { c: fc, o, .. } = self.tris[f as usize];
        let j = corner_of(fc, c.t);
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
        // The ends' lists drop it as they merge ([`Work::move_star`]).
        let third = fc[prev(on_edge)];
        debug_assert!(third != c.t && third != c.u);
        self.faces_of.remove(third, f);
    }

    /// The triangles left around `t` and `u`, all but the dying ones, become the new node
    /// `s`'s (the kept child's first, which the settling ([`Work::take_over`]) relies on);
    /// returns how many came from the kept child.
    fn move_star(&mut self, c: Collapse, s: u32) -> usize {
        let (t, u) = (c.t, c.u);
        let kept = self.faces_of.push_merged(t, u, [c.fl, c.fr]);
        for &f in self.faces_of.of(s) {
            let mut tri = self.tris[f as usize];
            for x in tri.c.iter_mut() {
                if *x == t || *x == u {
                    *x = s;
                }
            }
            self.tris[f as usize] = tri;
        }
        kept
    }

    /// The ends' rings share just `l` and `r` (the link condition): the new node has the
    /// other neighbours of both, and `l` and `r` lose one.
    fn update_valences(&mut self, c: Collapse) {
        let (l, r) = (
            self.tris[c.fl as usize].c[prev(c.rot_l as usize)],
            self.third(c.fr, c.t),
        );
        let shared = 1 + u32::from(r != NONE);
        // The new node is at the kept child's position.
        let (pt, pu) = (self.at_node(c.t), self.at_node(c.u));
        self.valence[pt] = self.valence[pt] + self.valence[pu] - 2 - shared;
        for x in [l, r] {
            if x != NONE {
                let px = self.at_node(x);
                self.valence[px] -= 1;
            }
        }
    }

    /// The kept valences of the new node `s` and its neighbours match their rings.
    #[cfg(debug_assertions)]
    fn check_valences(&self, s: u32) {
        let mut ring = Vec::new();
        self.find_ring(s, &mut ring);
        let mut around = Vec::new();
        for x in std::iter::once(s).chain(ring.iter().copied()) {
            self.find_ring(x, &mut around);
            debug_assert_eq!(self.valence[self.at_node(x)] as usize, around.len(), "{x}");
        }
    }
}

/// Adds the quadrics of the wedges at position `pu` to those of the same groups at `pt`,
/// in `rows`, the quadrics of the wedges from the first of the position whose first wedge
/// is `base` on.
fn merge_at(
    wedges: &[Wedge],
    wedge_start: &[u32],
    rows: &mut QuadricsMut<'_>,
    base: usize,
    pt: usize,
    pu: usize,
) {
    let range = |p: usize| wedge_start[p] as usize..wedge_start[p + 1] as usize;
    let at_t = range(pt);
    for i in range(pu) {
        let (group, _) = wedges[i];
        if let Some(j) = at_t.clone().find(|&j| wedges[j].0 == group) {
            rows.merge(j - base, i - base);
        }
    }
}
