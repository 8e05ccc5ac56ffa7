//! Crowd: a thousand instances of one g-mesh held to a polygon budget by the greedy predictive
//! controller of Southern & Gain (§5.1), along the paper's two camera paths, reproducing its
//! Figure 10 as plots and CSV.
//!
//! ```text
//! cargo run --release -p caveclod-examples --example crowd -- [OPTIONS]
//!
//!   --mesh FILE       mesh to bake (default data/spot/spot_triangulated.obj; a generated
//!                     sphere of 20,480 triangles if that file is absent)
//!   --instances N     instances (default 1000)
//!   --frames F        frames per run (default 720)
//!   --budget P        polygon budget (default 500000)
//!   --epsilon E       tolerance (default |c0| - |c1|, the paper's)
//!   --path P          circle | volatile | both (default both)
//!   --levels L        at most L g-mesh levels (default 10)
//!   --out DIR         where plots and CSV go (default out/crowd)
//!   --json            print one JSON object per path for the controlled run with cap 0.1
//!   --no-render       CPU only: no pictures
//! ```
//!
//! For each path it runs the scene three times: without control (`T` from distance only),
//! and with control capped at `|T_change| ≤ 0.01` and `≤ 0.1` per frame. The circle path
//! (camera circling the crowd, looking at its centre) is the paper's non-volatile case; the
//! volatile one flies low across the centre looking straight down, so instances rush in and
//! out of the view frustum. Writes `crowd.csv` (one row per path, run and frame) and one SVG
//! plot per path: polygons per frame for the three runs against the budget and its `±ε` band,
//! and `T_bias` per frame. Unless `--no-render`, it also draws frames 0, 1/3, 2/3 and the last
//! of the controlled circle run (cap 0.1) to `crowd-circle-NNN.png` on the Vulkan device
//! (lavapipe by default): each g-mesh level is one instanced draw through the geomorph vertex
//! stage, every visible instance morphing by its own factor.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use caveclod_bake::baked::Baked;
use caveclod_bake::generate::meshes::{self, Rng};
use caveclod_bake::generate::to_mesh;
use caveclod_bake::gmesh::GMeshData;
use caveclod_bake::gmesh::{build as build_gmesh, GMeshOptions};
use caveclod_bake::import::ImportOptions;
use caveclod_bake::pipeline::{bake_file, bake_mesh};
use caveclod_core::glam::Vec3;
use caveclod_core::gmesh::GMesh;
use caveclod_core::gmesh::{
    control, scene_polygons, t_from_distance, ControlEntry, ControlParams, LodInstance, LodModel,
    Partitions,
};
use caveclod_core::Hierarchy;

mod flight;
mod plot;
mod render;

use flight::{CameraPath, Run, CROWD_RADIUS, D_FAR, D_NEAR};

const USAGE: &str = "usage: crowd [--mesh FILE] [--instances N] [--frames F] [--budget P] \
[--epsilon E] [--path circle|volatile|both] [--levels L] [--out DIR] [--json] [--no-render]";

/// Frames a controlled run needs to settle from the uncontrolled start.
const WARM_UP: usize = 20;

#[derive(Clone, Debug)]
struct Args {
    mesh: PathBuf,
    instances: usize,
    frames: usize,
    budget: u64,
    epsilon: Option<u64>,
    paths: Vec<CameraPath>,
    levels: u32,
    out: PathBuf,
    json: bool,
    render: bool,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        mesh: PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../data/spot/spot_triangulated.obj"
        )),
        instances: 1000,
        frames: 720,
        budget: 500_000,
        epsilon: None,
        paths: vec![CameraPath::Circle, CameraPath::Volatile],
        levels: 10,
        out: PathBuf::from("out/crowd"),
        json: false,
        render: true,
    };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value\n{USAGE}"));
        let num = |s: String, name: &str| -> Result<u64, String> {
            s.parse().map_err(|_| format!("{name}: not a number: {s}"))
        };
        match arg.as_str() {
            "--mesh" => a.mesh = PathBuf::from(value("--mesh")?),
            "--instances" => a.instances = num(value("--instances")?, "--instances")? as usize,
            "--frames" => a.frames = num(value("--frames")?, "--frames")? as usize,
            "--budget" => a.budget = num(value("--budget")?, "--budget")?,
            "--epsilon" => a.epsilon = Some(num(value("--epsilon")?, "--epsilon")?),
            "--levels" => a.levels = num(value("--levels")?, "--levels")? as u32,
            "--out" => a.out = PathBuf::from(value("--out")?),
            "--path" => {
                a.paths = match value("--path")?.as_str() {
                    "circle" => vec![CameraPath::Circle],
                    "volatile" => vec![CameraPath::Volatile],
                    "both" => vec![CameraPath::Circle, CameraPath::Volatile],
                    other => return Err(format!("--path: unknown path {other}\n{USAGE}")),
                }
            }
            "--json" => a.json = true,
            "--no-render" => a.render = false,
            "-h" | "--help" => return Err(USAGE.to_string()),
            other => return Err(format!("unknown argument {other}\n{USAGE}")),
        }
    }
    if a.instances == 0 || a.frames == 0 || a.levels < 2 {
        return Err(format!(
            "instances and frames must be positive, levels at least 2\n{USAGE}"
        ));
    }
    Ok(a)
}

/// Places the crowd: uniform on the disc, deterministic.
fn place(n: usize) -> Vec<Vec3> {
    let mut rng = Rng(0x5eed);
    (0..n)
        .map(|_| {
            let r = CROWD_RADIUS * rng.unit().sqrt();
            let a = rng.unit() * std::f32::consts::TAU;
            Vec3::new(r * a.cos(), 1.0, r * a.sin())
        })
        .collect()
}

fn run_path(
    path: CameraPath,
    model: &LodModel<'_>,
    places: &[Vec3],
    args: &Args,
    epsilon: u64,
    cap: Option<f32>,
    label: &'static str,
) -> Result<Run, String> {
    let models = [*model];
    let mut instances: Vec<LodInstance> = places
        .iter()
        .map(|_| LodInstance {
            model: 0,
            t: 0.0,
            visible: true,
        })
        .collect();
    let mut scratch = vec![ControlEntry::default(); instances.len()];
    let mut bias = 0.0f32;
    let mut run = Run {
        label,
        cap,
        polygons: Vec::with_capacity(args.frames),
        bias: Vec::with_capacity(args.frames),
        visible: Vec::with_capacity(args.frames),
    };
    for f in 0..args.frames {
        let look = path.look_at(f as f32 / args.frames as f32);
        let view = look.view(1280, 720);
        let mut visible = 0;
        for (inst, &p) in instances.iter_mut().zip(places) {
            inst.t = t_from_distance(look.eye.distance(p), D_NEAR, D_FAR);
            inst.visible = view.sphere_visible(p, 1.0);
            visible += usize::from(inst.visible);
        }
        let q = match cap {
            None => scene_polygons(&models, &instances, 0.0).map_err(|e| e.to_string())?,
            Some(cap) => {
                let params = ControlParams {
                    budget: args.budget,
                    epsilon,
                    max_change: cap,
                };
                let o = control(&models, &instances, bias, &params, &mut scratch)
                    .map_err(|e| e.to_string())?;
                bias = o.bias;
                o.polygons
            }
        };
        run.polygons.push(q);
        run.bias.push(bias);
        run.visible.push(visible);
    }
    Ok(run)
}

/// Frames after the warm-up within `±ε`, and the largest deviation after it.
fn settle(run: &Run, budget: u64, epsilon: u64) -> (usize, usize, u64) {
    let after = &run.polygons[WARM_UP.min(run.polygons.len())..];
    let within = after
        .iter()
        .filter(|&&q| q.abs_diff(budget) <= epsilon)
        .count();
    let worst = after.iter().map(|&q| q.abs_diff(budget)).max().unwrap_or(0);
    (within, after.len(), worst)
}

fn main() {
    if let Err(e) = real_main() {
        eprintln!("crowd: {e}");
        std::process::exit(1);
    }
}

fn real_main() -> Result<(), String> {
    let args = parse_args()?;
    let (baked, source) = bake_input(&args)?;
    let h = baked.hierarchy().map_err(|e| e.to_string())?;
    let options = GMeshOptions {
        min_polygons: 200,
        max_levels: args.levels,
        ..GMeshOptions::default()
    };
    let g = build_gmesh(&h, &options).map_err(|e| e.to_string())?;
    let partitions = Partitions::new(&g.boundaries).map_err(|e| e.to_string())?;
    let model = LodModel::new(partitions, &g.level_polygons).map_err(|e| e.to_string())?;
    let epsilon = args.epsilon.unwrap_or_else(|| model.default_epsilon());
    let places = place(args.instances);
    std::fs::create_dir_all(&args.out).map_err(|e| format!("{}: {e}", args.out.display()))?;
    if !args.json {
        print_setup(&source, &g, &args, epsilon);
    }
    let gm =
        GMesh::new(g.parts(), h.vertices().len(), h.surface_count()).map_err(|e| e.to_string())?;
    let mut pictures: Vec<PathBuf> = Vec::new();
    let mut csv = String::from("path,run,frame,polygons,t_bias,visible\n");
    for &path in &args.paths {
        let runs = fly_runs(path, &model, &places, &args, epsilon)?;
        csv_rows(&mut csv, path, &runs);
        if args.render && path == CameraPath::Circle {
            pictures.extend(draw_pictures(&h, &gm, path, &places, &runs[2], &args));
        }
        let svg = args.out.join(format!("crowd-{}.svg", path.name()));
        plot::plot(&svg, path, &runs, args.instances, args.budget, epsilon)
            .map_err(|e| format!("{}: {e}", svg.display()))?;
        if args.json {
            print_json(path, &runs[2], &args, epsilon, &g);
        } else {
            print_settling(path, &svg, &runs, &args, epsilon);
        }
    }
    let csv_path = args.out.join("crowd.csv");
    std::fs::write(&csv_path, csv).map_err(|e| format!("{}: {e}", csv_path.display()))?;
    if !args.json {
        println!("\nwrote {}", csv_path.display());
        for p in &pictures {
            println!("wrote {}", p.display());
        }
    }
    Ok(())
}

/// Bakes the mesh, or a generated sphere when the file is absent; returns it with its
/// description.
fn bake_input(args: &Args) -> Result<(Baked, String), String> {
    if args.mesh.exists() {
        let (b, _) = bake_file(&args.mesh, &ImportOptions::default(), &mut |_| {})
            .map_err(|e| e.to_string())?;
        Ok((b, args.mesh.display().to_string()))
    } else {
        let (b, _) = bake_mesh(&to_mesh(&meshes::sphere(5)), "sphere", &mut |_| {})
            .map_err(|e| e.to_string())?;
        Ok((
            b,
            format!("generated sphere ({} absent)", args.mesh.display()),
        ))
    }
}

/// The mesh, its g-mesh levels and partitions, and the runs' parameters.
fn print_setup(source: &str, g: &GMeshData, args: &Args, epsilon: u64) {
    println!(
        "mesh: {source}; g-mesh levels {:?} polygons, partitions {:?}",
        g.level_polygons,
        g.boundaries
            .iter()
            .map(|r| (r * 1000.0).round() / 1000.0)
            .collect::<Vec<_>>()
    );
    println!(
        "{} instances, budget {}, epsilon {epsilon}, {} frames per run",
        args.instances, args.budget, args.frames
    );
}

/// The path's three runs: without control, and with control capped at 0.01 and 0.1.
fn fly_runs(
    path: CameraPath,
    model: &LodModel<'_>,
    places: &[Vec3],
    args: &Args,
    epsilon: u64,
) -> Result<[Run; 3], String> {
    Ok([
        run_path(path, model, places, args, epsilon, None, "no control")?,
        run_path(
            path,
            model,
            places,
            args,
            epsilon,
            Some(0.01),
            "control, |T_change| ≤ 0.01",
        )?,
        run_path(
            path,
            model,
            places,
            args,
            epsilon,
            Some(0.1),
            "control, |T_change| ≤ 0.1",
        )?,
    ])
}

/// One CSV row per run and frame.
fn csv_rows(csv: &mut String, path: CameraPath, runs: &[Run]) {
    for run in runs {
        for f in 0..run.polygons.len() {
            let _ = writeln!(
                csv,
                "{},{},{f},{},{},{}",
                path.name(),
                run.label.replace(',', ";"),
                run.polygons[f],
                run.bias[f],
                run.visible[f]
            );
        }
    }
}

/// Frames 0, 1/3, 2/3 and the last of `run` as PNG; none (with a note on stderr) when no
/// Vulkan device draws them.
fn draw_pictures(
    h: &Hierarchy<'_>,
    gm: &GMesh<'_>,
    path: CameraPath,
    places: &[Vec3],
    run: &Run,
    args: &Args,
) -> Vec<PathBuf> {
    let shots = [0, args.frames / 3, 2 * args.frames / 3, args.frames - 1];
    match render::render_run(h, gm, path, places, run, args.frames, &shots, &args.out) {
        Ok(files) => files,
        Err(e) => {
            eprintln!(
                "crowd: no pictures ({e}); install a Vulkan driver (cargo xtask setup) or \
                 pass --no-render"
            );
            Vec::new()
        }
    }
}

/// The controlled run's settling as one JSON object.
fn print_json(path: CameraPath, run: &Run, args: &Args, epsilon: u64, g: &GMeshData) {
    let (within, counted, worst) = settle(run, args.budget, epsilon);
    println!(
        "{}",
        serde_json::json!({
            "path": path.name(),
            "instances": args.instances,
            "frames": args.frames,
            "budget": args.budget,
            "epsilon": epsilon,
            "frames_within_epsilon": within,
            "frames_counted": counted,
            "warm_up_frames": WARM_UP,
            "max_deviation": worst,
            "max_change": 0.1,
            "gmesh_level_polygons": g.level_polygons,
        })
    );
}

/// How each run kept to the budget after the warm-up.
fn print_settling(path: CameraPath, svg: &Path, runs: &[Run], args: &Args, epsilon: u64) {
    println!("\n{} path ({}):", path.name(), svg.display());
    for run in runs {
        let (within, counted, worst) = settle(run, args.budget, epsilon);
        println!(
            "  {:<28} within ±ε on {within:>4} of {counted} frames after the first \
             {WARM_UP}; largest deviation {worst}",
            run.label
        );
    }
}
