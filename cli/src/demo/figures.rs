//! The demo's figures (SVG): operations, active polygons, memory and scaling.

use std::path::{Path, PathBuf};

use super::flights::refine_ms_all_cameras;
use super::flights::{Flights, DISPLAY_FPS};
use super::plots::{self, Series};
use crate::flyover::Flyover;

/// Mean over cameras, per frame, of `pick(record)[frame]`.
fn per_frame_mean(
    fl: &Flyover,
    pick: impl Fn(&crate::flyover::Record) -> Vec<f64>,
) -> Vec<(f64, f64)> {
    let columns: Vec<Vec<f64>> = fl.flight.records.iter().map(&pick).collect();
    let frames = columns.iter().map(Vec::len).min().unwrap_or(0);
    (1..frames)
        .map(|i| {
            let m = columns.iter().map(|c| c[i]).sum::<f64>() / columns.len().max(1) as f64;
            (i as f64, m)
        })
        .collect()
}

/// Writes the figures; returns their paths.
pub(super) fn write_plots(out: &Path, f: &Flights) -> Result<Vec<PathBuf>, String> {
    Ok(vec![
        fig_operations(out, f)?,
        fig_active_polygons(out, f)?,
        fig_memory(out, f)?,
        fig_scaling(out, f)?,
    ])
}

/// A figure's error, naming its file.
fn plot_error(p: &Path, e: Box<dyn std::error::Error>) -> String {
    format!("{}: {e}", p.display())
}

/// Refinement operations per camera per frame: a state per camera against one shared
/// state, with the paper's per-second unit on the second axis.
fn fig_operations(out: &Path, f: &Flights) -> Result<PathBuf, String> {
    let ops = |r: &crate::flyover::Record| r.ops.iter().map(|&x| f64::from(x)).collect();
    let per = per_frame_mean(&f.per_camera, ops);
    let shared = per_frame_mean(&f.shared, ops);
    let p = out.join("fig-operations.svg");
    plots::lines(
        &p,
        "Refinement operations per camera (4 cameras, St. Helens)",
        "frame",
        "splits + collapses per camera per frame (log scale)",
        &[
            Series {
                label: "a state per camera (mean of 4)".into(),
                points: &per,
                baseline: false,
            },
            Series {
                label: "one shared state re-refined per camera (mean of 4)".into(),
                points: &shared,
                baseline: true,
            },
        ],
        true,
        Some(plots::SecondAxis {
            scale: DISPLAY_FPS,
            desc: "per camera per second at 30 frames/s (the paper's unit)",
        }),
    )
    .map_err(|e| plot_error(&p, e))?;
    Ok(p)
}

/// Active polygons per camera per frame, a state per camera.
fn fig_active_polygons(out: &Path, f: &Flights) -> Result<PathBuf, String> {
    let active: Vec<Vec<(f64, f64)>> = f
        .per_camera
        .flight
        .records
        .iter()
        .map(|r| {
            r.active_polygons
                .iter()
                .enumerate()
                .map(|(i, &a)| (i as f64, f64::from(a)))
                .collect()
        })
        .collect();
    let series: Vec<Series<'_>> = f
        .per_camera
        .names
        .iter()
        .zip(&active)
        .map(|(n, pts)| Series {
            label: format!("camera: {n}"),
            points: pts,
            baseline: false,
        })
        .collect();
    let p = out.join("fig-active-polygons.svg");
    plots::lines(
        &p,
        "Active polygons per camera (a state per camera)",
        "frame",
        "active polygons",
        &series,
        false,
        None,
    )
    .map_err(|e| plot_error(&p, e))?;
    Ok(p)
}

/// Static plus per-camera memory against the number of cameras: caveclod's cameras sized to
/// their flight, lean cameras, and the paper's equation 1.
fn fig_memory(out: &Path, f: &Flights) -> Result<PathBuf, String> {
    let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
    let m = &f.per_camera.memory_budgeted;
    let ours: Vec<(f64, f64)> = (1..=8u64)
        .map(|c| (c as f64, mib(m.static_bytes + c * m.camera_bytes)))
        .collect();
    let lean_bytes = f.lean.memory_budgeted.camera_bytes;
    let lean: Vec<(f64, f64)> = (1..=8u64)
        .map(|c| (c as f64, mib(m.static_bytes + c * lean_bytes)))
        .collect();
    let paper: Vec<(f64, f64)> = (1..=8u64)
        .map(|c| {
            (
                c as f64,
                mib(m.paper_static_bytes + c * m.paper_camera_bytes),
            )
        })
        .collect();
    let p = out.join("fig-memory.svg");
    plots::lines(
        &p,
        "Memory against the number of cameras (static + per-camera state)",
        "cameras",
        "MiB",
        &[
            Series {
                label: "caveclod (cameras sized to their flight + 10%)".into(),
                points: &ours,
                baseline: false,
            },
            Series {
                label: "caveclod, lean cameras (no index cache, hashed pair map)".into(),
                points: &lean,
                baseline: false,
            },
            Series {
                label: "CAVECLOD paper, equation 1, same mesh and fronts".into(),
                points: &paper,
                baseline: true,
            },
        ],
        false,
        None,
    )
    .map_err(|e| plot_error(&p, e))?;
    Ok(p)
}

/// Refinement time per frame of 1 to 4 cameras flying together against the sum of the same
/// routes each flown alone.
fn fig_scaling(out: &Path, f: &Flights) -> Result<PathBuf, String> {
    // Cameras 1..c of the routes flying together, against the sum of the same routes each
    // flown alone: equal when adding a camera costs exactly its own refinement.
    let mut measured: Vec<(f64, f64)> = Vec::new();
    if let Some(first) = f.alone.first() {
        measured.push((1.0, refine_ms_all_cameras(first)));
    }
    measured.extend(
        f.fewer
            .iter()
            .map(|fl| (fl.options.cameras as f64, refine_ms_all_cameras(fl))),
    );
    measured.push((4.0, refine_ms_all_cameras(&f.per_camera)));
    let linear: Vec<(f64, f64)> = (1..=f.alone.len())
        .map(|c| {
            let sum: f64 = f.alone[..c].iter().map(refine_ms_all_cameras).sum();
            (c as f64, sum)
        })
        .collect();
    let p = out.join("fig-scaling.svg");
    plots::lines(
        &p,
        "Refinement time per frame, all cameras together (a state per camera)",
        "cameras",
        "ms per frame",
        &[
            Series {
                label: "measured".into(),
                points: &measured,
                baseline: false,
            },
            Series {
                label: "linear: the same routes' times, each camera flown alone, summed".into(),
                points: &linear,
                baseline: true,
            },
        ],
        false,
        None,
    )
    .map_err(|e| plot_error(&p, e))?;
    Ok(p)
}
