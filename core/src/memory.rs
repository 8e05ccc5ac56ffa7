//! Memory figures beside the CAVECLOD paper's Equation 1,
//! `b = 44n + 12p + 32d + 2se + 12n_a + 36p_a + c(4n + 4p + 16)`.
//!
//! The paper's per-camera share is `4n + 4p + 16` plus its part of `12n_a + 36p_a`; ours is
//! [`CameraState::bytes`](crate::CameraState::bytes): one word per splittable node (not per
//! node and per polygon) plus the active front sized by the camera's capacity.

use crate::hierarchy::Hierarchy;

/// Static and per-camera bytes of a hierarchy, ours and the paper's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryReport {
    /// Nodes (`n`).
    pub nodes: u64,
    /// Full-resolution polygons (`p`).
    pub polygons: u64,
    /// Vertices (`d`).
    pub vertices: u64,
    /// Surface-group ids (`s`).
    pub surface_group_ids: u64,
    /// Node positions (`e`).
    pub positions: u64,
    /// Active nodes of the camera (`n_a` for one camera).
    pub active_nodes: u64,
    /// Active polygons of the camera (`p_a` for one camera).
    pub active_polygons: u64,
    /// Our static bytes: every section's records.
    pub static_bytes: u64,
    /// Our bytes for one camera.
    pub camera_bytes: u64,
    /// The paper's static bytes, `44n + 12p + 32d + 2se`.
    pub paper_static_bytes: u64,
    /// The paper's bytes for one camera with these active counts,
    /// `4n + 4p + 16 + 12n_a + 36p_a`.
    pub paper_camera_bytes: u64,
}

impl MemoryReport {
    /// Figures for `h` and one camera of `camera_bytes` holding the given active counts.
    pub fn new(
        h: &Hierarchy<'_>,
        camera_bytes: usize,
        active_nodes: u64,
        active_polygons: u64,
    ) -> Self {
        let m = h.meta();
        let (n, p, d) = (
            m.node_count as u64,
            m.polygon_count as u64,
            m.vertex_count as u64,
        );
        let (s, e) = (m.surface_group_count as u64, m.position_count as u64);
        Self {
            nodes: n,
            polygons: p,
            vertices: d,
            surface_group_ids: s,
            positions: e,
            active_nodes,
            active_polygons,
            static_bytes: h.static_bytes() as u64,
            camera_bytes: camera_bytes as u64,
            paper_static_bytes: 44 * n + 12 * p + 32 * d + 2 * s * e,
            paper_camera_bytes: Self::paper_camera(n, p, active_nodes, active_polygons),
        }
    }

    /// The paper's per-camera bytes: `4n + 4p + 16 + 12n_a + 36p_a`.
    pub fn paper_camera(n: u64, p: u64, active_nodes: u64, active_polygons: u64) -> u64 {
        4 * n + 4 * p + 16 + 12 * active_nodes + 36 * active_polygons
    }

    /// Our per-camera bytes over the paper's (goal: at most 0.25; target: at most 0.5).
    pub fn camera_ratio(&self) -> f64 {
        self.camera_bytes as f64 / self.paper_camera_bytes.max(1) as f64
    }
}
