//! The CAVECLOD paper's experiment: several cameras fly scripted routes over one hierarchy,
//! each refining its own [`CameraState`] (the default), or one shared state re-refined to each
//! camera's view in turn every frame (`Mode::Shared`, the paper's baseline), or a state per
//! camera on a thread per camera (`Mode::Threads`, the paper's future work).
//!
//! Per-camera modes first size their cameras: a refine-only flight of full-capacity cameras
//! ([`CameraConfig::full`]) over every third frame finds the largest front each camera needs;
//! the measured flight then uses cameras sized by [`CameraConfig::with_polygon_budget`] to that
//! front plus 10%, which is what a runtime with fixed memory would allocate. Capacity refusals
//! are counted. Memory is reported for both capacities against the paper's equation 1.
//! Views are computed before the flight, so it times only the runtime (refine and emit).
//!
//! Per-camera refinement is amortised by default (a third of the active list per frame,
//! [`FlyoverOptions::visit_fraction`]); compaction is incremental with
//! [`FlyoverOptions::compact_step`] (0: whole when due), inside the timed refinement. After each frame,
//! outside the timed work, [`CameraState::lag`] measures how far the front lags its view:
//! the share of active nodes whose error projects over the tolerance (the nodes a full pass
//! would split) and their excess in pixels; a flight with `visit_fraction` 1 is the baseline
//! to compare it with.

pub mod fly;
pub mod gate;
pub mod pilot;
pub mod placement;
pub mod popping;
mod report;
pub mod routes;
pub mod streamed;
mod streamed_baseline;
mod streamed_report;

use std::sync::Arc;

use caveclod_core::glam::Mat4;
use caveclod_core::{CameraConfig, CameraState, Hierarchy, MemoryReport, RefineParams, View};

pub use fly::{fly_per_camera, fly_shared, summarise, Compaction, Flight, Record, Summary};
pub use pilot::{fly_piloted, Pilot};
pub use popping::{PopMeter, PopTables};
pub use routes::{clip, eye_at, look_at, routes, view_at, Ground, FOV_Y_DEG, HEIGHT, WIDTH};

/// Headroom over the sizing flight's largest front when budgeting cameras.
const BUDGET_HEADROOM: f64 = 1.10;
/// The sizing flight refines every this many frames.
const SIZING_STRIDE: usize = 3;
/// Headroom of a regulated camera's polygon budget over its target.
const REGULATED_HEADROOM: f64 = 1.25;
/// Geomorphs a full-capacity camera holds at once when the fly-over morphs
/// ([`FlyoverOptions::geomorphs`]); budgeted cameras hold [`morphs_for_budget`] or, sized by a
/// sizing flight, the larger of that and [`morphs_for_sizing`].
pub const MAX_MORPHS: u32 = 16384;
/// A sized camera's morph memory over the operations of its sizing flight within one
/// morph's duration: about half the operations are of nodes outside the view, which split and
/// collapse at once, and the other half then has half again as much room.
const MORPH_HEADROOM: f64 = 0.75;

/// Morph memory for a camera of `budget` polygons: half its budget. Morphs slowed by a
/// screen speed limit ([`RefineParams::morph_speed_px_s`]) near the eye outlast their
/// durations, so the operations of one duration underestimate them; a morph belongs to a live
/// split, and a camera's splits are at most half its polygons, so half the budget is room
/// for every morph a flight can hold.
pub fn morphs_for_budget(budget: u32) -> u32 {
    (budget / 2).max(256)
}

/// Morph memory for the cameras of a sizing flight flown every `stride` frames with
/// `params`' morph durations: the most operations of any camera within one refine morph's
/// duration (each operation may start a morph that lasts at most that long, at 60 frames
/// per second), times three quarters (about half the operations are of nodes outside the
/// view, which split and collapse at once).
pub fn morphs_for_sizing(sizing: &Flight, stride: usize, params: &RefineParams) -> u32 {
    let frames = (params.refine_morph_s.max(params.coarsen_morph_s) / params.dt_s.max(1e-6))
        .ceil()
        .max(1.0) as usize;
    let window = frames.div_ceil(stride.max(1)).max(1);
    let most = sizing
        .records
        .iter()
        .map(|r| {
            let steady = Record::steady(&r.ops);
            steady
                .windows(window.min(steady.len()).max(1))
                .map(|w| w.iter().map(|&x| u64::from(x)).sum::<u64>())
                .max()
                .unwrap_or(0)
        })
        .max()
        .unwrap_or(0);
    ((most as f64 * MORPH_HEADROOM).ceil() as u32).max(256)
}

/// The fly-over's default most work per frame of an incremental compaction: the library's
/// [`caveclod_core::COMPACT_STEP`]. Whole compaction when due (`--compact-step 0`) spends a
/// cycle's work in one frame: on a rough 1200 × 1200 grid at 1 px (80,000 polygons per
/// camera) it lifts the refinement p99 about three times, on St. Helens at 1 px (14,000)
/// more than twice.
pub const COMPACT_STEP: u32 = caveclod_core::COMPACT_STEP;
/// The fly-over's default share of the active list a refinement visits per frame.
pub const VISIT_FRACTION: f32 = 1.0 / 3.0;

/// How the cameras share state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// A state per camera, one thread.
    PerCamera,
    /// A state per camera, one thread per camera.
    Threads,
    /// One shared state re-refined for each camera in turn (the paper's baseline).
    Shared,
}

impl Mode {
    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::PerCamera => "per-camera",
            Self::Threads => "per-camera-threads",
            Self::Shared => "shared-state",
        }
    }
}

/// What to fly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlyoverOptions {
    /// 1 to 4 cameras.
    pub cameras: usize,
    /// Frames per camera.
    pub frames: usize,
    /// Screen-space tolerance in pixels (1280 x 720, 60° field of view).
    pub tolerance: f32,
    /// State sharing.
    pub mode: Mode,
    /// Fly full-capacity cameras instead of sizing them first.
    pub full_capacity: bool,
    /// The first camera flies this route (0 to 3); the others follow in order.
    pub first_route: usize,
    /// Each state compacts ([`CameraState::compact`]) every this many of its frames, inside
    /// the timed refinement (0: never). Compaction sorts a front's records back into node
    /// order; without it a moving camera's front scatters over its memory and four cameras
    /// together no longer fit the caches one camera alone fits, so their refinement costs
    /// far more than four times one camera's.
    pub compact_every: usize,
    /// Most work per frame of an incremental compaction ([`CameraState::compact_step`]): a
    /// compaction due starts a cycle that each frame of the state advances by an eighth of
    /// its front's nodes, up to this ([`CameraState::compact_budget`]), until it ends, inside
    /// the timed refinement; 0 compacts whole when due
    /// ([`CameraState::compact`]), a spike of several milliseconds on a large front.
    pub compact_step: u32,
    /// Share of its active list a camera's refinement visits per frame
    /// ([`RefineParams::visit_fraction`]; Hoppe's demos visit a third); 1 visits it all, as
    /// the shared state always does.
    pub visit_fraction: f32,
    /// Frames in flight (at least 1): each camera emits into this many index lists in turn,
    /// and with a thread per camera a camera may run this many frames less one ahead of the
    /// slowest (see [`gate`]); 1 is a barrier every frame.
    pub frames_in_flight: usize,
    /// Keep each camera's index cache ([`CameraConfig::index_cache`], the library's
    /// default); without it, emission looks every active polygon up every frame, as the
    /// paper's cameras did.
    pub index_cache: bool,
    /// With a thread per camera, pin each thread to a core and share the cameras out so
    /// the cores carry equal work (see [`placement`]); otherwise the system places them.
    pub pin_threads: bool,
    /// Keep each budgeted camera's split-to-pair map hashed where that is smaller
    /// ([`CameraConfig::hashed_pair_map`]): less memory, slower refinement.
    pub hashed_pair_map: bool,
    /// Geomorph splits and collapses of visible nodes ([`RefineParams`]' default durations
    /// at 60 frames per second; morph memory from [`morphs_for_sizing`], [`morphs_for_budget`]
    /// or [`MAX_MORPHS`]); the shared state never morphs (its front is re-refined for another
    /// camera every turn).
    pub geomorphs: bool,
    /// The fastest a morphing vertex glides across the screen, in pixels per second
    /// ([`RefineParams::morph_speed_px_s`]; 0 for no limit).
    pub morph_speed_px_s: f32,
    /// How large on the screen a morphing camera's nodes may stay, in tolerances
    /// ([`RefineParams::morph_radius_tolerances`]; 0 for no bound).
    pub morph_radius_tolerances: f32,
    /// How far beyond the view's sides a morphing camera refines, in radians
    /// ([`RefineParams::morph_guard_rad`]).
    pub morph_guard_rad: f32,
    /// Index edits ([`CameraConfig::edit_list`]): each camera keeps its polygons' places
    /// in a device index buffer and a list of this many changed places; after emission,
    /// each frame also takes the camera's edits ([`CameraState::index_edits`]), timed
    /// apart, so the two ways to prepare a draw are measured in the same run (0: off).
    pub index_edits: u32,
    /// Fly every camera with a [`caveclod_core::Regulator`] holding this many active
    /// polygons, starting at `tolerance` (a state per camera on one thread only). The
    /// cameras are budgeted to the target plus 25%, without a sizing flight.
    pub target_polygons: Option<u32>,
}

impl Default for FlyoverOptions {
    fn default() -> Self {
        Self {
            cameras: 4,
            frames: 300,
            tolerance: 1.0,
            mode: Mode::PerCamera,
            full_capacity: false,
            first_route: 0,
            compact_every: 30,
            compact_step: COMPACT_STEP,
            visit_fraction: VISIT_FRACTION,
            frames_in_flight: gate::FRAMES_IN_FLIGHT,
            index_cache: true,
            pin_threads: true,
            hashed_pair_map: false,
            geomorphs: true,
            morph_speed_px_s: RefineParams::default().morph_speed_px_s,
            morph_radius_tolerances: RefineParams::default().morph_radius_tolerances,
            morph_guard_rad: RefineParams::default().morph_guard_rad,
            target_polygons: None,
            index_edits: 0,
        }
    }
}

impl FlyoverOptions {
    /// How the flight's states compact.
    pub fn compaction(&self) -> Compaction {
        Compaction {
            every: self.compact_every,
            step: self.compact_step,
        }
    }
}

/// The result of a fly-over.
pub struct Flyover {
    /// What was flown.
    pub options: FlyoverOptions,
    /// The route names, per camera.
    pub names: Vec<&'static str>,
    /// The measured flight.
    pub flight: Flight,
    /// Its summary.
    pub summary: Summary,
    /// The sizing flight, if one was flown.
    pub sizing: Option<Flight>,
    /// Polygon budget the measured cameras were sized to, if sized.
    pub budget: Option<u32>,
    /// Memory of a full-capacity camera against the paper.
    pub memory_full: MemoryReport,
    /// Memory of a budgeted camera against the paper.
    pub memory_budgeted: MemoryReport,
    /// Polygons the budgeted figure is for.
    pub budget_polygons: u32,
    /// Vertex-table cells and filled cells.
    pub vertex_table_fill: (u64, u64),
    /// Per camera, its pilot (regulator and popping meter): per-camera states on one thread
    /// only ([`fly()`]); empty otherwise.
    pub pilots: Vec<Pilot>,
    /// Morphs each camera could hold at once (0: no geomorphs).
    pub max_morphs: u32,
}

/// Every camera's views for `options`, computed up front.
pub fn views(h: &Hierarchy<'_>, options: &FlyoverOptions) -> (Vec<&'static str>, Vec<Vec<View>>) {
    views_over(&Ground::new(h), options)
}

/// Every camera's views for `options` over `ground`, computed up front.
pub fn views_over(
    ground: &Ground,
    options: &FlyoverOptions,
) -> (Vec<&'static str>, Vec<Vec<View>>) {
    let speed = ground.size / 600.0;
    let all = routes();
    let chosen: Vec<_> = (0..options.cameras.clamp(1, 4))
        .map(|i| &all[(options.first_route + i) % all.len()])
        .collect();
    let names = chosen.iter().map(|r| r.name).collect();
    let views = chosen
        .iter()
        .map(|r| {
            (0..options.frames)
                .map(|f| view_at(r, f, speed, ground))
                .collect()
        })
        .collect();
    (names, views)
}

/// Every camera's view-projection matrices for `options` (those of [`views`]).
pub fn view_projections(h: &Hierarchy<'_>, options: &FlyoverOptions) -> Vec<Vec<Mat4>> {
    let ground = Ground::new(h);
    let speed = ground.size / 600.0;
    let all = routes();
    (0..options.cameras.clamp(1, 4))
        .map(|i| &all[(options.first_route + i) % all.len()])
        .map(|r| {
            (0..options.frames)
                .map(|f| look_at(r, f, speed, &ground).view_projection(WIDTH / HEIGHT))
                .collect()
        })
        .collect()
}

/// The refinement parameters of `options` (morphs as the camera's memory has them), checked.
pub fn refine_params(options: &FlyoverOptions) -> Result<RefineParams, String> {
    let params = RefineParams {
        tolerance_px: options.tolerance,
        visit_fraction: options.visit_fraction,
        morph_speed_px_s: options.morph_speed_px_s,
        morph_radius_tolerances: options.morph_radius_tolerances,
        morph_guard_rad: options.morph_guard_rad,
        ..RefineParams::default()
    };
    params.validate().map_err(|e| e.to_string())?;
    Ok(params)
}

/// A flight's views and cameras, sized, before the measured flight.
struct Prepared {
    names: Vec<&'static str>,
    views: Vec<Vec<View>>,
    params: RefineParams,
    config: CameraConfig,
    sizing: Option<Flight>,
    budget: Option<u32>,
}

/// Checks `options`, computes the views and, for budgeted per-camera states, flies the
/// sizing flight.
fn prepare(h: &Hierarchy<'_>, options: &FlyoverOptions) -> Result<Prepared, String> {
    if !(1..=4).contains(&options.cameras) {
        return Err(format!("cameras must be 1 to 4, not {}", options.cameras));
    }
    if options.frames < 2 {
        return Err("need at least 2 frames".into());
    }
    if options.target_polygons.is_some() && options.mode != Mode::PerCamera {
        return Err("a polygon target flies a state per camera on one thread".into());
    }
    let (names, views) = views(h, options);
    let morphing = options.geomorphs && options.mode != Mode::Shared;
    let params = refine_params(options)?;
    // The shared state's baseline re-refines to each camera's view in full.
    let params = if options.mode == Mode::Shared {
        params.amortised(1.0)
    } else {
        params
    };
    let params = if morphing {
        params
    } else {
        params.without_morphs()
    };
    let morphs = |n: u32| if morphing { n } else { 0 };
    let full_config = CameraConfig {
        index_cache: options.index_cache,
        hashed_pair_map: options.hashed_pair_map,
        ..CameraConfig::full(h)
    };
    if options.mode == Mode::Shared || options.full_capacity {
        return Ok(Prepared {
            names,
            views,
            params,
            config: full_config.with_morphs(morphs(MAX_MORPHS)),
            sizing: None,
            budget: None,
        });
    }
    if let Some(target) = options.target_polygons {
        let budget = ((f64::from(target) * REGULATED_HEADROOM).ceil() as u32)
            .max(h.base_polygon_count() as u32);
        return Ok(Prepared {
            names,
            views,
            params,
            config: CameraConfig {
                index_cache: options.index_cache,
                hashed_pair_map: options.hashed_pair_map,
                ..CameraConfig::with_polygon_budget(h, budget)
                    .with_morphs(morphs(morphs_for_budget(budget)))
            },
            sizing: None,
            budget: Some(budget),
        });
    }
    // The sizing flight refines every third frame: it finds fronts. Its cameras morph as the
    // flight's do, so they refine against the same criterion (a morphing camera's guard band
    // and radius bound) and hold the collapses their coarsen morphs defer. They are
    // full-capacity states, so they fly one at a time: a single full state at once (about 52
    // bytes per polygon of the hierarchy) rather than one per camera.
    let sizing_config = full_config.with_morphs(morphs(MAX_MORPHS));
    let s = fly_one_at_a_time(h, &views, &params, &sizing_config, options)?;
    let largest = summarise(&s.records).active_max;
    let budget =
        ((f64::from(largest) * BUDGET_HEADROOM).ceil() as u32).max(h.base_polygon_count() as u32);
    Ok(Prepared {
        names,
        views,
        params,
        config: CameraConfig {
            index_cache: options.index_cache,
            hashed_pair_map: options.hashed_pair_map,
            ..CameraConfig::with_polygon_budget(h, budget).with_morphs(morphs(
                morphs_for_sizing(&s, SIZING_STRIDE, &params).max(morphs_for_budget(budget)),
            ))
        },
        sizing: Some(s),
        budget: Some(budget),
    })
}

/// The sizing flight: each camera's views flown on their own, one camera after the other, as
/// one [`Flight`] with a record per camera.
fn fly_one_at_a_time(
    h: &Hierarchy<'_>,
    views: &[Vec<View>],
    params: &RefineParams,
    config: &CameraConfig,
    options: &FlyoverOptions,
) -> Result<Flight, String> {
    let mut all: Option<Flight> = None;
    for one in views.chunks(1) {
        let f = fly_per_camera(
            h,
            one,
            params,
            config,
            SIZING_STRIDE,
            false,
            false,
            options.frames_in_flight,
            options.compaction(),
            None,
        )?;
        match &mut all {
            None => all = Some(f),
            Some(a) => {
                a.records.extend(f.records);
                a.wall += f.wall;
            }
        }
    }
    all.ok_or_else(|| "no camera to fly".to_string())
}

/// The cameras' costs to balance pinned threads by: their mean refinement time in the
/// sizing flight (`None`: no pinning).
fn pin_costs(options: &FlyoverOptions, p: &Prepared) -> Option<Vec<f64>> {
    if !options.pin_threads || options.mode != Mode::Threads {
        return None;
    }
    Some(match &p.sizing {
        Some(s) => s.records.iter().map(Record::refine_ms_mean).collect(),
        None => vec![1.0; p.views.len()],
    })
}

/// Flies `options` over `h`.
pub fn fly(h: &Hierarchy<'_>, options: &FlyoverOptions) -> Result<Flyover, String> {
    let mut p = prepare(h, options)?;
    if options.index_cache {
        p.config.edit_list = options.index_edits;
    }
    let mut pilots = Vec::new();
    let flight = if options.mode == Mode::Shared {
        fly_shared(h, &p.views, &p.params, &p.config, options.compaction())?
    } else if options.mode == Mode::PerCamera {
        let tables = Arc::new(PopTables::new(h));
        pilots = p
            .views
            .iter()
            .map(|_| {
                Pilot::new(
                    tables.clone(),
                    options.target_polygons,
                    options.tolerance,
                    p.params.visit_fraction,
                )
            })
            .collect();
        fly_piloted(
            h,
            &p.views,
            &view_projections(h, options),
            &p.params,
            &p.config,
            options.frames_in_flight,
            options.compaction(),
            &mut pilots,
        )?
    } else {
        fly_per_camera(
            h,
            &p.views,
            &p.params,
            &p.config,
            1,
            true,
            options.mode == Mode::Threads,
            options.frames_in_flight,
            options.compaction(),
            pin_costs(options, &p).as_deref(),
        )?
    };
    let mut flyover = finish(h, options, &p, flight);
    flyover.pilots = pilots;
    Ok(flyover)
}

/// Sizing flights already flown, by the options they were flown for: flights given the same
/// options share one ([`fly_interleaved_sharing`]).
#[derive(Default)]
pub struct Sizings(Vec<(FlyoverOptions, Prepared)>);

/// Flies every one of `options` (per-camera modes only) over `h` interleaved in segments of
/// `segment` frames ([`fly::fly_interleaved`]), so that flights compared with each other are
/// measured under the same load. Each is sized by a sizing flight first, as [`fly()`] sizes it,
/// unless `sizings` (those of earlier calls) holds one for the same options; new sizings are
/// added to it, and options given more than once (flown again, with fresh states) share theirs.
pub fn fly_interleaved_sharing(
    h: &Hierarchy<'_>,
    options: &[FlyoverOptions],
    segment: usize,
    sizings: &mut Sizings,
) -> Result<Vec<Flyover>, String> {
    if options.iter().any(|o| o.mode == Mode::Shared) {
        return Err("the shared state flies on its own (fly), not interleaved".into());
    }
    let mut which = Vec::with_capacity(options.len());
    for o in options {
        match sizings.0.iter().position(|(earlier, _)| earlier == o) {
            Some(k) => which.push(k),
            None => {
                sizings.0.push((*o, prepare(h, o)?));
                which.push(sizings.0.len() - 1);
            }
        }
    }
    let prepared: Vec<&Prepared> = sizings.0.iter().map(|(_, p)| p).collect();
    let first_costs: Vec<Option<Vec<f64>>> = which
        .iter()
        .zip(options)
        .map(|(&k, o)| pin_costs(o, prepared[k]))
        .collect();
    let groups: Vec<fly::Group<'_>> = which
        .iter()
        .zip(options)
        .zip(&first_costs)
        .map(|((&k, o), first)| {
            let p = prepared[k];
            fly::Group {
                views: &p.views,
                config: p.config,
                threads: o.mode == Mode::Threads,
                in_flight: o.frames_in_flight,
                params: p.params,
                compaction: o.compaction(),
                pin: o.pin_threads,
                first_costs: first.as_deref(),
            }
        })
        .collect();
    let flights = fly::fly_interleaved(h, &groups, segment)?;
    Ok(which
        .iter()
        .zip(flights)
        .zip(options)
        .map(|((&k, f), o)| finish(h, o, prepared[k], f))
        .collect())
}

/// The report of a measured flight.
fn finish(h: &Hierarchy<'_>, options: &FlyoverOptions, p: &Prepared, flight: Flight) -> Flyover {
    let (names, sizing, budget) = (p.names.clone(), p.sizing.clone(), p.budget);
    let summary = summarise(&flight.records);
    let full_bytes = match &sizing {
        Some(sz) => sz.camera_bytes,
        None if options.mode == Mode::Shared || options.full_capacity => flight.camera_bytes,
        None => 0,
    };
    let budget_polygons = budget.unwrap_or_else(|| {
        ((f64::from(summary.active_max) * BUDGET_HEADROOM).ceil() as u32)
            .max(h.base_polygon_count() as u32)
    });
    let budget_bytes = if budget.is_some() {
        flight.camera_bytes
    } else {
        let config = CameraConfig {
            index_cache: options.index_cache,
            hashed_pair_map: options.hashed_pair_map,
            ..CameraConfig::with_polygon_budget(h, budget_polygons)
        };
        4 * CameraState::words_needed_for(h, &config) + std::mem::size_of::<CameraState<'_>>()
    };
    let (na, pa) = (
        u64::from(summary.max_active_nodes),
        u64::from(summary.active_max),
    );
    Flyover {
        options: *options,
        names,
        flight,
        summary,
        sizing,
        budget,
        memory_full: MemoryReport::new(h, full_bytes, na, pa),
        memory_budgeted: MemoryReport::new(h, budget_bytes, na, pa),
        budget_polygons,
        vertex_table_fill: h.vertex_table_fill(),
        pilots: Vec::new(),
        max_morphs: p.config.max_morphs,
    }
}

// The shared hierarchy may be read from any thread; a camera state may move to its thread.
const fn is_sync<T: Sync>() {}
const fn is_send<T: Send>() {}
const _: () = is_sync::<Hierarchy<'static>>();
const _: () = is_send::<CameraState<'static>>();
