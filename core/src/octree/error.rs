//! Why octree sections were refused, and the format's limit on levels.

use crate::format::Tag;

/// The most levels an octree may have. Selection needs no stack, so this is a format limit
/// (what 32-bit cell coordinates can address), not a run-time one.
pub const MAX_OCTREE_LEVELS: u32 = 32;

/// Why octree sections were refused. Each names the section and the record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OctreeFormatError {
    /// Some but not all octree sections are present.
    MissingSection(Tag),
    /// A section's size is not a whole number of records, or it is not 4-byte aligned.
    BadSection(Tag),
    /// A section holds another number of records than `OCMT` says (`OCMT` itself: one).
    CountMismatch {
        /// The section.
        tag: Tag,
        /// Records expected.
        expected: u64,
        /// Records found.
        got: u64,
    },
    /// `OCMT` names another surface count than the hierarchy has.
    SurfaceCount {
        /// The octree's.
        octree: u32,
        /// The hierarchy's.
        hierarchy: u32,
    },
    /// `OCMT` names more surfaces than a [`SurfaceId`](crate::SurfaceId) can name (65535).
    TooManySurfaces {
        /// `surface_count` of `OCMT`.
        surfaces: u32,
    },
    /// The octree has no node.
    Empty,
    /// More levels than [`MAX_OCTREE_LEVELS`], or none.
    LevelCount {
        /// `level_count` of `OCMT`.
        levels: u32,
    },
    /// A node's box or error is not a finite number.
    NotFinite {
        /// The node.
        node: u32,
    },
    /// A node's box has `min > max` on some axis.
    EmptyBox {
        /// The node.
        node: u32,
    },
    /// A node's error is negative.
    NegativeError {
        /// The node.
        node: u32,
    },
    /// A node's level is not its parent's minus one, the root's is not `level_count - 1`,
    /// or it has children at level 0 / none above.
    BadLevel {
        /// The node.
        node: u32,
    },
    /// A node's children run past the last node.
    ChildOutOfRange {
        /// The parent.
        node: u32,
    },
    /// A node's children start among nodes that already have a parent: some node would
    /// have two parents (or be its own ancestor).
    SharedChild {
        /// The second parent.
        node: u32,
    },
    /// A node is nobody's child (the children ranges leave a gap before it).
    Orphan {
        /// The node.
        node: u32,
    },
    /// A child's error is larger than its parent's.
    ErrorAboveParent {
        /// The child.
        node: u32,
    },
    /// A child's box is not inside its parent's.
    ChildOutsideParent {
        /// The child.
        node: u32,
    },
    /// A node's ranges run past the last range.
    RangesOutOfRange {
        /// The node.
        node: u32,
    },
    /// A node's ranges do not have strictly ascending surfaces.
    SurfacesNotAscending {
        /// The node.
        node: u32,
    },
    /// A range names a surface at or above the surface count.
    SurfaceOutOfRange {
        /// The range.
        range: u32,
    },
    /// A range's index count is zero or not a multiple of 3.
    BadIndexCount {
        /// The range.
        range: u32,
    },
    /// A range runs past the last index.
    IndicesOutOfRange {
        /// The range.
        range: u32,
    },
    /// The nodes' ranges hold more than `u32::MAX` indices together.
    TooManyIndices,
    /// An index names a vertex past the last one.
    VertexOutOfRange {
        /// Entry of `OCIX`.
        index: u32,
        /// Its value.
        vertex: u32,
    },
    /// A vertex holds a number that is not finite.
    VertexNotFinite {
        /// The vertex.
        vertex: u32,
    },
}

impl core::fmt::Display for OctreeFormatError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::MissingSection(t) => write!(f, "octree section {t} is missing"),
            Self::BadSection(t) => write!(
                f,
                "octree section {t}: size or alignment does not fit its records"
            ),
            Self::CountMismatch { tag, expected, got } => write!(
                f,
                "octree section {tag}: {got} records, {expected} expected"
            ),
            Self::SurfaceCount { octree, hierarchy } => write!(
                f,
                "octree section OCMT: {octree} surfaces, the hierarchy has {hierarchy}"
            ),
            Self::TooManySurfaces { surfaces } => write!(
                f,
                "octree section OCMT: {surfaces} surfaces, at most 65535 can be named"
            ),
            Self::Empty => write!(f, "octree section OCND: no root node"),
            Self::LevelCount { levels } => write!(
                f,
                "octree section OCMT: {levels} levels, 1 to {MAX_OCTREE_LEVELS} allowed"
            ),
            Self::NotFinite { node } => {
                write!(
                    f,
                    "octree section OCND, record {node}: box or error not finite"
                )
            }
            Self::EmptyBox { node } => {
                write!(f, "octree section OCND, record {node}: min > max")
            }
            Self::NegativeError { node } => {
                write!(f, "octree section OCND, record {node}: negative error")
            }
            Self::BadLevel { node } => write!(
                f,
                "octree section OCND, record {node}: level does not fit its parent or children"
            ),
            Self::ChildOutOfRange { node } => write!(
                f,
                "octree section OCND, record {node}: children past the last node"
            ),
            Self::SharedChild { node } => write!(
                f,
                "octree section OCND, record {node}: a child already has a parent"
            ),
            Self::Orphan { node } => {
                write!(f, "octree section OCND, record {node}: no parent")
            }
            Self::ErrorAboveParent { node } => write!(
                f,
                "octree section OCND, record {node}: error larger than its parent's"
            ),
            Self::ChildOutsideParent { node } => write!(
                f,
                "octree section OCND, record {node}: box not inside its parent's"
            ),
            Self::RangesOutOfRange { node } => write!(
                f,
                "octree section OCND, record {node}: ranges past the last OCRG record"
            ),
            Self::SurfacesNotAscending { node } => write!(
                f,
                "octree section OCND, record {node}: range surfaces not strictly ascending"
            ),
            Self::SurfaceOutOfRange { range } => write!(
                f,
                "octree section OCRG, record {range}: surface past the surface count"
            ),
            Self::BadIndexCount { range } => write!(
                f,
                "octree section OCRG, record {range}: index count not a positive multiple of 3"
            ),
            Self::IndicesOutOfRange { range } => write!(
                f,
                "octree section OCRG, record {range}: indices past the last OCIX entry"
            ),
            Self::TooManyIndices => write!(
                f,
                "octree section OCRG: the nodes' ranges hold more than 2^32 - 1 indices"
            ),
            Self::VertexOutOfRange { index, vertex } => write!(
                f,
                "octree section OCIX, entry {index}: vertex {vertex} is past the last vertex"
            ),
            Self::VertexNotFinite { vertex } => {
                write!(f, "octree section OCVX, record {vertex}: not finite")
            }
        }
    }
}

impl core::error::Error for OctreeFormatError {}
