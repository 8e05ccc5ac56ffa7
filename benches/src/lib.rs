//! Criterion benchmarks of caveclod live in `benches/`; this library holds what several of
//! them share.

pub mod distance;

use caveclod_core::glam::Vec3;
use caveclod_core::View;

/// A 1280 × 720, 60° camera at `eye` looking along the horizontal `forward`, 15 degrees down,
/// seeing as far as `far`: the fly-over's low pass over a terrain.
pub fn low_pass_view(eye: Vec3, forward: Vec3, far: f32) -> View {
    let pitch = 15f32.to_radians();
    let dir = forward * pitch.cos() - Vec3::Y * pitch.sin();
    View::perspective(
        eye,
        eye + dir,
        Vec3::Y,
        60f32.to_radians(),
        1280.0 / 720.0,
        0.1,
        far,
        720.0,
    )
}
