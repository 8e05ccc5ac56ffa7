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
mod collapse;
mod geometry;
pub(crate) use geometry::merge_cones;
mod handover;
mod legality;
mod pass;
mod prefetch;
mod rank;
mod setup;
mod stars;
mod surface;
#[cfg(test)]
mod tests;
mod work;

use crate::weld::Welded;

const NONE: u32 = u32::MAX;

/// Weights of the attribute kinds, relative to the mesh's bounding-box diagonal: an
/// attribute difference of 1 costs as much as a distance of `weight × diagonal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AttributeWeights {
    /// Unit normals.
    pub normal: f64,
    /// Texture coordinates.
    pub uv: f64,
    /// Colours (0..1 per channel).
    pub color: f64,
}

impl Default for AttributeWeights {
    fn default() -> Self {
        Self {
            normal: 0.01,
            uv: 0.02,
            color: 0.01,
        }
    }
}

/// One collapse, as its split will replay it.
#[derive(Clone, Copy, Debug)]
pub struct Collapse {
    /// The stationary child (kept).
    pub t: u32,
    /// The floating child (removed).
    pub u: u32,
    /// Triangle left of the edge `t→u` (dies).
    pub fl: u32,
    /// Triangle right of it, or `NONE` on a border (dies).
    pub fr: u32,
    /// `[fl_ccw, fl_clw, fr_clw, fr_ccw]`, triangle ids or `NONE`.
    pub neighbours: [u32; 4],
    /// Corner of `fl` holding `t` (the polygon's rotation).
    pub rot_l: u8,
    /// Corner of `fr` holding `t`.
    pub rot_r: u8,
}

/// The result: nodes `0..positions` are the leaves; collapse `c` creates node
/// `positions + c`.
#[derive(Clone, Debug, Default)]
pub struct Hierarchy {
    /// Collapses in the order applied.
    pub collapses: Vec<Collapse>,
    /// Parent of every node, `NONE` for roots.
    pub parent: Vec<u32>,
    /// Position of every node.
    pub node_position: Vec<u32>,
    /// Radius of the sphere around the node's position bounding its descendants' triangles.
    pub radius: Vec<f32>,
    /// Normal cone `(axis, half angle)` of every node.
    pub cone: Vec<([f32; 3], f32)>,
    /// Error bound of every node (world units; zero for leaves).
    pub error: Vec<f32>,
    /// Current corners of every triangle at the end (the base mesh's for those alive).
    pub corners: Vec<[u32; 3]>,
    /// Which triangles are in the base mesh.
    pub alive: Vec<bool>,
    /// Number of batches (passes).
    pub passes: u32,
}

/// Progress of a build: `(collapses so far, at most collapsible)`.
pub type Progress<'a> = &'a mut dyn FnMut(u64, u64);

/// Share of a pass's ranked collapses it may apply: the cheapest half. Applying every
/// independent collapse lets an expensive one take a neighbourhood that a cheaper one of
/// the next pass would have used; the cut costs passes, not depth to speak of.
const PASS_SHARE: f64 = 0.5;

/// Parts the parallel steps split their work into at most (rayon tasks).
const MAX_THREADS: usize = 8;

/// Triangles below which work stays on one thread.
const PARALLEL_MIN: usize = 4096;

/// The step of a build in which an invariant broke.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuildStage {
    /// The sequence of passes: one that applies nothing ends it, every other removes a node.
    Passes,
    /// A full pass (after one that applied nothing of its share): it goes through every
    /// ranked collapse.
    FullPass,
    /// One pass's collapses: each ranked one is tried once, with at most one other direction.
    Pass,
}

impl std::fmt::Display for BuildStage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Passes => "the collapse passes",
            Self::FullPass => "a full collapse pass",
            Self::Pass => "a collapse pass",
        })
    }
}

/// A build that broke an invariant its termination rests on (a baker bug): it stops with
/// this error instead of looping.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "internal error: the hierarchy build broke an invariant in {stage} (pass {pass}, \
     {collapses} of at most {most} collapses): {invariant}"
)]
pub struct BuildError {
    /// Where.
    pub stage: BuildStage,
    /// The pass (from 1).
    pub pass: u32,
    /// Collapses applied so far.
    pub collapses: u64,
    /// Collapses the mesh allows at most (its positions less one).
    pub most: u64,
    /// The invariant that broke.
    pub invariant: &'static str,
}

/// Builds the hierarchy of a welded mesh.
pub fn build(
    w: &Welded,
    weights: &AttributeWeights,
    progress: Progress<'_>,
) -> Result<Hierarchy, BuildError> {
    build_frozen(w, weights, &[], 0, progress)
}

/// Builds the hierarchy of a welded mesh whose positions `frozen[x]` (absent: not frozen)
/// stay where they are: a frozen position is never the one a collapse removes, as if it were
/// RIGID, but others may collapse onto it. A block of a larger mesh is built this way with its
/// border frozen ([`crate::blocked`]), so that the blocks around it still fit. The passes end
/// early after the first that leaves `stop_at` triangles or fewer (0: they go on until none
/// applies anything); the collapses until then are those a full build begins with.
pub fn build_frozen(
    w: &Welded,
    weights: &AttributeWeights,
    frozen: &[bool],
    stop_at: usize,
    progress: Progress<'_>,
) -> Result<Hierarchy, BuildError> {
    let threads = rayon::current_num_threads().min(MAX_THREADS);
    let mut work = setup::work(w, weights, frozen, threads);
    pass::collapse_all(&mut work, (threads, pass::SEGMENT), stop_at, progress)?;
    Ok(work.into_hierarchy())
}
