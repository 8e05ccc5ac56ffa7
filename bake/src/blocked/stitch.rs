//! The whole hierarchy as the blocks' hierarchies add to it: each block's collapses in the
//! order its build applied them, with its nodes and triangles renamed to the whole mesh's, the
//! neighbours its border hid found across that border, and bounds that hold everything below
//! a node, earlier levels included.
//!
//! The order of the whole: a level's blocks one after another, the levels in turn. The
//! blocks of a level share only frozen positions, which no collapse removes, so each block's
//! collapses change only its own triangles and the order within a level is free. The one
//! thing the order decides is which triangle lies across a block's border when one of its
//! collapses names it (Hoppe's `fl_ccw` or `fr_clw` across an edge between two frozen
//! positions): the neighbouring block's triangle as it stands at the end of that block's
//! collapses if the neighbour comes earlier, at the start of the level if later.

use std::collections::HashMap;

use super::block::Block;
use super::replay::Replay;
use super::BlockedError;
use crate::hierarchy::{merge_cones, Collapse, Hierarchy};

const NONE: u32 = u32::MAX;

/// The hierarchy of the whole mesh so far, and the node standing at each position.
pub(super) struct Whole {
    pub(super) h: Hierarchy,
    /// The node at each position now (its latest).
    current: Vec<u32>,
    /// Per position: a leaf's bounds were set by a block.
    leaf_set: Vec<bool>,
    /// The triangle holding each directed edge `(a, b)` between two frozen positions, as the
    /// level's blocks stitched so far left it.
    border: HashMap<(u32, u32), u32>,
}

impl Whole {
    /// The leaves of `positions` positions over the triangles `corners`, all alive.
    pub(super) fn new(positions: usize, corners: Vec<[u32; 3]>) -> Self {
        let nt = corners.len();
        Self {
            h: Hierarchy {
                collapses: Vec::new(),
                parent: vec![NONE; positions],
                node_position: (0..positions as u32).collect(),
                radius: vec![0.0; positions],
                cone: vec![([0.0, 0.0, 1.0], 0.0); positions],
                error: vec![0.0; positions],
                corners,
                alive: vec![true; nt],
                passes: 0,
            },
            current: (0..positions as u32).collect(),
            leaf_set: vec![false; positions],
            border: HashMap::new(),
        }
    }

    /// Records the border edges of the live triangles `tris` (both ends frozen).
    pub(super) fn add_border(&mut self, tris: &[u32], frozen: &[bool]) {
        for &f in tris {
            self.border_edges(f, frozen, |b, e| {
                b.insert(e, f);
            });
        }
    }

    /// Calls `op` on the border map with each directed edge of triangle `f` between two
    /// frozen positions.
    fn border_edges(
        &mut self,
        f: u32,
        frozen: &[bool],
        mut op: impl FnMut(&mut HashMap<(u32, u32), u32>, (u32, u32)),
    ) {
        let c = self.h.corners[f as usize].map(|v| self.h.node_position[v as usize]);
        for k in 0..3 {
            let (a, b) = (c[k], c[(k + 1) % 3]);
            if frozen[a as usize] && frozen[b as usize] {
                op(&mut self.border, (a, b));
            }
        }
    }

    /// Forgets the level's border edges.
    pub(super) fn clear_border(&mut self) {
        self.border.clear();
    }

    /// Adds block `b`'s hierarchy `local` (built with its border frozen), or as many of its
    /// first collapses as `keep` says; `frozen` per position of the whole mesh. The leaves of
    /// the first level (`first`) take their bounds from the blocks that hold them.
    pub(super) fn stitch(
        &mut self,
        b: &Block,
        local: &Hierarchy,
        frozen: &[bool],
        first: bool,
        keep: Keep,
    ) -> Result<(), BlockedError> {
        let nl = b.positions.len();
        let mut node: Vec<u32> = b
            .positions
            .iter()
            .map(|&x| self.current[x as usize])
            .collect();
        if first {
            self.leaf_bounds(b, local);
        }
        // Per local node: the largest error of the whole's nodes this level started from
        // below it (the errors the block's own bounds, measured on its level, add to).
        let mut below: Vec<f32> = node.iter().map(|&v| self.h.error[v as usize]).collect();
        for f in &b.tris {
            let f = *f as usize;
            if !self.h.alive[f] {
                return Err(BlockedError::Stitch("a block holds a dead triangle"));
            }
        }
        for f in &b.tris {
            self.border_edges(*f, frozen, |m, e| {
                m.remove(&e);
            });
        }
        let mut replay = Replay::new(
            b.welded.triangles.iter().map(|t| t.p).collect(),
            nl,
            local.collapses.len(),
        );
        let stop = match keep {
            Keep::All => 0,
            Keep::Share(share) => (b.tris.len() as f64 * share) as usize,
        };
        for (i, c) in local.collapses.iter().enumerate() {
            if replay.live <= stop {
                break;
            }
            let n_local = nl + i;
            let (t, u) = (node[c.t as usize], node[c.u as usize]);
            let tri = |f: u32| if f == NONE { NONE } else { b.tris[f as usize] };
            let mut neighbours = c.neighbours.map(tri);
            let pos_of = |v: u32| b.positions[local.node_position[v as usize] as usize];
            let corner = |f: u32, k: usize| pos_of(replay.corners[f as usize][k]);
            if replay.corners[c.fl as usize][c.rot_l as usize] != c.t {
                return Err(BlockedError::Stitch("a collapse's f_l does not hold its t"));
            }
            // `fl_ccw` lies across `fl`'s edge `x → t`; `fr_clw` across `fr`'s `t → y`.
            let pt = pos_of(c.t);
            if neighbours[0] == NONE {
                let x = corner(c.fl, (c.rot_l as usize + 2) % 3);
                neighbours[0] = self.border.get(&(pt, x)).copied().unwrap_or(NONE);
            }
            if c.fr != NONE && neighbours[2] == NONE {
                let y = corner(c.fr, (c.rot_r as usize + 1) % 3);
                neighbours[2] = self.border.get(&(y, pt)).copied().unwrap_or(NONE);
            }
            let created = self.h.parent.len() as u32;
            let (ti, ui) = (t as usize, u as usize);
            let d = distance(b, local, c.t, c.u);
            let from_below = below[c.t as usize].max(below[c.u as usize]);
            below.push(from_below);
            let radius = (local.radius[n_local])
                .max(self.h.radius[ti])
                .max((d + f64::from(self.h.radius[ui])) as f32);
            let cone = merge_cones(
                local.cone[n_local],
                merge_cones(self.h.cone[ti], self.h.cone[ui]),
            );
            let error = (local.error[n_local] + from_below)
                .max(self.h.error[ti])
                .max(self.h.error[ui]);
            self.h.parent.push(NONE);
            self.h.node_position.push(self.h.node_position[ti]);
            self.h.radius.push(radius);
            self.h.cone.push(cone);
            self.h.error.push(error);
            self.h.parent[ti] = created;
            self.h.parent[ui] = created;
            self.current[pt as usize] = created;
            node.push(created);
            replay.apply(local, nl, i);
            self.h.collapses.push(Collapse {
                t,
                u,
                fl: tri(c.fl),
                fr: tri(c.fr),
                neighbours,
                rot_l: c.rot_l,
                rot_r: c.rot_r,
            });
        }
        for (i, &f) in b.tris.iter().enumerate() {
            self.h.corners[f as usize] = replay.corners[i].map(|v| node[v as usize]);
            self.h.alive[f as usize] = replay.alive[i];
        }
        for (i, &f) in b.tris.iter().enumerate() {
            if replay.alive[i] {
                self.border_edges(f, frozen, |m, e| {
                    m.insert(e, f);
                });
            }
        }
        Ok(())
    }

    /// The first level's leaves: radius and cone over every block that holds them.
    fn leaf_bounds(&mut self, b: &Block, local: &Hierarchy) {
        for (i, &x) in b.positions.iter().enumerate() {
            let x = x as usize;
            if self.leaf_set[x] {
                self.h.radius[x] = self.h.radius[x].max(local.radius[i]);
                self.h.cone[x] = merge_cones(self.h.cone[x], local.cone[i]);
            } else {
                self.h.radius[x] = local.radius[i];
                self.h.cone[x] = local.cone[i];
                self.leaf_set[x] = true;
            }
        }
    }
}

/// How much of a block's build a level keeps.
#[derive(Clone, Copy, Debug)]
pub(super) enum Keep {
    /// Every collapse.
    All,
    /// The first collapses, until no more than this share of the block's triangles is left.
    Share(f64),
}

/// The distance between the positions of the block's nodes `t` and `u`.
fn distance(b: &Block, local: &Hierarchy, t: u32, u: u32) -> f64 {
    let p = |v: u32| b.welded.positions[local.node_position[v as usize] as usize];
    let (a, c) = (p(t), p(u));
    (0..3)
        .map(|k| f64::from(a[k] - c[k]).powi(2))
        .sum::<f64>()
        .sqrt()
}
