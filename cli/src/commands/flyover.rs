//! `caveclod flyover`: the CAVECLOD paper's experiment over a .clod file or a heightfield.

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
    match (a.file, a.dem) {
        (Some(file), None) => with_hierarchy(&file, |h| {
            print(&fly(h, &options)?);
            Ok(())
        }),
        (None, Some(dem)) => {
            let (baked, _) = bake_file(&dem, &ImportOptions { spacing: a.spacing }, &mut |_| {})
                .map_err(|e| e.to_string())?;
            let h = baked.hierarchy().map_err(|e| e.to_string())?;
            print(&fly(&h, &options)?);
            Ok(())
        }
        _ => Err("give a .clod file or --dem FILE".into()),
    }
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
    }
}
