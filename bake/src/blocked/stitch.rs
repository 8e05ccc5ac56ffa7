//! The whole hierarchy as the blocks' hierarchies add to it: each block's collapses in the
//! order its build applied them, with its nodes and triangles renamed to the whole mesh's, the
//! neighbours its border hid found across that border, and bounds that hold everything below
//! a node, earlier levels included.
//!
//! The whole keeps in memory only what stitching needs — per node its parent, per position
//! the node standing there and that node's bounds, per triangle the positions of its corners
//! and whether it lives; each collapse goes to the spill file ([`super::spill`]) as it is
//! stitched.
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
use super::error::BlockedError;
use super::replay::Replay;
use super::spill::{Bounds, Record, SpillWriter, Spilled};
use crate::hierarchy::{merge_cones, Collapse, Hierarchy};

const NONE: u32 = u32::MAX;

/// The hierarchy of the whole mesh so far, and the node standing at each position.
pub(super) struct Whole {
    /// Parent of every node so far, `NONE` for roots.
    parent: Vec<u32>,
    /// Per triangle, the positions of its corners now.
    pub(super) corners: Vec<[u32; 3]>,
    /// Per triangle, whether it lives.
    pub(super) alive: Vec<bool>,
    /// Batches (passes) of the blocks' builds so far.
    pub(super) passes: u32,
    /// The node at each position now (its latest).
    current: Vec<u32>,
    /// The bounds of the node at each position now.
    bounds: Vec<Bounds>,
    /// The collapses so far.
    spill: SpillWriter,
    /// Per position: a leaf's bounds were set by a block.
    leaf_set: Vec<bool>,
    /// The triangle holding each directed edge `(a, b)` between two frozen positions, as the
    /// level's blocks stitched so far left it.
    border: HashMap<(u32, u32), u32>,
}

impl Whole {
    /// The leaves of `positions` positions under the triangles `corners`, all alive.
    pub(super) fn new(positions: usize, corners: Vec<[u32; 3]>) -> std::io::Result<Self> {
        let nt = corners.len();
        Ok(Self {
            parent: vec![NONE; positions],
            corners,
            alive: vec![true; nt],
            passes: 0,
            current: (0..positions as u32).collect(),
            bounds: vec![Bounds::LEAF; positions],
            spill: SpillWriter::new()?,
            leaf_set: vec![false; positions],
            border: HashMap::new(),
        })
    }

    /// Collapses so far.
    pub(super) fn collapses(&self) -> usize {
        self.spill.len()
    }

    /// The hierarchy, its collapses on disk.
    pub(super) fn finish(self) -> std::io::Result<Spilled> {
        Spilled::new(
            self.spill,
            self.parent,
            self.corners,
            self.alive,
            self.current,
            self.passes,
        )
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
        let c = self.corners[f as usize];
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
        let mut below: Vec<f32> = b
            .positions
            .iter()
            .map(|&x| self.bounds[x as usize].error)
            .collect();
        for f in &b.tris {
            let f = *f as usize;
            if !self.alive[f] {
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
        // The whole mesh's position of a local node.
        let pos_of = |v: u32| b.positions[local.node_position[v as usize] as usize];
        for (i, c) in local.collapses.iter().enumerate() {
            if replay.live <= stop {
                break;
            }
            let n_local = nl + i;
            let (t, u) = (node[c.t as usize], node[c.u as usize]);
            let tri = |f: u32| if f == NONE { NONE } else { b.tris[f as usize] };
            let mut neighbours = c.neighbours.map(tri);
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
            let created = self.parent.len() as u32;
            let (bt, bu) = (self.bounds[pt as usize], self.bounds[pos_of(c.u) as usize]);
            let d = distance(b, local, c.t, c.u);
            let from_below = below[c.t as usize].max(below[c.u as usize]);
            below.push(from_below);
            let made = Bounds {
                radius: (local.radius[n_local])
                    .max(bt.radius)
                    .max((d + f64::from(bu.radius)) as f32),
                cone: merge_cones(local.cone[n_local], merge_cones(bt.cone, bu.cone)),
                error: (local.error[n_local] + from_below)
                    .max(bt.error)
                    .max(bu.error),
            };
            self.parent.push(NONE);
            self.parent[t as usize] = created;
            self.parent[u as usize] = created;
            self.current[pt as usize] = created;
            self.bounds[pt as usize] = made;
            node.push(created);
            replay.apply(local, nl, i);
            let collapse = Collapse {
                t,
                u,
                fl: tri(c.fl),
                fr: tri(c.fr),
                neighbours,
                rot_l: c.rot_l,
                rot_r: c.rot_r,
            };
            self.spill
                .push(&Record::new(&collapse, pt, &made))
                .map_err(|e| BlockedError::Spill(e.to_string()))?;
        }
        for (i, &f) in b.tris.iter().enumerate() {
            self.corners[f as usize] = replay.corners[i].map(pos_of);
            self.alive[f as usize] = replay.alive[i];
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
            let leaf = &mut self.bounds[x];
            if self.leaf_set[x] {
                leaf.radius = leaf.radius.max(local.radius[i]);
                leaf.cone = merge_cones(leaf.cone, local.cone[i]);
            } else {
                leaf.radius = local.radius[i];
                leaf.cone = local.cone[i];
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
