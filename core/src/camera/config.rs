//! How much a camera holds ([`CameraConfig`]) and why one could not be made
//! ([`CameraError`]).

use crate::hierarchy::HierarchyRecords;

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
    /// Most geomorphs at once ([`with_morphs`](Self::with_morphs), which says how to size
    /// it; see the [`CameraState`](crate::CameraState) docs): each moves a split's floating
    /// child, one or two vertices, between its parent's position and its own over
    /// [`RefineParams::refine_morph_s`](crate::RefineParams::refine_morph_s) or
    /// [`coarsen_morph_s`](crate::RefineParams::coarsen_morph_s). 72 bytes per morph, and a
    /// bit per vertex of the hierarchy and per pair; 0 in
    /// [`full`](Self::full) and [`with_polygon_budget`](Self::with_polygon_budget), and a
    /// camera without morphs splits and collapses at once.
    pub max_morphs: u32,
    /// Entries of the list of index-buffer places that changed since the host last took
    /// the camera's [`index_edits`](crate::CameraState::index_edits); 0 (the default) keeps
    /// no placement. With one, each polygon keeps a place in a device index buffer and the
    /// host writes only the places that changed ([`with_index_edits`](Self::with_index_edits)
    /// says how to size it). Needs the index cache.
    pub edit_list: u32,
}

impl CameraConfig {
    /// Room for every split of `h`: the camera can reach full resolution anywhere.
    pub fn full(h: &impl HierarchyRecords) -> Self {
        Self {
            max_pairs: h.meta().split_count,
            stack_len: Self::default_stack(h),
            index_cache: true,
            hashed_pair_map: false,
            max_morphs: 0,
            edit_list: 0,
        }
    }

    /// Room for at most `max_active_polygons` active polygons (at least the base mesh).
    pub fn with_polygon_budget(h: &impl HierarchyRecords, max_active_polygons: u32) -> Self {
        // Each split adds at most two polygons.
        let extra = max_active_polygons.saturating_sub(h.base_polygon_count() as u32) / 2;
        Self {
            max_pairs: extra.min(h.meta().split_count),
            stack_len: Self::default_stack(h),
            index_cache: true,
            hashed_pair_map: false,
            max_morphs: 0,
            edit_list: 0,
        }
    }

    /// This configuration with room for `max_morphs` geomorphs at once.
    ///
    /// How to size it: a morph starts with each split of a visible node and each wanted
    /// collapse of a visible parent, and lives for its duration
    /// ([`RefineParams::refine_morph_s`](crate::RefineParams::refine_morph_s) or
    /// [`coarsen_morph_s`](crate::RefineParams::coarsen_morph_s); longer under a
    /// [`morph_speed_px_s`](crate::RefineParams::morph_speed_px_s) limit). So the morphs in
    /// progress are about the visible splits and collapses per pass times the passes one
    /// morph lasts (`refine_morph_s / dt_s`, 32 at the defaults): a view that moves fast
    /// over fine detail needs the most. Measure the peak of
    /// [`RefineStats::morphing`](crate::RefineStats::morphing) (or
    /// [`CameraState::morph_count`](crate::CameraState::morph_count)) over a flight like the
    /// application's and leave headroom. A morph belongs to a live split, so a camera never
    /// holds more morphs than `max_pairs`: that many suffices for any flight. Each morph costs
    /// 72 bytes (see [`max_morphs`](Self::max_morphs)).
    ///
    /// When the room is taken, a split or collapse that wanted a morph happens at once, a
    /// pop, counted in
    /// [`RefineStats::morphs_dropped`](crate::RefineStats::morphs_dropped): a count above 0
    /// says the room is too small for the flight.
    pub fn with_morphs(self, max_morphs: u32) -> Self {
        Self { max_morphs, ..self }
    }

    /// This configuration keeping its polygons' places in a device index buffer, with a
    /// list of `list` changed places between two [`index_edits`](crate::CameraState::index_edits).
    ///
    /// How to size it: an operation changes the places of its pair and of the polygons round
    /// the vertex it moves, a morph's start or end those round its vertex, and a frame's list
    /// holds each place once: on a rough terrain about five or six places per operation,
    /// morphs included (`caveclod flyover --index-edits` reports the edits per frame). A list
    /// that fills asks the host to rewrite every place on its next edits (counted in
    /// [`IndexEdits::everything`](crate::IndexEdits::everything)), which is exact but costs
    /// what full emission costs. Each camera keeps 4 bytes per polygon slot, 4 bytes and two
    /// bits per place (a place per slot and surface) and 4 bytes per entry.
    pub fn with_index_edits(self, list: u32) -> Self {
        Self {
            edit_list: list,
            ..self
        }
    }

    /// The default forced-split stack: 32 entries per level of the hierarchy's depth, at
    /// least 256. A forced split pushes, for each node it cannot split yet, that node's
    /// parent or the creators of its missing neighbours (at most four), so the stack grows
    /// with the depth of the chain of splits it forces; an overflow abandons that one wanted
    /// split ([`RefineStats::stack_overflows`](crate::RefineStats::stack_overflows)), it
    /// is not an error.
    pub fn default_stack(h: &impl HierarchyRecords) -> u32 {
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
    /// Index edits asked for without the index cache they read, or with more places
    /// (polygon slots × surfaces) than 32-bit indices can address three at a time.
    IndexEdits {
        /// Places the configuration needs.
        places: u64,
        /// Whether the index cache is on.
        index_cache: bool,
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
            Self::IndexEdits {
                places,
                index_cache,
            } => {
                if *index_cache {
                    write!(
                        f,
                        "index edits: {places} places exceed 32-bit index offsets"
                    )
                } else {
                    write!(f, "index edits need the index cache")
                }
            }
        }
    }
}

impl core::error::Error for CameraError {}
