//! What the settling of the error bounds reads of a pass's applied collapses, taken from the
//! work as each is applied (`Work::take_over`, while what it reads is in cache): the new
//! node, the positions of its two children, and the corners of its triangles and of the two
//! that died. The collapses of a pass have disjoint stars, which no later collapse of the
//! pass changes, so this is what the settling would read at the end of the pass, and it can
//! run while the pass goes on.

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

impl Entry {
    /// The collapse that made `node`, with its `error` from its children, at position `at`
    /// (the kept child's), the removed child's being `was`; its triangles are added with it
    /// ([`Handover::push`]).
    pub(super) fn new(node: u32, error: f32, at: u32, was: u32) -> Self {
        Self {
            node,
            error,
            at,
            was,
            start: 0,
            kept: 0,
            star: 0,
            dying: 0,
        }
    }
}

impl Handover {
    /// Adds the collapse `entry` just applied: its new node's triangles `star` (the `kept`
    /// from the kept child first), then the triangles that died.
    pub(super) fn push(
        &mut self,
        entry: Entry,
        kept: usize,
        star: impl Iterator<Item = Corners>,
        dying: impl Iterator<Item = Corners>,
    ) {
        let start = self.tris.len() as u32;
        self.tris.extend(star);
        let star = self.tris.len() as u32 - start;
        self.tris.extend(dying);
        self.entries.push(Entry {
            start,
            kept: kept as u32,
            star,
            dying: self.tris.len() as u32 - start - star,
            ..entry
        });
    }

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
