//! `caveclod`: bake meshes into view-dependent hierarchies, inspect and export them.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use caveclod_bake::baked::write_atomically;
use caveclod_bake::export::{self, Level};
use caveclod_bake::gmesh::GMeshOptions;
use caveclod_bake::import::ImportOptions;
use caveclod_bake::ooc::{OocOptions, OocStage};
use caveclod_bake::pipeline::{bake_file, bake_out_of_core, Stage};
use caveclod_bake::report::BakeInfo;
use caveclod_cli::aligned::AlignedBytes;
use caveclod_cli::demo::{self, DemoOptions};
use caveclod_cli::flyover::{fly, Flyover, FlyoverOptions, Mode};
use caveclod_cli::info as report;
use caveclod_core::Hierarchy;
use clap::{Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

#[derive(Parser)]
#[command(
    name = "caveclod",
    version,
    about = "View-dependent continuous level of detail: bake, inspect, export"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Bake a mesh (.gltf .glb .obj .ply .dem .npy) into a .clod hierarchy.
    Bake {
        /// The input mesh.
        input: PathBuf,
        /// The .clod file to write (replaced only once complete).
        #[arg(short, long)]
        output: PathBuf,
        /// Grid spacing in metres for heightfields (.npy needs it; overrides a .dem's).
        #[arg(long)]
        spacing: Option<f32>,
        /// Print the report as one JSON object.
        #[arg(long)]
        json: bool,
        /// Simplify the input (.ply, .obj) out of core first, streaming it from disk, down to a
        /// size whose hierarchy fits the memory budget.
        #[arg(long)]
        out_of_core: bool,
        /// Memory budget for --out-of-core (256M, 1G, ...).
        #[arg(long, default_value = "256M", value_parser = caveclod_bake::ooc::parse_size)]
        memory_budget: u64,
        /// Directory for --out-of-core's temporary files (the system's by default).
        #[arg(long)]
        temp_dir: Option<PathBuf>,
        /// Output triangles for --out-of-core to aim for (from the budget by default).
        #[arg(long)]
        target_triangles: Option<u64>,
        /// Most triangles in an octree leaf for --out-of-core.
        #[arg(long, default_value_t = 65536)]
        leaf_triangles: u64,
        /// Also store g-mesh levels (batched collapses, geomorph pairs, volume partitions).
        #[arg(long)]
        gmesh: bool,
        /// With --gmesh: stop adding levels below this many polygons (default |c0| / 64).
        #[arg(long)]
        gmesh_min_polygons: Option<u32>,
    },
    /// The demo: bake St. Helens and Spot, fly 4 cameras, write figures, CSV and out/report.md.
    Demo {
        /// Where to write (created if missing).
        #[arg(long, default_value = "out")]
        out: PathBuf,
        /// Frames per flight.
        #[arg(long, default_value_t = 300)]
        frames: usize,
        /// The repository's data directory (St. Helens and Spot).
        #[arg(long)]
        data: Option<PathBuf>,
        /// Bake again even if out/cache has the files.
        #[arg(long)]
        rebake: bool,
        /// CPU figures only, no Vulkan pictures.
        #[arg(long)]
        no_render: bool,
    },
    /// The CAVECLOD paper's experiment: cameras fly scripted routes over a hierarchy.
    Flyover {
        /// A .clod file (or use --dem).
        file: Option<PathBuf>,
        /// Bake this heightfield (.dem, .npy) in memory and fly over it.
        #[arg(long, conflicts_with = "file")]
        dem: Option<PathBuf>,
        /// Grid spacing in metres for --dem.
        #[arg(long)]
        spacing: Option<f32>,
        /// Cameras, 1 to 4.
        #[arg(long, default_value_t = 4)]
        cameras: usize,
        /// Frames per camera.
        #[arg(long, default_value_t = 300)]
        frames: usize,
        /// Screen-space tolerance in pixels (1280 x 720, 60 degree field of view).
        #[arg(long, default_value_t = 1.0)]
        tolerance: f32,
        /// One shared state re-refined for each camera in turn (the paper's baseline).
        #[arg(long, conflicts_with = "threads")]
        shared_state: bool,
        /// One thread per camera.
        #[arg(long)]
        threads: bool,
        /// Fly full-capacity cameras instead of sizing them to a first flight.
        #[arg(long)]
        full_capacity: bool,
        /// Compact each camera state every N of its frames, inside the timed refinement
        /// (0: never).
        #[arg(long, default_value_t = 30)]
        compact_every: usize,
        /// Frames in flight: index lists per camera, and with --threads how far apart the
        /// camera threads may run (1: a barrier every frame).
        #[arg(long, default_value_t = caveclod_cli::flyover::gate::FRAMES_IN_FLIGHT as u8,
              value_parser = clap::value_parser!(u8).range(1..=8))]
        frames_in_flight: u8,
        /// Emit without the index cache: look every active polygon up every frame, as the
        /// paper's cameras did (the library keeps each polygon's indices by default).
        #[arg(long)]
        no_index_cache: bool,
        /// With --threads, leave the camera threads to the system instead of pinning each to
        /// a core with the cameras shared out by cost.
        #[arg(long)]
        no_pin: bool,
        /// Keep each budgeted camera's split-to-pair map hashed where that is smaller than an
        /// array over the hierarchy (less memory, slower refinement).
        #[arg(long)]
        hashed_pair_map: bool,
        /// Print the report as one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Counts, sizes and validation status of a .clod file.
    Info {
        /// The file.
        file: PathBuf,
        /// Print the report as one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Generate a procedural terrain (normals, colours, UVs) as binary PLY, streamed to disk.
    Generate {
        /// At least this many triangles.
        #[arg(long)]
        triangles: u64,
        /// The .ply file to write (replaced only once complete).
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Write one level of a .clod file as Wavefront OBJ.
    Export {
        /// The file.
        file: PathBuf,
        /// Which level.
        #[arg(long, value_enum, default_value = "full")]
        level: LevelArg,
        /// The OBJ file to write.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Render a .clod file headless (lavapipe unless --gpu) from 1-4 cameras orbiting it, each
    /// refining its own front, into one split-screen PNG (or one PNG per camera).
    Render {
        /// The file.
        file: PathBuf,
        /// Cameras, 1 to 4, evenly spaced around the mesh.
        #[arg(long, default_value_t = 1)]
        cameras: usize,
        /// Screen-space tolerance of refinement, in pixels.
        #[arg(long, default_value_t = 1.0)]
        tolerance: f32,
        /// Image width in pixels.
        #[arg(long, default_value_t = 512)]
        width: u32,
        /// Image height in pixels.
        #[arg(long, default_value_t = 512)]
        height: u32,
        /// One PNG per camera (camera0.png, ...) instead of one split-screen image.
        #[arg(long)]
        separate: bool,
        /// Prefer a GPU over lavapipe.
        #[arg(long)]
        gpu: bool,
        /// Enable the Vulkan validation layer (if installed) and print its messages.
        #[arg(long)]
        validate: bool,
        /// Draw the multiresolution octree of an out-of-core bake (each camera its own cut)
        /// instead of the hierarchy.
        #[arg(long)]
        octree: bool,
        /// Directory for the PNG files (created if missing).
        #[arg(long)]
        out: PathBuf,
    },
}

#[derive(Clone, Copy, ValueEnum)]
enum LevelArg {
    Full,
    Base,
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("caveclod: error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Reads a .clod file into 8-byte aligned memory.
fn with_hierarchy<T>(
    path: &Path,
    f: impl FnOnce(&Hierarchy<'_>) -> Result<T, String>,
) -> Result<T, String> {
    // Cache-line aligned: no record straddles two lines.
    let file = AlignedBytes::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let h = file
        .hierarchy()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    f(&h)
}

fn run(cli: Cli) -> Result<(), String> {
    match cli.command {
        Command::Bake {
            input,
            output,
            spacing,
            json,
            out_of_core,
            memory_budget,
            temp_dir,
            target_triangles,
            leaf_triangles,
            gmesh,
            gmesh_min_polygons,
        } => {
            let bar = ProgressBar::new(0);
            bar.set_style(
                ProgressStyle::with_template(
                    "{spinner} {msg} [{bar:30}] {pos}/{len} collapses ({elapsed})",
                )
                .map_err(|e| e.to_string())?
                .progress_chars("=> "),
            );
            let mut on_stage = |s: Stage| match s {
                Stage::Import => bar.set_message("importing"),
                Stage::Weld => bar.set_message("welding"),
                Stage::Collapse(done, most) => {
                    bar.set_message("collapsing");
                    bar.set_length(most);
                    bar.set_position(done);
                }
                Stage::Assemble => bar.set_message("assembling"),
            };
            let mut ooc_stats = None;
            let mut octree = None;
            let result = if out_of_core {
                let options = OocOptions {
                    temp_dir,
                    target_triangles,
                    leaf_triangles,
                    ..OocOptions::with_budget(memory_budget)
                };
                let ooc_bar = ProgressBar::new(0);
                ooc_bar.set_style(
                    ProgressStyle::with_template(
                        "{spinner} {msg} [{bar:30}] {pos}/{len} triangles ({elapsed})",
                    )
                    .map_err(|e| e.to_string())?
                    .progress_chars("=> "),
                );
                let mut on_ooc = |s: OocStage| {
                    let (msg, done, total) = match s {
                        OocStage::Read(d, t) => ("reading and sorting".to_string(), d, t),
                        OocStage::Merge(d, t) => ("merging sorted runs".to_string(), d, t),
                        OocStage::Cluster(r, d, t) => (format!("clustering on a {r}^3 grid"), d, t),
                    };
                    ooc_bar.set_message(msg);
                    ooc_bar.set_length(total);
                    ooc_bar.set_position(done);
                };
                let r = bake_out_of_core(&input, &options, &mut on_ooc, &mut |s| {
                    ooc_bar.finish_and_clear();
                    on_stage(s)
                });
                ooc_bar.finish_and_clear();
                r.map(|o| {
                    ooc_stats = Some(o.stats);
                    octree = o.octree;
                    (o.baked, o.info)
                })
            } else {
                bake_file(&input, &ImportOptions { spacing }, &mut on_stage)
            };
            bar.finish_and_clear();
            let (baked, info) = result.map_err(|e| e.to_string())?;
            let json_info = info.to_json();
            let levels = if gmesh {
                bar.set_message("building g-mesh levels");
                let h = baked.hierarchy().map_err(|e| e.to_string())?;
                let options = GMeshOptions {
                    min_polygons: gmesh_min_polygons.unwrap_or(0),
                    ..GMeshOptions::default()
                };
                Some(caveclod_bake::gmesh::build(&h, &options).map_err(|e| e.to_string())?)
            } else {
                None
            };
            let mut sections = vec![BakeInfo::section(&json_info)];
            if let Some(g) = &levels {
                sections.extend(g.sections());
            }
            let octree_parts = octree.as_ref().map(|o| o.parts());
            if let Some(p) = &octree_parts {
                sections.extend(p.sections());
            }
            baked.write(&output, &sections).map_err(|e| e.to_string())?;
            with_hierarchy(&output, |h| {
                let mut r = report::report(h, Some(&info));
                r.insert("bake_seconds".into(), serde_json::json!(info.bake_seconds));
                if let Some(st) = &ooc_stats {
                    r.insert(
                        "input_triangles_per_second".into(),
                        serde_json::json!(st.input_triangles as f64 / info.bake_seconds),
                    );
                    r.insert(
                        "out_of_core".into(),
                        serde_json::json!({
                            "memory_budget": memory_budget,
                            "input_vertices": st.input_vertices,
                            "clustered_triangles": st.output_triangles,
                            "clusters": st.clusters,
                            "resolution": st.resolution,
                            "target_triangles": st.target_triangles,
                            "sort_octree_nodes": st.octree_nodes,
                            "sort_octree_leaves": st.octree_leaves,
                            "lod_levels": st.lod_levels,
                            "lod_nodes": st.lod_nodes,
                            "lod_seconds": st.lod_seconds,
                            "sorted_runs": st.runs,
                            "temp_bytes": st.temp_bytes,
                            "read_seconds": st.seconds[0],
                            "merge_seconds": st.seconds[1],
                            "cluster_seconds": st.seconds[2],
                            "triangles_per_second": st.input_triangles as f64
                                / (st.seconds[0] + st.seconds[1] + st.seconds[2]),
                        }),
                    );
                }
                r.insert(
                    "peak_rss_bytes".into(),
                    serde_json::json!(caveclod_bake::ooc::peak_rss_bytes()),
                );
                if json {
                    println!("{}", serde_json::Value::Object(r));
                } else {
                    println!(
                        "baked {} -> {}\n{}",
                        input.display(),
                        output.display(),
                        report::human(&r)
                    );
                }
                Ok(())
            })
        }
        Command::Demo {
            out,
            frames,
            data,
            rebake,
            no_render,
        } => {
            let mut options = DemoOptions {
                out,
                frames,
                rebake,
                no_render,
                ..DemoOptions::default()
            };
            if let Some(d) = data {
                options.data = d;
            }
            let outcome = demo::run(&options, &mut |line| eprintln!("{line}"))?;
            let r = outcome.ratios;
            println!(
                "operations per camera, shared / per-camera state: {:.1}x (target >= 7)\n\
                 refinement time, shared / per-camera: {:.1}x (target >= 3)\n\
                 refinement time, 4 cameras together / one alone (mean): {:.2}x (target <= 4.4)\n\
                 a thread per camera, speed-up: {:.2}x (target >= 1.6 on 2 cores)\n\
                 per-camera memory / the paper's: {:.2} (target <= 0.5)",
                r.ops, r.refine_time, r.four_over_one, r.threads_speedup, r.memory
            );
            for f in &outcome.files {
                println!("wrote {}", f.display());
            }
            println!("report: {}", outcome.report.display());
            Ok(())
        }
        Command::Flyover {
            file,
            dem,
            spacing,
            cameras,
            frames,
            tolerance,
            shared_state,
            threads,
            full_capacity,
            compact_every,
            frames_in_flight,
            no_index_cache,
            no_pin,
            hashed_pair_map,
            json,
        } => {
            let options = FlyoverOptions {
                cameras,
                frames,
                tolerance,
                mode: if shared_state {
                    Mode::Shared
                } else if threads {
                    Mode::Threads
                } else {
                    Mode::PerCamera
                },
                full_capacity,
                first_route: 0,
                compact_every,
                frames_in_flight: usize::from(frames_in_flight),
                index_cache: !no_index_cache,
                pin_threads: !no_pin,
                hashed_pair_map,
            };
            let print = |f: &Flyover| {
                if json {
                    println!("{}", f.json());
                } else {
                    print!("{}", f.human());
                }
            };
            match (file, dem) {
                (Some(file), None) => with_hierarchy(&file, |h| {
                    print(&fly(h, &options)?);
                    Ok(())
                }),
                (None, Some(dem)) => {
                    let (baked, _) = bake_file(&dem, &ImportOptions { spacing }, &mut |_| {})
                        .map_err(|e| e.to_string())?;
                    let h = baked.hierarchy().map_err(|e| e.to_string())?;
                    print(&fly(&h, &options)?);
                    Ok(())
                }
                _ => Err("give a .clod file or --dem FILE".into()),
            }
        }
        Command::Info { file, json } => with_hierarchy(&file, |h| {
            let info = BakeInfo::read(h);
            let mut r = report::report(h, info.as_ref());
            r.insert("valid".into(), serde_json::json!(true));
            if let Some(i) = &info {
                r.insert("bake_seconds".into(), serde_json::json!(i.bake_seconds));
            }
            if json {
                println!("{}", serde_json::Value::Object(r));
            } else {
                println!("{}: valid\n{}", file.display(), report::human(&r));
            }
            Ok(())
        }),
        Command::Generate { triangles, output } => {
            let bar = ProgressBar::new(0);
            bar.set_style(
                ProgressStyle::with_template("{spinner} writing [{bar:30}] {percent}% ({elapsed})")
                    .map_err(|e| e.to_string())?
                    .progress_chars("=> "),
            );
            let grid = caveclod_tests::generate::terrain(&output, triangles, &mut |done, total| {
                bar.set_length(total);
                bar.set_position(done);
            });
            bar.finish_and_clear();
            let grid = grid.map_err(|e| e.to_string())?;
            println!(
                "generated {}: terrain {}x{} quads, {} vertices, {} triangles",
                output.display(),
                grid.columns,
                grid.rows,
                grid.vertices(),
                grid.triangles()
            );
            Ok(())
        }
        Command::Export {
            file,
            level,
            output,
        } => with_hierarchy(&file, |h| {
            let level = match level {
                LevelArg::Full => Level::Full,
                LevelArg::Base => Level::Base,
            };
            let text = export::obj(h, level);
            write_atomically(&output, text.as_bytes()).map_err(|e| e.to_string())
        }),
        Command::Render {
            file,
            cameras,
            tolerance,
            width,
            height,
            separate,
            gpu,
            validate,
            octree,
            out,
        } => with_hierarchy(&file, |h| {
            render(
                h,
                &RenderArgs {
                    octree,
                    cameras,
                    tolerance,
                    width,
                    height,
                    separate,
                    gpu,
                    validate,
                    out,
                },
            )
        }),
    }
}

/// Options of `caveclod render`.
struct RenderArgs {
    cameras: usize,
    tolerance: f32,
    width: u32,
    height: u32,
    separate: bool,
    gpu: bool,
    validate: bool,
    octree: bool,
    out: PathBuf,
}

/// `caveclod render`: one frame of orbiting cameras, read back and written as PNG.
fn render(h: &Hierarchy<'_>, a: &RenderArgs) -> Result<(), String> {
    use caveclod_cli::snapshot::{
        render_octree_snapshot, render_snapshot, write_png, Layout, SnapshotDesc,
    };
    use caveclod_vulkan::{Context, HeadlessDesc};
    let octree = if a.octree {
        match caveclod_core::Octree::from_hierarchy(h) {
            Ok(Some(o)) => Some(o),
            Ok(None) => {
                return Err(
                    "--octree: the file has no octree (bake it with --out-of-core)".to_string(),
                )
            }
            Err(e) => return Err(format!("--octree: {e}")),
        }
    } else {
        None
    };
    if !(1..=4).contains(&a.cameras) {
        return Err(format!("--cameras {}: 1 to 4 supported", a.cameras));
    }
    if a.width < 2 || a.height < 2 {
        return Err(format!(
            "--width {} --height {}: at least 2",
            a.width, a.height
        ));
    }
    let ctx = Context::headless(&HeadlessDesc {
        validation: a.validate,
        prefer_lavapipe: !a.gpu,
    })
    .map_err(|e| format!("no Vulkan device for rendering: {e}"))?;
    let desc = SnapshotDesc {
        cameras: a.cameras,
        tolerance_px: a.tolerance,
        width: a.width,
        height: a.height,
        layout: if a.separate {
            Layout::Separate
        } else {
            Layout::SplitScreen
        },
    };
    let snapshot = match &octree {
        Some(o) => render_octree_snapshot(&ctx, o, &desc),
        None => render_snapshot(&ctx, h, &desc),
    };
    let messages = ctx.take_validation_messages();
    ctx.destroy().map_err(|e| e.to_string())?;
    let snapshot = snapshot.map_err(|e| e.to_string())?;
    std::fs::create_dir_all(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let mut written = Vec::new();
    for (i, image) in snapshot.images.iter().enumerate() {
        let name = if a.separate {
            format!("camera{i}.png")
        } else {
            format!("split{}.png", a.cameras)
        };
        let path = a.out.join(name);
        write_png(image, &path).map_err(|e| e.to_string())?;
        written.push(path.display().to_string());
    }
    for (i, (polys, bytes)) in snapshot
        .active_polygons
        .iter()
        .zip(&snapshot.stats.camera_index_bytes)
        .enumerate()
    {
        println!("camera {i}: {polys} active polygons, {bytes} index bytes");
    }
    println!(
        "{} draws, {} index bytes in the frame; wrote {}",
        snapshot.stats.draws,
        snapshot.stats.index_bytes,
        written.join(", ")
    );
    if !messages.is_empty() {
        return Err(format!(
            "{} validation message(s):\n{}",
            messages.len(),
            messages.join("\n")
        ));
    }
    Ok(())
}
