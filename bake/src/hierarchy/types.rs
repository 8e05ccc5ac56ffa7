//! What the build takes and gives: the attribute weights, the collapses and the hierarchy,
//! the progress callback and the error; and the constants every step shares.

/// No node, triangle or position.
pub(super) const NONE: u32 = u32::MAX;

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

/// Triangles below which work stays on one thread.
pub(super) const PARALLEL_MIN: usize = 4096;

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
