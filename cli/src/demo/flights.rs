//! The demo's flights and the ratios it reports: which runs fly, in what order, and how their
//! times are compared.

use caveclod_core::Hierarchy;

use crate::flyover::{fly, fly_interleaved_sharing, Flyover, FlyoverOptions, Mode, Sizings};

/// The measured flights.
pub struct Flights {
    /// Four cameras, a state each.
    pub per_camera: Flyover,
    /// Four cameras, one shared state.
    pub shared: Flyover,
    /// Four cameras, a state and a thread each.
    pub threads: Flyover,
    /// Per round of [`THREADS_ROUNDS`], four cameras' flight time on one thread over a thread
    /// each, the two flown one after the other.
    pub threads_rounds: Vec<f64>,
    /// Two and three cameras together, a state each (for scaling).
    pub fewer: Vec<Flyover>,
    /// Each route flown by one camera alone.
    pub alone: Vec<Flyover>,
    /// Four cameras, a state each, emitting as the paper's cameras did: every polygon looked
    /// up every frame, without the index cache the other flights keep (the library's
    /// default).
    pub uncached: Flyover,
    /// Four cameras as lean in memory as the library allows: no index cache, and the
    /// split-to-pair map hashed (`CameraConfig::hashed_pair_map`).
    pub lean: Flyover,
    /// Four cameras, a state each on one thread, with geomorphs and the popping meter.
    pub morphed: Flyover,
    /// The same without geomorphs.
    pub unmorphed: Flyover,
    /// Four cameras regulated to 20,000 polygons, with geomorphs.
    pub regulated: Flyover,
    /// Four cameras with geomorphs held to a screen speed ([`SPEED_LIMIT_PX_S`]).
    pub speed_limited: Flyover,
}

/// The polygon target of the demo's regulated flight.
pub const REGULATED_TARGET: u32 = 20_000;
/// The screen speed limit of the demo's speed-limited flight, in pixels per second
/// ([`caveclod_core::RefineParams::morph_speed_px_s`]): 0.15 px a frame at 60 Hz, under the
/// popping acceptance's 99th percentile. The defaults set none, because a long slide then
/// takes many seconds (a slide of a few hundred pixels, half a minute) and the row shows what
/// that costs.
pub const SPEED_LIMIT_PX_S: f32 = 9.0;

/// The display rate the report converts per-frame figures at, for comparison with the CAVECLOD
/// paper, which counts operations per camera per second: the flights run as fast as they
/// can, so "per second" means at this rate (300 frames: a 10-second flight).
pub const DISPLAY_FPS: f64 = 30.0;

/// Frames per segment of the interleaved flights: long enough that a camera's first frame
/// after the other flights' turns (its caches taken by them) is one frame in thirty, which
/// barely moves a per-frame middle value; short enough that the flights compared run within
/// a fraction of a second of each other.
pub const SEGMENT: usize = 30;

/// How many times four cameras fly on one thread and then on a thread each, for the threads'
/// speed-up, which is a ratio of wall times, not of per-frame figures: the middle value of
/// the rounds' ratios, so that one round disturbed by other work does not decide it.
///
/// These two fly whole flights in turn, not the segments the other flights take turns in:
/// every segment of threads ends as a barrier would (the camera threads that finish first
/// wait for the last, and a core idles meanwhile), which a renderer's threads pay once, not
/// every few frames. A whole flight is short, so the two flights of a round still run close
/// enough together to see the same load.
pub const THREADS_ROUNDS: usize = 5;

/// Flies every run of the demo: the shared state on its own; four cameras on one thread and
/// on a thread each, whole flights in turn, [`THREADS_ROUNDS`] times; and the per-camera
/// flights (four cameras on one thread, two and three cameras, each camera alone, four
/// cameras without the index cache, four without it and with hashed pair maps) interleaved
/// in segments of [`SEGMENT`] frames, so that the ratios compare flights measured under the
/// same load; then four cameras with and without geomorphs, regulated, and with geomorphs
/// held to a screen speed, for popping and regulation.
pub fn fly_all(h: &Hierarchy<'_>, frames: usize) -> Result<Flights, String> {
    // The paper's experiment refines each camera's whole front every frame, as the shared
    // state does, so the comparisons weigh the states, not amortisation.
    let base = FlyoverOptions {
        cameras: 4,
        frames,
        visit_fraction: 1.0,
        ..FlyoverOptions::default()
    };
    let shared = fly(
        h,
        &FlyoverOptions {
            mode: Mode::Shared,
            ..base
        },
    )?;
    let threaded = FlyoverOptions {
        mode: Mode::Threads,
        ..base
    };
    let rounds: Vec<FlyoverOptions> = (0..THREADS_ROUNDS).flat_map(|_| [base, threaded]).collect();
    // One set of sizing flights for both interleaved calls: `base` is sized once.
    let mut sizings = Sizings::default();
    let pairs = fly_interleaved_sharing(h, &rounds, frames, &mut sizings)?;
    let threads_rounds = pairs
        .chunks_exact(2)
        .map(|p| p[0].flight.wall.as_secs_f64() / p[1].flight.wall.as_secs_f64().max(1e-9))
        .collect();
    let threads = pairs
        .into_iter()
        .nth(1)
        .ok_or("the threaded flight is missing")?;
    let mut options = vec![base];
    options.extend((2..4).map(|c| FlyoverOptions { cameras: c, ..base }));
    options.extend((0..4).map(|r| FlyoverOptions {
        cameras: 1,
        first_route: r,
        ..base
    }));
    options.push(FlyoverOptions {
        index_cache: false,
        ..base
    });
    options.push(FlyoverOptions {
        index_cache: false,
        hashed_pair_map: true,
        ..base
    });
    let mut flown = fly_interleaved_sharing(h, &options, SEGMENT, &mut sizings)?.into_iter();
    let mut next = || flown.next().ok_or("an interleaved flight is missing");
    let per_camera = next()?;
    let fewer = vec![next()?, next()?];
    let alone = (0..4).map(|_| next()).collect::<Result<Vec<_>, _>>()?;
    let uncached = next()?;
    let lean = next()?;
    // Popping and regulation are measured on flights of their own (one thread, a pilot per
    // camera), after the timed comparisons.
    let morphed = fly(h, &base)?;
    let unmorphed = fly(
        h,
        &FlyoverOptions {
            geomorphs: false,
            ..base
        },
    )?;
    let regulated = fly(
        h,
        &FlyoverOptions {
            target_polygons: Some(REGULATED_TARGET),
            ..base
        },
    )?;
    let speed_limited = fly(
        h,
        &FlyoverOptions {
            morph_speed_px_s: SPEED_LIMIT_PX_S,
            ..base
        },
    )?;
    Ok(Flights {
        per_camera,
        shared,
        threads,
        threads_rounds,
        fewer,
        alone,
        uncached,
        lean,
        morphed,
        unmorphed,
        regulated,
        speed_limited,
    })
}

/// Refinement time per frame over all cameras, in milliseconds: the sum of each camera's
/// middle value over its frames (frame 0 left out). Middle values, because a short flight's
/// mean moves with every burst of other work on the machine.
pub(super) fn refine_ms_all_cameras(f: &Flyover) -> f64 {
    f.flight.records.iter().map(|r| r.refine_ms_median()).sum()
}

/// Emission time per frame over all cameras, in milliseconds (the sum of each camera's
/// middle value over its frames).
pub(super) fn emit_ms_all_cameras(f: &Flyover) -> f64 {
    f.flight.records.iter().map(|r| r.emit_ms_median()).sum()
}

/// The ratios the report and the acceptance checks use.
#[derive(Clone, Copy, Debug)]
pub struct Ratios {
    /// Shared-state operations per camera per frame over per-camera's (goal ≥ 7).
    pub ops: f64,
    /// Shared-state refinement time over per-camera's (goal ≥ 3).
    pub refine_time: f64,
    /// Four cameras' refinement time together over the mean of each camera's alone
    /// (goal ≤ 4.4: cost grows linearly with cameras).
    pub four_over_one: f64,
    /// One thread's flight time over a thread per camera's (goal ≥ 1.6 on 2 cores).
    pub threads_speedup: f64,
    /// Per-camera memory over the paper's (goal ≤ 0.5, 0.25 the stretch).
    pub memory: f64,
}

/// The middle value of `v` once sorted (the upper one of an even count; 0 for none).
fn median(v: &[f64]) -> f64 {
    let mut r = v.to_vec();
    r.sort_by(f64::total_cmp);
    r.get(r.len() / 2).copied().unwrap_or(0.0)
}

/// Computes the ratios of a demo's flights.
pub fn ratios(f: &Flights) -> Ratios {
    let one = f.alone.iter().map(refine_ms_all_cameras).sum::<f64>() / f.alone.len().max(1) as f64;
    Ratios {
        ops: f.shared.summary.ops_mean / f.per_camera.summary.ops_mean.max(1e-9),
        refine_time: refine_ms_all_cameras(&f.shared)
            / refine_ms_all_cameras(&f.per_camera).max(1e-9),
        four_over_one: refine_ms_all_cameras(&f.per_camera) / one.max(1e-9),
        threads_speedup: median(&f.threads_rounds),
        memory: f.per_camera.memory_budgeted.camera_ratio(),
    }
}
