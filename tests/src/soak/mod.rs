//! A soak of the runtime: four cameras over one shared hierarchy of a real terrain, for
//! many frames, with everything a runtime does to them drawn at random from one seed.
//!
//! Each frame, each camera flies a step ([`pilot`]) and may be teleported, change speed,
//! tolerance (fixed or regulated), viewport, the bounds of a refinement call (whole passes,
//! amortised shares, visit and operation caps), culling and the morph clock; be reset,
//! compacted whole, or take a step of an incremental compaction; have a random active node
//! force-split or its parent collapsed through the operations API, or its morphs finished.
//! Then it is refined and its indices are emitted into the caller's buffers in one of the
//! four forms (packed or per-surface lists, plain or morphed), and a camera keeping index
//! edits applies them to its copy of its index buffer ([`edits`]). Now and then every camera
//! is made again in its own memory with a new capacity ([`pilot::draw_config`]: full or a
//! polygon budget, morph memory or none, hashed pair map, index cache, index edits, small
//! forced-split stacks).
//!
//! Every frame checks what is cheap (the counts a pass reports against the camera's, the
//! capacity, emitted counts); every `check_every` frames, and after the last,
//! [`FrontChecker`] checks every camera's full invariants from scratch, and each edited copy
//! against morphed emission (allocations outside the frame loop's count). The frame loop
//! allocates nothing: set-up sizes every buffer, and [`run`] counts the allocations of the
//! loop with the caller's counter (a counting global allocator), reporting them.

pub mod edits;
pub mod invariants;
pub mod pilot;
pub mod streamed;
pub mod terrain;

use std::fmt;
use std::hint::black_box;

use caveclod_core::{CameraConfig, CameraState, Hierarchy, NodeId, OpError, RefineStats};

use edits::{EditedCopy, MAX_MOVES};
pub use invariants::{Checked, FrontChecker};
use pilot::{draw_config, one_in, Pilot, Terrain, Tolerance, EDIT_LIST, MAX_MORPHS};

use caveclod_bake::generate::SplitMix64;

/// Cameras over the shared hierarchy.
pub const CAMERAS: usize = 4;

/// What to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SoakConfig {
    /// Frames; each refines every camera once.
    pub frames: u64,
    /// The seed every random choice comes from.
    pub seed: u64,
    /// Frames between full invariant checks of every camera.
    pub check_every: u64,
}

/// What a soak did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SoakReport {
    /// Frames run.
    pub frames: u64,
    /// Refinement calls (frames × cameras).
    pub refinements: u64,
    /// Splits applied by refinement, forced ones included.
    pub splits: u64,
    /// Of those, splits forced to make a wanted one legal.
    pub forced_splits: u64,
    /// Collapses applied by refinement.
    pub collapses: u64,
    /// Splits applied by forced splits through the operations API.
    pub api_splits: u64,
    /// Collapses applied through the operations API.
    pub api_collapses: u64,
    /// Operations refused through the API for capacity or stack (expected on budgets).
    pub api_refusals: u64,
    /// Morphs begun, ended, turned back and dropped (memory full).
    pub morphs_started: u64,
    pub morphs_finished: u64,
    pub morphs_aborted: u64,
    pub morphs_dropped: u64,
    /// Splits refused because a budgeted camera was full.
    pub capacity_refusals: u64,
    /// Wanted splits abandoned because the forced-split stack was full.
    pub stack_overflows: u64,
    /// Active-node visits of refinement.
    pub nodes_visited: u64,
    /// Teleports, resets, cameras made again with a new capacity.
    pub teleports: u64,
    pub resets: u64,
    pub reconfigurations: u64,
    /// Whole compactions, incremental steps, and incremental cycles finished.
    pub compactions: u64,
    pub compaction_steps: u64,
    pub compaction_cycles: u64,
    /// Calls of `finish_morphs`.
    pub morph_finishes: u64,
    /// Indices emitted into the caller's buffers.
    pub indices_emitted: u64,
    /// Index edits applied to the cameras' copies of their index buffers.
    pub edits_applied: u64,
    /// Most active polygons of one camera after a pass.
    pub max_active_polygons: u32,
    /// Full invariant checks (one camera each) and what they covered.
    pub invariant_checks: u64,
    pub checked: Checked,
    /// Allocations during the frame loop (the caller's progress reports excluded).
    pub allocations: u64,
    /// A hash of every pass's counts: equal for equal seeds.
    pub fingerprint: u64,
}

impl SoakReport {
    /// Operations of every kind: splits and collapses by refinement and the API, and morphs
    /// begun.
    pub fn operations(&self) -> u64 {
        self.splits + self.collapses + self.api_splits + self.api_collapses + self.morphs_started
    }

    fn add_pass(&mut self, s: &RefineStats) {
        self.refinements += 1;
        self.splits += u64::from(s.splits);
        self.forced_splits += u64::from(s.forced_splits);
        self.collapses += u64::from(s.collapses);
        self.morphs_started += u64::from(s.morphs_started);
        self.morphs_finished += u64::from(s.morphs_finished);
        self.morphs_aborted += u64::from(s.morphs_aborted);
        self.morphs_dropped += u64::from(s.morphs_dropped);
        self.capacity_refusals += u64::from(s.capacity_refusals);
        self.stack_overflows += u64::from(s.stack_overflows);
        self.nodes_visited += u64::from(s.nodes_visited);
        self.max_active_polygons = self.max_active_polygons.max(s.active_polygons);
        for x in [
            s.splits,
            s.collapses,
            s.active_polygons,
            s.morphing,
            s.nodes_visited,
        ] {
            self.fingerprint = (self.fingerprint ^ u64::from(x)).wrapping_mul(0x100_0000_01b3);
        }
    }
}

/// Where and why a soak failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SoakError {
    /// The seed, to reproduce it.
    pub seed: u64,
    /// The frame (counting from 0).
    pub frame: u64,
    /// The camera.
    pub camera: usize,
    /// What went wrong.
    pub what: String,
}

impl fmt::Display for SoakError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "soak seed {} frame {} camera {}: {}",
            self.seed, self.frame, self.camera, self.what
        )
    }
}

impl std::error::Error for SoakError {}

/// The caller's buffers every camera emits into.
struct Outputs {
    packed: Vec<u32>,
    offsets: Vec<u32>,
    written: Vec<u32>,
}

/// Runs the soak over `h`; `allocations` reads the caller's allocation counter (of this
/// thread), and `progress` is called after every full check with the report so far.
pub fn run(
    h: &Hierarchy<'_>,
    config: &SoakConfig,
    allocations: &dyn Fn() -> u64,
    progress: &mut dyn FnMut(&SoakReport),
) -> Result<SoakReport, SoakError> {
    let fail = |frame: u64, camera: usize, what: String| SoakError {
        seed: config.seed,
        frame,
        camera,
        what,
    };
    // Set-up: everything that allocates.
    let largest = CameraConfig::full(h)
        .with_morphs(MAX_MORPHS)
        .with_index_edits(EDIT_LIST);
    let words = CameraState::words_needed_for(h, &largest);
    let mut memory: [Vec<u32>; CAMERAS] = std::array::from_fn(|_| vec![0u32; words]);
    let places = (h.base_polygon_count() + 2 * h.splits().len()) * h.surface_count();
    let mut copies: [EditedCopy; CAMERAS] = std::array::from_fn(|_| EditedCopy::new(h, places));
    let mut checker = FrontChecker::new(h);
    let most = 3 * h.polygon_count();
    let mut out = Outputs {
        packed: vec![0; most],
        offsets: vec![0; h.surface_count() + 1],
        written: vec![0; h.surface_count()],
    };
    let mut lists: Vec<Vec<u32>> = (0..h.surface_count()).map(|_| vec![0; most]).collect();
    let mut slices: Vec<&mut [u32]> = lists.iter_mut().map(Vec::as_mut_slice).collect();
    let terrain = Terrain::of(h.meta());
    let mut rng = SplitMix64::new(config.seed);
    let mut pilots: [Pilot; CAMERAS] = std::array::from_fn(|_| Pilot::new(&mut rng, &terrain));
    let mut report = SoakReport::default();
    let check_every = config.check_every.max(1);

    let start = allocations();
    let mut outside = 0;
    let mut frame = 0;
    while frame < config.frames {
        // A life of the cameras: each made in its memory with a new capacity.
        let life =
            (check_every + rng.below(9 * check_every as usize) as u64).min(config.frames - frame);
        let configs: [CameraConfig; CAMERAS] = std::array::from_fn(|_| draw_config(&mut rng, h));
        let [m0, m1, m2, m3] = &mut memory;
        let made = [
            CameraState::with_config(h, m0, &configs[0]),
            CameraState::with_config(h, m1, &configs[1]),
            CameraState::with_config(h, m2, &configs[2]),
            CameraState::with_config(h, m3, &configs[3]),
        ];
        if let Some((c, Err(e))) = made.iter().enumerate().find(|(_, m)| m.is_err()) {
            return Err(fail(frame, c, format!("camera with {:?}: {e}", configs[c])));
        }
        let mut cams = made.map(|m| m.ok());
        report.reconfigurations += CAMERAS as u64;
        for _ in 0..life {
            for (c, ((cam, pilot), copy)) in cams
                .iter_mut()
                .zip(&mut pilots)
                .zip(&mut copies)
                .enumerate()
            {
                let Some(cam) = cam.as_mut() else { continue };
                let moves = rng.below(MAX_MOVES as usize + 1) as u32;
                copy.update(h, cam, moves).map_err(|e| fail(frame, c, e))?;
                camera_frame(
                    h,
                    cam,
                    pilot,
                    &terrain,
                    &mut rng,
                    &mut out,
                    &mut slices,
                    &mut report,
                )
                .map_err(|e| fail(frame, c, e))?;
            }
            frame += 1;
            report.frames = frame;
            if frame % check_every == 0 || frame == config.frames {
                for (c, (cam, copy)) in cams.iter_mut().zip(&mut copies).enumerate() {
                    let Some(cam) = cam.as_mut() else { continue };
                    let done = checker.check(h, cam).map_err(|e| fail(frame - 1, c, e))?;
                    report.invariant_checks += 1;
                    add_checked(&mut report.checked, &done);
                    let before = allocations();
                    check_copy(h, cam, copy, &mut out).map_err(|e| fail(frame - 1, c, e))?;
                    report.edits_applied += copy.applied;
                    copy.applied = 0;
                    outside += allocations() - before;
                }
                report.allocations = allocations() - start - outside;
                let before = allocations();
                progress(&report);
                outside += allocations() - before;
            }
        }
    }
    report.allocations = allocations() - start - outside;
    Ok(report)
}

/// Brings `copy` up to `cam`'s front and checks it against morphed emission.
fn check_copy(
    h: &Hierarchy<'_>,
    cam: &mut CameraState<'_>,
    copy: &mut EditedCopy,
    out: &mut Outputs,
) -> Result<(), String> {
    copy.update(h, cam, 0)?;
    cam.emit_indices_packed_morphed(h, &mut out.packed, &mut out.offsets)
        .map_err(|e| format!("emission: {e}"))?;
    copy.check(cam, &out.packed, &out.offsets)
}

fn add_checked(total: &mut Checked, c: &Checked) {
    total.nodes += c.nodes;
    total.polygons += c.polygons;
    total.links += c.links;
    total.indices += c.indices;
    total.morph_slots += c.morph_slots;
}

/// One camera's frame: events, flight, refinement, the cheap checks, emission.
#[allow(clippy::too_many_arguments)]
fn camera_frame(
    h: &Hierarchy<'_>,
    cam: &mut CameraState<'_>,
    pilot: &mut Pilot,
    terrain: &Terrain,
    rng: &mut SplitMix64,
    out: &mut Outputs,
    slices: &mut [&mut [u32]],
    report: &mut SoakReport,
) -> Result<(), String> {
    redraw_knobs(h, pilot, terrain, rng, report);
    maintain(h, cam, pilot, rng, report);
    operate(h, cam, rng, report)?;
    pilot.fly(terrain);
    let view = pilot.view(terrain);
    let params = pilot.frame_params();
    let stats = cam
        .refine(h, &view, &params)
        .map_err(|e| format!("refine: {e}"))?;
    report.add_pass(&stats);
    check_pass(cam, &stats)?;
    if let Tolerance::Regulated(r) = &mut pilot.tolerance {
        r.update(stats.active_polygons + 2 * stats.capacity_refusals);
    }
    if one_in(rng, 100) {
        black_box(
            cam.lag(h, &view, &params)
                .map_err(|e| format!("lag: {e}"))?,
        );
    }
    emit(h, cam, rng, out, slices, report)
}

/// The pilot's random changes of course and knobs.
fn redraw_knobs(
    h: &Hierarchy<'_>,
    pilot: &mut Pilot,
    terrain: &Terrain,
    rng: &mut SplitMix64,
    report: &mut SoakReport,
) {
    if one_in(rng, 500) {
        pilot.teleport(rng, terrain);
        report.teleports += 1;
    }
    if one_in(rng, 300) {
        pilot.draw_speed(rng);
    }
    if one_in(rng, 400) {
        let from = pilot.tolerance_px();
        pilot.draw_tolerance(rng, from, h.polygon_count());
    }
    if one_in(rng, 400) {
        pilot.draw_bounds(rng);
    }
    if one_in(rng, 500) {
        pilot.draw_clock(rng);
    }
}

/// Resets, compactions (whole, or incremental cycles a budget per frame), finished morphs.
fn maintain(
    h: &Hierarchy<'_>,
    cam: &mut CameraState<'_>,
    pilot: &mut Pilot,
    rng: &mut SplitMix64,
    report: &mut SoakReport,
) {
    if one_in(rng, 3000) {
        cam.reset(h);
        report.resets += 1;
    }
    if one_in(rng, 700) {
        cam.compact(h);
        report.compactions += 1;
    }
    if pilot.compaction_budget.is_none() && one_in(rng, 300) {
        pilot.compaction_budget = Some(1 << (4 + rng.below(12)));
    }
    if let Some(budget) = pilot.compaction_budget {
        let p = cam.compact_step(h, budget);
        report.compaction_steps += 1;
        if p.finished {
            report.compaction_cycles += 1;
            pilot.compaction_budget = None;
        }
    }
    if one_in(rng, 2000) {
        cam.finish_morphs();
        report.morph_finishes += 1;
    }
}

/// Now and then, through the operations API, a forced split of a random active node or a
/// collapse of its parent when legal (refinement may undo either on its next pass).
fn operate(
    h: &Hierarchy<'_>,
    cam: &mut CameraState<'_>,
    rng: &mut SplitMix64,
    report: &mut SoakReport,
) -> Result<(), String> {
    if !one_in(rng, 50) {
        return Ok(());
    }
    let k = rng.below(cam.active_node_count().max(1) as usize);
    let Some(v) = cam.active_nodes().nth(k) else {
        return Err(format!(
            "active node {k} of {} missing",
            cam.active_node_count()
        ));
    };
    let parent = h.node(v).map_or(NodeId::NONE, |n| n.parent);
    if one_in(rng, 2) && parent.is_some() && cam.can_collapse(h, parent) {
        cam.collapse(h, parent)
            .map_err(|e| format!("collapse({parent}) after can_collapse: {e}"))?;
        report.api_collapses += 1;
    } else if h.split(v).is_some() {
        match cam.force_split_own_stack(h, v) {
            Ok(n) => report.api_splits += u64::from(n),
            Err(OpError::CapacityFull { .. } | OpError::StackFull { .. }) => {
                report.api_refusals += 1;
            }
            Err(e) => return Err(format!("force_split({v}): {e}")),
        }
    }
    Ok(())
}

/// What every pass must agree with.
fn check_pass(cam: &CameraState<'_>, s: &RefineStats) -> Result<(), String> {
    if s.active_polygons != cam.active_polygon_count() || s.active_nodes != cam.active_node_count()
    {
        return Err(format!(
            "pass reports {} nodes, {} polygons; camera has {}, {}",
            s.active_nodes,
            s.active_polygons,
            cam.active_node_count(),
            cam.active_polygon_count()
        ));
    }
    if cam.split_count() > cam.max_pairs() {
        return Err(format!(
            "{} splits, room for {}",
            cam.split_count(),
            cam.max_pairs()
        ));
    }
    if s.morphing != cam.morph_count() || cam.morph_count() > cam.max_morphs() {
        return Err(format!(
            "pass reports {} morphing, camera {} (room for {})",
            s.morphing,
            cam.morph_count(),
            cam.max_morphs()
        ));
    }
    Ok(())
}

/// Emission into the caller's buffers, in one of the four forms.
fn emit(
    h: &Hierarchy<'_>,
    cam: &CameraState<'_>,
    rng: &mut SplitMix64,
    out: &mut Outputs,
    slices: &mut [&mut [u32]],
    report: &mut SoakReport,
) -> Result<(), String> {
    let emitted = match rng.below(4) {
        0 => cam.emit_indices_packed(h, &mut out.packed, &mut out.offsets),
        1 => cam.emit_indices_packed_morphed(h, &mut out.packed, &mut out.offsets),
        2 => cam.emit_indices(h, slices, &mut out.written),
        _ => cam.emit_indices_morphed(h, slices, &mut out.written),
    }
    .map_err(|e| format!("emission: {e}"))?;
    if emitted != cam.total_index_count() {
        return Err(format!(
            "emitted {emitted} indices, {} expected",
            cam.total_index_count()
        ));
    }
    report.indices_emitted += emitted as u64;
    Ok(())
}
