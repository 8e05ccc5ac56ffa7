//! How much a camera holds ([`CameraConfig`]) and why one could not be made
//! ([`CameraError`]).

use crate::hierarchy::Hierarchy;

/// How much a camera can hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CameraConfig {
    /// Most splits that may be applied at once. Each adds one active node and one or two
    /// active polygons; the full hierarchy needs `split_count`.
    pub max_pairs: u32,
    /// Entries of the forced-split stack.
    pub stack_len: u32,
    /// Keep each active polygon's vertex indices between frames, so emission copies them
    /// instead of looking every polygon up in the hierarchy (16 bytes per polygon slot; see
    /// the [`CameraState`](crate::CameraState) docs). On in [`full`](Self::full) and
    /// [`with_polygon_budget`](Self::with_polygon_budget).
    pub index_cache: bool,
    /// Keep only the split nodes in the map from split to pair, hashed, where that is smaller
    /// than an array over every splittable node (a budget of fewer than about a sixth of the
    /// hierarchy's splits; see `pair_map`). Off in [`full`](Self::full) and
    /// [`with_polygon_budget`](Self::with_polygon_budget): it saves memory on a budgeted camera
    /// but makes refinement slower, because the array keeps the entries of nearby nodes
    /// together and the table scatters them.
    pub hashed_pair_map: bool,
    /// Most geomorphs at once ([`with_morphs`](Self::with_morphs); see the
    /// [`CameraState`](crate::CameraState) docs): each moves a split's floating child, one or
    /// two vertices, between its parent's position and its own over
    /// [`RefineParams::refine_morph_s`](crate::RefineParams::refine_morph_s) or
    /// [`coarsen_morph_s`](crate::RefineParams::coarsen_morph_s). 72 bytes per morph, and a
    /// bit per vertex of the hierarchy and per pair; 0 in
    /// [`full`](Self::full) and [`with_polygon_budget`](Self::with_polygon_budget), and a
    /// camera without morphs splits and collapses at once.
    pub max_morphs: u32,
}

impl CameraConfig {
    /// Room for every split of `h`: the camera can reach full resolution anywhere.
    pub fn full(h: &Hierarchy<'_>) -> Self {
        Self {
            max_pairs: h.splits().len() as u32,
            stack_len: Self::default_stack(h),
            index_cache: true,
            hashed_pair_map: false,
            max_morphs: 0,
        }
    }

    /// Room for at most `max_active_polygons` active polygons (at least the base mesh).
    pub fn with_polygon_budget(h: &Hierarchy<'_>, max_active_polygons: u32) -> Self {
        // Each split adds at most two polygons.
        let extra = max_active_polygons.saturating_sub(h.base_polygon_count() as u32) / 2;
        Self {
            max_pairs: extra.min(h.splits().len() as u32),
            stack_len: Self::default_stack(h),
            index_cache: true,
            hashed_pair_map: false,
            max_morphs: 0,
        }
    }

    /// This configuration with room for `max_morphs` geomorphs at once: enough for the
    /// splits and collapses of visible nodes the camera makes within one morph's duration.
    /// When the room is taken, a split happens at once
    /// ([`RefineStats::morphs_dropped`](crate::RefineStats::morphs_dropped)).
    pub fn with_morphs(self, max_morphs: u32) -> Self {
        Self { max_morphs, ..self }
    }

    /// A forced split pushes at most a few nodes per level; 32 per level of depth (and at
    /// least 256) has never been exceeded in our tests. Overflow is reported, not fatal.
    pub fn default_stack(h: &Hierarchy<'_>) -> u32 {
        (h.meta().max_depth + 1).saturating_mul(32).max(256)
    }
}

/// Why a camera could not be created.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraError {
    /// The memory given is too small.
    Capacity {
        /// Words needed.
        needed: usize,
        /// Words given.
        given: usize,
    },
    /// The configuration asks for more splits than the hierarchy has.
    TooManyPairs {
        /// Asked for.
        max_pairs: u32,
        /// Splits in the hierarchy.
        split_count: u32,
    },
    /// The configuration asks for more morphs than indices can name: morphed emission
    /// writes `vertex_count + slot`, two slots per morph, which must stay below `u32::MAX`.
    TooManyMorphs {
        /// Asked for.
        max_morphs: u32,
        /// Vertices of the hierarchy.
        vertex_count: u32,
    },
}

impl core::fmt::Display for CameraError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Capacity { needed, given } => {
                write!(
                    f,
                    "camera memory too small: {needed} words needed, {given} given"
                )
            }
            Self::TooManyPairs {
                max_pairs,
                split_count,
            } => {
                write!(
                    f,
                    "max_pairs {max_pairs} exceeds the hierarchy's {split_count} splits"
                )
            }
            Self::TooManyMorphs {
                max_morphs,
                vertex_count,
            } => write!(
                f,
                "max_morphs {max_morphs}: two slots per morph after {vertex_count} vertices \
                 exceed 32-bit indices"
            ),
        }
    }
}

impl core::error::Error for CameraError {}
