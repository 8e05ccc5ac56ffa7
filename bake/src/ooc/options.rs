//! How an out-of-core run is set up ([`OocOptions`]), and the progress it reports
//! ([`OocStage`]).

use std::path::PathBuf;

use super::cluster::Weights;
use super::multires::MultiresOptions;

/// Settings of an out-of-core run.
#[derive(Clone, Debug, PartialEq)]
pub struct OocOptions {
    /// Bytes the whole bake may use (approximately: the chunks, caches and output are sized
    /// from it).
    pub memory_budget: u64,
    /// Where to make the temporary directory (the system's temporary directory if `None`).
    pub temp_dir: Option<PathBuf>,
    /// Most bytes of temporary files (unlimited if `None`): a full disk on demand.
    pub temp_quota: Option<u64>,
    /// Most triangles in an octree leaf (below the maximum depth).
    pub leaf_triangles: u64,
    /// Maximum octree depth (at most 21).
    pub max_depth: u32,
    /// Output triangles to aim for (from the budget if `None`).
    pub target_triangles: Option<u64>,
    /// Attribute weights of the quadrics.
    pub weights: Weights,
    /// Clustering threads.
    pub threads: usize,
    /// Build the multiresolution octree ([`super::multires`]) with these settings, or not.
    pub octree: Option<MultiresOptions>,
}

impl OocOptions {
    /// Defaults for a budget.
    pub fn with_budget(memory_budget: u64) -> Self {
        Self {
            memory_budget,
            temp_dir: None,
            temp_quota: None,
            leaf_triangles: 1 << 16,
            max_depth: 12,
            target_triangles: None,
            weights: Weights::default(),
            threads: std::thread::available_parallelism().map_or(1, |n| n.get().min(8)),
            octree: Some(MultiresOptions::default()),
        }
    }
}

/// Progress of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OocStage {
    /// Reading the input: triangles `(done, expected)`.
    Read(u64, u64),
    /// Merging sorted runs: `(done, total)`.
    Merge(u64, u64),
    /// Clustering at a grid resolution: triangles `(resolution, done, total)`.
    Cluster(u32, u64, u64),
}
