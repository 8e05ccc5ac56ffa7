//! Scripted flight paths over a hierarchy's ground: four routes (wide circle, straight pass,
//! figure-eight, tight circle), each following the terrain at a clearance, as in the
//! CAVECLOD paper's four-camera fly-over.
//!
//! Positions are taken as a terrain with `y` up (what the heightfield importers make): the
//! ground is the highest point of the full-resolution mesh in each cell of a 256 x 256 grid
//! over the `x`/`z` extent, so cameras clear the surface whatever the mesh; for a closed
//! object the routes circle above it.

use caveclod_core::glam::Vec3;
use caveclod_core::{Hierarchy, LookAt, View};

/// Viewport width in pixels (the screen-space tolerance is relative to it).
pub const WIDTH: f32 = 1280.0;
/// Viewport height in pixels.
pub const HEIGHT: f32 = 720.0;
/// Vertical field of view, degrees.
pub const FOV_Y_DEG: f32 = 60.0;
/// Cells per side of the ground grid.
const GROUND_CELLS: usize = 256;

/// Terrain heights on a grid over the mesh's `x`/`z` extent, for terrain-following flight.
#[derive(Clone, Debug)]
pub struct Ground {
    min: [f32; 2],
    cell: f32,
    cells: usize,
    heights: Vec<f32>,
    /// Extent along `x` and `z` (the square the routes fly over has the smaller one as side).
    pub size: f32,
    /// Centre of the extent.
    pub centre: [f32; 2],
}

impl Ground {
    /// The ground of a hierarchy: highest full-resolution point per cell; cells without
    /// points take the highest point of all, so the routes stay clear.
    pub fn new(h: &Hierarchy<'_>) -> Self {
        Self::of_points(|| h.positions().iter().map(|p| p.xyz))
    }

    /// The ground of the points `points` gives (called twice): highest point per cell.
    pub fn of_points<I: Iterator<Item = [f32; 3]>>(points: impl Fn() -> I) -> Self {
        let mut lo = [f32::INFINITY; 2];
        let mut hi = [f32::NEG_INFINITY; 2];
        let mut top = f32::NEG_INFINITY;
        for [x, y, z] in points() {
            lo = [lo[0].min(x), lo[1].min(z)];
            hi = [hi[0].max(x), hi[1].max(z)];
            top = top.max(y);
        }
        if !top.is_finite() {
            (lo, hi, top) = ([0.0; 2], [1.0; 2], 0.0);
        }
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-6);
        let cells = GROUND_CELLS;
        let cell = extent / cells as f32;
        let mut heights = vec![f32::NEG_INFINITY; (cells + 1) * (cells + 1)];
        for [x, y, z] in points() {
            let i = (((x - lo[0]) / cell) as usize).min(cells);
            let j = (((z - lo[1]) / cell) as usize).min(cells);
            let c = &mut heights[j * (cells + 1) + i];
            *c = c.max(y);
        }
        for c in &mut heights {
            if !c.is_finite() {
                *c = top;
            }
        }
        Self {
            min: lo,
            cell,
            cells,
            heights,
            size: (hi[0] - lo[0]).min(hi[1] - lo[1]).max(1e-6),
            centre: [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])],
        }
    }

    /// Bilinear height at (x, z), clamped to the grid.
    pub fn at(&self, x: f32, z: f32) -> f32 {
        let n = self.cells as f32;
        let gx = ((x - self.min[0]) / self.cell).clamp(0.0, n);
        let gz = ((z - self.min[1]) / self.cell).clamp(0.0, n);
        let (i, j) = (
            (gx as usize).min(self.cells - 1),
            (gz as usize).min(self.cells - 1),
        );
        let (fx, fz) = (gx - i as f32, gz - j as f32);
        let side = self.cells + 1;
        let h = |i: usize, j: usize| self.heights[j * side + i];
        let a = h(i, j) * (1.0 - fx) + h(i + 1, j) * fx;
        let b = h(i, j + 1) * (1.0 - fx) + h(i + 1, j + 1) * fx;
        a * (1.0 - fz) + b * fz
    }
}

/// The scripted flight paths: ground point as a function of distance flown.
#[derive(Clone, Copy, Debug)]
pub enum Path {
    /// Circle around the centre, clockwise seen from above.
    Circle { radius: f32, phase: f32 },
    /// Circle the other way.
    CircleBack { radius: f32, phase: f32 },
    /// Straight pass along the diagonal, back and forth.
    Pass,
    /// A figure-eight (lemniscate of Gerono) around the centre.
    FigureEight { a: f32 },
}

pub struct Route {
    /// Its name in reports.
    pub name: &'static str,
    /// The ground track.
    pub path: Path,
    /// Height above the highest ground around the camera, in terrain sizes.
    pub clearance: f32,
    /// Look-down angle, degrees.
    pub pitch_deg: f32,
}

/// The four routes, in camera order.
pub fn routes() -> [Route; 4] {
    [
        Route {
            name: "wide circle",
            path: Path::Circle {
                radius: 0.32,
                phase: 0.0,
            },
            clearance: 0.03,
            pitch_deg: 25.0,
        },
        Route {
            name: "straight pass",
            path: Path::Pass,
            clearance: 0.015,
            pitch_deg: 15.0,
        },
        Route {
            name: "figure-eight",
            path: Path::FigureEight { a: 0.3 },
            clearance: 0.02,
            pitch_deg: 20.0,
        },
        Route {
            name: "tight circle",
            path: Path::CircleBack {
                radius: 0.15,
                phase: 2.0,
            },
            clearance: 0.06,
            pitch_deg: 35.0,
        },
    ]
}

/// Ground-plane position (x, z) after flying `s` world units over a square of side `size`
/// centred on `centre`.
fn ground_point(path: Path, s: f32, size: f32, centre: [f32; 2]) -> (f32, f32) {
    let c = 0.5 * size;
    let (ox, oz) = (centre[0] - c, centre[1] - c);
    let (x, z) = ground_point_local(path, s, size);
    (ox + x, oz + z)
}

fn ground_point_local(path: Path, s: f32, size: f32) -> (f32, f32) {
    let c = 0.5 * size;
    match path {
        Path::Circle { radius, phase } => {
            let r = radius * size;
            let t = phase + s / r;
            (c + r * t.cos(), c + r * t.sin())
        }
        Path::CircleBack { radius, phase } => {
            let r = radius * size;
            let t = phase - s / r;
            (c + r * t.cos(), c + r * t.sin())
        }
        Path::Pass => {
            let (a, b) = (0.1 * size, 0.9 * size);
            let len = (b - a) * std::f32::consts::SQRT_2;
            let u = (s / len).rem_euclid(2.0);
            let u = if u > 1.0 { 2.0 - u } else { u };
            let p = a + (b - a) * u;
            (p, p)
        }
        Path::FigureEight { a } => {
            let a = a * size;
            // Roughly constant speed: the lemniscate's length is about 6.1 a.
            let t = s / (6.1 * a) * std::f32::consts::TAU;
            (c + a * t.sin(), c + a * t.sin() * t.cos())
        }
    }
}

/// Eye and look direction of `route` at frame `frame`, flying `speed` world units per frame.
pub fn eye_at(route: &Route, frame: usize, speed: f32, ground: &Ground) -> (Vec3, Vec3) {
    let size = ground.size;
    let s = frame as f32 * speed;
    let (x, z) = ground_point(route.path, s, size, ground.centre);
    let (x2, z2) = ground_point(route.path, s + speed.max(1e-3), size, ground.centre);
    let mut forward = Vec3::new(x2 - x, 0.0, z2 - z).normalize_or_zero();
    if forward == Vec3::ZERO {
        forward = Vec3::X;
    }
    // Clear the highest ground near and ahead of the camera.
    let look = 0.03 * size;
    let mut floor = f32::MIN;
    for k in 0..=6 {
        let d = look * k as f32 / 6.0;
        floor = floor.max(ground.at(x + forward.x * d, z + forward.z * d));
    }
    let eye = Vec3::new(x, floor + route.clearance * size, z);
    let pitch = route.pitch_deg.to_radians();
    (eye, forward * pitch.cos() - Vec3::Y * pitch.sin())
}

/// Near clip distance as a share of the ground's size: well inside the lowest clearance (0.015),
/// so no ground under the flight is clipped, and as far out as that allows, because a depth
/// buffer's resolution at distance `d` is about `d² / (near · 2²⁴)`. At a near of 0.1 on a
/// 14 km terrain it would be tens of metres at the horizon, where the far side of a ridge then
/// wins the depth test through its front and its back faces, lit from behind, show as dark
/// specks.
const NEAR_SHARE: f32 = 2e-3;

/// Near and far clip distances of the fly-over's views over `ground`.
pub fn clip(ground: &Ground) -> (f32, f32) {
    (NEAR_SHARE * ground.size, 2.0 * ground.size)
}

/// The view of `route` at frame `frame` (1280 x 720, 60 degrees), flying `speed` world units
/// per frame.
pub fn view_at(route: &Route, frame: usize, speed: f32, ground: &Ground) -> View {
    look_at(route, frame, speed, ground).view(WIDTH as u32, HEIGHT as u32)
}

/// The camera of `route` at frame `frame`, flying `speed` world units per frame: its view
/// is [`view_at`], and its view-projection `look_at(..).view_projection(WIDTH / HEIGHT)`.
pub fn look_at(route: &Route, frame: usize, speed: f32, ground: &Ground) -> LookAt {
    let (eye, dir) = eye_at(route, frame, speed, ground);
    let (near, far) = clip(ground);
    LookAt {
        eye,
        target: eye + dir,
        up: Vec3::Y,
        fov_y: FOV_Y_DEG.to_radians(),
        near,
        far,
    }
}
