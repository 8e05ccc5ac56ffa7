//! What every flight shares: the per-frame records and their summary, one camera's frame,
//! the index lists and the cores camera threads are pinned to.

use std::time::{Duration, Instant};

use caveclod_core::{
    CameraConfig, CameraState, FrontLag, Hierarchy, IndexEdit, RefineParams, RefineStats,
    SurfaceDraw, View,
};

use caveclod_io::CameraPool;

use crate::flyover::placement::{balance, Cores};

/// Per-frame figures of one camera.
#[derive(Clone, Debug, Default)]
pub struct Record {
    pub ops: Vec<u32>,
    pub splits: u64,
    pub forced: u64,
    pub collapses: u64,
    pub refine_ns: Vec<u64>,
    /// Per frame, the refining thread's CPU time for the same work as `refine_ns`: the
    /// wall time less what other processes took while it was preempted.
    pub refine_cpu_ns: Vec<u64>,
    pub emit_ns: Vec<u64>,
    pub active_polygons: Vec<u32>,
    pub max_active_nodes: u32,
    pub indices: Vec<u32>,
    pub refusals: u64,
    pub overflows: u64,
    /// Per frame, the share of active nodes over the tolerance ([`FrontLag::share`]).
    pub lag_share: Vec<f32>,
    /// Per frame, their excess over the tolerance in pixels, per active node.
    pub lag_px: Vec<f32>,
    /// The largest excess of any node in any frame, in pixels.
    pub lag_worst_px: f32,
    pub morphs_started: u64,
    pub morphs_dropped: u64,
    /// Per frame with index edits: the time to take them, the edits, and the polygons
    /// whose places they wrote (edits less hole moves).
    pub edits_ns: Vec<u64>,
    pub edits: Vec<u32>,
    pub edit_changes: Vec<u32>,
    /// Frames whose edits rewrote every place (a reset, or more changes than the list).
    pub edits_everything: u64,
}

impl Record {
    /// An empty record per camera of `views`, each with room for the flight's frames.
    pub fn per_camera(views: &[Vec<View>]) -> Vec<Self> {
        let frames = views.first().map_or(0, Vec::len);
        views.iter().map(|_| Self::with_capacity(frames)).collect()
    }

    pub fn with_capacity(frames: usize) -> Self {
        Self {
            ops: Vec::with_capacity(frames),
            refine_ns: Vec::with_capacity(frames),
            refine_cpu_ns: Vec::with_capacity(frames),
            emit_ns: Vec::with_capacity(frames),
            active_polygons: Vec::with_capacity(frames),
            indices: Vec::with_capacity(frames),
            lag_share: Vec::with_capacity(frames),
            lag_px: Vec::with_capacity(frames),
            ..Self::default()
        }
    }

    pub fn push(&mut self, st: &RefineStats, refine: Duration, emit: Duration, indices: usize) {
        self.ops.push(st.operations());
        self.splits += u64::from(st.splits);
        self.forced += u64::from(st.forced_splits);
        self.collapses += u64::from(st.collapses);
        self.refine_ns.push(refine.as_nanos() as u64);
        self.emit_ns.push(emit.as_nanos() as u64);
        self.active_polygons.push(st.active_polygons);
        self.max_active_nodes = self.max_active_nodes.max(st.active_nodes);
        self.indices.push(indices as u32);
        self.refusals += u64::from(st.capacity_refusals);
        self.overflows += u64::from(st.stack_overflows);
        self.morphs_started += u64::from(st.morphs_started);
        self.morphs_dropped += u64::from(st.morphs_dropped);
    }

    /// Records a frame's index edits, taken in `took`.
    pub fn push_edits(&mut self, e: &caveclod_core::IndexEdits, took: Duration) {
        self.edits_ns.push(took.as_nanos() as u64);
        self.edits.push(e.edits as u32);
        self.edit_changes
            .push((e.edits as u32).saturating_sub(e.moves));
        self.edits_everything += u64::from(e.everything);
    }

    /// Mean time to take a frame's index edits, ms (0 without edits).
    pub fn edits_ms_mean(&self) -> f64 {
        mean(Self::steady(&self.edits_ns).iter().map(|&x| x as f64)) * 1e-6
    }

    /// Bytes the edits of the steady frames write to the device per changed polygon: each
    /// edit is [`IndexEdit`]'s 16 bytes, a place and its three indices.
    pub fn edit_bytes_per_change(&self) -> f64 {
        let edits: u64 = Self::steady(&self.edits)
            .iter()
            .map(|&x| u64::from(x))
            .sum();
        let changes: u64 = Self::steady(&self.edit_changes)
            .iter()
            .map(|&x| u64::from(x))
            .sum();
        (edits * std::mem::size_of::<IndexEdit>() as u64) as f64 / changes.max(1) as f64
    }

    /// Mean edits per frame.
    pub fn edits_mean(&self) -> f64 {
        mean(Self::steady(&self.edits).iter().map(|&x| f64::from(x)))
    }

    /// Records how far the front lags its view (measured outside the timed work).
    pub fn push_lag(&mut self, lag: &FrontLag) {
        self.lag_share.push(lag.share());
        self.lag_px
            .push(lag.excess_px / lag.active_nodes.max(1) as f32);
        self.lag_worst_px = self.lag_worst_px.max(lag.worst_excess_px);
    }

    /// The mean share of active nodes over the tolerance.
    pub fn lag_share_mean(&self) -> f64 {
        mean(Self::steady(&self.lag_share).iter().map(|&x| f64::from(x)))
    }

    /// The mean excess over the tolerance per active node, in pixels.
    pub fn lag_px_mean(&self) -> f64 {
        mean(Self::steady(&self.lag_px).iter().map(|&x| f64::from(x)))
    }

    /// Frames after the first: the first frame refines from the base mesh.
    pub fn steady<T: Copy>(v: &[T]) -> &[T] {
        v.get(1..).unwrap_or(&[])
    }

    pub fn ops_mean(&self) -> f64 {
        mean(Self::steady(&self.ops).iter().map(|&x| f64::from(x)))
    }

    pub fn ops_max(&self) -> u32 {
        Self::steady(&self.ops).iter().copied().max().unwrap_or(0)
    }

    pub fn refine_ms_mean(&self) -> f64 {
        mean(Self::steady(&self.refine_ns).iter().map(|&x| x as f64)) * 1e-6
    }

    /// Median refinement time per frame, ms (robust to the machine's bursts).
    pub fn refine_ms_median(&self) -> f64 {
        percentile(Self::steady(&self.refine_ns), 0.5) as f64 * 1e-6
    }

    pub fn refine_ms_p99(&self) -> f64 {
        percentile(Self::steady(&self.refine_ns), 0.99) as f64 * 1e-6
    }

    /// The 99th percentile of the refining thread's CPU time per frame, ms (0 where it was
    /// not measured).
    pub fn refine_cpu_ms_p99(&self) -> f64 {
        percentile(Self::steady(&self.refine_cpu_ns), 0.99) as f64 * 1e-6
    }

    /// Median emission time per frame, ms.
    pub fn emit_ms_median(&self) -> f64 {
        percentile(Self::steady(&self.emit_ns), 0.5) as f64 * 1e-6
    }

    pub fn emit_ms_mean(&self) -> f64 {
        mean(Self::steady(&self.emit_ns).iter().map(|&x| x as f64)) * 1e-6
    }

    pub fn active_mean(&self) -> f64 {
        mean(
            Self::steady(&self.active_polygons)
                .iter()
                .map(|&x| f64::from(x)),
        )
    }

    pub fn active_max(&self) -> u32 {
        self.active_polygons.iter().copied().max().unwrap_or(0)
    }

    pub fn indices_total(&self) -> u64 {
        self.indices.iter().map(|&x| u64::from(x)).sum()
    }
}

/// The mean (0 for none).
pub fn mean(it: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for x in it {
        s += x;
        n += 1;
    }
    if n == 0 {
        0.0
    } else {
        s / n as f64
    }
}

/// The `q`-quantile (nearest rank; 0 for none).
pub fn percentile(v: &[u64], q: f64) -> u64 {
    if v.is_empty() {
        return 0;
    }
    let mut s = v.to_vec();
    s.sort_unstable();
    let i = ((s.len() as f64 * q).ceil() as usize).clamp(1, s.len()) - 1;
    s[i]
}

/// Index output of one camera, allocated once and reused every frame.
pub struct IndexBuffers {
    /// Indices of all surfaces, packed.
    pub indices: Vec<u32>,
    /// Where each surface starts in `indices`.
    pub offsets: Vec<u32>,
    /// A camera's index edits of a frame, and its surfaces' draws.
    pub edits: Vec<IndexEdit>,
    pub draws: Vec<SurfaceDraw>,
}

/// Holes closed per frame of index edits at most: a bound on the frame's extra edits; holes
/// beyond it wait for the next frames (the draws count them as degenerate triangles).
pub const HOLE_MOVES: u32 = 256;

impl IndexBuffers {
    /// Room for the largest front a camera with `max_pairs` splits can hold.
    pub fn new(h: &Hierarchy<'_>, max_pairs: u32) -> Self {
        let polys = h.base_polygon_count() + 2 * max_pairs as usize;
        Self {
            indices: vec![0; 3 * polys],
            offsets: vec![0; h.surface_count() + 1],
            edits: Vec::new(),
            draws: vec![SurfaceDraw::default(); h.surface_count()],
        }
    }
}

/// A camera's index lists: one per frame in flight (`count`, 0 when it does not emit).
pub(crate) fn index_lists(
    h: &Hierarchy<'_>,
    config: &CameraConfig,
    count: usize,
) -> Vec<IndexBuffers> {
    (0..count)
        .map(|_| IndexBuffers::new(h, config.max_pairs))
        .collect()
}

/// A camera of capacity `config` in each of `pool`'s memories.
pub(crate) fn cameras<'p>(
    h: &Hierarchy<'_>,
    pool: &'p mut CameraPool,
    config: &CameraConfig,
) -> Result<Vec<CameraState<'p>>, String> {
    pool.memories()
        .map(|m| CameraState::with_config(h, m, config).map_err(|e| e.to_string()))
        .collect()
}

/// How a flight's states compact, inside the timed refinement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Compaction {
    /// A compaction starts every this many of a state's frames (0: never).
    pub every: usize,
    /// Most work per frame of an incremental compaction ([`CameraState::compact_budget`]),
    /// every frame until its cycle ends; 0 compacts whole ([`CameraState::compact`]) when
    /// due.
    pub step: u32,
}

/// A frame's compaction: whether one is due, and how (see [`Compaction`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CompactNow {
    due: bool,
    step: u32,
}

impl CompactNow {
    /// No compaction, nor a step of one under way.
    pub const NONE: Self = Self {
        due: false,
        step: 0,
    };
}

/// Refines `cam` to `view`, emits its indices, and records the frame; then measures, outside
/// the timed work, how far the front lags the view.
pub fn frame(
    h: &Hierarchy<'_>,
    cam: &mut CameraState<'_>,
    view: &View,
    params: &RefineParams,
    out: Option<&mut IndexBuffers>,
    rec: &mut Record,
    compact: CompactNow,
) -> Result<(), String> {
    // A camera at its base mesh settles in one full pass, without morphs in its first
    // (`CameraState::refine`).
    let c0 = thread_cpu_ns();
    let t0 = Instant::now();
    // Compaction counts as refinement time: it is what keeps the next passes local.
    if compact.step == 0 && compact.due {
        cam.compact(h);
    } else if compact.step > 0 && (compact.due || cam.compacting()) {
        cam.compact_step(h, cam.compact_budget(compact.step));
    }
    let st = cam
        .refine(h, view, params)
        .map_err(|e| format!("refine: {e}"))?;
    let t1 = Instant::now();
    let c1 = thread_cpu_ns();
    let mut edits = None;
    let n = match out {
        Some(out) => {
            // A camera with morph memory points its morphing corners at their slots.
            let n = if cam.max_morphs() > 0 {
                cam.emit_indices_packed_morphed(h, &mut out.indices, &mut out.offsets)
            } else {
                cam.emit_indices_packed(h, &mut out.indices, &mut out.offsets)
            }
            .map_err(|e| format!("emit: {e}"))?;
            std::hint::black_box(&out.indices);
            if cam.index_places() > 0 {
                edits = Some(take_edits(h, cam, out)?);
            }
            n
        }
        None => 0,
    };
    let t2 = Instant::now();
    let t2 = match edits {
        Some((e, took)) => {
            rec.push_edits(&e, took);
            t2 - took
        }
        None => t2,
    };
    rec.push(&st, t1 - t0, t2 - t1, n);
    rec.refine_cpu_ns.push(c1.saturating_sub(c0));
    rec.push_lag(&cam.lag(h, view, params).map_err(|e| format!("lag: {e}"))?);
    Ok(())
}

/// Takes `cam`'s index edits into `out` (room made first, outside the time), and the time
/// they took.
fn take_edits(
    h: &Hierarchy<'_>,
    cam: &mut CameraState<'_>,
    out: &mut IndexBuffers,
) -> Result<(caveclod_core::IndexEdits, Duration), String> {
    let needed = cam.index_edits_needed(HOLE_MOVES);
    if out.edits.len() < needed {
        out.edits.resize(needed, IndexEdit::default());
    }
    let t = Instant::now();
    let e = cam
        .index_edits(h, HOLE_MOVES, &mut out.edits, &mut out.draws)
        .map_err(|e| format!("index edits: {e}"))?;
    std::hint::black_box(&out.edits);
    Ok((e, t.elapsed()))
}

/// This thread's CPU time in nanoseconds (0 where the clock cannot be read).
fn thread_cpu_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec for the duration of the call, and
    // CLOCK_THREAD_CPUTIME_ID is a clock every Linux and BSD libc provides.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    if rc != 0 {
        return 0;
    }
    (ts.tv_sec as u64)
        .saturating_mul(1_000_000_000)
        .saturating_add(ts.tv_nsec as u64)
}

/// What one flight of several cameras measured.
/// A camera's bytes without its morph memory, and its morph memory (0, 0 for none).
pub fn state_bytes(cam: Option<&CameraState<'_>>) -> (usize, usize) {
    cam.map_or((0, 0), |c| (c.bytes() - c.morph_bytes(), c.morph_bytes()))
}

#[derive(Clone)]
pub struct Flight {
    /// Per camera.
    pub records: Vec<Record>,
    /// Bytes of one camera state, without its morph memory (the paper's cameras have none).
    pub camera_bytes: usize,
    /// Bytes of one camera's morph memory.
    pub morph_bytes: usize,
    /// Wall time of the whole flight (of its segments, when flown interleaved).
    pub wall: Duration,
    /// Wall time of each segment when flown interleaved with other flights
    /// ([`fly_interleaved`](super::fly_interleaved)); empty otherwise. The reports use
    /// [`wall`](Self::wall); the tests check the segmentation with it.
    #[cfg_attr(not(test), allow(dead_code))]
    pub segment_walls: Vec<Duration>,
}

/// The order in which one thread takes its cameras in frame `n`: forwards in even frames,
/// backwards in odd ones, so the last camera of a frame is the first of the next and finds
/// its state and the records it reads still in the caches; the others wait for their turn
/// as long as in a fixed order, on average. (With a front per camera larger than a quarter
/// of the cache, a fixed order makes every camera start cold.) A renderer may order its
/// cameras freely within a frame.
pub(super) fn camera_order(n: usize, cameras: usize) -> impl Iterator<Item = usize> {
    let backwards = n % 2 == 1;
    (0..cameras).map(move |k| if backwards { cameras - 1 - k } else { k })
}

/// Whether a state starts a compaction before its `n`-th refinement (every `c.every`,
/// 0 = never), and how.
pub(crate) fn compact_now(n: usize, c: Compaction) -> CompactNow {
    CompactNow {
        due: c.every > 0 && n % c.every == c.every - 1,
        step: c.step,
    }
}

/// The cores to pin camera threads to and each camera's core, balanced by `costs` (none
/// without costs, or with fewer than two cores).
pub(super) fn placement(costs: Option<&[f64]>) -> (Option<Cores>, Vec<usize>) {
    match (costs, costs.and_then(|_| Cores::available())) {
        (Some(costs), Some(cores)) => {
            let core_of = balance(costs, cores.len());
            (Some(cores), core_of)
        }
        _ => (None, Vec::new()),
    }
}

/// Pins the calling camera thread `c` to its core, if the flight pins.
pub(super) fn pin(cores: &Option<Cores>, core_of: &[usize], c: usize) {
    if let (Some(cores), Some(&k)) = (cores, core_of.get(c)) {
        // A refusal leaves the thread where the system puts it; the flight is still valid.
        let _ = cores.pin(k);
    }
}

/// Summary over all cameras of one flight.
pub struct Summary {
    pub ops_mean: f64,
    pub ops_max: u32,
    pub first_frame_ops: f64,
    pub refine_ms_mean: f64,
    pub refine_ms_p99: f64,
    pub emit_ms_mean: f64,
    pub active_mean: f64,
    pub active_max: u32,
    pub max_active_nodes: u32,
    pub refusals: u64,
}

/// Summary over the cameras of one flight.
pub fn summarise(records: &[Record]) -> Summary {
    let all_refine: Vec<u64> = records
        .iter()
        .flat_map(|r| Record::steady(&r.refine_ns).iter().copied())
        .collect();
    let n = records.len().max(1) as f64;
    Summary {
        ops_mean: records.iter().map(Record::ops_mean).sum::<f64>() / n,
        ops_max: records.iter().map(Record::ops_max).max().unwrap_or(0),
        first_frame_ops: records
            .iter()
            .map(|r| f64::from(r.ops.first().copied().unwrap_or(0)))
            .sum::<f64>()
            / n,
        refine_ms_mean: records.iter().map(Record::refine_ms_mean).sum::<f64>() / n,
        refine_ms_p99: percentile(&all_refine, 0.99) as f64 * 1e-6,
        emit_ms_mean: records.iter().map(Record::emit_ms_mean).sum::<f64>() / n,
        active_mean: records.iter().map(Record::active_mean).sum::<f64>() / n,
        active_max: records.iter().map(Record::active_max).max().unwrap_or(0),
        max_active_nodes: records
            .iter()
            .map(|r| r.max_active_nodes)
            .max()
            .unwrap_or(0),
        refusals: records.iter().map(|r| r.refusals).sum(),
    }
}
