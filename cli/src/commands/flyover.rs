//! `caveclod flyover`: the CAVECLOD paper's experiment over a .clod file or a heightfield.

use std::time::Duration;

use crate::flyover::streamed::{fly_streamed, StreamOptions};
use crate::flyover::{fly, Flyover, FlyoverOptions, Mode};
use caveclod_bake::import::ImportOptions;
use caveclod_bake::pipeline::bake_file;

use super::load::with_hierarchy;
use crate::args::FlyoverArgs;

/// Flies the cameras over the file (or the heightfield baked in memory) and prints the report.
pub fn flyover(a: FlyoverArgs) -> Result<(), String> {
    let options = options(&a);
    let print = |f: &Flyover| {
        if a.json {
            println!("{}", f.json());
        } else {
            print!("{}", f.human());
        }
    };
    if let Some(pool_bytes) = a.pool {
        return streamed(&a, &options, pool_bytes);
    }
    match (a.files.as_slice(), a.dem.clone()) {
        ([file], None) => with_hierarchy(file, |h| {
            print(&fly(h, &options)?);
            Ok(())
        }),
        ([], Some(dem)) => {
            let (baked, _) = bake_file(&dem, &ImportOptions { spacing: a.spacing }, &mut |_| {})
                .map_err(|e| e.to_string())?;
            let h = baked.hierarchy().map_err(|e| e.to_string())?;
            print(&fly(&h, &options)?);
            Ok(())
        }
        _ => Err("give one .clod file or --dem FILE (several files stream with --pool)".into()),
    }
}

/// Flies over paged files with their pages streaming into a pool of `pool_bytes`.
fn streamed(a: &FlyoverArgs, options: &FlyoverOptions, pool_bytes: u64) -> Result<(), String> {
    if a.files.is_empty() {
        return Err("--pool flies paged .clod files: give one or more".into());
    }
    let stream = StreamOptions {
        pool_bytes,
        io_latency: Duration::from_secs_f32(a.io_latency / 1e3),
        io_bytes_per_s: f64::from(a.io_bandwidth) * 1e6,
        camera_polygons: a.camera_polygons,
        max_pressure: a.max_pressure,
        baseline: a.baseline.clone(),
    };
    let flight = fly_streamed(&a.files, options, &stream)?;
    if a.json {
        println!("{}", flight.json());
    } else {
        print!("{}", flight.human());
    }
    Ok(())
}

/// The experiment's options from the flags.
fn options(a: &FlyoverArgs) -> FlyoverOptions {
    FlyoverOptions {
        cameras: a.cameras,
        frames: a.frames,
        tolerance: a.tolerance,
        mode: if a.shared_state {
            Mode::Shared
        } else if a.threads {
            Mode::Threads
        } else {
            Mode::PerCamera
        },
        full_capacity: a.full_capacity,
        first_route: 0,
        compact_every: a.compact_every,
        compact_step: a.compact_step,
        visit_fraction: a.visit_fraction,
        frames_in_flight: usize::from(a.frames_in_flight),
        index_cache: !a.no_index_cache,
        pin_threads: !a.no_pin,
        hashed_pair_map: a.hashed_pair_map,
        geomorphs: !a.no_geomorphs,
        morph_speed_px_s: a.morph_speed,
        morph_radius_tolerances: a.morph_radius,
        morph_guard_rad: a.morph_guard.to_radians(),
        target_polygons: a.target_polygons,
        index_edits: a.index_edits,
    }
}
