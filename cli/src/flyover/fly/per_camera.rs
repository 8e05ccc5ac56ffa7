//! A state per camera: the cameras flown in turn on one thread, or each on its own thread
//! held within a few frames of the others.

use std::time::Instant;

use caveclod_core::{CameraConfig, CameraState, Hierarchy, RefineParams, View};

use super::common::{
    camera_order, cameras, compact_now, frame, index_lists, pin, placement, state_bytes,
    Compaction, Flight, IndexBuffers, Record,
};
use crate::flyover::gate::FrameGate;
use caveclod_io::CameraPool;

/// One flight of every camera, each with its own state of capacity `config`, over every
/// `stride`-th frame; `emit` also writes the index lists each frame, into one of
/// `in_flight` lists per camera in turn (frames in flight, see `gate`), and with `threads`
/// a camera's thread runs at most `in_flight - 1` frames ahead of the slowest, pinned to a
/// core when `pin_by` gives the cameras' costs to balance the cores by (see `placement`);
/// each state compacts as `compaction` says.
#[allow(clippy::too_many_arguments)]
pub fn fly_per_camera(
    h: &Hierarchy<'_>,
    views: &[Vec<View>],
    params: &RefineParams,
    config: &CameraConfig,
    stride: usize,
    emit: bool,
    threads: bool,
    in_flight: usize,
    compaction: Compaction,
    pin_by: Option<&[f64]>,
) -> Result<Flight, String> {
    let in_flight = in_flight.max(1);
    let start = Instant::now();
    let mut pool = CameraPool::new(CameraState::words_needed_for(h, config), views.len());
    let mut cams = cameras(h, &mut pool, config)?;
    let (camera_bytes, morph_bytes) = state_bytes(cams.first());
    let mut outs: Vec<Vec<IndexBuffers>> = views
        .iter()
        .map(|_| index_lists(h, config, if emit { in_flight } else { 0 }))
        .collect();
    let frames = views.first().map_or(0, Vec::len).div_ceil(stride);
    let records = if threads {
        let gate = FrameGate::new(views.len(), in_flight);
        let (cores, core_of) = placement(pin_by);
        let (cores, core_of) = (&cores, &core_of);
        std::thread::scope(|scope| {
            let handles: Vec<_> = cams
                .into_iter()
                .zip(outs.iter_mut())
                .zip(views)
                .enumerate()
                .map(|(c, ((mut cam, out), cam_views))| {
                    let gate = &gate;
                    // The camera state moves to its thread (`Send`); every thread reads the
                    // one hierarchy (`Sync`). Frames stay within the frames in flight of
                    // each other, as a renderer's would.
                    scope.spawn(move || -> Result<Record, String> {
                        pin(cores, core_of, c);
                        let mut rec = Record::with_capacity(frames);
                        let mut failed = Ok(());
                        for (n, view) in cam_views.iter().step_by(stride).enumerate() {
                            gate.enter(n);
                            if failed.is_ok() {
                                failed = frame(
                                    h,
                                    &mut cam,
                                    view,
                                    params,
                                    out.get_mut(n % in_flight),
                                    &mut rec,
                                    compact_now(n, compaction),
                                );
                            }
                            gate.leave(c);
                        }
                        failed.map(|()| rec)
                    })
                })
                .collect();
            handles
                .into_iter()
                .map(|t| t.join().map_err(|_| "camera thread panicked".to_string())?)
                .collect::<Result<Vec<_>, _>>()
        })?
    } else {
        let mut records = Record::per_camera(views);
        for (n, f) in (0..views.first().map_or(0, Vec::len))
            .step_by(stride)
            .enumerate()
        {
            for c in camera_order(n, cams.len()) {
                frame(
                    h,
                    &mut cams[c],
                    &views[c][f],
                    params,
                    outs[c].get_mut(n % in_flight),
                    &mut records[c],
                    compact_now(n, compaction),
                )?;
            }
        }
        records
    };
    Ok(Flight {
        records,
        camera_bytes,
        morph_bytes,
        wall: start.elapsed(),
        segment_walls: Vec::new(),
    })
}
