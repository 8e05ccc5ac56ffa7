//! The demo's streaming row: the terrain written paged, and four cameras flown over it with
//! its pages streaming into a pool a third of the file through a slow simulated disk.

use std::time::Duration;

use caveclod_bake::paged::{write_paged, PageOptions};
use caveclod_io::PagedFile;

use super::inputs::Loaded;
use crate::flyover::streamed::{fly_streamed, StreamOptions, StreamedFlight};
use crate::flyover::FlyoverOptions;

/// The paged form's page size.
const PAGE_BYTES: u32 = 16 * 1024;
/// The pool holds this share of the paged file.
const POOL_SHARE: u64 = 3;
/// The simulated disk: latency per read, and bandwidth in bytes per second.
const IO_LATENCY: Duration = Duration::from_millis(8);
const IO_BYTES_PER_S: f64 = 20e6;
/// Each camera's polygon budget.
const CAMERA_POLYGONS: u32 = 65_536;
/// Acceptance: the share of settled frames, and the time from opening to the first frame.
const SETTLED_SHARE: f64 = 0.99;
const OPEN_MS: f64 = 100.0;

/// Writes the terrain paged next to its cached bake (once) and flies `frames` frames of the
/// demo's four routes over it, streaming.
pub(super) fn fly(terrain: &Loaded, frames: usize) -> Result<StreamedFlight, String> {
    let paged = terrain.clod.with_extension("paged-16k.clod");
    if PagedFile::open(&paged)
        .and_then(|f| f.root().map(|_| ()))
        .is_err()
    {
        let h = terrain.hierarchy()?;
        write_paged(
            &h,
            &paged,
            &PageOptions {
                page_bytes: PAGE_BYTES,
            },
        )
        .map_err(|e| format!("{}: {e}", paged.display()))?;
    }
    let bytes = std::fs::metadata(&paged)
        .map_err(|e| format!("{}: {e}", paged.display()))?
        .len();
    let options = FlyoverOptions {
        cameras: 4,
        frames,
        ..FlyoverOptions::default()
    };
    let stream = StreamOptions {
        pool_bytes: bytes / POOL_SHARE,
        io_latency: IO_LATENCY,
        io_bytes_per_s: IO_BYTES_PER_S,
        camera_polygons: CAMERA_POLYGONS,
        max_pressure: 16.0,
        baseline: None,
    };
    fly_streamed(&[paged], &options, &stream)
}

/// The results table's streaming row.
pub(super) fn row(f: &StreamedFlight) -> String {
    let settled = f.settled_share();
    let open_ms = f.open_to_first_frame.as_secs_f64() * 1e3;
    let pressure =
        f.frames.iter().map(|f| f64::from(f.pressure)).sum::<f64>() / f.frames.len().max(1) as f64;
    let polygons = f
        .frames
        .iter()
        .map(|f| f64::from(f.active_polygons))
        .sum::<f64>()
        / (f.frames.len() * f.names.len()).max(1) as f64;
    let ok = settled >= SETTLED_SHARE && open_ms <= OPEN_MS && f.reads.absent_reads == 0;
    format!(
        "| streaming: the terrain in {} KiB pages, a pool a third of the file, an {} ms, {} MB/s simulated disk, 4 cameras at 1 px: frames after the first second whose deferred splits are within 1% of the fronts with no page wanted for over 30 frames (tolerance scale under pool pressure, mean; polygons per camera; open to the first frame; reads of absent pages) | {:.1}% ({:.2}; {:.0}; {:.1} ms; {}) | >= 99%, <= 100 ms, 0 | {} |\n",
        PAGE_BYTES / 1024,
        IO_LATENCY.as_millis(),
        IO_BYTES_PER_S / 1e6,
        settled * 100.0,
        pressure,
        polygons,
        open_ms,
        f.reads.absent_reads,
        if ok { "met" } else { "not met" }
    )
}
