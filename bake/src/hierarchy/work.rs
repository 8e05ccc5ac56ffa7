//! The mesh being simplified: triangles with their neighbours, the triangles around every
//! node, the wedges' quadrics, and the bounds recorded per node.

use std::borrow::Cow;

use super::geometry::{corner_of, cross, next, prev, sub, V3};
use super::handover::{Entry, Handover};
use super::prefetch::prefetch;
use super::records::{Frame, Marks, NodeOut, PosInfo, Tri, Wedge};
use super::stars::Stars;
use super::types::{AttributeWeights, Collapse, Hierarchy, NONE};
use crate::quadric::{Quadrics, M};
use crate::weld::Welded;

/// The mesh being simplified, with per node its triangles.
pub(super) struct Work<'w> {
    pub(super) w: &'w Welded,
    pub(super) weights: AttributeWeights,
    /// The bounding box's diagonal, which scales the attributes.
    pub(super) diagonal: f64,
    /// The bounding box's centre, which [`Work::at`] takes the positions relative to.
    pub(super) centre: V3,
    pub(super) info: Vec<PosInfo>,
    pub(super) tris: Vec<Tri>,
    pub(super) alive: Vec<bool>,
    /// Triangles around every node.
    pub(super) faces_of: Stars,
    /// Number of distinct neighbours of every live node, by its position
    /// ([`Work::at_node`]).
    pub(super) valence: Vec<u32>,
    pub(super) node_pos: Vec<u32>,
    /// Wedges of position `x`: `wedges[wedge_start[x]..wedge_start[x + 1]]` (none once the
    /// position is removed and [`Work::release_removed_wedges`] has run). A position's
    /// wedges are its vertices, in the same order, so until the first release the starts
    /// are the welded mesh's vertex lists' own, borrowed rather than copied, and so are the
    /// wedges (the first pass, when the build's memory peaks, holds no copy of either).
    pub(super) wedges: Cow<'w, [Wedge]>,
    pub(super) wedge_start: Cow<'w, [u32]>,
    /// The quadric of every wedge, by its index.
    pub(super) quadrics: Quadrics,
    /// Collapses whose removed positions' wedges are released.
    pub(super) wedges_released: usize,
    /// The wedges of the positions removed since, not yet released.
    pub(super) wedges_unreleased: usize,
    pub(super) h: Hierarchy,
    /// Per node: parent, and the bounds of [`Hierarchy`] (kept together here).
    pub(super) nodes: Vec<NodeOut>,
    /// Whether a collapse of this pass took a node's neighbourhood (stamped it), by its
    /// position. The live node at a position is the last made there (the kept child's
    /// parent is at its position): a collapse stamps both children and the new node, so a
    /// position stamped in a pass is one whose node, live at the start of the pass or made
    /// in it, was stamped.
    pub(super) stamp: Marks,
    /// Whether a node lost a neighbour in this pass, by its position: a node losing one is
    /// stamped by that collapse, so no new node of the same pass is made at its position.
    pub(super) shrunk: Marks,
    /// A node's number of neighbours at the start of the pass it last lost one in, by its
    /// position.
    pub(super) start_valence: Vec<u32>,
    /// The first collapse of the pass (an index of [`Hierarchy::collapses`]).
    pub(super) pass_start: usize,
    /// The collapses applied since the settling last took them ([`Work::handover`]).
    pub(super) taken: Handover,
}

impl Work<'_> {
    /// The scaled attributes of a wedge.
    #[inline]
    pub(super) fn attrs_of(&self, &(_, attr): &Wedge) -> [f64; M] {
        scaled_attributes(self.w, attr, &self.weights, self.diagonal)
    }

    #[inline]
    pub(super) fn wedges_at(&self, pos: usize) -> &[Wedge] {
        &self.wedges[self.wedge_range(pos)]
    }

    /// The indices of position `pos`'s wedges (and quadrics).
    #[inline]
    pub(super) fn wedge_range(&self, pos: usize) -> std::ops::Range<usize> {
        let start = &*self.wedge_start;
        start[pos] as usize..start[pos + 1] as usize
    }

    /// The triangle with the directed edge `a → b` and the corner of `a` in it.
    #[inline]
    pub(super) fn dir_face(&self, a: u32, b: u32) -> Option<(u32, usize)> {
        for &f in self.faces_of.of(a) {
            let c = self.tris[f as usize].c;
            let j = corner_of(c, a);
            if c[next(j)] == b {
                return Some((f, j));
            }
        }
        None
    }

    /// The distinct neighbours of `v` into `out`; returns whether `v` is on a border.
    ///
    /// Every neighbour `x` is reached once: through the triangle with the edge `v → x`, or,
    /// when there is none, through the border triangle with `x → v`.
    pub(super) fn find_ring(&self, v: u32, out: &mut Vec<u32>) -> bool {
        out.clear();
        let mut border = false;
        for &f in self.faces_of.of(v) {
            let t = &self.tris[f as usize];
            let j = corner_of(t.c, v);
            out.push(t.c[next(j)]);
            if t.o[prev(j)] == NONE {
                out.push(t.c[prev(j)]);
                border = true;
            }
            border |= t.o[j] == NONE;
        }
        border
    }

    /// Starts loading, a step at a time (`step` 0, 1, 2, a candidate or so apart), what the
    /// checks and the application of a collapse with the end `v` read: where its star is,
    /// its position and its bounds, then its star, its figures and its point, then its
    /// triangles. A hint, which changes no result.
    #[inline]
    pub(super) fn prefetch_around(&self, v: u32, step: usize) {
        match step {
            0 => {
                self.faces_of.prefetch_place(v);
                prefetch(&self.node_pos[v as usize]);
                prefetch(&self.nodes[v as usize]);
            }
            1 => {
                self.faces_of.prefetch_list(v);
                let p = self.at_node(v);
                prefetch(&self.valence[p]);
                prefetch(&self.w.positions[p]);
            }
            _ => {
                for &f in self.faces_of.of(v) {
                    prefetch(&self.tris[f as usize]);
                }
            }
        }
    }

    /// Starts loading, a step at a time (`step` 0, 1, 2, a few triangles apart), what the
    /// ranking of triangle `f`'s edges reads of its corners: where they are, then their
    /// figures and where their wedges are, then the wedges and their quadrics. A hint,
    /// which changes no result.
    #[inline]
    pub(super) fn prefetch_ends(&self, f: u32, step: usize) {
        for v in self.tris[f as usize].c {
            match step {
                0 => prefetch(&self.node_pos[v as usize]),
                1 => {
                    let p = self.at_node(v);
                    prefetch(&self.info[p]);
                    prefetch(&self.wedge_start[p]);
                    prefetch(&self.w.positions[p]);
                }
                _ => {
                    let wedges = self.wedge_range(self.at_node(v));
                    if let Some(w) = self.wedges.get(wedges.start) {
                        prefetch(w);
                    }
                    for i in wedges {
                        for line in self.quadrics.row(i).chunks(8) {
                            prefetch(&line[0]);
                        }
                    }
                }
            }
        }
    }

    /// Where the live node `v`'s per-node figures are kept (`valence`, `stamp`, `shrunk`,
    /// `start_valence`): at its position, which only one live node holds at a time.
    #[inline]
    pub(super) fn at_node(&self, v: u32) -> usize {
        self.node_pos[v as usize] as usize
    }

    /// The point of node `v` (its position's).
    #[inline]
    pub(super) fn pos(&self, v: u32) -> V3 {
        self.at(self.node_pos[v as usize] as usize)
    }

    /// The point of position `x`, relative to the centre in f64: computed where read (the
    /// same bits every time, [`Frame::at`]) rather than kept, which saves 24 bytes a position.
    #[inline]
    pub(super) fn at(&self, x: usize) -> V3 {
        self.frame().at(x as u32)
    }

    /// The number of positions (leaves).
    #[inline]
    pub(super) fn positions(&self) -> usize {
        self.w.positions.len()
    }

    #[inline]
    pub(super) fn triangle_normal(&self, c: [u32; 3]) -> V3 {
        let (a, b, d) = (self.pos(c[0]), self.pos(c[1]), self.pos(c[2]));
        cross(sub(b, a), sub(d, a))
    }

    /// The corner of triangle `f` after `v` (for a triangle on the edge `u → v`, its third
    /// corner), or `NONE` for no triangle.
    #[inline]
    pub(super) fn third(&self, f: u32, v: u32) -> u32 {
        if f == NONE {
            return NONE;
        }
        let c = self.tris[f as usize].c;
        c[next(corner_of(c, v))]
    }
}

impl Work<'_> {
    /// Releases the wedges and quadrics of the positions the collapses since the last
    /// release removed, once they hold a [`RELEASE_PARTS`]th of the positions' count: the
    /// others move down in place, a run of positions at a time, and the arrays' tails go
    /// back to the system. A removed position's wedges are never read again, so the
    /// quadrics, the largest table of the build, shrink with the mesh while the hierarchy
    /// grows; a release goes through every position, so there are at most that many. The
    /// quadrics go first, so that the first release, which copies the wedges and their
    /// starts out of the welded mesh's lists, does so with the quadrics' memory given back.
    /// Runs at the end of every pass, whose collapses (from [`Work::pass_start`]) it counts.
    pub(super) fn release_removed_wedges(&mut self) {
        let gone_at = |c: &Collapse| self.node_pos[c.u as usize] as usize;
        // The wedges of the pass's removed positions, counted once each.
        let count: usize = self.h.collapses[self.pass_start..]
            .iter()
            .map(|c| self.wedges_at(gone_at(c)).len())
            .sum();
        self.wedges_unreleased += count;
        let count = self.wedges_unreleased;
        if count == 0 || RELEASE_PARTS * count < self.positions() {
            return;
        }
        let removed = &self.h.collapses[self.wedges_released..];
        let mut gone = vec![false; self.positions()];
        for c in removed {
            gone[gone_at(c)] = true;
        }
        let (runs, start) = kept_runs(&gone, &self.wedge_start);
        let kept = start[self.positions()] as usize;
        for (from, to) in runs.iter().filter(|(from, to)| from.start != *to) {
            self.quadrics.move_rows(from.clone(), *to);
        }
        self.quadrics.truncate(kept);
        self.wedges = match std::mem::take(&mut self.wedges) {
            Cow::Borrowed(all) => {
                let mut wedges = Vec::with_capacity(kept);
                for (from, _) in &runs {
                    wedges.extend_from_slice(&all[from.clone()]);
                }
                Cow::Owned(wedges)
            }
            Cow::Owned(mut wedges) => {
                for (from, to) in runs.iter().filter(|(from, to)| from.start != *to) {
                    wedges.copy_within(from.clone(), *to);
                }
                wedges.truncate(kept);
                wedges.shrink_to_fit();
                Cow::Owned(wedges)
            }
        };
        self.wedge_start = Cow::Owned(start);
        self.wedges_released = self.h.collapses.len();
        self.wedges_unreleased = 0;
    }
}

impl<'w> Work<'w> {
    /// The frame of the work's positions, borrowing its welded mesh rather than the work.
    #[inline]
    pub(super) fn frame(&self) -> Frame<'w> {
        Frame::new(&self.w.positions, self.centre)
    }
}

impl Work<'_> {
    /// Adds the collapse `c` just applied, which made node `s` with `kept` triangles from
    /// its kept child (listed first), to the collapses taken for the settling.
    pub(super) fn take_over(&mut self, c: Collapse, s: u32, kept: usize) {
        let (tris, node_pos) = (&self.tris, &self.node_pos);
        let corners = |f: u32| (f, tris[f as usize].c.map(|v| node_pos[v as usize]));
        let entry = Entry::new(
            s,
            self.nodes[s as usize].error,
            node_pos[c.t as usize],
            node_pos[c.u as usize],
        );
        let star = self.faces_of.of(s).iter().map(|&f| corners(f));
        let dying = [c.fl, c.fr].into_iter().filter(|&f| f != NONE).map(corners);
        self.taken.push(entry, kept, star, dying);
    }

    /// The collapses taken since the last call, for the settling.
    pub(super) fn handover(&mut self) -> Handover {
        std::mem::take(&mut self.taken)
    }
}

/// The attributes `attr` of `w`, each kind scaled by its weight times `scale`.
pub(super) fn scaled_attributes(
    w: &Welded,
    attr: u32,
    weights: &AttributeWeights,
    scale: f64,
) -> [f64; M] {
    let a = &w.attributes[attr as usize];
    let normal = if a.normal_from_geometry {
        0.0
    } else {
        weights.normal
    };
    let (wn, wu, wc) = (normal * scale, weights.uv * scale, weights.color * scale);
    [
        a.normal[0] as f64 * wn,
        a.normal[1] as f64 * wn,
        a.normal[2] as f64 * wn,
        a.uv[0] as f64 * wu,
        a.uv[1] as f64 * wu,
        a.color[0] as f64 * wc,
        a.color[1] as f64 * wc,
        a.color[2] as f64 * wc,
    ]
}

/// The runs of wedges of the positions not `gone` between two that are, where each run
/// moves to (in order, each after the one before), and the positions' wedges' starts
/// after the move (a gone position's is the next kept one's, so its range is empty).
pub(super) fn kept_runs(
    gone: &[bool],
    starts: &[u32],
) -> (Vec<(std::ops::Range<usize>, usize)>, Vec<u32>) {
    let mut runs = Vec::new();
    let mut start = Vec::with_capacity(starts.len());
    let (mut run, mut kept) = (0..0, 0);
    for (x, &gone) in gone.iter().enumerate() {
        let hi = starts[x + 1] as usize;
        start.push((kept + run.len()) as u32);
        if gone {
            let run = std::mem::replace(&mut run, hi..hi);
            let len = run.len();
            if len > 0 {
                runs.push((run, kept));
            }
            kept += len;
        } else {
            run.end = hi;
        }
    }
    let len = run.len();
    if len > 0 {
        runs.push((run, kept));
    }
    start.push((kept + len) as u32);
    (runs, start)
}

/// [`Work::release_removed_wedges`] releases the wedges of this share of the positions at
/// a time.
const RELEASE_PARTS: usize = 8;

impl Work<'_> {
    /// The hierarchy, with the bounds gathered per node and the triangles as they end. The
    /// work's tables are freed first, and the nodes and triangles once copied, so that the
    /// hierarchy's arrays never take memory beside them (the peak of a build would be here).
    pub(super) fn into_hierarchy(mut self) -> Hierarchy {
        drop((
            std::mem::take(&mut self.wedges),
            std::mem::take(&mut self.wedge_start),
            std::mem::take(&mut self.quadrics),
            std::mem::take(&mut self.faces_of),
            std::mem::take(&mut self.info),
            std::mem::take(&mut self.valence),
        ));
        drop((
            std::mem::take(&mut self.stamp),
            std::mem::take(&mut self.shrunk),
            std::mem::take(&mut self.start_valence),
            std::mem::take(&mut self.taken),
        ));
        let mut h = self.h;
        let nodes = self.nodes;
        h.parent = nodes.iter().map(|n| n.parent).collect();
        h.error = nodes.iter().map(|n| n.error).collect();
        h.radius = nodes.iter().map(|n| n.radius).collect();
        h.cone = nodes.iter().map(|n| n.cone).collect();
        drop(nodes);
        h.node_position = self.node_pos;
        h.corners = self.tris.iter().map(|t| t.c).collect();
        drop(self.tris);
        h.alive = self.alive;
        h
    }
}
