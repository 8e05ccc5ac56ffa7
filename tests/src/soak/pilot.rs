//! One soak camera's flight and knobs, redrawn at random: where it is and how fast it moves,
//! its viewport, its pixel tolerance (fixed or regulated), how a refinement call is bounded
//! (whole pass, amortised share, visit and operation caps), culling, the morph clock; and, per
//! life of a camera, its capacity (full or a polygon budget, morph memory, hashed pair map,
//! index cache, forced-split stack).

use std::f32::consts::PI;

use caveclod_core::format::Meta;
use caveclod_core::glam::Vec3;
use caveclod_core::{CameraConfig, Hierarchy, LookAt, RefineParams, Regulator, View};

use caveclod_bake::generate::SplitMix64;

/// Most geomorphs a soak camera may be given; camera memory is sized for it.
pub const MAX_MORPHS: u32 = 4096;
/// The longest list of changed index places a soak camera keeps.
pub const EDIT_LIST: u32 = 4096;

/// The motion clock: one frame at 60 Hz (the morph clock `dt_s` is drawn separately).
const FRAME_S: f32 = 1.0 / 60.0;

/// How a camera's tolerance is chosen each frame.
#[derive(Clone, Copy, Debug)]
pub enum Tolerance {
    /// A fixed tolerance in pixels.
    Fixed(f32),
    /// Regulated towards a polygon count.
    Regulated(Regulator),
}

/// A camera's flight and refinement knobs.
#[derive(Clone, Debug)]
pub struct Pilot {
    pub eye: Vec3,
    pub yaw: f32,
    pub pitch: f32,
    /// Metres per second.
    pub speed: f32,
    /// Radians per second.
    pub turn: f32,
    pub fov_y: f32,
    pub viewport: (u32, u32),
    pub tolerance: Tolerance,
    pub params: RefineParams,
    /// While set, each frame takes a step of incremental compaction of at most this budget.
    pub compaction_budget: Option<u32>,
}

/// The terrain's box: lowest and highest corner, and the larger horizontal extent.
#[derive(Clone, Copy, Debug)]
pub struct Terrain {
    pub lo: Vec3,
    pub hi: Vec3,
    pub size: f32,
}

impl Terrain {
    /// The box of the positions of the file whose counts are `m` (whole or paged).
    pub fn of(m: &Meta) -> Self {
        let (lo, hi) = (
            Vec3::from_array(m.bounds_min),
            Vec3::from_array(m.bounds_max),
        );
        let size = (hi.x - lo.x).max(hi.z - lo.z).max(1e-3);
        Self { lo, hi, size }
    }
}

/// `true` with probability `1 / n`.
pub fn one_in(rng: &mut SplitMix64, n: usize) -> bool {
    rng.below(n) == 0
}

/// Log-uniform in `lo..hi`.
fn log_uniform(rng: &mut SplitMix64, lo: f32, hi: f32) -> f32 {
    lo * (hi / lo).powf(rng.unit())
}

/// One of `options`, uniformly.
fn pick<T: Copy>(rng: &mut SplitMix64, options: &[T]) -> T {
    options[rng.below(options.len())]
}

/// A camera configuration: full or a polygon budget (from a fiftieth of the hierarchy's
/// polygons to all), with or without morph memory (from
/// one morph to [`MAX_MORPHS`]), the pair map hashed or not, the index cache on or off, with
/// the cache half the time index edits (a list from 1 to [`EDIT_LIST`] places), and now and
/// then a forced-split stack too small for deep forced splits.
pub fn draw_config(rng: &mut SplitMix64, h: &Hierarchy<'_>) -> CameraConfig {
    let mut c = if one_in(rng, 3) {
        CameraConfig::full(h)
    } else {
        let all = h.polygon_count() as f32;
        CameraConfig::with_polygon_budget(h, log_uniform(rng, all / 50.0 + 1.0, all + 2.0) as u32)
    };
    if !one_in(rng, 3) {
        c = c.with_morphs(pick(rng, &[1, 16, 256, MAX_MORPHS]));
    }
    c.hashed_pair_map = one_in(rng, 4);
    c.index_cache = !one_in(rng, 4);
    if c.index_cache && one_in(rng, 2) {
        c = c.with_index_edits(pick(rng, &[1, 64, EDIT_LIST]));
    }
    if one_in(rng, 8) {
        c.stack_len = pick(rng, &[4, 16, 64]);
    }
    c
}

impl Pilot {
    /// A pilot somewhere over `t`, with knobs drawn.
    pub fn new(rng: &mut SplitMix64, t: &Terrain) -> Self {
        let mut p = Self {
            eye: Vec3::ZERO,
            yaw: 0.0,
            pitch: 0.0,
            speed: 0.0,
            turn: 0.0,
            fov_y: 1.0,
            viewport: (1280, 720),
            tolerance: Tolerance::Fixed(1.0),
            params: RefineParams::default(),
            compaction_budget: None,
        };
        p.teleport(rng, t);
        p.draw_speed(rng);
        p.draw_tolerance(rng, 1.0, 1000);
        p.draw_bounds(rng);
        p.draw_clock(rng);
        p
    }

    /// Somewhere else: anywhere over the terrain (or a little beyond), from just above its
    /// lowest point to far above its highest, looking anywhere from the horizon to down.
    pub fn teleport(&mut self, rng: &mut SplitMix64, t: &Terrain) {
        let span = t.hi - t.lo;
        let (u, v, w) = (rng.unit(), rng.unit(), rng.unit());
        self.eye = Vec3::new(
            t.lo.x + span.x * (1.2 * u - 0.1),
            t.lo.y + span.y * (0.3 + v) + t.size * w * w * w,
            t.lo.z + span.z * (1.2 * rng.unit() - 0.1),
        );
        self.yaw = 2.0 * PI * rng.unit();
        self.pitch = -1.3 * rng.unit() + 0.1;
        self.fov_y = 0.4 + 1.0 * rng.unit();
        self.viewport = pick(rng, &[(320, 240), (1280, 720), (1920, 1080), (3840, 2160)]);
    }

    /// Still, walking, driving, flying or a fast jet; and a turn rate.
    pub fn draw_speed(&mut self, rng: &mut SplitMix64) {
        self.speed = pick(rng, &[0.0, 5.0, 50.0, 300.0, 3000.0]);
        self.turn = (rng.unit() - 0.5) * pick(rng, &[0.0, 0.2, 2.0]);
    }

    /// A fixed tolerance from a fifth of a pixel to 8, or a regulator towards a polygon count
    /// from twice the base mesh to the whole hierarchy (starting at `from_px`).
    pub fn draw_tolerance(&mut self, rng: &mut SplitMix64, from_px: f32, polygons: usize) {
        self.tolerance = if one_in(rng, 3) {
            let lo = 2.0 * polygons.min(1000) as f32;
            let target = log_uniform(rng, lo.max(2.0), (polygons as f32).max(lo + 1.0));
            Tolerance::Regulated(Regulator::new(target as u32).with_tolerance(from_px))
        } else {
            Tolerance::Fixed(log_uniform(rng, 0.2, 8.0))
        };
    }

    /// How a call is bounded: a whole pass, or an amortised share, a visit cap, an
    /// operation cap; and culling on or off.
    pub fn draw_bounds(&mut self, rng: &mut SplitMix64) {
        let p = &mut self.params;
        p.visit_fraction = if one_in(rng, 2) {
            1.0
        } else {
            pick(rng, &[0.5, 1.0 / 3.0, 0.1, 0.01])
        };
        p.max_visits = if one_in(rng, 4) {
            64 + rng.below(10_000) as u32
        } else {
            u32::MAX
        };
        p.max_ops = if one_in(rng, 3) {
            1 + rng.below(2000) as u32
        } else {
            u32::MAX
        };
        p.frustum_culling = !one_in(rng, 8);
        p.backface_culling = !one_in(rng, 4);
    }

    /// The morph clock: the pass's seconds (0 now and then: a repeated pass), and the refine
    /// and coarsen morphs' durations (0: at once).
    pub fn draw_clock(&mut self, rng: &mut SplitMix64) {
        let p = &mut self.params;
        p.dt_s = pick(rng, &[0.0, 1.0 / 120.0, FRAME_S, 1.0 / 30.0, 0.2]);
        let (refine, coarsen) = (2.0 * rng.unit(), rng.unit());
        p.refine_morph_s = pick(rng, &[0.0, 32.0 / 60.0, refine]);
        p.coarsen_morph_s = pick(rng, &[0.0, 16.0 / 60.0, coarsen]);
    }

    /// One frame of flight: turn, move along the heading, and turn round past the border.
    pub fn fly(&mut self, t: &Terrain) {
        self.yaw += self.turn * FRAME_S;
        let heading = Vec3::new(self.yaw.cos(), 0.0, self.yaw.sin());
        self.eye += heading * self.speed * FRAME_S;
        let margin = 0.5 * t.size;
        let outside = self.eye.x < t.lo.x - margin
            || self.eye.x > t.hi.x + margin
            || self.eye.z < t.lo.z - margin
            || self.eye.z > t.hi.z + margin;
        if outside {
            self.yaw += PI;
            self.eye -= heading * self.speed * FRAME_S;
        }
    }

    /// The refinement view from where the pilot is.
    pub fn view(&self, t: &Terrain) -> View {
        let dir = Vec3::new(
            self.yaw.cos() * self.pitch.cos(),
            self.pitch.sin(),
            self.yaw.sin() * self.pitch.cos(),
        );
        let look = LookAt {
            eye: self.eye,
            target: self.eye + dir,
            up: Vec3::Y,
            fov_y: self.fov_y,
            near: 1e-4 * t.size,
            far: 10.0 * t.size,
        };
        look.view(self.viewport.0, self.viewport.1)
    }

    /// This frame's parameters: the knobs with the current tolerance.
    pub fn frame_params(&self) -> RefineParams {
        match &self.tolerance {
            Tolerance::Fixed(px) => RefineParams {
                tolerance_px: *px,
                ..self.params
            },
            Tolerance::Regulated(r) => r.params(self.params),
        }
    }

    /// The pixel tolerance this frame refines with.
    pub fn tolerance_px(&self) -> f32 {
        self.frame_params().tolerance_px
    }
}
