//! Whether a collapse is legal: the surface-group rules, the link condition, Hoppe's
//! neighbours, no triangle flipped or collapsed, and how the checks stand within a pass.

use caveclod_core::format::PositionClass;

use super::geometry::{corner_of, cross, dot, len, next, prev, sub};
use super::types::{Collapse, NONE};
use super::work::Work;

/// What [`Work::verdict`] found.
pub(super) enum Verdict {
    /// Not legal at the start of the pass.
    Illegal,
    /// Legal at the start of the pass but no longer.
    Lapsed,
    /// Legal: the collapse.
    Legal(Collapse),
}

impl Work<'_> {
    /// Quadric cost of moving `u`'s wedges onto `t`.
    pub(super) fn cost(&self, t: u32, u: u32) -> f64 {
        let (pt, pu) = (
            self.node_pos[t as usize] as usize,
            self.node_pos[u as usize] as usize,
        );
        let at = self.wedges_at(pt);
        let (p, wedges) = (self.at(pt), &self.wedges);
        self.wedge_range(pu)
            .map(|i| match at.iter().find(|wt| wt.0 == wedges[i].0) {
                Some(wt) => self.quadrics.eval(i, p, &self.attrs_of(wt)),
                None => f64::INFINITY,
            })
            .sum()
    }

    /// The link condition on the edge `a`–`b` (the ends share exactly the neighbours that
    /// are the third corners of the triangles on the edge, `r` being the second's or
    /// `NONE` on a border), and no interior edge between two border nodes.
    pub(super) fn link_ok(ra: &[u32], border_a: bool, rb: &[u32], border_b: bool, r: u32) -> bool {
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

    /// Number of neighbours of `x` at the start of the pass.
    #[inline]
    pub(super) fn valence_at_start(&self, x: u32) -> usize {
        let px = self.at_node(x);
        if self.shrunk.get(px) {
            self.start_valence[px] as usize
        } else {
            self.valence[px] as usize
        }
    }

    /// The surface-group rules for moving `u` onto `t` across an edge with the triangles
    /// `fl` and `fr` (`NONE` on a border): a RIGID or frozen position never floats; a SHARP one
    /// floats only along a boundary onto a non-FREE one; every group at `u` has a vertex
    /// at `t`.
    #[inline]
    pub(super) fn groups_ok(&self, t: u32, u: u32, fl: u32, fr: u32) -> bool {
        let (pt, pu) = (
            self.node_pos[t as usize] as usize,
            self.node_pos[u as usize] as usize,
        );
        let (it, iu) = (self.info[pt], self.info[pu]);
        if iu.frozen {
            return false;
        }
        match iu.class {
            PositionClass::Rigid => return false,
            PositionClass::Sharp => {
                let group = |f: u32| self.w.triangles[f as usize].group;
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
    pub(super) fn moves(&self, t: u32, u: u32, fl: u32, jl: usize, fr: u32) -> Option<Collapse> {
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
        let p_t = self.pos(t);
        for &f in self.faces_of.of(u) {
            if f == fl || f == fr {
                continue;
            }
            let tri = &self.tris[f as usize];
            let c = tri.c;
            let mut q = [self.pos(c[0]), self.pos(c[1]), self.pos(c[2])];
            let before = cross(sub(q[1], q[0]), sub(q[2], q[0]));
            q[corner_of(c, u)] = p_t;
            let after = cross(sub(q[1], q[0]), sub(q[2], q[0]));
            let lb = len(before);
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

    /// The checks of the collapse of `u` into `t` (which the surface-group rules allow, at
    /// a finite cost) as they stood at the start of the pass, and as they stand now;
    /// the rings of `t` and `u` go to `rings`. Neither end was touched since (callers skip
    /// stamped ends), so their stars, rings and borders are as they were; only a third
    /// corner of the edge may have lost a neighbour since.
    pub(super) fn verdict(&self, t: u32, u: u32, rings: &mut [Vec<u32>; 2]) -> Verdict {
        let Some((fl, jl)) = self.dir_face(t, u) else {
            return Verdict::Illegal;
        };
        let fr = self.tris[fl as usize].o[jl];
        let l = self.tris[fl as usize].c[prev(jl)];
        let r = self.third(fr, t);
        let opposite = [l, r];
        if !opposite
            .iter()
            .all(|&x| x == NONE || self.valence_at_start(x) > 3)
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
            .all(|&x| x == NONE || self.valence[self.at_node(x)] > 3)
        {
            Verdict::Legal(c)
        } else {
            Verdict::Lapsed
        }
    }
}
