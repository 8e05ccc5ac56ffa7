//! Applying a checked collapse: the new node and its bounds, the merged wedges, the dying
//! triangles' neighbours, the star moved onto the new node, and the valences.

use super::geometry::{corner_of, len, merge_cones, next, prev, sub};
use super::work::{NodeOut, Tri, Work};
use super::{Collapse, NONE};

impl Work<'_> {
    /// Applies a checked collapse of pass `pass` and stamps the neighbourhood it took (the
    /// rings of `t` and `u` in `rings`, the ends and the new node), so that no later
    /// collapse of the pass overlaps it. The third corners of the edge remember their
    /// number of neighbours at the start of the pass before they lose one.
    pub(super) fn apply_in_pass(&mut self, c: Collapse, pass: u32, rings: &[Vec<u32>; 2]) {
        let l = self.tris[c.fl as usize].c[prev(c.rot_l as usize)];
        let r = self.third(c.fr, c.t);
        for x in [l, r] {
            if x != NONE && self.shrunk[self.at_node(x)] != pass {
                let px = self.at_node(x);
                self.shrunk[px] = pass;
                self.start_valence[px] = self.valence[px];
            }
        }
        let s = self.apply(c);
        for &v in rings.iter().flatten().chain(&[c.t, c.u, s]) {
            let pv = self.at_node(v);
            self.stamp[pv] = pass;
        }
    }

    /// Applies a checked collapse; returns the new node. The points of `u`'s triangles
    /// (those dying included) wait for [`Work::settle`] to find their nearest triangle
    /// around the new node.
    pub(super) fn apply(&mut self, c: Collapse) -> u32 {
        let s = self.node_pos.len() as u32;
        for &f in self.faces_of.of(c.u) {
            let mut x = std::mem::replace(&mut self.pts_head[f as usize], NONE);
            while x != NONE {
                self.moved.push((x, s));
                x = self.pts_next[x as usize];
            }
        }
        self.push_node(c);
        self.merge_wedges(c);
        for f in [c.fl, c.fr] {
            if f != NONE {
                self.remove_dying(c, f);
            }
        }
        self.move_star(c, s);
        self.update_valences(c);
        #[cfg(debug_assertions)]
        self.check_valences(s);
        self.h.collapses.push(c);
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

    /// The removed position's wedges merge into the kept position's (those of its groups;
    /// the surface-group rules made sure every group at `u` has a wedge at `t`).
    fn merge_wedges(&mut self, c: Collapse) {
        let (pt, pu) = (self.node_pos[c.t as usize], self.node_pos[c.u as usize]);
        let (st, et) = (
            self.wedge_start[pt as usize] as usize,
            self.wedge_start[pt as usize + 1] as usize,
        );
        for i in self.wedge_start[pu as usize] as usize..self.wedge_start[pu as usize + 1] as usize
        {
            let g = self.wedges[i].group;
            if let Some(j) = (st..et).find(|&j| self.wedges[j].group == g) {
                self.quadrics.merge(j, i);
            }
        }
    }

    /// Removes the dying triangle `f` (`f_l` or `f_r` of `c`): the triangles across its two
    /// other edges become neighbours, and its corners forget it.
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
        for x in fc {
            self.faces_of.remove(x, f);
        }
    }

    /// The triangles left around `t` and `u` become the new node `s`'s (the kept child's
    /// first, which [`Work::settle`] relies on).
    fn move_star(&mut self, c: Collapse, s: u32) {
        let (t, u) = (c.t, c.u);
        self.from_kept.push(self.faces_of.of(t).len() as u32);
        self.faces_of.push_merged(t, u);
        for &f in self.faces_of.of(s) {
            let mut tri = self.tris[f as usize];
            for x in tri.c.iter_mut() {
                if *x == t || *x == u {
                    *x = s;
                }
            }
            self.tris[f as usize] = tri;
        }
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
