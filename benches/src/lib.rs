//! Criterion benchmarks of caveclod live in `benches/`; this library holds what several of
//! them share.

pub mod cut;
pub mod distance;

use caveclod_core::glam::Vec3;
use caveclod_core::{LookAt, View};

/// A 1280 × 720, 60° camera at `eye` looking along the horizontal `forward`, 15 degrees down,
/// seeing as far as `far`: the fly-over's low pass over a terrain.
pub fn low_pass_view(eye: Vec3, forward: Vec3, far: f32) -> View {
    let pitch = 15f32.to_radians();
    let dir = forward * pitch.cos() - Vec3::Y * pitch.sin();
    let look = LookAt {
        eye,
        target: eye + dir,
        up: Vec3::Y,
        fov_y: 60f32.to_radians(),
        near: 0.1,
        far,
    };
    look.view(1280, 720)
}
