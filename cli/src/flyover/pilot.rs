//! Flights with a pilot per camera: a [`Regulator`] that sets the camera's tolerance each
//! frame to hold a polygon target, and a [`PopMeter`] that measures how far refinement moves
//! the drawn vertices. Both work between the timed refinement and emission of
//! [`fly::frame`], never inside them; their time is left out of the flight's wall time too.

use std::sync::Arc;
use std::time::{Duration, Instant};

use caveclod_core::glam::Mat4;
use caveclod_core::{CameraConfig, CameraState, Hierarchy, RefineParams, Regulator, View};

use super::fly::{self, Compaction, Flight, IndexBuffers, Record};
use super::popping::{PopMeter, PopTables, Screen};
use caveclod_io::CameraPool;

/// Frames at the start of a regulated flight that the regulation figures leave out: the
/// first refines from the base mesh, and the regulator needs a few to find the tolerance.
pub const SETTLING_FRAMES: usize = 30;

/// How close to the target a frame's active polygons must be to count as held: ±5%.
pub const HELD_WITHIN: f64 = 0.05;

/// One camera's pilot and what it saw.
pub struct Pilot {
    /// The tolerance's regulator, when the camera flies to a polygon target.
    pub regulator: Option<Regulator>,
    /// The popping meter.
    pub meter: PopMeter,
    /// Per frame, the tolerance the camera refined with, in pixels.
    pub tolerance: Vec<f32>,
    /// Most morphs running at once after a pass.
    pub max_morphing: u32,
}

impl Pilot {
    /// A pilot with a regulator for `target` polygons (none: the flight's tolerance),
    /// starting at `tolerance_px`, for a camera whose refinement visits `visit_fraction` of
    /// its front per frame (its count shows a change of tolerance over `1 / visit_fraction`
    /// frames).
    pub fn new(
        tables: Arc<PopTables>,
        target: Option<u32>,
        tolerance_px: f32,
        visit_fraction: f32,
    ) -> Self {
        // A share that is a third up to rounding visits the front in three frames.
        let frames = (1.0 / visit_fraction.clamp(1e-3, 1.0) - 1e-3).ceil();
        let frames = frames.min(f32::from(Regulator::MAX_RESPONSE_FRAMES)) as u8;
        Self {
            regulator: target.map(|t| {
                Regulator::new(t)
                    .with_tolerance(tolerance_px)
                    .with_response_frames(frames)
            }),
            meter: PopMeter::new(tables),
            tolerance: Vec::new(),
            max_morphing: 0,
        }
    }

    /// The parameters of this camera's next frame.
    fn params(&self, params: &RefineParams) -> RefineParams {
        match &self.regulator {
            Some(r) => r.params(*params),
            None => *params,
        }
    }

    /// After the frame: measures its popping and steps the regulator.
    fn after(&mut self, cam: &CameraState<'_>, screen: &Screen, used: f32, refused: u32) {
        self.tolerance.push(used);
        self.max_morphing = self.max_morphing.max(cam.morph_count());
        self.meter.observe(cam, screen);
        if let Some(r) = &mut self.regulator {
            // A camera at its budget refuses splits: each refused split is up to two
            // polygons the front wants and cannot hold. Collapses waiting for their coarsen
            // morphs still show, and the regulator tells them apart (`update_settling`).
            let wanted = refused.saturating_mul(2);
            r.update_settling(
                cam.active_polygon_count().saturating_add(wanted),
                cam.settled_polygon_count().saturating_add(wanted),
            );
        }
    }

    /// The share of frames after [`SETTLING_FRAMES`] whose active polygons lie within
    /// [`HELD_WITHIN`] of the target (`None` without a regulator).
    pub fn held_share(&self, rec: &Record) -> Option<f64> {
        let target = f64::from(self.regulator?.target());
        let after = rec.active_polygons.get(SETTLING_FRAMES..).unwrap_or(&[]);
        let held = after
            .iter()
            .filter(|&&p| (f64::from(p) / target - 1.0).abs() <= HELD_WITHIN)
            .count();
        Some(held as f64 / after.len().max(1) as f64)
    }

    /// The share of frames after [`SETTLING_FRAMES`] that refined at the regulator's floor
    /// ([`Regulator::DEFAULT_MIN_TOLERANCE`]) and still drew fewer polygons than the target
    /// less [`HELD_WITHIN`]: frames whose view holds too few polygons for any tolerance down
    /// to the floor to reach the target, which [`held_share`](Self::held_share) can therefore
    /// not count (`None` without a regulator).
    pub fn out_of_reach_share(&self, rec: &Record) -> Option<f64> {
        let target = f64::from(self.regulator?.target());
        let counts = rec.active_polygons.get(SETTLING_FRAMES..).unwrap_or(&[]);
        let used = self.tolerance.get(SETTLING_FRAMES..).unwrap_or(&[]);
        let out = counts
            .iter()
            .zip(used)
            .filter(|&(&p, &t)| {
                t <= Regulator::DEFAULT_MIN_TOLERANCE && f64::from(p) < target * (1.0 - HELD_WITHIN)
            })
            .count();
        Some(out as f64 / counts.len().max(1) as f64)
    }

    /// How many times the tolerance's step changed direction (frames that held it left
    /// out): the regulator's oscillations, which a moving view also causes a few of.
    pub fn sign_changes(&self) -> u32 {
        let mut last = 0.0f32;
        let mut changes = 0;
        for w in self.tolerance.windows(2) {
            let s = (w[1] - w[0]).signum() * f32::from(w[1] != w[0]);
            if s != 0.0 {
                changes += u32::from(last != 0.0 && s != last);
                last = s;
            }
        }
        changes
    }

    /// Mean, least and largest tolerance over the flight, in pixels.
    pub fn tolerance_range(&self) -> (f64, f32, f32) {
        let mean = fly::mean(self.tolerance.iter().map(|&t| f64::from(t)));
        let min = self.tolerance.iter().copied().fold(f32::INFINITY, f32::min);
        let max = self.tolerance.iter().copied().fold(0.0, f32::max);
        (mean, if min.is_finite() { min } else { 0.0 }, max)
    }
}

/// A flight of every camera on one thread, each with its own state of capacity `config` and
/// its pilot: camera `c` refines to `views[c][f]`, and its popping is projected with
/// `view_projs[c][f]`; each state compacts as `compaction` says and emits into one of
/// `in_flight` index lists in turn.
#[allow(clippy::too_many_arguments)]
pub fn fly_piloted(
    h: &Hierarchy<'_>,
    views: &[Vec<View>],
    view_projs: &[Vec<Mat4>],
    params: &RefineParams,
    config: &CameraConfig,
    in_flight: usize,
    compaction: Compaction,
    pilots: &mut [Pilot],
) -> Result<Flight, String> {
    let in_flight = in_flight.max(1);
    let start = Instant::now();
    let mut measuring = Duration::ZERO;
    let mut pool = CameraPool::new(CameraState::words_needed_for(h, config), views.len());
    let mut cams = fly::cameras(h, &mut pool, config)?;
    let (camera_bytes, morph_bytes) = fly::state_bytes(cams.first());
    let mut outs: Vec<Vec<IndexBuffers>> = views
        .iter()
        .map(|_| fly::index_lists(h, config, in_flight))
        .collect();
    let frames = views.first().map_or(0, Vec::len);
    let mut records = Record::per_camera(views);
    for f in 0..frames {
        for k in 0..cams.len() {
            // Forwards in even frames, backwards in odd ones, as the fly-over's one thread.
            let c = if f % 2 == 1 { cams.len() - 1 - k } else { k };
            let (pilot, cam) = (&mut pilots[c], &mut cams[c]);
            let p = pilot.params(params);
            let compact = fly::compact_now(f, compaction);
            let view = &views[c][f];
            let out = outs[c].get_mut(f % in_flight);
            let refusals_before = records[c].refusals;
            fly::frame(h, cam, view, &p, out, &mut records[c], compact)?;
            let t = Instant::now();
            let screen = Screen {
                view_proj: view_projs[c][f],
                eye: view.eye,
            };
            let refused = records[c].refusals - refusals_before;
            pilot.after(cam, &screen, p.tolerance_px, refused as u32);
            measuring += t.elapsed();
        }
    }
    Ok(Flight {
        records,
        camera_bytes,
        morph_bytes,
        wall: start.elapsed().saturating_sub(measuring),
        segment_walls: Vec::new(),
    })
}
