//! What the settling of the error bounds reads of a pass's applied collapses, taken from the
//! work once they are applied ([`Work::handover`]): the new node, the positions of its two
//! children, and the corners of its triangles and of the two that died. The collapses of a
//! pass have disjoint stars, which no later collapse of the pass changes, so this is what the
//! settling would read at the end of the pass, and it can run while the pass goes on.

use std::ops::Range;

use super::work::Work;
use super::NONE;

/// A triangle as the settling reads it: its id and its corners' positions.
pub(super) type Corners = (u32, [u32; 3]);

/// One collapse as the settling reads it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Entry {
    /// The new node.
    pub(super) node: u32,
    /// Its error from its children.
    pub(super) error: f32,
    /// The positions of the new node (the kept child's) and of the removed child.
    pub(super) at: u32,
    pub(super) was: u32,
    /// Where its triangles start in [`Handover::tris`]: the new node's star (those from the
    /// kept child first), then the one or two that died.
    start: u32,
    /// How many of the star's came from the kept child.
    kept: u32,
    /// How many the star has.
    star: u32,
    /// How many died.
    dying: u32,
}

/// A run of a pass's applied collapses, in order, as the settling reads them.
#[derive(Debug, Default)]
pub(super) struct Handover {
    entries: Vec<Entry>,
    tris: Vec<Corners>,
}

impl Handover {
    /// The collapses.
    pub(super) fn entries(&self) -> &[Entry] {
        &self.entries
    }

    /// The new node's triangles.
    pub(super) fn star(&self, e: &Entry) -> &[Corners] {
        let s = e.start as usize;
        &self.tris[s..s + e.star as usize]
    }

    /// The new node's triangles from the kept child.
    pub(super) fn kept(&self, e: &Entry) -> &[Corners] {
        &self.star(e)[..e.kept as usize]
    }

    /// The new node's triangles from the removed child (it gave them).
    pub(super) fn given(&self, e: &Entry) -> &[Corners] {
        &self.star(e)[e.kept as usize..]
    }

    /// The triangles that died, with their corners as they were.
    pub(super) fn dying(&self, e: &Entry) -> &[Corners] {
        let s = (e.start + e.star) as usize;
        &self.tris[s..s + e.dying as usize]
    }
}

impl Work<'_> {
    /// The pass's applied collapses `collapses` (indices of [`super::Hierarchy::collapses`])
    /// as the settling reads them.
    pub(super) fn handover(&self, collapses: Range<usize>) -> Handover {
        let first_of_pass = self.h.collapses.len() - self.from_kept.len();
        let mut out = Handover {
            entries: Vec::with_capacity(collapses.len()),
            tris: Vec::new(),
        };
        let corners = |f: u32| (f, self.tris[f as usize].c.map(|v| self.at_node(v) as u32));
        for i in collapses {
            let c = self.h.collapses[i];
            let node = (self.positions() + i) as u32;
            let star = self.faces_of.of(node);
            let start = out.tris.len() as u32;
            out.tris.extend(star.iter().map(|&f| corners(f)));
            let dying = [c.fl, c.fr].into_iter().filter(|&f| f != NONE);
            out.tris.extend(dying.map(corners));
            out.entries.push(Entry {
                node,
                error: self.nodes[node as usize].error,
                at: self.at_node(c.t) as u32,
                was: self.at_node(c.u) as u32,
                start,
                kept: (self.from_kept[i - first_of_pass] as usize).min(star.len()) as u32,
                star: star.len() as u32,
                dying: out.tris.len() as u32 - start - star.len() as u32,
            });
        }
        out
    }
}
