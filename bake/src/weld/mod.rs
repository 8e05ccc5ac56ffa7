//! From an imported [`Mesh`](crate::mesh::Mesh) to a clean, manifold, welded mesh with
//! surface groups.
//!
//! Steps, each counted in [`Repairs`]:
//! 1. positions with identical coordinates are welded into one node position;
//! 2. degenerate triangles (a repeated position or zero area) and duplicate triangles (the
//!    same three positions, either orientation) are dropped;
//! 3. an edge used by more than two triangles, or twice in one direction, is cut: the later
//!    triangle gets its own copies of the edge's two positions;
//! 4. a position whose triangles form several fans (a non-manifold vertex) is split, one
//!    copy per extra fan;
//! 5. surface groups grow over edges where the surface and the attributes at both ends match,
//!    never taking a triangle that would give the group a second attribute set at one
//!    position (a UV seam that closes on itself, as on a cylinder, is cut open instead);
//! 6. positions are classified FREE / SHARP / RIGID by the boundary edges through them (mesh
//!    borders and surface-group changes), and groups that share no position share an id
//!    (greedy colouring, largest groups first).
//!
//! Missing normals are computed (area-weighted, per position), missing UVs are zero and
//! missing colours white. Each attribute set records whether its normal follows from the
//! geometry (computed here, or within [`GEOMETRIC_NORMAL_DEGREES`] of the computed one),
//! which simplification then ignores.
//!
//! [`weld`] runs these steps in order, one module each: `repair` (1–4), `groups` (5–6),
//! and between them `attributes` (the corners' attributes, deduplicated).

mod attributes;
mod groups;
mod in_core;
mod repair;
pub mod store;
#[cfg(test)]
mod tests;
pub mod tiled;
mod vector;
mod vertex_lists;
mod welded;

pub use in_core::weld;
pub use vertex_lists::{Lists, VertexLists};
pub use welded::{
    Attributes, Repairs, WeldError, WeldInfo, Welded, WeldedTri, GEOMETRIC_NORMAL_DEGREES,
    MAX_TRIANGLES,
};
