//! What the render benchmarks share: the target's size, the cameras around the terrain, the
//! scene every frame draws and its index rings filled, and the exit on a failed step.

use caveclod_core::glam::Vec3;
use caveclod_core::{CameraState, Hierarchy};
use caveclod_vulkan::{
    CameraIndices, Context, IndexSource, LookAt, RecordCamera, VertexBuffer, Viewport,
};

pub const WIDTH: u32 = 960;
pub const HEIGHT: u32 = 540;
pub const COLOURS: [[f32; 4]; 2] = [[0.9, 0.6, 0.3, 1.0], [0.3, 0.7, 0.9, 1.0]];

pub fn or_exit<T, E: std::fmt::Display>(r: Result<T, E>, what: &str) -> T {
    match r {
        Ok(x) => x,
        Err(e) => {
            eprintln!("render bench: {what}: {e}");
            std::process::exit(1)
        }
    }
}

/// Camera `i` of four, around and above the middle of a `size` terrain.
pub fn look(i: usize, size: f32) -> LookAt {
    let c = Vec3::new(size * 0.5, 0.0, size * 0.5);
    let angle = 0.4 + i as f32 * std::f32::consts::FRAC_PI_2;
    let (distance, height) = [(0.45, 0.25), (0.35, 0.15), (0.6, 0.35), (0.3, 0.2)][i % 4];
    LookAt {
        eye: c + Vec3::new(
            angle.sin() * distance * size,
            height * size,
            angle.cos() * distance * size,
        ),
        target: c,
        up: Vec3::Y,
        fov_y: 60f32.to_radians(),
        near: 0.01 * size,
        far: 3.0 * size,
    }
}

/// What every benchmark draws.
pub struct Scene<'a> {
    pub ctx: &'a Context,
    pub h: &'a Hierarchy<'a>,
    pub vertices: &'a VertexBuffer,
    pub size: f32,
}

impl Scene<'_> {
    /// Fills each camera's ring for frame slot `slot` from its front (`cams[i]` into
    /// `indices[i]`).
    pub fn fill(&self, slot: usize, indices: &mut [CameraIndices], cams: &[CameraState<'_>]) {
        for (ind, cam) in indices.iter_mut().zip(cams) {
            or_exit(
                ind.fill(self.ctx, slot, IndexSource::camera(self.h, cam)),
                "fill",
            );
        }
    }

    /// Camera `i` of `indices` drawn plainly into `viewports[i]`.
    pub fn cameras<'a>(
        &'a self,
        indices: &'a [CameraIndices],
        viewports: &[Viewport],
    ) -> Vec<RecordCamera<'a>> {
        indices
            .iter()
            .enumerate()
            .map(|(i, ind)| {
                let view_proj = look(i, self.size).view_projection(viewports[i].aspect());
                RecordCamera::new(viewports[i], view_proj, self.vertices, ind).colours(&COLOURS)
            })
            .collect()
    }
}
