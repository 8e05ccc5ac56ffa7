//! The command line: one subcommand per job, each with its options.

use std::path::PathBuf;

use caveclod_core::RefineParams;
use clap::{Args, Parser, Subcommand, ValueEnum};

#[derive(Parser)]
#[command(
    name = "caveclod",
    version,
    about = "View-dependent continuous level of detail: bake, inspect, export"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// Bake a mesh (.gltf .glb .obj .ply .dem .npy) into a .clod hierarchy.
    Bake(BakeArgs),
    /// The demo: bake St. Helens and Spot, fly 4 cameras, write figures, CSV and out/report.md.
    Demo(DemoArgs),
    /// The CAVECLOD paper's experiment: cameras fly scripted routes over a hierarchy.
    Flyover(FlyoverArgs),
    /// Counts, sizes and validation status of a .clod file.
    Info(InfoArgs),
    /// Generate a procedural terrain (normals, colours, UVs) as binary PLY, streamed to disk.
    Generate(GenerateArgs),
    /// Write the paged form of a baked .clod file: a root read on opening, pages that stream.
    Page(PageArgs),
    /// Write one level of a .clod file as Wavefront OBJ, with an MTL file and the embedded
    /// textures beside it when the file has materials.
    Export(ExportArgs),
    /// Render a .clod file headless (lavapipe unless --gpu) from 1-4 cameras orbiting it, each
    /// refining its own front, into one split-screen PNG (or one PNG per camera).
    Render(RenderArgs),
    /// Refine one camera over a .clod file until a pass changes nothing, emit its indices and
    /// print the counts (1280 × 720, 60° vertical fov, +Y up, near 0.1, far 1e5, 1 px,
    /// culling on: the views of the C example `capi/examples/refine.c`).
    Refine(RefineArgs),
}

/// Options of `caveclod bake`.
#[derive(Args, Clone)]
pub struct BakeArgs {
    /// The input mesh.
    pub input: PathBuf,
    /// The .clod file to write (replaced only once complete).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Grid spacing in metres for heightfields (.npy needs it; overrides a .dem's).
    #[arg(long)]
    pub spacing: Option<f32>,
    /// Print the report as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Simplify the input (.ply, .obj) out of core first, streaming it from disk, down to a
    /// size whose hierarchy fits the memory budget.
    #[arg(long)]
    pub out_of_core: bool,
    /// Build the hierarchy in blocks, level by level: square blocks of the input built with
    /// their borders frozen, then merged two by two and built across the old borders. The
    /// whole hierarchy, as many polygons as the input; each block's build fits the memory
    /// budget, several at once.
    #[arg(long, conflicts_with = "out_of_core")]
    pub blocked: bool,
    /// Memory budget for --out-of-core and --blocked (256M, 1G, ...).
    #[arg(long, default_value = "256M", value_parser = caveclod_bake::ooc::parse_size)]
    pub memory_budget: u64,
    /// Directory for --out-of-core's temporary files (the system's by default).
    #[arg(long)]
    pub temp_dir: Option<PathBuf>,
    /// Output triangles for --out-of-core to aim for (from the budget by default).
    #[arg(long)]
    pub target_triangles: Option<u64>,
    /// Most triangles in an octree leaf for --out-of-core.
    #[arg(long, default_value_t = 65536)]
    pub leaf_triangles: u64,
    /// Also store g-mesh levels (batched collapses, geomorph pairs, volume partitions).
    #[arg(long)]
    pub gmesh: bool,
    /// With --gmesh: stop adding levels below this many polygons (default |c0| / 64).
    #[arg(long)]
    pub gmesh_min_polygons: Option<u32>,
    /// Write the paged form, in pages of at most this size (e.g. 128K): opening it reads its
    /// root only, and its pages stream into a pool (`flyover --pool`).
    #[arg(long, value_parser = caveclod_bake::ooc::parse_size, conflicts_with_all = ["out_of_core", "gmesh"])]
    pub page_size: Option<u64>,
}

/// Options of `caveclod demo`.
#[derive(Args)]
pub struct DemoArgs {
    /// Where to write (created if missing).
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Frames per flight.
    #[arg(long, default_value_t = 300)]
    pub frames: usize,
    /// The repository's data directory (St. Helens and Spot).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Bake again even if out/cache has the files.
    #[arg(long)]
    pub rebake: bool,
    /// CPU figures only, no Vulkan pictures.
    #[arg(long)]
    pub no_render: bool,
}

/// Options of `caveclod flyover`.
#[derive(Args)]
pub struct FlyoverArgs {
    /// A .clod file (or use --dem); with --pool, one or more paged files.
    pub files: Vec<PathBuf>,
    /// Bake this heightfield (.dem, .npy) in memory and fly over it.
    #[arg(long, conflicts_with = "files")]
    pub dem: Option<PathBuf>,
    /// Grid spacing in metres for --dem.
    #[arg(long)]
    pub spacing: Option<f32>,
    /// Cameras, 1 to 4.
    #[arg(long, default_value_t = 4)]
    pub cameras: usize,
    /// Frames per camera.
    #[arg(long, default_value_t = 300)]
    pub frames: usize,
    /// Screen-space tolerance in pixels (1280 x 720, 60 degree field of view).
    #[arg(long, default_value_t = 1.0)]
    pub tolerance: f32,
    /// One shared state re-refined for each camera in turn (the paper's baseline).
    #[arg(long, conflicts_with = "threads")]
    pub shared_state: bool,
    /// One thread per camera.
    #[arg(long)]
    pub threads: bool,
    /// Fly full-capacity cameras instead of sizing them to a first flight.
    #[arg(long)]
    pub full_capacity: bool,
    /// Compact each camera state every N of its frames, inside the timed refinement
    /// (0: never).
    #[arg(long, default_value_t = 30)]
    pub compact_every: usize,
    /// Most work per frame of an incremental compaction (comparisons and moves: an eighth of
    /// the front's nodes, up to this), advanced every frame of a state until its cycle ends;
    /// 0 compacts whole when due (a spike).
    #[arg(long, default_value_t = crate::flyover::COMPACT_STEP)]
    pub compact_step: u32,
    /// Share of its active list a camera's refinement visits per frame, resuming where the
    /// last frame stopped (1: every node every frame).
    #[arg(long, default_value_t = crate::flyover::VISIT_FRACTION)]
    pub visit_fraction: f32,
    /// Frames in flight: index lists per camera, and with --threads how far apart the
    /// camera threads may run (1: a barrier every frame).
    #[arg(long, default_value_t = crate::flyover::gate::FRAMES_IN_FLIGHT as u8,
          value_parser = clap::value_parser!(u8).range(1..=8))]
    pub frames_in_flight: u8,
    /// Emit without the index cache: look every active polygon up every frame, as the
    /// paper's cameras did (the library keeps each polygon's indices by default).
    #[arg(long)]
    pub no_index_cache: bool,
    /// Keep each camera's index buffer edited in place: a place per polygon and a list of
    /// this many changed places, taken each frame after emission and timed apart (0: off).
    #[arg(long, default_value_t = 0)]
    pub index_edits: u32,
    /// With --threads, leave the camera threads to the system instead of pinning each to
    /// a core with the cameras shared out by cost.
    #[arg(long)]
    pub no_pin: bool,
    /// Keep each budgeted camera's split-to-pair map hashed where that is smaller than an
    /// array over the hierarchy (less memory, slower refinement).
    #[arg(long)]
    pub hashed_pair_map: bool,
    /// Split and collapse at once instead of geomorphing visible vertices (on by default: a
    /// camera holds up to half its polygon budget in morphs, 16,384 at full capacity).
    #[arg(long)]
    pub no_geomorphs: bool,
    /// Fastest a morphing vertex may glide across the screen, in pixels per second (a morph
    /// long on the screen takes longer than its duration); 0, the default, for no limit
    #[arg(long, default_value_t = 0.0, value_parser = non_negative)]
    pub morph_speed: f32,
    /// How large on the screen a morphing camera's nodes may stay, in tolerances: a node
    /// whose bounding radius projects larger splits, which keeps morphs' paths short on the
    /// screen for more polygons (16 to 32 is a useful range); 0, the default, for no bound
    #[arg(long, default_value_t = 0.0, value_parser = non_negative)]
    pub morph_radius: f32,
    /// How far beyond the view's sides a morphing camera refines, in degrees (what turns
    /// into view is refined and morphing before it shows); 0 for none
    #[arg(long, default_value_t = RefineParams::default().morph_guard_rad.to_degrees(), value_parser = non_negative)]
    pub morph_guard: f32,
    /// Regulate each camera's tolerance to hold this many active polygons (starting at
    /// --tolerance; a state per camera on one thread).
    #[arg(long, conflicts_with_all = ["shared_state", "threads"])]
    pub target_polygons: Option<u32>,
    /// Stream the paged files' pages into a pool of this size (e.g. 256M): each camera
    /// refines over each file, and splits that need absent pages wait for them.
    #[arg(long, value_parser = caveclod_bake::ooc::parse_size, conflicts_with_all = ["dem", "shared_state", "threads", "target_polygons"])]
    pub pool: Option<u64>,
    /// With --pool: simulated latency of each page read, in milliseconds (on the flight's
    /// 60 Hz clock).
    #[arg(long, default_value_t = 0.0, value_parser = non_negative, requires = "pool")]
    pub io_latency: f32,
    /// With --pool: simulated bandwidth in MB/s (0: no simulated disk).
    #[arg(long, default_value_t = 0.0, value_parser = non_negative, requires = "pool")]
    pub io_bandwidth: f32,
    /// With --pool: each camera's polygon budget, which its memory follows.
    #[arg(long, default_value_t = 262_144, requires = "pool")]
    pub camera_polygons: u32,
    /// With --pool: how far the cameras' tolerance may be scaled up when the pool is nearly
    /// full or the reads fall behind (1: never; the flight then waits at full quality).
    #[arg(long, default_value_t = 16.0, value_parser = at_least_one, requires = "pool")]
    pub max_pressure: f32,
    /// With --pool and one paged file: fly the same views over this whole-file form of it
    /// afterwards, at the tolerances the streamed flight used, and compare refinement times.
    #[arg(long, requires = "pool")]
    pub baseline: Option<PathBuf>,
    /// Print the report as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// Options of `caveclod info`.
#[derive(Args)]
pub struct InfoArgs {
    /// The file.
    pub file: PathBuf,
    /// Print the report as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// For a paged file, also read and check every page (opening reads the root only).
    #[arg(long)]
    pub validate_all: bool,
}

/// Options of `caveclod refine`.
#[derive(Args)]
pub struct RefineArgs {
    /// The file.
    pub file: PathBuf,
    /// Eye point, `X,Y,Z`.
    #[arg(long, value_parser = parse_point, allow_hyphen_values = true)]
    pub eye: [f32; 3],
    /// Point looked at, `X,Y,Z`.
    #[arg(long, value_parser = parse_point, allow_hyphen_values = true)]
    pub target: [f32; 3],
    /// Print one JSON line `{"active_polygons": N, "indices": M, "surfaces": S}`.
    #[arg(long)]
    pub json: bool,
}

/// A point written `X,Y,Z`.
fn parse_point(s: &str) -> Result<[f32; 3], String> {
    let parts: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>().map_err(|e| format!("`{p}`: {e}")))
        .collect::<Result<_, _>>()?;
    <[f32; 3]>::try_from(parts).map_err(|p| format!("{} numbers given, 3 needed (X,Y,Z)", p.len()))
}

/// Options of `caveclod page`.
#[derive(Args)]
pub struct PageArgs {
    /// A baked (whole-file) .clod.
    pub input: PathBuf,
    /// The paged .clod to write (replaced only once complete and read back).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Most bytes in a streamed page (e.g. 128K).
    #[arg(long, default_value = "128K", value_parser = caveclod_bake::ooc::parse_size)]
    pub page_size: u64,
    /// Print the result as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// Options of `caveclod generate`.
#[derive(Args)]
pub struct GenerateArgs {
    /// At least this many triangles.
    #[arg(long)]
    pub triangles: u64,
    /// Fractal detail on the hills (a sum of sines): octaves of gradient noise from a quarter
    /// of the terrain's side down to two grid cells, the one at 1/64 of the side (15.6 units)
    /// ROUGHNESS times its scale high, the others scaled as scale^0.7 (coarse ones gentler,
    /// fine ones rougher). The default keeps four cameras at a pixel's tolerance refining
    /// tens of thousands of polygons each over a few million triangles; 0 is the smooth
    /// sines alone (a few thousand); larger values give steeper, craggier ground.
    #[arg(long, default_value_t = caveclod_bake::generate::TerrainStyle::DEFAULT_ROUGHNESS,
          value_parser = non_negative)]
    pub roughness: f32,
    /// Seed of the fractal detail: the same seed, roughness and size give the same file.
    #[arg(long, default_value_t = caveclod_bake::generate::TerrainStyle::DEFAULT_SEED)]
    pub seed: u64,
    /// The .ply file to write (replaced only once complete).
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Options of `caveclod export`.
#[derive(Args)]
pub struct ExportArgs {
    /// The file.
    pub file: PathBuf,
    /// Which level.
    #[arg(long, value_enum, default_value = "full")]
    pub level: LevelArg,
    /// The OBJ file to write; its MTL file (same name, `.mtl`) and the embedded textures
    /// (`<name>_<material>.<ext>`) go beside it. Files are replaced only once complete, and
    /// never one the export reads.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Options of `caveclod render`.
#[derive(Args)]
pub struct RenderArgs {
    /// The file.
    pub file: PathBuf,
    /// Cameras, 1 to 4, evenly spaced around the mesh.
    #[arg(long, default_value_t = 1)]
    pub cameras: usize,
    /// Screen-space tolerance of refinement, in pixels.
    #[arg(long, default_value_t = 1.0)]
    pub tolerance: f32,
    /// Image width in pixels.
    #[arg(long, default_value_t = 512)]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 512)]
    pub height: u32,
    /// One PNG per camera (camera0.png, ...) instead of one split-screen image.
    #[arg(long)]
    pub separate: bool,
    /// Prefer a GPU over lavapipe.
    #[arg(long)]
    pub gpu: bool,
    /// Enable the Vulkan validation layer (if installed) and print its messages.
    #[arg(long)]
    pub validate: bool,
    /// Draw the multiresolution octree of an out-of-core bake (each camera its own cut)
    /// instead of the hierarchy.
    #[arg(long)]
    pub octree: bool,
    /// Directory for the PNG files (created if missing).
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum LevelArg {
    Full,
    Base,
}

/// A finite number of zero or more.
fn non_negative(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("`{s}`: expected a finite number of zero or more")),
    }
}

fn at_least_one(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v >= 1.0 => Ok(v),
        _ => Err(format!("`{s}`: expected a finite number of 1 or more")),
    }
}
