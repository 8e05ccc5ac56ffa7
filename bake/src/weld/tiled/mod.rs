//! The weld of a mesh too large to hold, tile by tile: each tile welded by [`super::weld`]
//! itself (so the repairs stay one implementation), the tiles then joined where they meet.
//!
//! The input ([`Tiles`]) has its identical positions welded already (step 1: a position per
//! distinct coordinate triple, numbered in input order as [`super::weld`] numbers them) and
//! its triangles cut into tiles, a triangle in the tile of its centroid taken over its
//! corners in position order, so that a triangle and its duplicates (the same three
//! positions) always share a tile. A position is a *border* position when triangles of two
//! tiles use it; the *band* is the triangles with a border corner, a small part of the mesh
//! on any surface whose tiles follow its layout (a border is short against a tile's area).
//!
//! Each tile is welded with a *halo*: the band's triangles of other tiles that use one of its
//! positions. Every triangle around every position the tile's own triangles use is then in
//! the tile's mesh, in input order, so every decision the weld takes at those positions is
//! the one it takes on the whole mesh: which triangles are degenerate or duplicates, which
//! edges are cut (the later triangle on an over-used edge), the fans a position splits into
//! (copies are named by the first triangle of their fan, so tiles that share a fan name its
//! copy alike), the computed normals, and whether two triangles across an edge match. Only a
//! tile's own triangles are kept from its weld. What one tile cannot see is then joined
//! (`join`):
//! - surface groups: a tile's groups are joined with the groups of the matching triangles
//!   across its border (union-find over `(tile, group)`), refusing a join that would give a
//!   group two attribute sets at one position, as the in-core growth refuses a triangle;
//! - classes of the positions where groups meet or tiles meet, counted again from the joined
//!   groups (elsewhere every edge is inside one tile's group, and the tile's class stands);
//! - attribute sets, made distinct over the whole mesh, and the colouring of the joined
//!   groups (greedy, largest first, as [`super::weld`] colours).
//!
//! On a mesh where the in-core weld takes no order-dependent choice (a group's growth never
//! refused, no chain of cut edges longer than a triangle's reach) the result is
//! [`super::weld`]'s up to the numbering of positions, attribute sets, triangles and groups;
//! elsewhere it keeps the weld's invariants (every edge at most two triangles, one fan per
//! position, no group with two attribute sets at one position).
//!
//! The tiles come from a mesh in memory ([`MeshTiles`]) or a PLY file streamed into files
//! of tiles ([`StreamTiles`]); the result goes to a [`WeldSink`] piece by piece (the welded
//! store takes it so; [`WeldedBuilder`] makes a [`Welded`](super::Welded) of it), so nothing
//! the size of the whole mesh's triangles is ever in memory: only per position its
//! coordinates, tile and class, the distinct attribute sets, the band, and the tiles being
//! welded.
//! [`crate::pipeline::import_and_weld`] chooses between this and the in-core import by the
//! file.

mod error;
mod join;
mod mesh_input;
mod run;
mod sink;
mod spool;
mod store_sink;
mod stream_input;
mod tile;
mod tiles;

pub use error::TiledWeldError;
pub use mesh_input::MeshTiles;
pub use run::{weld_tiled, weld_tiled_into};
pub use sink::{WeldSink, WeldedBuilder};
pub use stream_input::{StreamTiles, StreamedReport};
pub use tiles::{TileTriangle, TiledMesh, Tiles, SHARED};
