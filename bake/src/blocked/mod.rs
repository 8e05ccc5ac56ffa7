//! Building the vertex hierarchy of a mesh in blocks, level by level (Hoppe's construction
//! for terrains too large for one build).
//!
//! References:
//! - Hugues Hoppe. Smooth view-dependent level-of-detail control and its application to
//!   terrain rendering. 1998 (blocks simplified with their borders frozen, then merged with
//!   their neighbours and simplified across the old borders, level by level)
//!
//! The steps ([`build_spilled`]):
//! 1. the blocks of the first level: square tiles over the mesh's two widest axes, a
//!    triangle in the tile of its centroid, as many tiles as keep a block near
//!    [`BlockedOptions::block_triangles`]. The welded mesh is on disk in the tiles' Z order
//!    ([`crate::weld::store`], which cuts the tiles), so every block of every level is one
//!    range of triangles;
//! 2. each block of a level becomes a mesh of its own (`block`, read from the store) whose
//!    positions shared with another block are frozen, and is built on its own
//!    ([`crate::hierarchy::build_frozen`]): every collapse the rules allow that removes no
//!    frozen position, down to a quarter of its triangles on every level but the last
//!    (`LEVEL_SHARE`). The blocks are independent jobs; here as many run at once as there
//!    are threads;
//! 3. each block's collapses join the whole hierarchy (`stitch`), renamed to the whole
//!    mesh's nodes and triangles, each appended to a temporary file as it joins (`spill`):
//!    the whole keeps in memory only what the next collapses read;
//! 4. the tiles merge two by two on each axis (four consecutive tiles of the Z order), and
//!    the next level builds the merged blocks from what the last one left, their old borders
//!    no longer frozen; the level of a single block, nothing frozen, ends it, as the in-core
//!    build ends.
//!
//! The whole hierarchy has the in-core build's conventions: half-edge collapses, nodes
//! `0..positions` the leaves, collapse `c` creating node `positions + c`, so, read back into
//! memory ([`build`]), [`crate::baked::Baked::new`] turns it into a `.clod` as it does an
//! in-core build; [`crate::pipeline::SpilledBuild::write`] writes it from the temporary
//! file and the store (`write`). A node's bounds hold everything below it across the
//! levels: its radius holds its children's spheres, its cone their cones, and its error adds
//! the block's own measure (the distance of the level's positions from the triangles that
//! replace them) to the largest error of the nodes the level started from below it.

mod block;
mod error;
mod renumber;
mod replay;
mod spill;
mod stitch;
mod store_arrays;
pub(crate) mod write;

pub use error::BlockedError;
pub use spill::Spilled;

use std::ops::Range;

use rayon::prelude::*;

use crate::base::memory::release_freed;
use crate::hierarchy::{build_frozen, AttributeWeights, Hierarchy};
use crate::weld::store::WeldedStore;
use crate::weld::Welded;

/// Share of a block's triangles a level leaves (all but the last, which collapses all it
/// can): four blocks merged into one of the next level hold about as many triangles as one
/// of this level, and no block is simplified into the long thin fans a frozen border leaves
/// around the few positions that remain inside it, which the collapses across the old
/// border could then hardly undo.
const LEVEL_SHARE: f64 = 0.25;

/// How the blocks are cut.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BlockedOptions {
    /// Triangles a first-level block holds about (at most on average): the tiles per axis
    /// are the smallest power of two that keeps the blocks this small.
    pub block_triangles: usize,
}

impl BlockedOptions {
    /// Blocks whose in-core build fits `budget` bytes with `jobs` of them built at once,
    /// at `bytes_per_triangle` of the build's peak per triangle.
    pub fn for_budget(budget: u64, jobs: usize, bytes_per_triangle: u64) -> Self {
        let per_job = budget / jobs.max(1) as u64;
        Self {
            block_triangles: (per_job / bytes_per_triangle.max(1)).max(1024) as usize,
        }
    }
}

/// What one level did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LevelStats {
    /// Blocks built.
    pub blocks: usize,
    /// Triangles of the largest block.
    pub largest_block: usize,
    /// Triangles alive at the level's start.
    pub triangles: usize,
    /// Collapses the level applied.
    pub collapses: usize,
}

/// The whole hierarchy and the levels that built it.
#[derive(Clone, Debug)]
pub struct Blocked {
    /// The hierarchy, as [`crate::hierarchy::build`] would hand it over, read back from the
    /// spill file ([`Spilled::into_hierarchy`]: the leaves carry no bounds).
    pub hierarchy: Hierarchy,
    /// Per level, from the first.
    pub levels: Vec<LevelStats>,
}

/// [`build_spilled`] of `w` stored in block order ([`WeldedStore::from_welded`]), the
/// hierarchy read back into memory and named by `w`'s positions and triangles.
pub fn build(
    w: &Welded,
    weights: &AttributeWeights,
    options: &BlockedOptions,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<Blocked, BlockedError> {
    let store =
        WeldedStore::from_welded(w.clone(), options.block_triangles, true).map_err(store_error)?;
    let (spilled, levels) = build_spilled(&store, weights, progress)?;
    let hierarchy = spilled
        .into_hierarchy()
        .map_err(|e| BlockedError::Spill(e.to_string()))?;
    let hierarchy = match store.origins() {
        Some(origins) => renumber::to_origins(hierarchy, origins),
        None => hierarchy,
    };
    Ok(Blocked { hierarchy, levels })
}

/// Builds the hierarchy of the welded mesh in `store` in blocks (the store's first-level
/// tiles, merged two by two per level), its collapses on disk, and the levels that built it;
/// `progress` gets `(collapses so far, at most collapsible)` after each level. The ids are
/// the store's.
pub fn build_spilled(
    store: &WeldedStore,
    weights: &AttributeWeights,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<(Spilled, Vec<LevelStats>), BlockedError> {
    // What made the store (a weld, its tables) is freed by now.
    release_freed();
    let spill_error = |e: std::io::Error| BlockedError::Spill(e.to_string());
    let np = store.positions();
    let most = np.saturating_sub(1) as u64;
    let mut whole =
        stitch::Whole::new(np, corners_of(store).map_err(store_error)?).map_err(spill_error)?;
    let mut levels = Vec::new();
    let top = store.side().trailing_zeros();
    for level in 0..=top {
        let blocks: Vec<Range<u32>> = (0..store.blocks(level))
            .map(|code| store.block(level, code))
            .filter(|r| live(r, &whole.alive).next().is_some())
            .collect();
        let sizes: Vec<usize> = blocks
            .iter()
            .map(|r| live(r, &whole.alive).count())
            .collect();
        let frozen = shared_positions(&blocks, &whole.alive, &whole.corners, np);
        let mut stats = LevelStats {
            blocks: blocks.len(),
            largest_block: sizes.iter().copied().max().unwrap_or(0),
            triangles: sizes.iter().sum(),
            collapses: whole.collapses(),
        };
        for b in &blocks {
            let tris: Vec<u32> = live(b, &whole.alive).collect();
            whole.add_border(&tris, &frozen);
        }
        // As many blocks at once as there are threads, stitched in block order before the
        // next ones are built: a level holds only the builds in flight, not all its blocks'.
        let mut passes = 0;
        let keep = if level == top {
            stitch::Keep::All
        } else {
            stitch::Keep::Share(LEVEL_SHARE)
        };
        for chunk in blocks.chunks(rayon::current_num_threads().max(1)) {
            let built: Vec<Result<(block::Block, Hierarchy), BlockedError>> = chunk
                .par_iter()
                .map(|range| {
                    let tris: Vec<u32> = live(range, &whole.alive).collect();
                    let b = block::extract(store, &whole.corners, tris, &frozen)
                        .map_err(store_error)?;
                    // The level keeps only the collapses down to its share; the passes
                    // after it would be thrown away.
                    let stop_at = match keep {
                        stitch::Keep::All => 0,
                        stitch::Keep::Share(share) => (b.tris.len() as f64 * share) as usize,
                    };
                    let h = build_frozen(&b.welded, weights, &b.frozen, stop_at, &mut |_, _| {})?;
                    Ok((b, h))
                })
                .collect();
            for result in built {
                let (b, h) = result?;
                passes = passes.max(h.passes);
                whole.stitch(&b, &h, &frozen, levels.is_empty(), keep)?;
            }
        }
        whole.clear_border();
        whole.passes += passes;
        stats.collapses = whole.collapses() - stats.collapses;
        levels.push(stats);
        release_freed();
        progress(whole.collapses() as u64, most);
    }
    Ok((whole.finish().map_err(spill_error)?, levels))
}

/// A failed read or write of the welded store.
fn store_error(e: std::io::Error) -> BlockedError {
    BlockedError::Store(e.to_string())
}

/// The corners (positions) of every triangle of `store`, read a chunk at a time.
fn corners_of(store: &WeldedStore) -> std::io::Result<Vec<[u32; 3]>> {
    const CHUNK: u32 = 1 << 16;
    let nt = store.triangles() as u32;
    let mut corners = Vec::with_capacity(nt as usize);
    for start in (0..nt).step_by(CHUNK as usize) {
        let tris = store.read_triangles(start..nt.min(start + CHUNK))?;
        corners.extend(tris.iter().map(|t| t.p));
    }
    Ok(corners)
}

/// The live triangles of `range`.
fn live<'a>(range: &Range<u32>, alive: &'a [bool]) -> impl Iterator<Item = u32> + 'a {
    range.clone().filter(move |&f| alive[f as usize])
}

/// Per position: whether live triangles of more than one block touch it (`corners`: the
/// positions of each triangle's corners).
fn shared_positions(
    blocks: &[Range<u32>],
    alive: &[bool],
    corners: &[[u32; 3]],
    positions: usize,
) -> Vec<bool> {
    const UNSEEN: u32 = u32::MAX;
    let mut owner = vec![UNSEEN; positions];
    let mut shared = vec![false; positions];
    for (i, b) in blocks.iter().enumerate() {
        for f in live(b, alive) {
            for x in corners[f as usize] {
                let x = x as usize;
                if owner[x] == UNSEEN {
                    owner[x] = i as u32;
                } else if owner[x] != i as u32 {
                    shared[x] = true;
                }
            }
        }
    }
    shared
}
