//! What the viewer shows, on the CPU: the hierarchy (a `.clod` file, or a source mesh baked
//! before the window opens, with progress on stderr), its cameras (each its own
//! `CameraState`, steered or animated, refined every frame against its own view unless
//! frozen) and the display settings.

use std::io::{IsTerminal as _, Write as _};
use std::path::{Path, PathBuf};
use std::time::Instant;

use caveclod_bake::import::ImportOptions;
use caveclod_bake::pipeline::{bake_file, Stage};
use caveclod_core::format::materials::Materials;
use caveclod_core::format::Meta;
use caveclod_core::stream::StreamedHierarchy;
use caveclod_core::{
    CameraConfig, CameraState, Hierarchy, HierarchyRecords, LookAt, RefineParams, View,
    COMPACT_STEP,
};
use caveclod_io::{AlignedBytes, ClodBytes, PagedFile};
use caveclod_vulkan::MorphStage;
use caveclod_vulkan::Viewport;

use crate::controls::CameraControl;
use crate::stream::Streamed;

/// The paged file at `path`, if it is a `.clod` file written paged (its root is read).
pub fn open_paged(path: &Path) -> Result<Option<PagedFile>, String> {
    let is_clod = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("clod"));
    if !is_clod {
        return Ok(None);
    }
    match PagedFile::open(path) {
        Ok(file) if file.root().is_ok() => Ok(Some(file)),
        _ => Ok(None),
    }
}

/// Maps a `.clod` file, or bakes any other file caveclod-bake imports (OBJ, PLY, glTF,
/// DEM, NPY) in memory, reporting its stages on stderr.
pub fn load(path: &Path, spacing: Option<f32>) -> Result<ClodBytes, String> {
    let is_clod = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("clod"));
    if is_clod {
        return ClodBytes::open(path).map_err(|e| e.to_string());
    }
    let start = Instant::now();
    let mut progress = BakeProgress::new();
    let baked = bake_file(path, &ImportOptions { spacing }, &mut |s| progress.show(s));
    progress.finish();
    let (baked, info) = baked.map_err(|e| e.to_string())?;
    let bytes = baked
        .to_bytes(&[])
        .map_err(|e| format!("{}: serialising the bake: {e}", path.display()))?;
    eprintln!(
        "baked {} ({} triangles) in {:.1} s",
        path.display(),
        info.input_triangles,
        start.elapsed().as_secs_f64()
    );
    Ok(AlignedBytes::from_slice(&bytes).into())
}

/// Shows the bake's stage on stderr: on a terminal one line rewritten in place, with the
/// collapses as a percentage; elsewhere (a log) one line per stage.
struct BakeProgress {
    terminal: bool,
    percent: Option<u64>,
    collapsing: bool,
}

impl BakeProgress {
    fn new() -> Self {
        Self {
            terminal: std::io::stderr().is_terminal(),
            percent: None,
            collapsing: false,
        }
    }

    fn show(&mut self, s: Stage) {
        let line = match s {
            Stage::Import => "importing".to_string(),
            Stage::Weld => "welding".to_string(),
            Stage::Collapse(done, most) => {
                let percent = 100 * done / most.max(1);
                let shown = if self.terminal {
                    self.percent == Some(percent)
                } else {
                    self.collapsing
                };
                if shown {
                    return;
                }
                self.percent = Some(percent);
                self.collapsing = true;
                if self.terminal {
                    format!("collapsing {percent:3}%")
                } else {
                    "collapsing".to_string()
                }
            }
            Stage::Assemble => "assembling".to_string(),
        };
        if self.terminal {
            eprint!("\rbaking: {line:<20}");
            let _ = std::io::stderr().flush();
        } else {
            eprintln!("baking: {line}");
        }
    }

    /// Ends the rewritten line.
    fn finish(&self) {
        if self.terminal {
            eprintln!();
        }
    }
}

/// How the mesh is coloured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColourMode {
    /// The file's materials (base-colour textures and factors).
    Materials,
    /// A palette colour per surface.
    Surface,
    /// A colour per band of hierarchy depth of the active front.
    Depth,
}

impl ColourMode {
    /// The next mode; materials only when the file has them, depth only over a whole file.
    pub fn next(self, has_materials: bool, has_depth: bool) -> Self {
        match self {
            Self::Materials => Self::Surface,
            Self::Surface if has_depth => Self::Depth,
            Self::Surface | Self::Depth if has_materials => Self::Materials,
            Self::Surface | Self::Depth => Self::Surface,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Materials => "materials",
            Self::Surface => "by surface",
            Self::Depth => "by hierarchy depth",
        }
    }
}

/// Morphs each camera holds at once: a few thousand splits and collapses in flight, for
/// 72 bytes each.
const MAX_MORPHS: u32 = 8192;

/// What the cameras refine over: a whole file, or a paged one streaming.
// One per viewer, made once and never moved in a loop: the variants' sizes do not matter.
#[allow(clippy::large_enum_variant)]
pub enum Records<'h> {
    Whole(Hierarchy<'h>),
    Streamed(Streamed<'h>),
}

impl<'h> Records<'h> {
    /// The configuration of the viewer's cameras: full resolution anywhere over a whole
    /// file, a polygon budget and index edits over a paged one; with morph memory.
    pub fn camera_config(&mut self) -> CameraConfig {
        match self {
            Self::Whole(h) => CameraConfig::full(h).with_morphs(MAX_MORPHS),
            Self::Streamed(s) => s.camera_config(MAX_MORPHS),
        }
    }

    /// Words each camera needs.
    pub fn camera_words(&mut self) -> usize {
        let config = self.camera_config();
        match self {
            Self::Whole(h) => CameraState::words_needed_for(h, &config),
            Self::Streamed(s) => CameraState::words_needed_for(&s.records(), &config),
        }
    }

    /// A camera in `memory`.
    fn camera(&mut self, memory: &'h mut [u32]) -> Result<CameraState<'h>, String> {
        let config = self.camera_config();
        match self {
            Self::Whole(h) => CameraState::with_config(h, memory, &config),
            Self::Streamed(s) => CameraState::with_config(&s.records(), memory, &config),
        }
        .map_err(|e| e.to_string())
    }

    pub fn meta(&self) -> &Meta {
        match self {
            Self::Whole(h) => h.meta(),
            Self::Streamed(s) => s.root().meta(),
        }
    }

    pub fn surface_count(&self) -> usize {
        self.meta().surface_count as usize
    }

    /// The file's materials (a paged file's are not drawn).
    pub fn materials(&self) -> Option<Materials<'h>> {
        match self {
            Self::Whole(h) => h.materials(),
            Self::Streamed(_) => None,
        }
    }

    /// The whole file, if it is one.
    pub fn whole(&self) -> Option<&Hierarchy<'h>> {
        match self {
            Self::Whole(h) => Some(h),
            Self::Streamed(_) => None,
        }
    }

    /// The streamed file, if it is one.
    pub fn streamed(&self) -> Option<&Streamed<'h>> {
        match self {
            Self::Whole(_) => None,
            Self::Streamed(s) => Some(s),
        }
    }
}

/// Fills a streamed camera's ring for the frame: camera `i`, over the frame's records.
pub type FillStreamed<'f, 'h> = dyn FnMut(usize, &StreamedHierarchy<'_, '_, 'h, 'h>, &mut CameraState<'h>) -> Result<(), String>
    + 'f;

/// Where geomorphs are blended, if they are on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Morphs {
    Vertex,
    Compute,
    Off,
}

impl Morphs {
    /// The mode after this one.
    pub fn next(self) -> Self {
        match self {
            Self::Vertex => Self::Compute,
            Self::Compute => Self::Off,
            Self::Off => Self::Vertex,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Vertex => "geomorphs in the vertex stage",
            Self::Compute => "geomorphs in the compute stage",
            Self::Off => "geomorphs off",
        }
    }

    /// The stage blending them, when on.
    pub fn stage(self) -> Option<MorphStage> {
        match self {
            Self::Vertex => Some(MorphStage::Vertex),
            Self::Compute => Some(MorphStage::Compute),
            Self::Off => None,
        }
    }
}

/// What the keys change.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Screen-space tolerance of refinement, pixels.
    pub tolerance_px: f32,
    pub colour: ColourMode,
    pub wireframe: bool,
    pub morphs: Morphs,
    /// The camera the keys and mouse steer.
    pub selected: usize,
}

/// One camera's figures of the last frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct CameraStats {
    pub polygons: u32,
    /// Morphs in progress.
    pub morphing: u32,
    /// Splits plus collapses.
    pub operations: u32,
    pub refine_ms: f64,
    /// Index emission into the mapped index buffers (and, coloured by depth, the regrouping).
    pub emit_ms: f64,
    /// Splits waiting for pages (a streamed file).
    pub deferred: u32,
}

/// A camera: its front, how it moves, and whether its front is frozen.
pub struct SceneCamera<'h> {
    pub state: CameraState<'h>,
    pub control: CameraControl,
    /// The view the front was last refined for, while frozen: the front stays as it was
    /// while the camera keeps moving.
    pub frozen: Option<Frozen>,
    /// Moves by itself until steered.
    pub animated: bool,
    pub stats: CameraStats,
}

/// A frozen camera's view and the aspect of its viewport then.
#[derive(Clone, Copy, Debug)]
pub struct Frozen {
    pub look: LookAt,
    pub aspect: f32,
}

/// The hierarchy, its cameras and the settings.
pub struct Scene<'h> {
    pub h: Records<'h>,
    /// The directory the materials' texture paths are relative to (the input's).
    pub texture_dir: PathBuf,
    pub cameras: Vec<SceneCamera<'h>>,
    pub settings: Settings,
    /// Seconds since the previous frame: how far morphs move.
    pub dt_s: f32,
}

impl<'h> Scene<'h> {
    /// One camera per memory (each [`CameraState::words_needed_for`] [`camera_config`]
    /// words), placed around
    /// the mesh as caveclod's snapshots place them; animated if `animate`.
    pub fn new(
        mut h: Records<'h>,
        texture_dir: PathBuf,
        memories: &'h mut [Vec<u32>],
        tolerance_px: f32,
        animate: bool,
    ) -> Result<Self, String> {
        let m = *h.meta();
        let (lo, hi) = (
            caveclod_core::glam::Vec3::from_array(m.bounds_min),
            caveclod_core::glam::Vec3::from_array(m.bounds_max),
        );
        let centre = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1e-6);
        let looks = caveclod_host::orbit_box(m.bounds_min, m.bounds_max, memories.len());
        let mut cameras = Vec::with_capacity(memories.len());
        for (i, (memory, look)) in memories.iter_mut().zip(looks).enumerate() {
            let state = h
                .camera(memory)
                .map_err(|e| format!("camera {}: {e}", i + 1))?;
            cameras.push(SceneCamera {
                state,
                control: CameraControl::from_look(&look, centre, radius, i),
                frozen: None,
                animated: animate,
                stats: CameraStats::default(),
            });
        }
        let colour = if h.materials().is_some() {
            ColourMode::Materials
        } else {
            ColourMode::Surface
        };
        Ok(Self {
            h,
            texture_dir,
            cameras,
            settings: Settings {
                tolerance_px,
                colour,
                wireframe: false,
                morphs: Morphs::Vertex,
                selected: 0,
            },
            dt_s: 1.0 / 60.0,
        })
    }

    /// Moves the animated cameras by `dt` seconds.
    pub fn animate(&mut self, dt: f32) {
        for c in self.cameras.iter_mut().filter(|c| c.animated) {
            c.control.animate(dt);
        }
    }

    /// Refines every camera that is not frozen against its own view in its viewport; over
    /// a streamed file `fill` then fills each camera's ring (frozen ones too) while the
    /// frame's records are at hand, and the pool streams.
    pub fn refine(
        &mut self,
        viewports: &[Viewport],
        fill: &mut FillStreamed<'_, 'h>,
    ) -> Result<(), String> {
        let params = RefineParams {
            tolerance_px: self.settings.tolerance_px,
            dt_s: self.dt_s,
            ..RefineParams::default()
        };
        // Off, morphs in progress end on the next pass and new operations happen at once.
        let params = match self.settings.morphs {
            Morphs::Off => params.without_morphs(),
            Morphs::Vertex | Morphs::Compute => params,
        };
        let views: Vec<Option<View>> = self
            .cameras
            .iter()
            .zip(viewports)
            .map(|(c, vp)| {
                let view = c.control.look().view(vp.width, vp.height);
                c.frozen.is_none().then_some(view)
            })
            .collect();
        match &mut self.h {
            Records::Whole(h) => refine_cameras(&mut self.cameras, h, &views, &params),
            Records::Streamed(s) => {
                let params = s.begin_frame(params);
                {
                    let h = s.records();
                    refine_cameras(&mut self.cameras, &h, &views, &params)?;
                    for (i, c) in self.cameras.iter_mut().enumerate() {
                        let start = Instant::now();
                        fill(i, &h, &mut c.state)?;
                        c.stats.emit_ms = start.elapsed().as_secs_f64() * 1e3;
                    }
                }
                let deferred = self.cameras.iter().map(|c| c.stats.deferred).sum();
                let nodes = self
                    .cameras
                    .iter()
                    .map(|c| c.state.active_node_count())
                    .sum();
                s.end_frame(deferred, nodes)
            }
        }
    }

    /// Freezes the selected camera's front at its current view, or thaws it.
    pub fn toggle_freeze(&mut self, viewport: Viewport) {
        if let Some(c) = self.cameras.get_mut(self.settings.selected) {
            c.frozen = match c.frozen {
                Some(_) => None,
                None => Some(Frozen {
                    look: c.control.look(),
                    aspect: viewport.aspect(),
                }),
            };
        }
    }

    /// Multiplies the tolerance by `factor`, within 0.05 to 500 pixels.
    pub fn scale_tolerance(&mut self, factor: f32) {
        self.settings.tolerance_px = (self.settings.tolerance_px * factor).clamp(0.05, 500.0);
    }

    /// Steers camera `i` from now on (if there is one).
    pub fn select(&mut self, i: usize) {
        if i < self.cameras.len() {
            self.settings.selected = i;
        }
    }

    /// The steered camera (stops animating).
    pub fn steered(&mut self) -> Option<&mut SceneCamera<'h>> {
        let c = self.cameras.get_mut(self.settings.selected)?;
        c.animated = false;
        Some(c)
    }
}

/// Refines each camera with a view (the others are frozen) over `h`, compacting its front
/// a bounded step first, and notes its figures.
fn refine_cameras<'h>(
    cameras: &mut [SceneCamera<'h>],
    h: &impl HierarchyRecords,
    views: &[Option<View>],
    params: &RefineParams,
) -> Result<(), String> {
    for (i, (c, view)) in cameras.iter_mut().zip(views).enumerate() {
        let Some(view) = view else {
            c.stats.operations = 0;
            c.stats.refine_ms = 0.0;
            continue;
        };
        // A new or reset camera's first pass does not morph (`CameraState::refine`).
        let start = Instant::now();
        // Incremental compaction keeps the front's records close in memory, a bounded step
        // a frame.
        c.state.compact_as_needed(h, COMPACT_STEP);
        let stats = c
            .state
            .refine(h, view, params)
            .map_err(|e| format!("camera {}: refinement: {e}", i + 1))?;
        c.stats.refine_ms = start.elapsed().as_secs_f64() * 1e3;
        c.stats.operations = stats.splits + stats.collapses;
        c.stats.polygons = stats.active_polygons;
        c.stats.morphing = stats.morphing;
        c.stats.deferred = stats.deferred_splits;
    }
    Ok(())
}
