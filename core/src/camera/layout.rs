//! Where a camera's arrays lie in its words, and the state besides them: what it takes to
//! view the same words as the same camera again.

use super::certificate::Odometer;
use super::compact_progress::Progress;
use super::config::CameraConfig;
use super::morph_map::MorphMap;
use super::morph_pool;
use super::morph_pool::{MorphScalars, Morphs};
use super::pair_map::PairMap;
use super::placement;
use super::placement::{Placement, PlacementScalars};
use super::records::{ACTIVE_WORDS, NONE, SLOT_WORDS, TRIANGLE_WORDS};
use super::state::{CameraState, Front};
use crate::hierarchy::HierarchyRecords;

/// Where a camera's arrays lie in its words: the hierarchy's counts the arrays are sized by,
/// and the configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Layout {
    splits: usize,
    vertices: usize,
    roots: usize,
    base: usize,
    surfaces: usize,
    config: CameraConfig,
}

impl Layout {
    /// Over sparse ids (a paged file's), a camera keeps no per-id arrays: the pair map is
    /// hashed and the morph map keeps no bit per vertex, so its memory follows its capacity.
    pub(crate) fn of(h: &impl HierarchyRecords, config: &CameraConfig) -> Self {
        let dense = h.dense_ids();
        let mut config = *config;
        config.hashed_pair_map |= !dense;
        Self {
            splits: h.split_id_bound(),
            vertices: if dense { h.vertex_id_bound() } else { 0 },
            roots: h.roots().len(),
            base: h.base_polygon_count(),
            surfaces: h.surface_count(),
            config,
        }
    }

    /// Polygon slots: the base polygons and two per pair.
    fn slots(&self) -> usize {
        self.base
            .saturating_add((self.config.max_pairs as usize).saturating_mul(2))
    }

    /// Words of each array, in the order they lie in memory.
    fn array_words(&self) -> [usize; 19] {
        let c = &self.config;
        let mp = c.max_pairs as usize;
        let triangles = if c.index_cache {
            self.slots().saturating_mul(TRIANGLE_WORDS)
        } else {
            0
        };
        let [morph_vertices, morph_states, morph_map, coarsening, morph_free] =
            morph_pool::words(c.max_morphs as usize, self.vertices, mp);
        let [place, slot_of, free, marked, list, regions] =
            placement::words(self.slots(), self.surfaces, c.edit_list as usize);
        [
            PairMap::words(self.splits, mp, c.hashed_pair_map),
            mp,
            self.roots.saturating_add(mp).saturating_mul(ACTIVE_WORDS),
            self.slots().saturating_mul(SLOT_WORDS),
            self.surfaces,
            mp.div_ceil(32),
            triangles,
            c.stack_len as usize,
            morph_vertices,
            morph_states,
            morph_map,
            coarsening,
            morph_free,
            place,
            slot_of,
            free,
            marked,
            list,
            regions,
        ]
    }

    /// Words of memory in all.
    pub(crate) fn words(&self) -> usize {
        self.array_words()
            .iter()
            .fold(0usize, |a, &b| a.saturating_add(b))
    }
}

/// A camera's state besides its arrays: what must be kept to view the same words again.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Scalars {
    hierarchy: u64,
    base: u32,
    pairs: u32,
    active_len: u32,
    free_head: u32,
    active_nodes: u32,
    active_polygons: u32,
    churn: u32,
    odometer: Odometer,
    morphs: MorphScalars,
    visit_cursor: u32,
    compaction: Progress,
    refined: bool,
    placement: PlacementScalars,
}

impl Scalars {
    /// Before the first [`reset`](CameraState::reset).
    pub(crate) fn initial(h: &impl HierarchyRecords) -> Self {
        Self {
            hierarchy: h.checksum(),
            base: h.base_polygon_count() as u32,
            pairs: 0,
            active_len: 0,
            free_head: NONE,
            active_nodes: 0,
            active_polygons: 0,
            churn: 0,
            odometer: Odometer::new(),
            morphs: MorphScalars::EMPTY,
            visit_cursor: 0,
            compaction: Progress::IDLE,
            refined: false,
            placement: PlacementScalars::default(),
        }
    }
}

impl<'m> CameraState<'m> {
    /// The camera whose arrays lie in `memory` as `layout` places them (`memory` holds at
    /// least `layout.words()` words) and whose other state is `scalars`. Nothing is written:
    /// the words are the camera's as they were when `scalars` was taken, or are reset next.
    pub(crate) fn carve(memory: &'m mut [u32], layout: &Layout, scalars: Scalars) -> Self {
        let [pair_words, owner_words, active_words, slot_words, surfaces, refused_len, triangle_words, stack_len, morph_vertex_words, morph_state_words, morph_map_words, coarsening_words, free_words, place_words, slot_of_words, hole_words, marked_words, list_words, region_words] =
            layout.array_words();
        let c = &layout.config;
        let (pair_of, rest) = memory.split_at_mut(pair_words);
        let (owner, rest) = rest.split_at_mut(owner_words);
        let (active, rest) = rest.split_at_mut(active_words);
        let (slots, rest) = rest.split_at_mut(slot_words);
        let (surface_polygons, rest) = rest.split_at_mut(surfaces);
        let (refused, rest) = rest.split_at_mut(refused_len);
        let (triangles, rest) = rest.split_at_mut(triangle_words);
        let (stack, rest) = rest.split_at_mut(stack_len);
        let (morph_vertices, rest) = rest.split_at_mut(morph_vertex_words);
        let (morph_states, rest) = rest.split_at_mut(morph_state_words);
        let (morph_map, rest) = rest.split_at_mut(morph_map_words);
        let (coarsening, rest) = rest.split_at_mut(coarsening_words);
        let (morph_free, rest) = rest.split_at_mut(free_words);
        let (place, rest) = rest.split_at_mut(place_words);
        let (slot_of, rest) = rest.split_at_mut(slot_of_words);
        let (holes, rest) = rest.split_at_mut(hole_words);
        let (marked, rest) = rest.split_at_mut(marked_words);
        let (list, rest) = rest.split_at_mut(list_words);
        let (regions, _) = rest.split_at_mut(region_words);
        let mp = c.max_pairs as usize;
        Self {
            front: Front {
                hierarchy: scalars.hierarchy,
                base: scalars.base,
                pair_of: PairMap::new(pair_of, layout.splits, mp, c.hashed_pair_map),
                owner: bytemuck::cast_slice_mut(owner),
                active: bytemuck::cast_slice_mut(active),
                slots: bytemuck::cast_slice_mut(slots),
                surface_polygons,
                refused,
                triangles: bytemuck::cast_slice_mut(triangles),
                pairs: scalars.pairs,
                active_len: scalars.active_len,
                free_head: scalars.free_head,
                active_nodes: scalars.active_nodes,
                active_polygons: scalars.active_polygons,
                churn: scalars.churn,
                odometer: scalars.odometer,
                morphs: Morphs {
                    vertices: bytemuck::cast_slice_mut(morph_vertices),
                    states: bytemuck::cast_slice_mut(morph_states),
                    map: MorphMap::new(morph_map, c.max_morphs as usize, layout.vertices),
                    coarsening,
                    free: morph_free,
                    scalars: scalars.morphs,
                },
                visit_cursor: scalars.visit_cursor,
                refined: scalars.refined,
                compaction: scalars.compaction,
                placement: Placement {
                    place,
                    slot_of,
                    free: holes,
                    marked,
                    list,
                    regions: bytemuck::cast_slice_mut(regions),
                    scalars: scalars.placement,
                },
            },
            stack: bytemuck::cast_slice_mut(stack),
        }
    }

    /// The state besides the arrays, to [`carve`](Self::carve) the same camera again.
    #[cfg(feature = "alloc")]
    pub(crate) fn scalars(&self) -> Scalars {
        let f = &self.front;
        Scalars {
            hierarchy: f.hierarchy,
            base: f.base,
            pairs: f.pairs,
            active_len: f.active_len,
            free_head: f.free_head,
            active_nodes: f.active_nodes,
            active_polygons: f.active_polygons,
            churn: f.churn,
            odometer: f.odometer,
            morphs: f.morphs.scalars,
            visit_cursor: f.visit_cursor,
            refined: f.refined,
            compaction: f.compaction,
            placement: f.placement.scalars,
        }
    }
}
