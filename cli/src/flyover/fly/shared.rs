//! The paper's baseline: one state shared by every camera, re-refined to each camera's view
//! in turn.

use std::time::Instant;

use caveclod_core::{CameraConfig, CameraState, Hierarchy, RefineParams, View};

use super::common::{compact_now, frame, CompactNow, Compaction, Flight, IndexBuffers, Record};
use caveclod_io::CameraPool;

/// The paper's baseline: one state of capacity `config`, re-refined to each camera's view in
/// turn every frame; it compacts as `compaction` says too (before the first camera's
/// turn).
pub fn fly_shared(
    h: &Hierarchy<'_>,
    views: &[Vec<View>],
    params: &RefineParams,
    config: &CameraConfig,
    compaction: Compaction,
) -> Result<Flight, String> {
    let start = Instant::now();
    let mut pool = CameraPool::new(CameraState::words_needed_for(h, config), 1);
    let memory = pool.memories().next().ok_or("no camera memory")?;
    let mut cam = CameraState::with_config(h, memory, config).map_err(|e| e.to_string())?;
    let mut out = IndexBuffers::new(h, cam.max_pairs());
    let frames = views.first().map_or(0, Vec::len);
    let mut records = Record::per_camera(views);
    for f in 0..frames {
        for c in 0..views.len() {
            frame(
                h,
                &mut cam,
                &views[c][f],
                params,
                Some(&mut out),
                &mut records[c],
                if c == 0 {
                    compact_now(f, compaction)
                } else {
                    CompactNow::NONE
                },
            )?;
        }
    }
    Ok(Flight {
        records,
        camera_bytes: cam.bytes() - cam.morph_bytes(),
        morph_bytes: cam.morph_bytes(),
        wall: start.elapsed(),
        segment_walls: Vec::new(),
    })
}
