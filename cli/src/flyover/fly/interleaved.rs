//! Several flights flown interleaved, segment by segment, so that the flights compared see
//! the same load.

use std::time::{Duration, Instant};

use caveclod_core::{CameraConfig, CameraState, Hierarchy, RefineParams, View};

use super::common::{
    camera_order, compact_now, frame, index_lists, pin, placement, state_bytes, Compaction, Flight,
    IndexBuffers, Record,
};
use crate::flyover::gate::FrameGate;
use caveclod_io::CameraPool;

/// One of the flights [`fly_interleaved`] flies: its cameras' views, their capacity, and
/// whether each camera has a thread.
pub struct Group<'v> {
    /// Per camera, its views.
    pub views: &'v [Vec<View>],
    /// The capacity of every camera of the group.
    pub config: CameraConfig,
    /// A thread per camera (frames within the frames in flight, as in [`fly_per_camera`](super::fly_per_camera)).
    pub threads: bool,
    /// Frames in flight: index lists per camera, and how far apart camera threads may run
    /// (0 counts as 1).
    pub in_flight: usize,
    /// Refinement knobs.
    pub params: RefineParams,
    /// How each state compacts.
    pub compaction: Compaction,
    /// With threads, pin each camera's thread to a core, the cameras shared out by their
    /// cost over the previous segment (see `placement`), or in the first segment by these
    /// costs (from a sizing flight; equal costs without).
    pub pin: bool,
    /// Each camera's cost before the flight, for pinning its first segment.
    pub first_costs: Option<&'v [f64]>,
}

/// Camera states, index lists and records of one group.
struct Flying<'m> {
    cams: Vec<CameraState<'m>>,
    /// Per camera, its index lists (one per frame in flight).
    outs: Vec<Vec<IndexBuffers>>,
    records: Vec<Record>,
    walls: Vec<Duration>,
}

/// Frames `frames` of one group: each camera refines, emits and records its frame; with
/// threads, a thread per camera, frames within the group's frames in flight.
fn fly_segment(
    h: &Hierarchy<'_>,
    g: &mut Flying<'_>,
    group: &Group<'_>,
    frames: std::ops::Range<usize>,
) -> Result<(), String> {
    let (views, params, compaction) = (group.views, &group.params, group.compaction);
    let in_flight = group.in_flight.max(1);
    if !group.threads {
        for f in frames {
            for c in camera_order(f, g.cams.len()) {
                frame(
                    h,
                    &mut g.cams[c],
                    &views[c][f],
                    params,
                    g.outs[c].get_mut(f % in_flight),
                    &mut g.records[c],
                    compact_now(f, compaction),
                )?;
            }
        }
        return Ok(());
    }
    let gate = FrameGate::new(g.cams.len(), in_flight);
    let costs = group.pin.then(|| match group.first_costs {
        Some(first) if frames.start == 0 => first.to_vec(),
        _ => recent_costs(&g.records, frames.start),
    });
    let (cores, core_of) = placement(costs.as_deref());
    let (cores, core_of) = (&cores, &core_of);
    std::thread::scope(|scope| {
        let handles: Vec<_> = g
            .cams
            .iter_mut()
            .zip(g.outs.iter_mut())
            .zip(g.records.iter_mut())
            .zip(views)
            .enumerate()
            .map(|(c, (((cam, out), rec), cam_views))| {
                let (gate, frames) = (&gate, frames.clone());
                scope.spawn(move || -> Result<(), String> {
                    pin(cores, core_of, c);
                    let mut failed = Ok(());
                    for (n, f) in frames.enumerate() {
                        gate.enter(n);
                        if failed.is_ok() {
                            failed = frame(
                                h,
                                cam,
                                &cam_views[f],
                                params,
                                out.get_mut(f % in_flight),
                                rec,
                                compact_now(f, compaction),
                            );
                        }
                        gate.leave(c);
                    }
                    failed
                })
            })
            .collect();
        handles
            .into_iter()
            .try_for_each(|t| t.join().map_err(|_| "camera thread panicked".to_string())?)
    })
}

/// Each camera's refinement and emission time over its last `SEGMENT_COST_FRAMES` frames
/// before frame `before` (equal costs before any frame was flown).
fn recent_costs(records: &[Record], before: usize) -> Vec<f64> {
    records
        .iter()
        .map(|r| {
            let end = before.min(r.refine_ns.len()).min(r.emit_ns.len());
            let start = end.saturating_sub(SEGMENT_COST_FRAMES);
            (start..end)
                .map(|i| (r.refine_ns[i] + r.emit_ns[i]) as f64)
                .sum::<f64>()
                .max(1.0)
        })
        .collect()
}

/// Frames of each camera's recent past that its cost is measured over, for pinning.
const SEGMENT_COST_FRAMES: usize = 30;

/// Flies several groups of cameras over the same frames, interleaved: every group flies
/// frames `0..segment`, then every group `segment..2 * segment`, and so on, each group with
/// its own states and index lists, refining and emitting every frame.
///
/// Flights measured one after the other on a shared machine are compared across whatever
/// else ran meanwhile, which can move a ratio of two flights more than the effect measured.
/// Interleaved, the flights compared see the same load within a segment (a second or less).
/// A group's cameras still run only their own frames in a row within a segment, so a camera
/// flown alone keeps its caches to itself as it would alone; only the first frame of a
/// segment starts after the other groups, and the per-frame figures are middle values, which
/// one such frame in a segment barely moves.
pub fn fly_interleaved(
    h: &Hierarchy<'_>,
    groups: &[Group<'_>],
    segment: usize,
) -> Result<Vec<Flight>, String> {
    let segment = segment.max(1);
    // Every group's cameras in one pool, so that all of them, the cameras flown alone too,
    // get the same kind of pages.
    let words = groups
        .iter()
        .map(|g| CameraState::words_needed_for(h, &g.config))
        .max()
        .unwrap_or(0);
    let mut pool = CameraPool::new(words, groups.iter().map(|g| g.views.len()).sum());
    let mut memories = pool.memories();
    let mut flying = Vec::with_capacity(groups.len());
    for g in groups {
        let frames = g.views.first().map_or(0, Vec::len);
        let mut cams = Vec::with_capacity(g.views.len());
        for _ in g.views {
            let m = memories.next().ok_or("the camera pool is short")?;
            cams.push(CameraState::with_config(h, m, &g.config).map_err(|e| e.to_string())?);
        }
        flying.push(Flying {
            cams,
            outs: g
                .views
                .iter()
                .map(|_| index_lists(h, &g.config, g.in_flight.max(1)))
                .collect(),
            records: g
                .views
                .iter()
                .map(|_| Record::with_capacity(frames))
                .collect(),
            walls: Vec::new(),
        });
    }
    let frames = groups
        .iter()
        .map(|g| g.views.first().map_or(0, Vec::len))
        .min()
        .unwrap_or(0);
    for start in (0..frames).step_by(segment) {
        let end = (start + segment).min(frames);
        for (g, fl) in groups.iter().zip(flying.iter_mut()) {
            let t = Instant::now();
            fly_segment(h, fl, g, start..end)?;
            fl.walls.push(t.elapsed());
        }
    }
    Ok(flying
        .into_iter()
        .map(|fl| Flight {
            camera_bytes: state_bytes(fl.cams.first()).0,
            morph_bytes: state_bytes(fl.cams.first()).1,
            records: fl.records,
            wall: fl.walls.iter().sum(),
            segment_walls: fl.walls,
        })
        .collect())
}
