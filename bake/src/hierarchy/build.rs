//! The build's steps in order: set up the work, collapse in passes, hand over the hierarchy.

use super::pass::{collapse_all, SEGMENT};
use super::setup::work;
use super::types::{AttributeWeights, BuildError, Hierarchy, Progress};
use crate::weld::Welded;

/// Parts the parallel steps split their work into at most (rayon tasks).
const MAX_THREADS: usize = 8;

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
    let mut work = work(w, weights, frozen, threads);
    collapse_all(&mut work, (threads, SEGMENT), stop_at, progress)?;
    Ok(work.into_hierarchy())
}
