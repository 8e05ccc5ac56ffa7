//! Making a camera and putting it back at the base mesh: sizing its memory, carving it,
//! and [`CameraState::reset`].

use super::compact_progress::Progress;
use super::config::{CameraConfig, CameraError};
use super::layout::{Layout, Scalars};
use super::records::{ActiveVertex, PolySlot, FREE, NONE, UNKNOWN};
use super::state::CameraState;
use crate::hierarchy::HierarchyRecords;
use crate::ids::NodeId;

impl<'m> CameraState<'m> {
    /// Words of memory a camera needs for full resolution anywhere ([`CameraConfig::full`]).
    pub fn words_needed(h: &impl HierarchyRecords) -> usize {
        Layout::of(h, &CameraConfig::full(h)).words()
    }

    /// Words of memory a camera with `config` needs.
    pub fn words_needed_for(h: &impl HierarchyRecords, config: &CameraConfig) -> usize {
        Layout::of(h, config).words()
    }

    /// A camera at the base mesh, able to reach full resolution, in `memory`
    /// (at least [`words_needed`](Self::words_needed) words; extra words are left unused).
    pub fn new(h: &impl HierarchyRecords, memory: &'m mut [u32]) -> Result<Self, CameraError> {
        Self::with_config(h, memory, &CameraConfig::full(h))
    }

    /// A camera at the base mesh with the given capacity.
    pub fn with_config(
        h: &impl HierarchyRecords,
        memory: &'m mut [u32],
        config: &CameraConfig,
    ) -> Result<Self, CameraError> {
        let layout = Self::checked_layout(h, config)?;
        let needed = layout.words();
        if memory.len() < needed {
            return Err(CameraError::Capacity {
                needed,
                given: memory.len(),
            });
        }
        let mut cam = Self::carve(memory, &layout, Scalars::initial(h));
        cam.reset(h);
        Ok(cam)
    }

    /// The layout of a camera with `config` over `h`, if the hierarchy has the splits.
    pub(crate) fn checked_layout(
        h: &impl HierarchyRecords,
        config: &CameraConfig,
    ) -> Result<Layout, CameraError> {
        let ns = h.meta().split_count as usize;
        if config.max_pairs as usize > ns {
            return Err(CameraError::TooManyPairs {
                max_pairs: config.max_pairs,
                split_count: ns as u32,
            });
        }
        if config.edit_list > 0 {
            let slots = h.base_polygon_count() as u64 + 2 * u64::from(config.max_pairs);
            let places = slots * h.surface_count() as u64;
            if !config.index_cache || 3 * places >= u64::from(NONE) {
                return Err(CameraError::IndexEdits {
                    places,
                    index_cache: config.index_cache,
                });
            }
        }
        let slots = 2 * u64::from(config.max_morphs);
        if h.vertex_id_bound() as u64 + slots >= u64::from(NONE) {
            return Err(CameraError::TooManyMorphs {
                max_morphs: config.max_morphs,
                vertex_count: h.vertex_id_bound() as u32,
            });
        }
        Ok(Layout::of(h, config))
    }

    /// Back to the base mesh.
    pub fn reset(&mut self, h: &impl HierarchyRecords) {
        let f = &mut self.front;
        // The front leaves every node it stood on (a camera just made stands on none).
        let live = (f.active_len as usize).min(f.active.len());
        for a in &f.active[..live] {
            if a.node & FREE == 0 {
                h.node_left_front(NodeId(a.node));
            }
        }
        f.pair_of.clear();
        f.pairs = 0;
        f.free_head = NONE;
        f.surface_polygons.fill(0);
        f.refused.fill(0);
        // Active-vertex record `i` of the base mesh is root `i`.
        for (i, r) in h.roots().iter().enumerate() {
            h.node_entered_front(*r);
            f.active[i] = ActiveVertex {
                node: r.0,
                coarsen: NONE,
                own_cert: UNKNOWN,
                parent_cert: UNKNOWN,
            };
        }
        f.active_len = h.roots().len() as u32;
        f.active_nodes = f.active_len;
        for (i, b) in h.base().iter().enumerate() {
            let mut corners = [NONE; 3];
            for (k, c) in b.corners.iter().enumerate() {
                // Validated at load: every corner is a root; roots are sorted.
                corners[k] = h.roots().binary_search(c).map_or(NONE, |x| x as u32);
            }
            f.slots[i] = PolySlot {
                corners,
                neighbours: b.neighbours.map(|n| n.0),
            };
            let s = h
                .polygon(crate::ids::PolyId(i as u32))
                .map_or(0, |p| p.surface.index());
            f.surface_polygons[s] += 1;
        }
        f.active_polygons = f.base;
        f.churn = 0;
        f.visit_cursor = 0;
        f.refined = false;
        f.compaction = Progress::IDLE;
        f.morphs.clear();
        f.cache_slots(h, 0, f.base as usize);
        f.place_base_slots();
    }
}
