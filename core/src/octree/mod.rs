//! The multiresolution octree of out-of-core bakes: a hierarchical level of detail (HLOD)
//! over a vertex-clustering octree, chosen per camera as a cut of the tree and drawn as
//! per-surface index lists, like the hierarchy path.
//!
//! # Design
//! The out-of-core bake clusters the input on a grid, then on grids twice as coarse, level by
//! level (`bake/src/ooc/multires.rs`). A node is one block of cells of one level: all the
//! triangles that level's clustering keeps in the block, with a box and an object-space error
//! bound of drawing them instead of the full-resolution input. A block of level `l + 1` is the
//! parent of the level-`l` blocks inside it, so the nodes form an octree over space. A cut
//! meets every root-to-leaf path at most once, and exactly once unless the path was culled,
//! so it draws every region it keeps once, at one level.
//!
//! - **Nodes are whole levels of a block.** A node's triangles are a complete clustering of
//!   its block, independent of its neighbours: unlike the vertex hierarchy, where a split may
//!   force splits around it, any cut is drawable. Selection is therefore a plain walk down the
//!   tree with no forced refinement and no per-camera connectivity — a few words per node —
//!   and its work is proportional to the nodes visited, not the triangles.
//! - **Cracks are bounded by the coarser node's error.** Neighbours drawn at different levels
//!   share no vertices. Each lies within its error of the input, so the gap between their
//!   borders is at most the sum of their errors, at most twice the coarser node's (errors never
//!   grow down the tree, which [`Octree::new`] checks). A taken node's error projects to at
//!   most the pixel tolerance from the nearest point of its box, so cracks stay under twice the
//!   tolerance on screen; halve the tolerance where that matters.
//! - **A node's data is contiguous.** One vertex buffer serves every level and is uploaded
//!   once; a node's ranges are consecutive `OCRG` records, one per surface, and the bake writes
//!   a node's indices as one span of `OCIX`. An engine that streams can therefore load or drop
//!   a node as one piece; [`OctreeCut::entered`] and [`OctreeCut::left`] name the nodes whose
//!   data a frame needs and no longer needs.
//!
//! # Selection
//! [`OctreeCut::select`] walks breadth first from the root. A node whose box lies outside a
//! frustum plane is skipped with its subtree (children's boxes nest in their parent's,
//! checked at load); a node is taken when its error projects to at most the tolerance —
//! `error × pixels_per_radian / distance <= tolerance_px`, the form the hierarchy's refinement
//! uses, with the distance from the eye to the node's box — or when it is at level 0;
//! otherwise its children are looked at. The cut is kept in caller memory (see
//! [`OctreeCut::words_needed`]); emission copies the taken nodes' ranges into per-surface index
//! lists ([`OctreeCut::emit_indices_packed`]), and the indices already point into the octree's
//! vertex buffer. The octree is read-only and `Copy`, so any number of cameras, each with its
//! own cut, select over one octree at once. Nothing here allocates.
//!
//! ```no_run
//! # fn demo(bytes: &[u8]) -> Result<(), Box<dyn core::error::Error>> {
//! use caveclod_core::{Hierarchy, Octree, OctreeCut, View};
//! let h = Hierarchy::from_bytes(bytes)?;
//! let Some(octree) = Octree::from_hierarchy(&h)? else { return Ok(()) };
//! let mut memory = vec![0u32; OctreeCut::words_needed(&octree)];
//! let mut cut = OctreeCut::new(&octree, &mut memory)?;
//! let view = View::without_frustum(glam::Vec3::new(0.0, 50.0, 200.0), 1000.0);
//! let stats = cut.select(&octree, &view, 1.0)?;
//! let mut indices = vec![0u32; cut.total_index_count()];
//! let mut offsets = vec![0u32; octree.surface_count() + 1];
//! cut.emit_indices_packed(&octree, &mut indices, &mut offsets)?;
//! # let _ = stats; Ok(()) }
//! ```

pub(crate) mod error;
pub(crate) mod model;
pub(crate) mod select;

pub use error::MAX_OCTREE_LEVELS;
pub use model::{octree_tags, OctreeMeta, OctreeNode, OctreeParts, OctreeRange};
pub use select::Difference;

// At the crate root (what an engine calls every frame); named here for the module's links.
#[cfg(doc)]
use crate::{Octree, OctreeCut};
