//! A welded mesh on disk: the arrays of a [`Welded`](super::Welded) in unlinked temporary
//! files, ordered so that each block of a blocked build ([`crate::blocked`]) is read with a
//! few positioned reads, and only small indexes in memory.
//!
//! The order (made by [`StoreWriter::finish`] from pieces pushed in any order):
//! - triangles by the tile of their centroid in the Z (Morton) order of the first level's
//!   `side × side` tiles, in push order within a tile. A tile of the next level is four
//!   consecutive tiles of this one, so every block of every level is one range of triangle
//!   ids ([`WeldedStore::block`]);
//! - positions by first use in that triangle order (corners in order), positions no triangle
//!   uses last: a block's positions are mostly one range, its border's in a few runs;
//! - attribute sets by first use in the positions' vertex lists in that position order;
//! - each position's vertex list `(surface group, attribute set)`, by group.
//!
//! A corner's attributes are its position's vertex of the triangle's group, so triangles
//! store no attribute ids ([`StoredTri`]).

mod column;
mod records;
mod tiles;
mod welded_store;
mod writer;

pub use records::{Origins, PositionLists, StoredTri};
pub use welded_store::WeldedStore;
pub use writer::StoreWriter;

pub(crate) use records::group_surfaces;
