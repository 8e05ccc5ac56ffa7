//! `caveclod demo`: the whole library in one run. Bakes the St. Helens terrain and Spot from
//! the repository's `data/` (cached in `out/cache/`), flies four cameras over the terrain with
//! a state per camera, with one shared state (the CAVECLOD paper's baseline) and with a thread
//! per camera, and with one to three cameras for scaling, then writes the figures, a CSV of
//! every frame and `report.md` with the measured ratios against the acceptance targets.
//!
//! Everything the demo measures comes from [`crate::flyover`]; this module only chooses the
//! runs, writes the files and words the report.

mod figures;
mod flights;
mod inputs;
mod plots;
pub mod render;
mod report;
mod smooth;
mod streamed;

use std::path::{Path, PathBuf};
use std::time::Instant;

use caveclod_bake::baked::write_atomically;
use caveclod_core::Hierarchy;
use caveclod_host::write_png;
use caveclod_vulkan::{Context, HeadlessDesc};

use crate::snapshot::{render_snapshot, Layout, SnapshotDesc};

pub use flights::{fly_all, ratios, Ratios};
use inputs::{bake_cached, shown, Loaded};
use report::results_table;

/// What to run.
#[derive(Clone, Debug)]
pub struct DemoOptions {
    /// Where the inputs are (`data/` of the repository).
    pub data: PathBuf,
    /// Where everything is written.
    pub out: PathBuf,
    /// Frames per flight.
    pub frames: usize,
    /// Bake again even if the cache has the file.
    pub rebake: bool,
    /// Skip the Vulkan pictures (CPU figures only).
    pub no_render: bool,
}

impl Default for DemoOptions {
    fn default() -> Self {
        Self {
            data: PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../data")),
            out: PathBuf::from("out"),
            frames: 300,
            rebake: false,
            no_render: false,
        }
    }
}

/// What the demo wrote and measured.
pub struct DemoOutcome {
    /// The report's path.
    pub report: PathBuf,
    /// Every file written.
    pub files: Vec<PathBuf>,
    /// The ratios.
    pub ratios: Ratios,
}

/// Runs the demo; `say` receives progress lines.
pub fn run(options: &DemoOptions, say: &mut dyn FnMut(&str)) -> Result<DemoOutcome, String> {
    let start = Instant::now();
    crate::outputs::prepare_output_dir(&options.out, &["report.md", "results.md"], &[])?;
    let (terrain, model) = bake_inputs(options, say)?;
    let h = terrain.hierarchy()?;
    say(&format!(
        "flying 4 cameras over {} polygons: a state per camera, one shared state, a thread per \
         camera, 2 and 3 cameras, each camera alone, 4 without the index cache, 4 lean in \
         memory, 4 with and without geomorphs and 4 regulated ({} frames each)",
        h.polygon_count(),
        options.frames
    ));
    let flights = fly_all(&h, options.frames)?;
    let r = ratios(&flights);
    say("flying the terrain paged, its pages streaming into a pool a third of its size");
    let streaming = streamed::row(&streamed::fly(&terrain, options.frames)?);
    let mut files = Vec::new();
    let csv = options.out.join("flyover.csv");
    report::write_csv(&csv, &flights)?;
    files.push(csv);
    files.extend(figures::write_plots(&options.out, &flights)?);
    let mut pictures = draw_pictures(&h, options, &mut files, say);
    pictures.push_str(&draw_model(&model, options, &mut files, say));
    let mut text = report::report(
        &terrain,
        &model,
        &flights,
        &r,
        &streaming,
        start.elapsed().as_secs_f64(),
    );
    text.push_str(&format!("\n## Pictures\n\n{pictures}\n"));
    let results_path = options.out.join("results.md");
    let table = results_table(&flights, &r) + &streaming;
    write_atomically(&results_path, table.as_bytes()).map_err(|e| e.to_string())?;
    files.push(results_path);
    let report_path = options.out.join("report.md");
    write_atomically(&report_path, text.as_bytes()).map_err(|e| e.to_string())?;
    files.push(report_path.clone());
    Ok(DemoOutcome {
        report: report_path,
        files,
        ratios: r,
    })
}

/// Bakes (or reads from the cache) the St. Helens terrain and Spot.
fn bake_inputs(
    options: &DemoOptions,
    say: &mut dyn FnMut(&str),
) -> Result<(Loaded, Loaded), String> {
    let cache = options.out.join("cache");
    let terrain_path = options.data.join("terrain/SainteHelens.dem");
    let model_path = options.data.join("spot/spot_triangulated.obj");
    say(&format!(
        "baking {} (cached in {})",
        shown(&terrain_path),
        shown(&cache)
    ));
    let terrain = bake_cached(&terrain_path, &cache, options.rebake)?;
    say(&format!("baking {}", shown(&model_path)));
    let model = bake_cached(&model_path, &cache, options.rebake)?;
    Ok((terrain, model))
}

/// Draws Spot with its texture from four orbiting cameras (one split-screen frame, each
/// camera refined at 1 px) into `spot.png`, adding it to `files`; returns the report's
/// sentence about it (empty when no pictures are drawn).
fn draw_model(
    model: &Loaded,
    options: &DemoOptions,
    files: &mut Vec<PathBuf>,
    say: &mut dyn FnMut(&str),
) -> String {
    if options.no_render {
        return String::new();
    }
    say("drawing Spot with its texture from 4 cameras");
    let drawn = (|| -> Result<PathBuf, String> {
        let h = model.hierarchy()?;
        let ctx = Context::headless(&HeadlessDesc {
            validation: false,
            prefer_lavapipe: true,
            synchronization_validation: false,
        })
        .map_err(|e| e.to_string())?;
        let desc = SnapshotDesc {
            cameras: 4,
            tolerance_px: 1.0,
            width: 1280,
            height: 720,
            layout: Layout::SplitScreen,
            materials_dir: model.input.parent().map(Path::to_path_buf),
        };
        let snapshot = render_snapshot(&ctx, &h, &desc).map_err(|e| e.to_string());
        let destroyed = ctx.destroy().map_err(|e| e.to_string());
        let snapshot = snapshot?;
        destroyed?;
        let path = options.out.join("spot.png");
        let image = snapshot.images.first().ok_or("no image drawn")?;
        write_png(image, &path).map_err(|e| e.to_string())?;
        Ok(path)
    })();
    match drawn {
        Ok(path) => {
            files.push(path);
            " Spot with its texture (its material, drawn by the record path), four cameras \
             at 1 px: `spot.png`."
                .to_string()
        }
        Err(e) => format!(" Spot was not drawn: {e}."),
    }
}

/// Draws the four cameras' split screen at four frames of the flight on the Vulkan device,
/// adding the pictures to `files`; returns the report's paragraph about them, which says why
/// there are none when no device draws them.
fn draw_pictures(
    h: &Hierarchy<'_>,
    options: &DemoOptions,
    files: &mut Vec<PathBuf>,
    say: &mut dyn FnMut(&str),
) -> String {
    let f = options.frames;
    let shots = [0, f / 3, 2 * f / 3, f.saturating_sub(1)];
    let pictures = if options.no_render {
        Err("--no-render given".to_string())
    } else {
        say("drawing the 4 cameras as a split screen on the Vulkan device");
        render::render_flight(h, f, &shots, &options.out)
    };
    match pictures {
        Ok((written, device)) => {
            files.extend(written.iter().cloned());
            format!(
                "{} split-screen frames of the 4 cameras (1280x720, frames {:?}) drawn on {device}: {}.",
                written.len(),
                shots,
                written
                    .iter()
                    .filter_map(|p| p.file_name())
                    .map(|n| format!("`{}`", n.to_string_lossy()))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        }
        Err(e) => {
            let msg = format!(
                "No pictures: {e}. The figures above need no GPU; for the pictures install a \
                 Vulkan driver (on Debian: apt-get install mesa-vulkan-drivers libvulkan1, or \
                 cargo xtask setup)."
            );
            say(&msg);
            msg
        }
    }
}
