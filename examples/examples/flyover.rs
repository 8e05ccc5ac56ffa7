//! Fly-over: several cameras fly scripted paths over one generated terrain of about a million
//! polygons, each refining its own [`CameraState`] over the one shared [`Hierarchy`] and
//! emitting its index lists every frame (CAVECLOD's multi-camera set-up).
//!
//! ```text
//! cargo run --release -p caveclod-examples --example flyover -- [OPTIONS]
//!
//!   --size N          terrain of N x N cells, 2 N^2 polygons (default 708: about 1.0 M)
//!   --seed S          terrain seed (default 7)
//!   --cameras N       1 to 4 cameras (default 4)
//!   --frames F        frames per camera (default 300)
//!   --tolerance PX    screen-space tolerance in pixels (default 1.0; 1280 x 720, fov 60 deg)
//!   --shared-state    one CameraState re-refined for each camera in turn (the paper's baseline)
//!   --threads         one thread per camera (std::thread::scope), frames kept in step
//!   --full-capacity   fly cameras that can reach full resolution anywhere, without sizing
//!   --json            print one JSON object instead of the report
//! ```
//!
//! Per-camera mode first sizes its cameras: a refine-only flight of full-capacity cameras
//! ([`CameraConfig::full`]) over every third frame finds the largest front each camera needs;
//! the measured flight then uses cameras sized by [`CameraConfig::with_polygon_budget`] to
//! that front plus 10%, which is what a runtime with fixed memory would allocate. Capacity
//! refusals (wanted splits a full camera declined) are counted and reported. Memory is
//! reported for both capacities against the CAVECLOD paper's equation 1.

use std::fmt::Write as _;
use std::sync::Barrier;
use std::time::{Duration, Instant};

use caveclod_core::glam::Vec3;
use caveclod_core::{
    CameraConfig, CameraState, Hierarchy, MemoryReport, RefineParams, RefineStats, View,
};
use caveclod_tests::{bake, meshes};

const WIDTH: f32 = 1280.0;
const HEIGHT: f32 = 720.0;
const FOV_Y_DEG: f32 = 60.0;
/// Headroom over the sizing flight's largest front when budgeting cameras.
const BUDGET_HEADROOM: f64 = 1.10;
/// The sizing flight refines every this many frames.
const SIZING_STRIDE: usize = 3;

const USAGE: &str = "usage: flyover [--size N] [--seed S] [--cameras 1-4] [--frames F] \
[--tolerance PX] [--shared-state] [--threads] [--full-capacity] [--json]";

#[derive(Clone, Debug)]
struct Args {
    size: u32,
    seed: u64,
    cameras: usize,
    frames: usize,
    tolerance: f32,
    shared_state: bool,
    threads: bool,
    full_capacity: bool,
    json: bool,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        size: 708,
        seed: 7,
        cameras: 4,
        frames: 300,
        tolerance: 1.0,
        shared_state: false,
        threads: false,
        full_capacity: false,
        json: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = |name: &str| {
            it.next()
                .ok_or_else(|| format!("{name} needs a value\n{USAGE}"))
        };
        fn num<T: std::str::FromStr>(name: &str, v: String) -> Result<T, String> {
            v.parse()
                .map_err(|_| format!("{name}: cannot parse {v:?}\n{USAGE}"))
        }
        match flag.as_str() {
            "--size" => a.size = num("--size", value("--size")?)?,
            "--seed" => a.seed = num("--seed", value("--seed")?)?,
            "--cameras" => a.cameras = num("--cameras", value("--cameras")?)?,
            "--frames" => a.frames = num("--frames", value("--frames")?)?,
            "--tolerance" => a.tolerance = num("--tolerance", value("--tolerance")?)?,
            "--shared-state" => a.shared_state = true,
            "--threads" => a.threads = true,
            "--full-capacity" => a.full_capacity = true,
            "--json" => a.json = true,
            "-h" | "--help" => return Err(USAGE.to_string()),
            other => return Err(format!("unknown argument {other:?}\n{USAGE}")),
        }
    }
    if !(1..=4).contains(&a.cameras) {
        return Err(format!("--cameras must be 1 to 4\n{USAGE}"));
    }
    if a.size < 4 || a.frames < 2 || !a.tolerance.is_finite() || a.tolerance <= 0.0 {
        return Err(format!(
            "need --size >= 4, --frames >= 2, --tolerance > 0\n{USAGE}"
        ));
    }
    if a.shared_state && a.threads {
        return Err("--shared-state and --threads exclude each other".into());
    }
    Ok(a)
}

/// Terrain heights on the grid, for terrain-following flight paths.
struct Ground {
    n: u32,
    heights: Vec<f32>,
}

impl Ground {
    fn new(mesh: &meshes::TestMesh, n: u32) -> Self {
        let side = (n + 1) as usize;
        let heights = if mesh.positions.len() == side * side {
            mesh.positions.iter().map(|p| p[1]).collect()
        } else {
            // Not the full grid: fly above the highest point everywhere.
            let top = mesh.positions.iter().map(|p| p[1]).fold(0.0, f32::max);
            vec![top; side * side]
        };
        Self { n, heights }
    }

    /// Bilinear height at (x, z), clamped to the terrain.
    fn at(&self, x: f32, z: f32) -> f32 {
        let n = self.n as f32;
        let (x, z) = (x.clamp(0.0, n), z.clamp(0.0, n));
        let (i, j) = ((x as u32).min(self.n - 1), (z as u32).min(self.n - 1));
        let (fx, fz) = (x - i as f32, z - j as f32);
        let side = self.n + 1;
        let h = |i: u32, j: u32| self.heights[(j * side + i) as usize];
        let a = h(i, j) * (1.0 - fx) + h(i + 1, j) * fx;
        let b = h(i, j + 1) * (1.0 - fx) + h(i + 1, j + 1) * fx;
        a * (1.0 - fz) + b * fz
    }
}

/// The scripted flight paths: ground point as a function of distance flown.
#[derive(Clone, Copy, Debug)]
enum Path {
    /// Circle around the centre, clockwise seen from above.
    Circle { radius: f32, phase: f32 },
    /// Circle the other way.
    CircleBack { radius: f32, phase: f32 },
    /// Straight pass along the diagonal, back and forth.
    Pass,
    /// A figure-eight (lemniscate of Gerono) around the centre.
    FigureEight { a: f32 },
}

struct Route {
    name: &'static str,
    path: Path,
    /// Height above the highest ground around the camera, in terrain sizes.
    clearance: f32,
    /// Look-down angle, degrees.
    pitch_deg: f32,
}

fn routes() -> [Route; 4] {
    [
        Route {
            name: "wide circle",
            path: Path::Circle {
                radius: 0.32,
                phase: 0.0,
            },
            clearance: 0.03,
            pitch_deg: 25.0,
        },
        Route {
            name: "straight pass",
            path: Path::Pass,
            clearance: 0.015,
            pitch_deg: 15.0,
        },
        Route {
            name: "figure-eight",
            path: Path::FigureEight { a: 0.3 },
            clearance: 0.02,
            pitch_deg: 20.0,
        },
        Route {
            name: "tight circle",
            path: Path::CircleBack {
                radius: 0.15,
                phase: 2.0,
            },
            clearance: 0.06,
            pitch_deg: 35.0,
        },
    ]
}

/// Ground-plane position (x, z) after flying `s` world units.
fn ground_point(path: Path, s: f32, size: f32) -> (f32, f32) {
    let c = 0.5 * size;
    match path {
        Path::Circle { radius, phase } => {
            let r = radius * size;
            let t = phase + s / r;
            (c + r * t.cos(), c + r * t.sin())
        }
        Path::CircleBack { radius, phase } => {
            let r = radius * size;
            let t = phase - s / r;
            (c + r * t.cos(), c + r * t.sin())
        }
        Path::Pass => {
            let (a, b) = (0.1 * size, 0.9 * size);
            let len = (b - a) * std::f32::consts::SQRT_2;
            let u = (s / len).rem_euclid(2.0);
            let u = if u > 1.0 { 2.0 - u } else { u };
            let p = a + (b - a) * u;
            (p, p)
        }
        Path::FigureEight { a } => {
            let a = a * size;
            // Roughly constant speed: the lemniscate's length is about 6.1 a.
            let t = s / (6.1 * a) * std::f32::consts::TAU;
            (c + a * t.sin(), c + a * t.sin() * t.cos())
        }
    }
}

/// The view of `route` at frame `frame`, flying `speed` world units per frame.
fn view_at(route: &Route, frame: usize, speed: f32, size: f32, ground: &Ground) -> View {
    let s = frame as f32 * speed;
    let (x, z) = ground_point(route.path, s, size);
    let (x2, z2) = ground_point(route.path, s + speed.max(1e-3), size);
    let mut forward = Vec3::new(x2 - x, 0.0, z2 - z).normalize_or_zero();
    if forward == Vec3::ZERO {
        forward = Vec3::X;
    }
    // Clear the highest ground near and ahead of the camera.
    let look = 0.03 * size;
    let mut floor = f32::MIN;
    for k in 0..=6 {
        let d = look * k as f32 / 6.0;
        floor = floor.max(ground.at(x + forward.x * d, z + forward.z * d));
    }
    let eye = Vec3::new(x, floor + route.clearance * size, z);
    let pitch = route.pitch_deg.to_radians();
    let dir = forward * pitch.cos() - Vec3::Y * pitch.sin();
    View::perspective(
        eye,
        eye + dir,
        Vec3::Y,
        FOV_Y_DEG.to_radians(),
        WIDTH / HEIGHT,
        0.1,
        2.0 * size,
        HEIGHT,
    )
}

/// Per-frame figures of one camera.
#[derive(Clone, Debug, Default)]
struct Record {
    ops: Vec<u32>,
    splits: u64,
    forced: u64,
    collapses: u64,
    refine_ns: Vec<u64>,
    emit_ns: Vec<u64>,
    active_polygons: Vec<u32>,
    max_active_nodes: u32,
    indices: Vec<u32>,
    refusals: u64,
    overflows: u64,
}

impl Record {
    fn with_capacity(frames: usize) -> Self {
        Self {
            ops: Vec::with_capacity(frames),
            refine_ns: Vec::with_capacity(frames),
            emit_ns: Vec::with_capacity(frames),
            active_polygons: Vec::with_capacity(frames),
            indices: Vec::with_capacity(frames),
            ..Self::default()
        }
    }

    fn push(&mut self, st: &RefineStats, refine: Duration, emit: Duration, indices: usize) {
        self.ops.push(st.operations());
        self.splits += u64::from(st.splits);
        self.forced += u64::from(st.forced_splits);
        self.collapses += u64::from(st.collapses);
        self.refine_ns.push(refine.as_nanos() as u64);
        self.emit_ns.push(emit.as_nanos() as u64);
        self.active_polygons.push(st.active_polygons);
        self.max_active_nodes = self.max_active_nodes.max(st.active_nodes);
        self.indices.push(indices as u32);
        self.refusals += u64::from(st.capacity_refusals);
        self.overflows += u64::from(st.stack_overflows);
    }

    /// Frames after the first: the first frame refines from the base mesh.
    fn steady<T: Copy>(v: &[T]) -> &[T] {
        v.get(1..).unwrap_or(&[])
    }

    fn ops_mean(&self) -> f64 {
        mean(Self::steady(&self.ops).iter().map(|&x| f64::from(x)))
    }

    fn ops_max(&self) -> u32 {
        Self::steady(&self.ops).iter().copied().max().unwrap_or(0)
    }

    fn refine_ms_mean(&self) -> f64 {
        mean(Self::steady(&self.refine_ns).iter().map(|&x| x as f64)) * 1e-6
    }

    fn refine_ms_p99(&self) -> f64 {
        percentile(Self::steady(&self.refine_ns), 0.99) as f64 * 1e-6
    }

    fn emit_ms_mean(&self) -> f64 {
        mean(Self::steady(&self.emit_ns).iter().map(|&x| x as f64)) * 1e-6
    }

    fn active_mean(&self) -> f64 {
        mean(
            Self::steady(&self.active_polygons)
                .iter()
                .map(|&x| f64::from(x)),
        )
    }

    fn active_max(&self) -> u32 {
        self.active_polygons.iter().copied().max().unwrap_or(0)
    }

    fn indices_mean(&self) -> f64 {
        mean(Self::steady(&self.indices).iter().map(|&x| f64::from(x)))
    }

    fn indices_total(&self) -> u64 {
        self.indices.iter().map(|&x| u64::from(x)).sum()
    }
}

fn mean(it: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for x in it {
        s += x;
        n += 1;
    }
    if n == 0 {
        0.0
    } else {
        s / n as f64
    }
}

fn percentile(v: &[u64], q: f64) -> u64 {
    if v.is_empty() {
        return 0;
    }
    let mut s = v.to_vec();
    s.sort_unstable();
    let i = ((s.len() as f64 * q).ceil() as usize).clamp(1, s.len()) - 1;
    s[i]
}

/// Index output of one camera, allocated once and reused every frame.
struct IndexBuffers {
    indices: Vec<u32>,
    offsets: Vec<u32>,
}

impl IndexBuffers {
    /// Room for the largest front a camera with `max_pairs` splits can hold.
    fn new(h: &Hierarchy<'_>, max_pairs: u32) -> Self {
        let polys = h.base_polygon_count() + 2 * max_pairs as usize;
        Self {
            indices: vec![0; 3 * polys],
            offsets: vec![0; h.surface_count() + 1],
        }
    }
}

/// Refines `cam` to `view`, emits its indices, and records the frame.
fn frame(
    h: &Hierarchy<'_>,
    cam: &mut CameraState<'_>,
    view: &View,
    params: &RefineParams,
    out: Option<&mut IndexBuffers>,
    rec: &mut Record,
) -> Result<(), String> {
    let t0 = Instant::now();
    let st = cam
        .refine(h, view, params)
        .map_err(|e| format!("refine: {e}"))?;
    let t1 = Instant::now();
    let n = match out {
        Some(out) => {
            let n = cam
                .emit_indices_packed(h, &mut out.indices, &mut out.offsets)
                .map_err(|e| format!("emit: {e}"))?;
            std::hint::black_box(&out.indices);
            n
        }
        None => 0,
    };
    let t2 = Instant::now();
    rec.push(&st, t1 - t0, t2 - t1, n);
    Ok(())
}

/// What one flight of several cameras measured.
struct Flight {
    records: Vec<Record>,
    /// Bytes of one camera state.
    camera_bytes: usize,
    wall: Duration,
}

/// One flight of every camera, each with its own state of capacity `config`, over every
/// `stride`-th frame; `emit` also writes the index lists each frame.
fn fly_per_camera(
    h: &Hierarchy<'_>,
    views: &[Vec<View>],
    params: &RefineParams,
    config: &CameraConfig,
    stride: usize,
    emit: bool,
    threads: bool,
) -> Result<Flight, String> {
    let start = Instant::now();
    let words = CameraState::words_needed_for(h, config);
    let mut memories: Vec<Vec<u32>> = views.iter().map(|_| vec![0u32; words]).collect();
    let mut cams = Vec::with_capacity(views.len());
    for m in memories.iter_mut() {
        cams.push(CameraState::with_config(h, m, config).map_err(|e| e.to_string())?);
    }
    let camera_bytes = cams.first().map_or(0, CameraState::bytes);
    let mut outs: Vec<Option<IndexBuffers>> = views
        .iter()
        .map(|_| emit.then(|| IndexBuffers::new(h, config.max_pairs)))
        .collect();
    let frames = views.first().map_or(0, Vec::len).div_ceil(stride);
    let records = if threads {
        let barrier = Barrier::new(views.len());
        std::thread::scope(|scope| {
            let handles: Vec<_> = cams
                .into_iter()
                .zip(outs.iter_mut())
                .zip(views)
                .map(|((mut cam, out), cam_views)| {
                    let barrier = &barrier;
                    // The camera state moves to its thread (`Send`); every thread reads the
                    // one hierarchy (`Sync`). Frames stay in step, as a renderer's would.
                    scope.spawn(move || -> Result<Record, String> {
                        let mut rec = Record::with_capacity(frames);
                        let mut failed = Ok(());
                        for view in cam_views.iter().step_by(stride) {
                            if failed.is_ok() {
                                failed = frame(h, &mut cam, view, params, out.as_mut(), &mut rec);
                            }
                            barrier.wait();
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
        let mut records: Vec<Record> = views
            .iter()
            .map(|_| Record::with_capacity(frames))
            .collect();
        for f in (0..views.first().map_or(0, Vec::len)).step_by(stride) {
            for (c, cam) in cams.iter_mut().enumerate() {
                frame(
                    h,
                    cam,
                    &views[c][f],
                    params,
                    outs[c].as_mut(),
                    &mut records[c],
                )?;
            }
        }
        records
    };
    Ok(Flight {
        records,
        camera_bytes,
        wall: start.elapsed(),
    })
}

/// The paper's baseline: one state, re-refined to each camera's view in turn every frame.
fn fly_shared(
    h: &Hierarchy<'_>,
    views: &[Vec<View>],
    params: &RefineParams,
) -> Result<Flight, String> {
    let start = Instant::now();
    let mut memory = vec![0u32; CameraState::words_needed(h)];
    let mut cam = CameraState::new(h, &mut memory).map_err(|e| e.to_string())?;
    let mut out = IndexBuffers::new(h, cam.max_pairs());
    let frames = views.first().map_or(0, Vec::len);
    let mut records: Vec<Record> = views
        .iter()
        .map(|_| Record::with_capacity(frames))
        .collect();
    for f in 0..frames {
        for c in 0..views.len() {
            frame(
                h,
                &mut cam,
                &views[c][f],
                params,
                Some(&mut out),
                &mut records[c],
            )?;
        }
    }
    Ok(Flight {
        records,
        camera_bytes: cam.bytes(),
        wall: start.elapsed(),
    })
}

/// Summary over all cameras of one flight.
struct Summary {
    ops_mean: f64,
    ops_max: u32,
    first_frame_ops: f64,
    refine_ms_mean: f64,
    refine_ms_p99: f64,
    emit_ms_mean: f64,
    active_mean: f64,
    active_max: u32,
    max_active_nodes: u32,
    refusals: u64,
}

fn summarise(records: &[Record]) -> Summary {
    let all_refine: Vec<u64> = records
        .iter()
        .flat_map(|r| Record::steady(&r.refine_ns).iter().copied())
        .collect();
    let n = records.len().max(1) as f64;
    Summary {
        ops_mean: records.iter().map(Record::ops_mean).sum::<f64>() / n,
        ops_max: records.iter().map(Record::ops_max).max().unwrap_or(0),
        first_frame_ops: records
            .iter()
            .map(|r| f64::from(r.ops.first().copied().unwrap_or(0)))
            .sum::<f64>()
            / n,
        refine_ms_mean: records.iter().map(Record::refine_ms_mean).sum::<f64>() / n,
        refine_ms_p99: percentile(&all_refine, 0.99) as f64 * 1e-6,
        emit_ms_mean: records.iter().map(Record::emit_ms_mean).sum::<f64>() / n,
        active_mean: records.iter().map(Record::active_mean).sum::<f64>() / n,
        active_max: records.iter().map(Record::active_max).max().unwrap_or(0),
        max_active_nodes: records
            .iter()
            .map(|r| r.max_active_nodes)
            .max()
            .unwrap_or(0),
        refusals: records.iter().map(|r| r.refusals).sum(),
    }
}

fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1024.0 * 1024.0)
}

fn print_table(names: &[&str], records: &[Record]) {
    println!(
        "  {:<14} {:>9} {:>7} {:>9} {:>8} {:>8} {:>8} {:>9} {:>9} {:>11} {:>8}",
        "camera",
        "first-op",
        "ops/f",
        "max-ops/f",
        "refine",
        "p99",
        "emit",
        "active",
        "max-act",
        "indices/f",
        "refused"
    );
    for (name, r) in names.iter().zip(records) {
        println!(
            "  {:<14} {:>9} {:>7.1} {:>9} {:>5.3} ms {:>5.3} ms {:>5.3} ms {:>9.0} {:>9} {:>11.0} {:>8}",
            name,
            r.ops.first().copied().unwrap_or(0),
            r.ops_mean(),
            r.ops_max(),
            r.refine_ms_mean(),
            r.refine_ms_p99(),
            r.emit_ms_mean(),
            r.active_mean(),
            r.active_max(),
            r.indices_mean(),
            r.refusals,
        );
    }
    for (name, r) in names.iter().zip(records) {
        println!(
            "  {:<14} totals: {} splits ({} forced), {} collapses, {} indices emitted{}",
            name,
            r.splits,
            r.forced,
            r.collapses,
            r.indices_total(),
            if r.overflows > 0 {
                format!(", {} stack overflows", r.overflows)
            } else {
                String::new()
            }
        );
    }
}

fn run() -> Result<(), String> {
    let args = parse_args()?;
    let start = Instant::now();
    let say = |s: String| {
        if !args.json {
            println!("{s}");
        }
    };

    let t = Instant::now();
    let mesh = meshes::terrain(args.size, args.size, args.seed);
    let mesh_time = t.elapsed();
    let ground = Ground::new(&mesh, args.size);
    let t = Instant::now();
    let baked = bake(&mesh);
    let build_time = t.elapsed();
    let polygons = mesh.triangles.len();
    drop(mesh);
    let t = Instant::now();
    let h = baked.hierarchy();
    let validate_time = t.elapsed();
    let m = *h.meta();
    say(format!(
        "terrain {0} x {0} (seed {1}): {2} polygons, generated in {3:.2} s, hierarchy baked in \
         {4:.2} s, validated in {5:.3} s",
        args.size,
        args.seed,
        polygons,
        mesh_time.as_secs_f64(),
        build_time.as_secs_f64(),
        validate_time.as_secs_f64()
    ));
    say(format!(
        "hierarchy: {} nodes ({} splits), {} roots, {} base polygons, {} vertices, {} surfaces, \
         {} surface-group ids, depth {}",
        m.node_count,
        m.split_count,
        m.root_count,
        m.base_polygon_count,
        m.vertex_count,
        m.surface_count,
        m.surface_group_count,
        m.max_depth
    ));

    // Every camera's views, computed up front so the flights time only the runtime.
    let size = args.size as f32;
    let speed = size / 600.0;
    let all = routes();
    let routes = &all[..args.cameras];
    let names: Vec<&str> = routes.iter().map(|r| r.name).collect();
    let views: Vec<Vec<View>> = routes
        .iter()
        .map(|r| {
            (0..args.frames)
                .map(|f| view_at(r, f, speed, size, &ground))
                .collect()
        })
        .collect();
    let params = RefineParams {
        tolerance_px: args.tolerance,
        ..RefineParams::default()
    };
    let mode = if args.shared_state {
        "shared-state"
    } else if args.threads {
        "per-camera-threads"
    } else {
        "per-camera"
    };
    say(format!(
        "{} camera(s), {} frames, tolerance {} px at {}x{}, fov {} deg, {:.2} units/frame; \
         mode: {}",
        args.cameras,
        args.frames,
        args.tolerance,
        WIDTH,
        HEIGHT,
        FOV_Y_DEG,
        speed,
        match mode {
            "shared-state" => "one shared state re-refined for each camera in turn (baseline)",
            "per-camera-threads" => "a state per camera, one thread per camera",
            _ => "a state per camera, one thread",
        }
    ));

    // Per-camera mode sizes its cameras first: a refine-only flight of full-capacity cameras
    // over every SIZING_STRIDE-th frame finds the largest front each camera needs.
    let full_config = CameraConfig::full(&h);
    let mut sizing = None;
    let (flight, budget) = if args.shared_state {
        (fly_shared(&h, &views, &params)?, None)
    } else if args.full_capacity {
        let f = fly_per_camera(&h, &views, &params, &full_config, 1, true, args.threads)?;
        (f, None)
    } else {
        let s = fly_per_camera(
            &h,
            &views,
            &params,
            &full_config,
            SIZING_STRIDE,
            false,
            args.threads,
        )?;
        let largest = summarise(&s.records).active_max;
        let budget = ((f64::from(largest) * BUDGET_HEADROOM).ceil() as u32)
            .max(h.base_polygon_count() as u32);
        say(format!(
            "sizing flight (full-capacity cameras, refine only, every {SIZING_STRIDE}rd frame): \
             {:.2} s, largest front {largest} polygons -> budget {budget} polygons \
             (+{:.0}%)",
            s.wall.as_secs_f64(),
            (BUDGET_HEADROOM - 1.0) * 100.0
        ));
        let config = CameraConfig::with_polygon_budget(&h, budget);
        let f = fly_per_camera(&h, &views, &params, &config, 1, true, args.threads)?;
        sizing = Some(s);
        (f, Some(budget))
    };
    let s = summarise(&flight.records);
    say(format!(
        "\nflight ({}): {:.2} s for {} camera-frames",
        match (args.shared_state, budget) {
            (true, _) => "one full-capacity state".to_string(),
            (false, Some(b)) => format!("cameras budgeted to {b} polygons"),
            (false, None) => "full-capacity cameras".to_string(),
        },
        flight.wall.as_secs_f64(),
        args.cameras * args.frames
    ));
    say(
        "(ops = splits + collapses; per-frame figures leave out frame 0, which refines from \
         the base mesh: its ops are in the first column)"
            .to_string(),
    );
    if !args.json {
        print_table(&names, &flight.records);
        println!(
            "  all cameras: {:.1} ops/frame/camera (max {}), refine {:.3} ms mean, {:.3} ms p99, \
             emit {:.3} ms mean, {:.0} active polygons mean, {} capacity refusals",
            s.ops_mean,
            s.ops_max,
            s.refine_ms_mean,
            s.refine_ms_p99,
            s.emit_ms_mean,
            s.active_mean,
            s.refusals
        );
    }

    // Memory, against the paper's equation 1 with this flight's largest front.
    let full_bytes = match &sizing {
        Some(sz) => sz.camera_bytes,
        None if args.shared_state || args.full_capacity => flight.camera_bytes,
        None => 0,
    };
    let budget_polygons = budget.unwrap_or_else(|| {
        ((f64::from(s.active_max) * BUDGET_HEADROOM).ceil() as u32)
            .max(h.base_polygon_count() as u32)
    });
    let budget_bytes = if budget.is_some() {
        flight.camera_bytes
    } else {
        let config = CameraConfig::with_polygon_budget(&h, budget_polygons);
        4 * CameraState::words_needed_for(&h, &config) + std::mem::size_of::<CameraState<'_>>()
    };
    let (na, pa) = (u64::from(s.max_active_nodes), u64::from(s.active_max));
    let report = MemoryReport::new(&h, full_bytes, na, pa);
    let report_budget = MemoryReport::new(&h, budget_bytes, na, pa);
    let fill = h.vertex_table_fill();
    let states = if args.shared_state { 1 } else { args.cameras };
    say(format!(
        "\nmemory (paper: b = 44n + 12p + 32d + 2se + 12n_a + 36p_a + c(4n + 4p + 16), with \
         n_a, p_a the largest front of one camera in this flight: {na} nodes, {pa} polygons)"
    ));
    say(format!(
        "  static:               ours {:>10} B ({:6.2} MiB)  paper {:>10} B ({:6.2} MiB)  \
         ratio {:.2}  (vertex table {:.1}% filled)",
        report.static_bytes,
        mib(report.static_bytes),
        report.paper_static_bytes,
        mib(report.paper_static_bytes),
        report.static_bytes as f64 / report.paper_static_bytes.max(1) as f64,
        100.0 * fill.1 as f64 / fill.0.max(1) as f64
    ));
    say(format!(
        "  per camera, full:     ours {:>10} B ({:6.2} MiB)  paper {:>10} B ({:6.2} MiB)  \
         ratio {:.2}",
        report.camera_bytes,
        mib(report.camera_bytes),
        report.paper_camera_bytes,
        mib(report.paper_camera_bytes),
        report.camera_ratio()
    ));
    say(format!(
        "  per camera, budgeted: ours {:>10} B ({:6.2} MiB)  paper {:>10} B ({:6.2} MiB)  \
         ratio {:.2}  (goal <= 0.25, target <= 0.5; {} polygons{})",
        report_budget.camera_bytes,
        mib(report_budget.camera_bytes),
        report_budget.paper_camera_bytes,
        mib(report_budget.paper_camera_bytes),
        report_budget.camera_ratio(),
        budget_polygons,
        if budget.is_some() {
            ", flown"
        } else {
            ", computed, not flown"
        }
    ));
    say(format!(
        "  all {} state(s) + static: ours {:.2} MiB full / {:.2} MiB budgeted, paper {:.2} MiB",
        states,
        mib(report.static_bytes + states as u64 * report.camera_bytes),
        mib(report.static_bytes + states as u64 * report_budget.camera_bytes),
        mib(report.paper_static_bytes + states as u64 * report.paper_camera_bytes)
    ));
    let total = start.elapsed();
    say(format!("\ntotal run time {:.2} s", total.as_secs_f64()));

    if args.json {
        let mut j = String::new();
        let _ = write!(
            j,
            "{{\"mode\":\"{mode}\",\"size\":{},\"polygons\":{polygons},\"nodes\":{},\
             \"build_s\":{:.3},\"cameras\":{},\"frames\":{},\"tolerance_px\":{},",
            args.size,
            m.node_count,
            build_time.as_secs_f64(),
            args.cameras,
            args.frames,
            args.tolerance
        );
        let _ = write!(
            j,
            "\"ops_per_camera_per_frame\":{{\"mean\":{:.2},\"max\":{},\"first_frame\":{:.1}}},\
             \"refine_ms_per_frame\":{{\"mean\":{:.4},\"p99\":{:.4}}},\
             \"emit_ms_per_frame\":{:.4},\
             \"active_polygons\":{{\"mean\":{:.1},\"max\":{}}},\"capacity_refusals\":{},",
            s.ops_mean,
            s.ops_max,
            s.first_frame_ops,
            s.refine_ms_mean,
            s.refine_ms_p99,
            s.emit_ms_mean,
            s.active_mean,
            s.active_max,
            s.refusals
        );
        let _ = write!(
            j,
            "\"static_bytes\":{},\"paper_static_bytes\":{},\
             \"camera_bytes\":{{\"full\":{},\"budgeted\":{},\"budget_polygons\":{},\
             \"budgeted_flown\":{}}},\"paper_camera_bytes\":{},\
             \"camera_ratio\":{{\"full\":{:.4},\"budgeted\":{:.4}}},",
            report.static_bytes,
            report.paper_static_bytes,
            report.camera_bytes,
            report_budget.camera_bytes,
            budget_polygons,
            budget.is_some(),
            report.paper_camera_bytes,
            report.camera_ratio(),
            report_budget.camera_ratio()
        );
        if let Some(sz) = &sizing {
            let _ = write!(
                j,
                "\"sizing_s\":{:.3},\"sizing_stride\":{SIZING_STRIDE},",
                sz.wall.as_secs_f64()
            );
        }
        j.push_str("\"per_camera\":[");
        for (i, (name, r)) in names.iter().zip(&flight.records).enumerate() {
            if i > 0 {
                j.push(',');
            }
            let _ = write!(
                j,
                "{{\"name\":\"{}\",\"ops_mean\":{:.2},\"ops_max\":{},\"first_frame_ops\":{},\
                 \"refine_ms_mean\":{:.4},\"refine_ms_p99\":{:.4},\"emit_ms_mean\":{:.4},\
                 \"active_polygons_mean\":{:.1},\"active_polygons_max\":{},\
                 \"indices_total\":{}}}",
                name,
                r.ops_mean(),
                r.ops_max(),
                r.ops.first().copied().unwrap_or(0),
                r.refine_ms_mean(),
                r.refine_ms_p99(),
                r.emit_ms_mean(),
                r.active_mean(),
                r.active_max(),
                r.indices_total()
            );
        }
        let _ = write!(
            j,
            "],\"flight_s\":{:.3},\"total_s\":{:.3}}}",
            flight.wall.as_secs_f64(),
            total.as_secs_f64()
        );
        println!("{j}");
    }
    Ok(())
}

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e}");
            std::process::ExitCode::FAILURE
        }
    }
}

// The shared hierarchy may be read from any thread; a camera state may move to its thread.
const fn is_sync<T: Sync>() {}
const fn is_send<T: Send>() {}
const _: () = is_sync::<Hierarchy<'static>>();
const _: () = is_send::<CameraState<'static>>();
