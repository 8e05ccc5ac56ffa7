//! A look-at perspective camera giving both what the GPU needs (a view-projection matrix)
//! and what refinement needs (a [`caveclod_core::View`] with the same frustum and the
//! viewport's pixel scale), so the two can never disagree.

use caveclod_core::View;
use glam::camera::rh::proj;
use glam::camera::rh::view::look_at_mat4;
use glam::{Mat4, Vec3};

use crate::frame::Viewport;

/// A perspective camera looking from `eye` at `target`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LookAt {
    /// Eye point.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up direction.
    pub up: Vec3,
    /// Vertical field of view, radians.
    pub fov_y: f32,
    /// Near clip distance.
    pub near: f32,
    /// Far clip distance.
    pub far: f32,
}

impl LookAt {
    /// The view-projection matrix for `viewport`'s aspect: right-handed y-up view space,
    /// Vulkan clip space (y down, depth 0..1).
    pub fn view_proj(&self, viewport: Viewport) -> Mat4 {
        proj::vulkan::perspective(self.fov_y, viewport.aspect(), self.near, self.far)
            * look_at_mat4(self.eye, self.target, self.up)
    }

    /// The refinement view: the same frustum, and pixels per radian of `viewport`.
    pub fn view(&self, viewport: Viewport) -> View {
        let pixels_per_radian = viewport.height as f32 / (2.0 * (self.fov_y * 0.5).tan());
        View::from_view_projection(self.view_proj(viewport), self.eye, pixels_per_radian)
    }
}
