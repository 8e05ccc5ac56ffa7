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
use std::path::PathBuf;

use caveclod_bake::gmesh::{build as build_gmesh, GMeshOptions};
use caveclod_bake::import::ImportOptions;
use caveclod_bake::pipeline::{bake_file, bake_mesh};
use caveclod_core::glam::Vec3;
use caveclod_core::gmesh::GMesh;
use caveclod_core::gmesh::{
    control, scene_polygons, t_from_distance, ControlEntry, ControlParams, LodInstance, LodModel,
    Partitions,
};
use caveclod_core::gpu::MorphInstance;
use caveclod_tests::meshes::{self, Rng};
use caveclod_tests::to_mesh;
use caveclod_vulkan::{
    CameraDraw, CameraIndices, Context, HeadlessDesc, IndexSource, LookAt, Morph, MorphInstances,
    Renderer, RendererDesc, VertexBuffer, Viewport,
};
use plotters::prelude::*;

const USAGE: &str = "usage: crowd [--mesh FILE] [--instances N] [--frames F] [--budget P] \
[--epsilon E] [--path circle|volatile|both] [--levels L] [--out DIR] [--json] [--no-render]";

/// The crowd stands on a disc of this radius (instances are scaled to radius 1).
const CROWD_RADIUS: f32 = 100.0;
/// Full detail up to here...
const D_NEAR: f32 = 5.0;
/// ...coarsest beyond here.
const D_FAR: f32 = 250.0;
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

#[derive(Clone, Copy, Debug, PartialEq)]
enum CameraPath {
    Circle,
    Volatile,
}

impl CameraPath {
    fn name(self) -> &'static str {
        match self {
            Self::Circle => "circle",
            Self::Volatile => "volatile",
        }
    }

    /// Eye, target and up at `s ∈ [0, 1)` of the path.
    fn at(self, s: f32) -> (Vec3, Vec3, Vec3) {
        match self {
            Self::Circle => {
                let a = s * std::f32::consts::TAU;
                let r = CROWD_RADIUS * 1.3;
                (
                    Vec3::new(r * a.cos(), 40.0, r * a.sin()),
                    Vec3::ZERO,
                    Vec3::Y,
                )
            }
            Self::Volatile => {
                let x = -2.0 * CROWD_RADIUS + 4.0 * CROWD_RADIUS * s;
                let eye = Vec3::new(x, 0.8 * CROWD_RADIUS, 0.0);
                (eye, eye - Vec3::Y, Vec3::Z)
            }
        }
    }
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

/// One run's per-frame figures.
struct Run {
    label: &'static str,
    cap: Option<f32>,
    polygons: Vec<u64>,
    bias: Vec<f32>,
    visible: Vec<usize>,
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
        let (eye, target, up) = path.at(f as f32 / args.frames as f32);
        let look = LookAt {
            eye,
            target,
            up,
            fov_y: 1.0,
            near: 0.5,
            far: 1000.0,
        };
        let view = look.view(1280, 720);
        let mut visible = 0;
        for (inst, &p) in instances.iter_mut().zip(places) {
            inst.t = t_from_distance(eye.distance(p), D_NEAR, D_FAR);
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

fn plot(
    file: &std::path::Path,
    path: CameraPath,
    runs: &[Run],
    instances: usize,
    budget: u64,
    epsilon: u64,
) -> Result<(), Box<dyn std::error::Error>> {
    let frames = runs.first().map_or(0, |r| r.polygons.len());
    let ymax = runs
        .iter()
        .flat_map(|r| r.polygons.iter().copied())
        .chain([budget + epsilon])
        .max()
        .unwrap_or(1) as f64
        * 1.08;
    let root = SVGBackend::new(file, (1100, 900)).into_drawing_area();
    root.fill(&WHITE)?;
    let (top, bottom) = root.split_vertically(600);
    let colours = [
        RGBColor(120, 120, 120),
        RGBColor(214, 39, 40),
        RGBColor(31, 119, 180),
    ];
    {
        let mut chart = ChartBuilder::on(&top)
            .caption(
                format!(
                    "Polygons per frame, {} path ({instances} instances, budget {budget}, ε = {epsilon})",
                    path.name(),
                ),
                ("sans-serif", 22),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(80)
            .build_cartesian_2d(0..frames, 0f64..ymax)?;
        chart
            .configure_mesh()
            .x_desc("frame")
            .y_desc("polygons drawn")
            .y_label_formatter(&|v| format!("{:.0}k", v / 1000.0))
            .draw()?;
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [
                    (0usize, budget.saturating_sub(epsilon) as f64),
                    (frames, (budget + epsilon) as f64),
                ],
                RGBColor(44, 160, 44).mix(0.15).filled(),
            )))?
            .label("budget ± ε")
            .legend(|(x, y)| {
                Rectangle::new(
                    [(x, y - 5), (x + 20, y + 5)],
                    RGBColor(44, 160, 44).mix(0.3).filled(),
                )
            });
        chart.draw_series(LineSeries::new(
            [(0usize, budget as f64), (frames, budget as f64)],
            RGBColor(44, 160, 44).stroke_width(1),
        ))?;
        for (run, colour) in runs.iter().zip(colours) {
            chart
                .draw_series(LineSeries::new(
                    run.polygons.iter().enumerate().map(|(f, &q)| (f, q as f64)),
                    colour.stroke_width(2),
                ))?
                .label(run.label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerMiddle)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
    }
    {
        let (lo, hi) = runs
            .iter()
            .flat_map(|r| r.bias.iter().copied())
            .fold((0f32, 0f32), |(lo, hi), b| (lo.min(b), hi.max(b)));
        let pad = ((hi - lo) * 0.1).max(0.01);
        let mut chart = ChartBuilder::on(&bottom)
            .caption("T_bias per frame (controller output)", ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(80)
            .build_cartesian_2d(0..frames, (lo - pad)..(hi + pad))?;
        chart
            .configure_mesh()
            .x_desc("frame")
            .y_desc("T_bias")
            .draw()?;
        for (run, colour) in runs.iter().zip(colours) {
            if run.cap.is_none() {
                continue;
            }
            chart
                .draw_series(LineSeries::new(
                    run.bias.iter().enumerate().map(|(f, &b)| (f, b)),
                    colour.stroke_width(2),
                ))?
                .label(run.label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerMiddle)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
    }
    root.present()?;
    Ok(())
}

/// A g-mesh level on the device: both attribute streams and the per-surface lists.
struct LevelBuffers {
    a: VertexBuffer,
    b: VertexBuffer,
    lists: Vec<Vec<u32>>,
}

/// Draws `frames` of a run to PNG; returns the files written.
#[allow(clippy::too_many_arguments)]
fn render_run(
    h: &caveclod_core::Hierarchy<'_>,
    gm: &GMesh<'_>,
    path: CameraPath,
    places: &[Vec3],
    run: &Run,
    total_frames: usize,
    frames: &[usize],
    out: &std::path::Path,
) -> Result<Vec<PathBuf>, String> {
    let ctx = Context::headless(&HeadlessDesc {
        validation: false,
        prefer_lavapipe: true,
    })
    .map_err(|e| e.to_string())?;
    let result = render_with(&ctx, h, gm, path, places, run, total_frames, frames, out);
    let destroyed = ctx.destroy().map_err(|e| e.to_string());
    let files = result?;
    destroyed?;
    Ok(files)
}

#[allow(clippy::too_many_arguments)]
fn render_with(
    ctx: &Context,
    h: &caveclod_core::Hierarchy<'_>,
    gm: &GMesh<'_>,
    path: CameraPath,
    places: &[Vec3],
    run: &Run,
    total_frames: usize,
    frames: &[usize],
    out: &std::path::Path,
) -> Result<Vec<PathBuf>, String> {
    let e = |e: caveclod_vulkan::Error| e.to_string();
    // Instances are placed at radius 1 around their point.
    let m = h.meta();
    let (lo, hi) = (
        Vec3::from_array(m.bounds_min),
        Vec3::from_array(m.bounds_max),
    );
    let centre = (lo + hi) * 0.5;
    let scale = 1.0 / ((hi - lo).length() * 0.5).max(1e-6);
    let mut levels = Vec::new();
    for i in 0..gm.levels() {
        let level = gm.level(i).ok_or("missing level")?;
        let gather = |side: usize| -> Vec<caveclod_core::format::Vertex> {
            level
                .vertices
                .iter()
                .map(|p| h.vertices()[p[side] as usize])
                .collect()
        };
        levels.push(LevelBuffers {
            a: VertexBuffer::from_vertices(ctx, "a_i", &gather(0)).map_err(e)?,
            b: VertexBuffer::from_vertices(ctx, "a'_i", &gather(1)).map_err(e)?,
            lists: (0..gm.surfaces())
                .map(|s| level.surface_indices(s).to_vec())
                .collect(),
        });
    }
    let (w, hgt) = (1280, 720);
    let mut renderer = Renderer::new(
        ctx,
        RendererDesc {
            targets: vec![(w, hgt)],
            frames_in_flight: 1,
            readback: true,
            clear_colour: [0.55, 0.7, 0.9, 1.0],
            geomorph: true,
        },
    )
    .map_err(e)?;
    let colours: Vec<[f32; 4]> = (0..gm.surfaces())
        .map(caveclod_cli::snapshot::palette)
        .collect();
    let mut written = Vec::new();
    let mut outcome = Ok(());
    for &f in frames {
        let (eye, target, up) = path.at(f as f32 / total_frames as f32);
        let look = LookAt {
            eye,
            target,
            up,
            fov_y: 1.0,
            near: 0.5,
            far: 1000.0,
        };
        let viewport = Viewport::full(w, hgt);
        let view = look.view(viewport.width, viewport.height);
        let bias = run.bias.get(f).copied().unwrap_or(0.0);
        let mut per_level: Vec<Vec<MorphInstance>> = vec![Vec::new(); levels.len()];
        for &p in places {
            if !view.sphere_visible(p, 1.0) {
                continue;
            }
            let lm = gm
                .partitions()
                .level_morph(t_from_distance(eye.distance(p), D_NEAR, D_FAR) + bias);
            let o = p - centre * scale;
            per_level[lm.level].push(MorphInstance {
                offset_scale: [o.x, o.y, o.z, scale],
                t: lm.t,
                _pad: [0.0; 3],
            });
        }
        let mut inst_buffers = Vec::new();
        for (i, list) in per_level.iter().enumerate() {
            if !list.is_empty() {
                match MorphInstances::new(ctx, "instances", list) {
                    Ok(b) => inst_buffers.push((i, b)),
                    Err(err) => {
                        outcome = Err(err.to_string());
                        break;
                    }
                }
            }
        }
        let mut indices: Vec<CameraIndices> = inst_buffers
            .iter()
            .map(|_| CameraIndices::new("level", gm.surfaces(), 1))
            .collect();
        if outcome.is_ok() {
            let refs: Vec<Vec<&[u32]>> = inst_buffers
                .iter()
                .map(|(i, _)| levels[*i].lists.iter().map(Vec::as_slice).collect())
                .collect();
            let mut draws: Vec<CameraDraw<'_, '_>> = inst_buffers
                .iter()
                .zip(indices.iter_mut())
                .zip(&refs)
                .map(|(((i, inst), ind), lists)| CameraDraw {
                    target: 0,
                    viewport,
                    view_proj: look.view_projection(viewport.aspect()),
                    vertices: &levels[*i].a,
                    indices: ind,
                    source: IndexSource::Lists(lists),
                    colours: &colours,
                    morph: Some(Morph {
                        fine: &levels[*i].b,
                        instances: inst,
                    }),
                })
                .collect();
            let image = renderer
                .render(ctx, &mut draws)
                .and_then(|_| renderer.read_target(ctx, 0));
            match image {
                Ok(img) => {
                    let file = out.join(format!("crowd-{}-{f:03}.png", path.name()));
                    match caveclod_cli::snapshot::write_png(&img, &file) {
                        Ok(()) => written.push(file),
                        Err(err) => outcome = Err(err.to_string()),
                    }
                }
                Err(err) => outcome = Err(err.to_string()),
            }
        }
        for ind in indices {
            if let Err(err) = ind.destroy(ctx) {
                outcome = Err(err.to_string());
            }
        }
        for (_, b) in inst_buffers {
            if let Err(err) = b.destroy(ctx) {
                outcome = Err(err.to_string());
            }
        }
        if outcome.is_err() {
            break;
        }
    }
    let mut cleanup = renderer.destroy(ctx);
    for l in levels {
        cleanup = cleanup
            .and_then(|()| l.a.destroy(ctx))
            .and_then(|()| l.b.destroy(ctx));
    }
    outcome?;
    cleanup.map_err(e)?;
    Ok(written)
}

fn main() {
    if let Err(e) = real_main() {
        eprintln!("crowd: {e}");
        std::process::exit(1);
    }
}

fn real_main() -> Result<(), String> {
    let args = parse_args()?;
    let (baked, source) = if args.mesh.exists() {
        let (b, _) = bake_file(&args.mesh, &ImportOptions::default(), &mut |_| {})
            .map_err(|e| e.to_string())?;
        (b, args.mesh.display().to_string())
    } else {
        let (b, _) = bake_mesh(&to_mesh(&meshes::sphere(5)), "sphere", &mut |_| {})
            .map_err(|e| e.to_string())?;
        (
            b,
            format!("generated sphere ({} absent)", args.mesh.display()),
        )
    };
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
    let gm =
        GMesh::new(g.parts(), h.vertices().len(), h.surface_count()).map_err(|e| e.to_string())?;
    let mut pictures: Vec<PathBuf> = Vec::new();
    let mut csv = String::from("path,run,frame,polygons,t_bias,visible\n");
    for &path in &args.paths {
        let runs = [
            run_path(path, &model, &places, &args, epsilon, None, "no control")?,
            run_path(
                path,
                &model,
                &places,
                &args,
                epsilon,
                Some(0.01),
                "control, |T_change| ≤ 0.01",
            )?,
            run_path(
                path,
                &model,
                &places,
                &args,
                epsilon,
                Some(0.1),
                "control, |T_change| ≤ 0.1",
            )?,
        ];
        for run in &runs {
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
        if args.render && path == CameraPath::Circle {
            let shots = [0, args.frames / 3, 2 * args.frames / 3, args.frames - 1];
            match render_run(
                &h,
                &gm,
                path,
                &places,
                &runs[2],
                args.frames,
                &shots,
                &args.out,
            ) {
                Ok(files) => pictures.extend(files),
                Err(e) => eprintln!(
                    "crowd: no pictures ({e}); install a Vulkan driver (cargo xtask setup) or \
                     pass --no-render"
                ),
            }
        }
        let svg = args.out.join(format!("crowd-{}.svg", path.name()));
        plot(&svg, path, &runs, args.instances, args.budget, epsilon)
            .map_err(|e| format!("{}: {e}", svg.display()))?;
        if args.json {
            let (within, counted, worst) = settle(&runs[2], args.budget, epsilon);
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
        } else {
            println!("\n{} path ({}):", path.name(), svg.display());
            for run in &runs {
                let (within, counted, worst) = settle(run, args.budget, epsilon);
                println!(
                    "  {:<28} within ±ε on {within:>4} of {counted} frames after the first \
                     {WARM_UP}; largest deviation {worst}",
                    run.label
                );
            }
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
