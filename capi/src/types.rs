//! The plain structs of the C interface: a view, refinement parameters and statistics,
//! a camera configuration, and the counts of a hierarchy and of a camera.

use caveclod_core::glam::Vec3;
use caveclod_core::{CameraConfig, HierarchyRecords, LookAt, RefineParams, RefineStats, View};

use crate::ffi::Result;
use crate::status::CaveclodStatus;

/// A perspective camera as refinement and the GPU see it: right-handed, y up (as `up`
/// says), Vulkan clip space for the matching projection.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CaveclodView {
    /// Eye point, world space.
    pub eye: [f32; 3],
    /// Point looked at; must differ from `eye`.
    pub target: [f32; 3],
    /// Up direction; must not be parallel to `target - eye`.
    pub up: [f32; 3],
    /// Vertical field of view in radians, in (0, π).
    pub fov_y: f32,
    /// Viewport width / height, positive.
    pub aspect: f32,
    /// Near clip distance, positive.
    pub near: f32,
    /// Far clip distance, beyond `near`.
    pub far: f32,
    /// Viewport height in pixels (the scale of the pixel tolerance), positive.
    pub viewport_height: u32,
}

impl CaveclodView {
    /// The refinement view: the frustum of the view-projection for `aspect` and the pixels
    /// per radian of the viewport's height, as the core's `LookAt::checked_view` makes and
    /// checks them.
    pub fn to_view(&self) -> Result<View> {
        let look = LookAt {
            eye: Vec3::from_array(self.eye),
            target: Vec3::from_array(self.target),
            up: Vec3::from_array(self.up),
            fov_y: self.fov_y,
            near: self.near,
            far: self.far,
        };
        Ok(look.checked_view(self.aspect, self.viewport_height)?)
    }
}

/// The knobs of one refinement pass (`caveclod_refine_params_default` fills the defaults).
/// The library checks their ranges as the core does (`RefineParams::validate`): a value out
/// of range makes the pass return `CAVECLOD_STATUS_INVALID_ARGUMENT` and do nothing.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CaveclodRefineParams {
    /// Screen-space tolerance in pixels: split while a node's error projects larger; a
    /// finite number above 0 (default 1).
    pub tolerance_px: f32,
    /// Most splits + collapses in one pass; `UINT32_MAX` for no limit (the default).
    pub max_ops: u32,
    /// Seconds since this camera's previous pass: how far its morphs move; finite, 0 or
    /// more (default 1/60).
    pub dt_s: f32,
    /// Seconds a refine morph takes, finite; 0 splits at once (default 32/60). Only a
    /// camera with morph memory morphs.
    pub refine_morph_s: f32,
    /// Seconds a coarsen morph takes, finite; 0 collapses at once (default 16/60).
    pub coarsen_morph_s: f32,
    /// Fastest a morphing vertex may glide across the screen, pixels per second: a morph
    /// whose path is long on the screen then takes longer than its duration (0 or infinity,
    /// the default: no limit; negative or NaN is refused).
    pub morph_speed_px_s: f32,
    /// How large on the screen a morphing camera's nodes may stay, in tolerances: a node
    /// whose bounding sphere projects larger splits, which keeps morphs' paths short on the
    /// screen for more polygons (0 or infinity, the default: no bound; negative or NaN is
    /// refused).
    pub morph_radius_tolerances: f32,
    /// How far beyond the view's sides a morphing camera refines, in radians, so what
    /// turns into view was refined before it shows (default 0.15; 0 for none; below π/2).
    pub morph_guard_rad: f32,
    /// Coarsen outside the view frustum (default true).
    pub frustum_culling: bool,
    /// Coarsen where the surface faces away from the eye (default true).
    pub backface_culling: bool,
}

impl From<RefineParams> for CaveclodRefineParams {
    fn from(p: RefineParams) -> Self {
        Self {
            tolerance_px: p.tolerance_px,
            max_ops: p.max_ops,
            dt_s: p.dt_s,
            refine_morph_s: p.refine_morph_s,
            coarsen_morph_s: p.coarsen_morph_s,
            morph_speed_px_s: p.morph_speed_px_s,
            morph_radius_tolerances: p.morph_radius_tolerances,
            morph_guard_rad: p.morph_guard_rad,
            frustum_culling: p.frustum_culling,
            backface_culling: p.backface_culling,
        }
    }
}

impl CaveclodRefineParams {
    /// The core's parameters (fields this struct lacks keep their defaults), as given: the
    /// core checks their ranges when it refines (`RefineParams::validate`).
    pub fn to_params(&self) -> RefineParams {
        // Parameters the core gains later keep their defaults.
        #[allow(clippy::needless_update)]
        RefineParams {
            tolerance_px: self.tolerance_px,
            max_ops: self.max_ops,
            frustum_culling: self.frustum_culling,
            backface_culling: self.backface_culling,
            dt_s: self.dt_s,
            refine_morph_s: self.refine_morph_s,
            coarsen_morph_s: self.coarsen_morph_s,
            morph_speed_px_s: self.morph_speed_px_s,
            morph_radius_tolerances: self.morph_radius_tolerances,
            morph_guard_rad: self.morph_guard_rad,
            ..RefineParams::default()
        }
    }
}

/// What one refinement pass did (the core's `RefineStats`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaveclodRefineStats {
    /// Splits applied, forced ones included.
    pub splits: u32,
    /// Splits applied only to make a wanted split legal.
    pub forced_splits: u32,
    /// Collapses applied.
    pub collapses: u32,
    /// Active-node visits.
    pub nodes_visited: u32,
    /// Active nodes after the pass.
    pub active_nodes: u32,
    /// Active polygons after the pass.
    pub active_polygons: u32,
    /// Wanted splits refused because the camera was full (its polygon budget).
    pub capacity_refusals: u32,
    /// Wanted splits abandoned because the forced-split stack was full.
    pub stack_overflows: u32,
    /// Wanted collapses checked and found illegal.
    pub collapses_refused: u32,
    /// Wanted collapses not checked again (refused before, nothing changed since).
    pub refusals_remembered: u32,
    /// Questions a certificate answered without reading bounds.
    pub certified: u32,
    /// Morphs begun.
    pub morphs_started: u32,
    /// Morphs ended.
    pub morphs_finished: u32,
    /// Coarsen morphs turned back towards the fine position.
    pub morphs_aborted: u32,
    /// Splits and collapses that wanted a morph but happened at once (morph memory full).
    pub morphs_dropped: u32,
    /// Morphs in progress after the pass.
    pub morphing: u32,
}

impl From<RefineStats> for CaveclodRefineStats {
    fn from(s: RefineStats) -> Self {
        Self {
            splits: s.splits,
            forced_splits: s.forced_splits,
            collapses: s.collapses,
            nodes_visited: s.nodes_visited,
            active_nodes: s.active_nodes,
            active_polygons: s.active_polygons,
            capacity_refusals: s.capacity_refusals,
            stack_overflows: s.stack_overflows,
            collapses_refused: s.collapses_refused,
            refusals_remembered: s.refusals_remembered,
            certified: s.certified,
            morphs_started: s.morphs_started,
            morphs_finished: s.morphs_finished,
            morphs_aborted: s.morphs_aborted,
            morphs_dropped: s.morphs_dropped,
            morphing: s.morphing,
        }
    }
}

/// How much a camera can hold (the core's `CameraConfig`); fill it with
/// `caveclod_camera_config_full` or `caveclod_camera_config_polygon_budget`, then set
/// `max_morphs` for geomorphs.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CaveclodCameraConfig {
    /// Most splits applied at once; each adds one or two polygons. At most the
    /// hierarchy's split count.
    pub max_pairs: u32,
    /// Entries of the forced-split stack (overflow is counted, not fatal).
    pub stack_len: u32,
    /// Most geomorphs at once; 0 splits and collapses at once.
    pub max_morphs: u32,
    /// Keep each active polygon's indices between frames (faster emission, 16 bytes per
    /// polygon slot).
    pub index_cache: bool,
    /// Hash the split-to-pair map (smaller for small budgets, slower refinement).
    pub hashed_pair_map: bool,
}

impl From<CameraConfig> for CaveclodCameraConfig {
    fn from(c: CameraConfig) -> Self {
        Self {
            max_pairs: c.max_pairs,
            stack_len: c.stack_len,
            max_morphs: c.max_morphs,
            index_cache: c.index_cache,
            hashed_pair_map: c.hashed_pair_map,
        }
    }
}

impl CaveclodCameraConfig {
    /// The core's configuration for `h` (a whole file or a streamed one), if `h` allows it.
    pub fn to_config(&self, h: &impl HierarchyRecords) -> Result<CameraConfig> {
        let splits = h.split_id_bound() as u64;
        let morph_slots = 2 * u64::from(self.max_morphs);
        if u64::from(self.max_pairs) > splits
            || h.vertex_id_bound() as u64 + morph_slots >= u64::from(u32::MAX)
        {
            return Err(CaveclodStatus::InvalidConfig);
        }
        // Fields the core gains later keep those of a full camera.
        #[allow(clippy::needless_update)]
        Ok(CameraConfig {
            max_pairs: self.max_pairs,
            stack_len: self.stack_len,
            index_cache: self.index_cache,
            hashed_pair_map: self.hashed_pair_map,
            max_morphs: self.max_morphs,
            ..CameraConfig::full(h)
        })
    }
}

/// The counts of a hierarchy: what a runtime sizes its buffers from.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaveclodHierarchyCounts {
    /// Surfaces (materials): index lists per camera.
    pub surfaces: u32,
    /// Vertices of the persistent vertex buffer; every emitted index is below it (morphed
    /// emission: below `vertices + 2 × max_morphs`).
    pub vertices: u32,
    /// Bytes of the vertex buffer (`vertices × vertex_stride`).
    pub vertex_buffer_bytes: u64,
    /// Bytes per vertex: 32.
    pub vertex_stride: u32,
    /// Byte offset of the position (3 × f32) in a vertex: 0.
    pub position_offset: u32,
    /// Byte offset of the unit normal (3 × f32): 12.
    pub normal_offset: u32,
    /// Byte offset of the texture coordinates (2 × f32): 24.
    pub uv_offset: u32,
    /// Nodes of the hierarchy.
    pub nodes: u32,
    /// Splits (a full camera's `max_pairs`).
    pub splits: u32,
    /// Polygons of the base mesh (the fewest a camera shows).
    pub base_polygons: u32,
    /// Polygons of the full-resolution mesh (the most a camera shows).
    pub polygons: u32,
}

/// An axis-aligned bounding box, world space.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CaveclodBounds {
    /// The least x, y and z.
    pub min: [f32; 3],
    /// The greatest x, y and z.
    pub max: [f32; 3],
}

/// The state of a camera.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaveclodCameraCounts {
    /// Active nodes.
    pub active_nodes: u32,
    /// Active polygons.
    pub active_polygons: u32,
    /// Splits applied.
    pub splits: u32,
    /// Most splits the camera holds.
    pub max_pairs: u32,
    /// Morphs in progress.
    pub morphs: u32,
    /// Most morphs at once.
    pub max_morphs: u32,
    /// Indices of all surfaces together: the room packed emission needs.
    pub total_indices: u64,
}
