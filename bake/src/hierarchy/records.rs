//! The plain records of the mesh being simplified ([`super::work::Work`]): a wedge, a
//! triangle with its neighbours, what the hierarchy records of a node, what the rules read
//! of a position, the flags a pass sets, and the frame positions are read in.

use caveclod_core::format::PositionClass;

use super::geometry::{sub, V3};

/// One surface group at a position, with that group's attributes there: `(group,
/// attribute id)`, a vertex of the welded mesh's lists ([`crate::weld::VertexLists`]), the
/// attributes an index into the welded mesh's ([`Work::attrs_of`](super::work::Work) scales
/// them when a cost reads them, which keeps the wedge 64 bytes smaller than holding them
/// scaled). Its quadric is the row of the work's quadrics with its index, over the
/// attributes the mesh has.
pub(super) type Wedge = (u32, u32);

/// A triangle of the mesh being simplified: 24 bytes (its normal is computed where a
/// check reads it, from the corners, and its surface group read from the welded mesh,
/// rather than kept).
#[derive(Clone, Copy, Debug)]
pub(super) struct Tri {
    /// Current corners (nodes), counter-clockwise.
    pub(super) c: [u32; 3],
    /// `o[k]`: the triangle across the edge `c[k] → c[k + 1]`, or `NONE`. The mesh stays
    /// an oriented manifold, so that triangle holds the edge the other way round.
    pub(super) o: [u32; 3],
}

/// What the hierarchy records of a node.
#[derive(Clone, Copy)]
pub(super) struct NodeOut {
    pub(super) parent: u32,
    pub(super) error: f32,
    pub(super) radius: f32,
    pub(super) cone: ([f32; 3], f32),
}

/// What the surface-group rules read of a position.
#[derive(Clone, Copy)]
pub(super) struct PosInfo {
    pub(super) class: PositionClass,
    /// Never removed by a collapse ([`super::build::build_frozen`]).
    pub(super) frozen: bool,
    /// The position's one surface group, or `NONE` when it has several.
    pub(super) group: u32,
}

/// A flag per position that a pass sets and the next pass clears: a bit each, so that the
/// flags of a whole mesh stay in cache while a pass tests them at random.
#[derive(Debug, Default)]
pub(super) struct Marks(Vec<u64>);

impl Marks {
    /// Flags for `n` positions, none set.
    pub(super) fn new(n: usize) -> Self {
        Self(vec![0; n.div_ceil(64)])
    }

    /// Clears every flag.
    pub(super) fn clear(&mut self) {
        self.0.fill(0);
    }

    /// Whether position `p`'s flag is set.
    #[inline]
    pub(super) fn get(&self, p: usize) -> bool {
        self.0[p / 64] >> (p % 64) & 1 != 0
    }

    /// Sets position `p`'s flag.
    #[inline]
    pub(super) fn set(&mut self, p: usize) {
        self.0[p / 64] |= 1 << (p % 64);
    }
}

/// Position `q` relative to `centre`, in f64.
#[inline]
pub(super) fn centred(q: [f32; 3], centre: V3) -> V3 {
    sub(q.map(f64::from), centre)
}

/// Where positions are read from: the welded mesh's, relative to the centre of its bounding
/// box (the work reads them through it, [`super::work::Work::at`]; the settling holds one
/// apart from the work).
#[derive(Clone, Copy)]
pub(super) struct Frame<'a> {
    pub(super) positions: &'a [[f32; 3]],
    pub(super) centre: V3,
}

impl<'a> Frame<'a> {
    /// The frame of `positions` centred on `centre`.
    pub(super) fn new(positions: &'a [[f32; 3]], centre: V3) -> Self {
        Self { positions, centre }
    }

    /// The point of position `x`, relative to the centre, in f64.
    #[inline]
    pub(super) fn at(&self, x: u32) -> V3 {
        centred(self.positions[x as usize], self.centre)
    }

    /// The point of the error bounds standing for position `x`: in single precision
    /// (ample for an error bound), relative to the centre.
    #[inline]
    pub(super) fn point(&self, x: u32) -> V3 {
        self.at(x).map(|c| c as f32 as f64)
    }
}
