//! How far a front lags its view: the active nodes whose split a full refinement pass would
//! want, and by how many pixels their error exceeds the tolerance. An amortised pass
//! ([`RefineParams::visit_fraction`]) leaves some behind for a few frames; this measures it,
//! at the cost of a full pass's reads, so it is for reports and tests, not for a frame loop.

use super::criterion::Criterion;
use super::ops::OpError;
use super::records::FREE;
use super::state::CameraState;
use crate::hierarchy::HierarchyRecords;
use crate::ids::NodeId;
use crate::params::RefineParams;
use crate::screen::ScreenTest;
use crate::view::View;

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

impl CameraState<'_> {
    /// The active nodes a full refinement pass against `view` with `params` would split
    /// (their errors against `params.tolerance_px`); reads every active node's bounds and
    /// changes nothing.
    ///
    /// [`OpError::WrongHierarchy`] for a camera of another hierarchy,
    /// [`OpError::InvalidParams`] for parameters out of range
    /// ([`RefineParams::validate`]).
    pub fn lag(
        &self,
        h: &impl HierarchyRecords,
        view: &View,
        params: &RefineParams,
    ) -> Result<FrontLag, OpError> {
        if !self.is_for(h) {
            return Err(OpError::WrongHierarchy);
        }
        let test = ScreenTest::new(view, params, self.front.morphs.capacity() > 0)?;
        let c = Criterion::new(&test);
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
                let excess = test.excess_px(b);
                lag.over_tolerance += 1;
                lag.excess_px += excess;
                lag.worst_excess_px = lag.worst_excess_px.max(excess);
            }
        }
        Ok(lag)
    }
}
