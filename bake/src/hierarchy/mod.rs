//! Building the vertex hierarchy by half-edge collapses.
//!
//! References:
//! - Hugues Hoppe. View-dependent refinement of progressive meshes. 1997 (the collapses,
//!   their neighbours `fl_clw`/`fr_ccw`, and the residual error bounds)
//! - Hugues Hoppe. New quadric metric for simplifying meshes with appearance attributes.
//!   1999 (the costs, [`crate::quadric`])
//! - Michael Garland, Paul Heckbert. Surface simplification using quadric error metrics.
//!   1997 (boundary planes)
//! - Tamal Dey, Herbert Edelsbrunner, Sumanta Guha, Dmitry Nekhayev. Topology preserving
//!   edge contraction. 1999 (the link condition)
//! - Christer Ericson. Real-Time Collision Detection. 2005 (the point–triangle distance)
//!
//! The build is a sequence of steps ([`build`]):
//! 1. set up the work (`setup`): positions centred on their bounding box, a wedge per
//!    surface group at each position with the quadrics of its triangles and boundary
//!    planes, the triangles with their neighbours, the leaves' bounds;
//! 2. collapse in passes (`pass`) until one finds nothing to apply (after one that stopped
//!    at its share, a full pass, which cuts nothing, must find nothing): rank every edge
//!    (`rank`), check the collapses the pass reaches (`legality`), apply them
//!    (`collapse`), then hand the moved input points to their nearest triangles
//!    (`bounds`);
//! 3. hand over the hierarchy.
//!
//! - **Half-edge collapses** only: the parent keeps the stationary child's position, so no
//!   vertex is ever created and the vertex buffer is the full-resolution one.
//! - **Batches of independent collapses** (as g-mesh builds its levels): each pass sorts the
//!   legal collapses by cost and applies those whose neighbourhoods do not overlap, so the
//!   hierarchy is balanced and shallow (depth grows with the logarithm of the size). A pass
//!   goes only through the cheapest half of its ranked collapses (`PASS_SHARE`): applying
//!   every independent one lets dear collapses take neighbourhoods that cheaper ones of the
//!   next pass would have used; the cut costs passes, not depth.
//! - **Cost**: the attribute-aware quadric of the removed position's wedges (one per surface
//!   group there) evaluated at the kept position with that group's attributes there
//!   ([`crate::quadric`]), plus boundary planes that hold mesh borders and surface-group
//!   boundaries in place, weighted more than a triangle's (sliding borders would be the
//!   largest errors on terrain). A normal that follows from the geometry
//!   ([`crate::weld::Attributes::normal_from_geometry`]: computed, or an importer's smooth
//!   one) gets no weight: it would only make curved regions dearer, which the distance
//!   term already does, at the expense of geometric accuracy.
//! - **Legality**: the surface-group rules (a RIGID or frozen position never floats; a SHARP one floats
//!   only along a boundary edge onto a non-FREE position; every group at the removed position
//!   must have a vertex at the kept one), the link condition, no doubled faces, no face
//!   flipped or collapsed, and Hoppe's requirement that `fl_clw` (and `fr_ccw` when `f_r`
//!   exists) are present.
//! - **Bounds for refinement**: the bounding-sphere radius and normal cone of everything
//!   below a node, and its error (`uni_error`) from the residuals of the input, as Hoppe's
//!   view-dependent progressive meshes measure it: every input position belongs to a
//!   current triangle near it; a collapse hands the positions of the removed node's
//!   triangles to the nearest of the triangles that replace them, and the node's error is
//!   the largest of those distances and its children's errors. It measures what a cut
//!   through the node loses, including borders that slide, where the planes' distances
//!   alone miss it. The points see one direction only, so the error is also raised to how
//!   far the collapse moved the surface (`surface`): the largest distance from the moved
//!   triangles' centroids and edge midpoints to the surface just before it, which catches a
//!   triangle laid across a gap or a fold that no input point lies near. Both run on the
//!   other threads while the pass applies its next collapses (a pass's last ones while the
//!   next pass ranks its edges): the collapses of a pass have disjoint stars, which no
//!   later collapse of the pass changes, so what they read is taken from each run of
//!   applied collapses (`handover`) and the settling never reads the mesh the pass is
//!   changing.
//!
//! A pass is built for speed without changing its outcome: every edge is ranked by the cost
//! of its cheaper allowed direction (a ranking stands while the edge's ends are the same
//! nodes, and ranking runs on all threads), and the legality checks run only for the
//! collapses the pass reaches with both ends free, as they stood at the start of the pass.
//! The result is the same as checking every edge first and sorting the legal collapses
//! stably by cost. The threads never change the result: sums are added in a fixed order.

mod bounds;
mod build;
mod collapse;
mod geometry;
mod handover;
mod legality;
mod pass;
mod prefetch;
mod rank;
mod records;
mod setup;
mod stars;
mod surface;
#[cfg(test)]
mod tests;
mod types;
mod work;

pub use build::{build, build_frozen};
pub(crate) use geometry::merge_cones;
pub use types::{AttributeWeights, BuildError, BuildStage, Collapse, Hierarchy, Progress};
