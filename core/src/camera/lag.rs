//! How far a front lags its view: the active nodes whose split a full refinement pass would
//! want, and by how many pixels their error exceeds the tolerance. An amortised pass
//! ([`RefineParams::visit_fraction`]) leaves some behind for a few frames; this measures it,
//! at the cost of a full pass's reads, so it is for reports and tests, not for a frame loop.

use glam::Vec3;

use super::criterion::Criterion;
use super::{CameraState, FREE};
use crate::format::SplitBounds;
use crate::hierarchy::Hierarchy;
use crate::ids::NodeId;
use crate::view::View;
use crate::RefineParams;

/// What [`CameraState::lag`] found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrontLag {
    /// Active nodes.
    pub active_nodes: u32,
    /// Active nodes whose split refinement wants (visible, error projecting to more than
    /// the tolerance).
    pub over_tolerance: u32,
    /// Their projected errors' excess over the tolerance, in pixels, summed.
    pub excess_px: f32,
    /// The largest of those excesses, in pixels.
    pub worst_excess_px: f32,
}

impl FrontLag {
    /// The share of the active nodes over the tolerance.
    pub fn share(&self) -> f32 {
        if self.active_nodes == 0 {
            0.0
        } else {
            self.over_tolerance as f32 / self.active_nodes as f32
        }
    }
}

/// A node's error projected to the screen, in pixels: the larger of its uniform error and
/// its directional error seen across the view direction, at its distance.
fn projected_px(view: &View, b: &SplitBounds) -> f32 {
    let pe = Vec3::from_array(b.point) - view.eye;
    let d2 = pe.length_squared();
    if d2 <= 0.0 {
        return f32::INFINITY;
    }
    let d = libm::sqrtf(d2);
    let across = if b.cone_sin2 >= 1.0 {
        1.0
    } else {
        let vdot = pe.dot(Vec3::from_array(b.cone_normal())) / d;
        libm::sqrtf((1.0 - vdot * vdot).max(0.0))
    };
    b.uni_error.max(b.dir_error * across) / d * view.pixels_per_radian
}

impl CameraState<'_> {
    /// The active nodes a full refinement pass against `view` with `params` would split
    /// (their errors against `params.tolerance_px`); reads every active node's bounds and
    /// changes nothing.
    pub fn lag(&self, h: &Hierarchy<'_>, view: &View, params: &RefineParams) -> FrontLag {
        let scale = if view.pixels_per_radian > 0.0 {
            params.tolerance_px / view.pixels_per_radian
        } else {
            f32::INFINITY
        };
        let morphing = self.front.morphs.capacity() > 0;
        let view = &params.refined_view(view, morphing);
        let radius_error = params.radius_error(morphing);
        let c = Criterion::new(view, scale * scale, radius_error, params);
        let mut lag = FrontLag {
            active_nodes: self.front.active_nodes,
            ..FrontLag::default()
        };
        let f = &self.front;
        for a in &f.active[..(f.active_len as usize).min(f.active.len())] {
            if a.node & FREE != 0 {
                continue;
            }
            let Some(b) = h.split_bounds(NodeId(a.node)) else {
                continue;
            };
            if c.wants_split(b) {
                let excess = (projected_px(view, b) - params.tolerance_px).max(0.0);
                lag.over_tolerance += 1;
                lag.excess_px += excess;
                lag.worst_excess_px = lag.worst_excess_px.max(excess);
            }
        }
        lag
    }
}
