//! The crowd's flights: the disc it stands on, the distances detail falls off over, the
//! camera paths, and one run's per-frame figures.

use caveclod_core::glam::Vec3;
use caveclod_core::LookAt;

/// The crowd stands on a disc of this radius (instances are scaled to radius 1).
pub const CROWD_RADIUS: f32 = 100.0;
/// Full detail up to here...
pub const D_NEAR: f32 = 5.0;
/// ...coarsest beyond here.
pub const D_FAR: f32 = 250.0;

/// The paths the camera flies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CameraPath {
    /// Round the crowd, looking at its centre.
    Circle,
    /// Straight across, looking down: the visible set changes fast.
    Volatile,
}

impl CameraPath {
    pub fn name(self) -> &'static str {
        match self {
            Self::Circle => "circle",
            Self::Volatile => "volatile",
        }
    }

    /// Eye, target and up at `s ∈ [0, 1)` of the path.
    pub fn at(self, s: f32) -> (Vec3, Vec3, Vec3) {
        match self {
            Self::Circle => {
                let a = s * std::f32::consts::TAU;
                let r = CROWD_RADIUS * 1.3;
                (
                    Vec3::new(r * a.cos(), 40.0, r * a.sin()),
                    Vec3::ZERO,
                    Vec3::Y,
                )
            }
            Self::Volatile => {
                let x = -2.0 * CROWD_RADIUS + 4.0 * CROWD_RADIUS * s;
                let eye = Vec3::new(x, 0.8 * CROWD_RADIUS, 0.0);
                (eye, eye - Vec3::Y, Vec3::Z)
            }
        }
    }

    /// The camera at `s ∈ [0, 1)` of the path, as the runs and the pictures see it.
    pub fn look_at(self, s: f32) -> LookAt {
        let (eye, target, up) = self.at(s);
        LookAt {
            eye,
            target,
            up,
            fov_y: 1.0,
            near: 0.5,
            far: 1000.0,
        }
    }
}

/// One run's per-frame figures.
pub struct Run {
    pub label: &'static str,
    pub cap: Option<f32>,
    pub polygons: Vec<u64>,
    pub bias: Vec<f32>,
    pub visible: Vec<usize>,
}
