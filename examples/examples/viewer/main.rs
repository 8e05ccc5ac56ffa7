//! Viewer: a window onto a caveclod hierarchy, 1 to 4 cameras in split screen, each refined
//! every frame against its own view and drawn through caveclod-vulkan's record path into
//! the viewer's own swapchain frame, with an egui panel on top. The viewer is the host
//! engine: caveclod-host's windowed `Host` makes the instance, device, allocator and
//! swapchain as an engine would, and caveclod gets only `Context::from_raw` and the
//! viewer's command buffers, through no API of caveclod-vulkan that an engine could not
//! use.
//!
//! ```text
//! cargo run --release -p caveclod-examples --example viewer -- FILE [OPTIONS]
//!
//!   FILE                a .clod file, or a mesh caveclod-bake imports (.obj, .ply, .gltf,
//!                       .glb, .dem, .npy), baked before the window opens (progress on
//!                       stderr)
//!   --cameras N         1 to 4 cameras, split screen (default 1)
//!   --tolerance PX      screen-space tolerance, pixels (default 1)
//!   --width/--height    window size (default 1280 x 720)
//!   --no-vsync          MAILBOX or IMMEDIATE presentation instead of FIFO
//!   --validation        the Khronos validation layer (always on in debug builds)
//!   --frames N          draw N frames with the cameras animated, then exit
//!   --screenshot FILE   with --frames: write the last frame as PNG
//!   --min-coverage F    with --screenshot: fail unless every camera's viewport is at
//!                       least F (0 to 1) non-background outside the panel
//!   --spacing M         metres per grid cell for .npy heightfields (and .dem override)
//!   --resize-every N    with --frames: a resize storm, a new window size every N frames
//!                       (see the `storm` module); fails unless each got a swapchain
//!   --vertex-pool MIB   a paged file's device vertex pool, MiB (default 64): its pages
//!                       stream from the file into a page pool of as many slots
//! ```
//!
//! Keys are listed in the panel ([`controls::KEY_HELP`]). With `--frames`, validation
//! messages make the exit status non-zero.

mod controls;
mod depth;
mod frame;
mod scene;
mod screenshot;
mod storm;
mod stream;
mod ui;
mod viewer;

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use caveclod_core::glam::Vec2;
use clap::Parser;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::PhysicalKey;
use winit::window::WindowId;

use controls::{Action, Input};
use frame::{Capture, Outcome};
use scene::Scene;
use storm::ResizeStorm;
use ui::PanelInfo;
use viewer::{Viewer, WindowDesc};

/// Seconds of animation per frame with `--frames`, so a run animates the same however
/// fast the device draws.
const FRAMES_DT: f32 = 1.0 / 30.0;
/// Frames after which a paged file's run makes no more device resources: its pool, index
/// buffers and staging are made, and a `--frames` run fails if another one is.
const WARM_UP: u64 = 60;

#[derive(Parser, Debug)]
#[command(about = "Interactive viewer of caveclod hierarchies (see the module docs)")]
struct Args {
    /// A .clod file, or a mesh to bake (.obj, .ply, .gltf, .glb, .dem, .npy).
    input: PathBuf,
    /// Cameras, 1 to 4, in split screen.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=4))]
    cameras: u8,
    /// Screen-space tolerance, pixels.
    #[arg(long, default_value_t = 1.0)]
    tolerance: f32,
    #[arg(long, default_value_t = 1280)]
    width: u32,
    #[arg(long, default_value_t = 720)]
    height: u32,
    /// Present without waiting for vertical blank (MAILBOX, else IMMEDIATE).
    #[arg(long)]
    no_vsync: bool,
    /// Enable the Khronos validation layer (always on in debug builds).
    #[arg(long)]
    validation: bool,
    /// Draw this many frames with animated cameras, then exit.
    #[arg(long)]
    frames: Option<u64>,
    /// With --frames: write the last frame to this PNG file.
    #[arg(long, requires = "frames")]
    screenshot: Option<PathBuf>,
    /// With --screenshot: least non-background fraction of each camera's viewport.
    #[arg(long, requires = "screenshot")]
    min_coverage: Option<f64>,
    /// Metres per grid cell (.npy heightfields; overrides a .dem header's spacing).
    #[arg(long)]
    spacing: Option<f32>,
    /// With --frames: ask for a new window size every N frames (a resize storm).
    #[arg(long, requires = "frames")]
    resize_every: Option<u64>,
    /// A paged file's device vertex pool, MiB.
    #[arg(long, default_value_t = 64)]
    vertex_pool: u64,
}

fn main() -> ExitCode {
    let args = Args::parse();
    match run(&args) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("viewer: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Opens the file (streamed, if it is paged), makes the cameras, runs the window until it
/// closes (or the frames are done) and reports.
fn run(args: &Args) -> Result<ExitCode, String> {
    let named = |e: &dyn std::fmt::Display| format!("{}: {e}", args.input.display());
    let mut memories = Vec::new();
    if let Some(file) = scene::open_paged(&args.input)? {
        let root = file.root().map_err(|e| named(&e))?;
        let mut memory = stream::StreamMemory::new(&root, args.vertex_pool << 20)?;
        let streamed = stream::Streamed::new(&file, root, &mut memory).map_err(|e| named(&e))?;
        return fly(args, scene::Records::Streamed(streamed), &mut memories);
    }
    let asset = scene::load(&args.input, args.spacing)?;
    let h = asset.hierarchy().map_err(|e| named(&e))?;
    fly(args, scene::Records::Whole(h), &mut memories)
}

/// Makes the cameras over `records`, each in one of `memories`, and runs the window.
fn fly<'h>(
    args: &Args,
    mut records: scene::Records<'h>,
    memories: &'h mut Vec<Vec<u32>>,
) -> Result<ExitCode, String> {
    let words = records.camera_words();
    *memories = vec![vec![0u32; words]; usize::from(args.cameras)];
    let texture_dir = args.input.parent().map_or_else(
        || std::path::PathBuf::from("."),
        std::path::Path::to_path_buf,
    );
    let scene = Scene::new(
        records,
        texture_dir,
        memories,
        args.tolerance,
        args.frames.is_some(),
    )?;
    let event_loop = EventLoop::new().map_err(|e| format!("event loop: {e}"))?;
    let mut app = App::new(args, scene);
    let looped = event_loop
        .run_app(&mut app)
        .map_err(|e| format!("event loop: {e}"));
    app.finish(looped)
}

/// Frames per second over the last second or so.
struct FpsMeter {
    since: Instant,
    frames: u32,
    fps: f64,
}

impl FpsMeter {
    fn tick(&mut self) {
        self.frames += 1;
        let s = self.since.elapsed().as_secs_f64();
        if s >= 0.5 {
            self.fps = f64::from(self.frames) / s;
            self.frames = 0;
            self.since = Instant::now();
        }
    }
}

/// The event loop's state.
struct App<'a, 'h> {
    args: &'a Args,
    scene: Scene<'h>,
    input: Input,
    viewer: Option<Viewer>,
    /// The first error, which ends the loop.
    error: Option<String>,
    drawn: u64,
    started: Option<Instant>,
    last: Instant,
    fps: FpsMeter,
    capture: Option<Capture>,
    storm: Option<ResizeStorm>,
    /// caveclod's device resources made by the end of the warm-up, and by the last frame.
    resources: (Option<u64>, u64),
}

impl<'a, 'h> App<'a, 'h> {
    fn new(args: &'a Args, scene: Scene<'h>) -> Self {
        Self {
            args,
            scene,
            input: Input::default(),
            viewer: None,
            error: None,
            drawn: 0,
            started: None,
            last: Instant::now(),
            fps: FpsMeter {
                since: Instant::now(),
                frames: 0,
                fps: 0.0,
            },
            capture: None,
            resources: (None, 0),
            storm: args.resize_every.zip(args.frames).map(|(every, frames)| {
                let base = winit::dpi::PhysicalSize::new(args.width, args.height);
                ResizeStorm::new(every, frames, base)
            }),
        }
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: String) {
        self.error.get_or_insert(e);
        event_loop.exit();
    }

    /// Applies a settings key.
    fn act(&mut self, event_loop: &ActiveEventLoop, a: Action) {
        let s = &mut self.scene;
        match a {
            Action::Select(i) => s.select(i),
            Action::Coarser => s.scale_tolerance(1.25),
            Action::Finer => s.scale_tolerance(0.8),
            Action::Wireframe => s.settings.wireframe = !s.settings.wireframe,
            Action::CycleColour => {
                let (materials, depth) = (s.h.materials().is_some(), s.h.whole().is_some());
                s.settings.colour = s.settings.colour.next(materials, depth)
            }
            Action::CycleMorphs => s.settings.morphs = s.settings.morphs.next(),
            Action::Freeze => {
                let viewport = self.viewer.as_ref().and_then(|v| {
                    let e = v.size();
                    caveclod_vulkan::Viewport::split_screen(e.width, e.height, s.cameras.len())
                        .ok()
                        .and_then(|vps| vps.get(s.settings.selected).copied())
                });
                if let Some(vp) = viewport {
                    s.toggle_freeze(vp);
                }
            }
            Action::Quit => event_loop.exit(),
        }
    }

    /// Moves the cameras, draws a frame and, with `--frames`, stops after the last.
    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        let now = Instant::now();
        let dt = (now - self.last).as_secs_f32().min(0.1);
        self.last = now;
        if self.input.active() {
            if let Some(c) = self.scene.steered() {
                self.input.steer(&mut c.control, dt);
            }
        }
        let limit = self.args.frames;
        let dt = if limit.is_some() { FRAMES_DT } else { dt };
        self.scene.animate(dt);
        self.scene.dt_s = dt;
        let last = limit.is_some_and(|n| self.drawn + 1 >= n);
        let capture = last && self.args.screenshot.is_some();
        let Some(viewer) = self.viewer.as_mut() else {
            return;
        };
        if let Some(size) = self.storm.as_mut().and_then(|s| s.next(self.drawn)) {
            // Applied by the window system while this frame is in flight; the frame or the
            // next finds the swapchain out of date or suboptimal.
            let _ = viewer.window.request_inner_size(size);
        }
        let device = viewer.host.device_name().to_string();
        let info = PanelInfo {
            device: &device,
            fps: self.fps.fps,
            wireframe_available: viewer.res.recorder.desc().wireframe,
            validation_messages: viewer.host.log().len(),
            bands: viewer.bands.band_count(),
            levels: viewer.bands.levels(),
        };
        match viewer.frame(&mut self.scene, &info, capture) {
            Err(e) => self.fail(event_loop, e),
            Ok(Outcome::Skipped) => {}
            Ok(Outcome::Drawn(shot)) => {
                self.started.get_or_insert(now);
                self.drawn += 1;
                let made = viewer.ctx.resources_created();
                if self.drawn == WARM_UP {
                    self.resources.0 = Some(made);
                }
                self.resources.1 = made;
                self.fps.tick();
                self.capture = shot.or(self.capture.take());
                if last {
                    self.report_speed(&device);
                    event_loop.exit();
                }
            }
        }
    }

    /// Prints the frame rate and each camera's last figures.
    fn report_speed(&self, device: &str) {
        let secs = self.started.map_or(0.0, |s| s.elapsed().as_secs_f64());
        eprintln!(
            "{} frames in {secs:.1} s on {device}: {:.1} fps",
            self.drawn,
            self.drawn.saturating_sub(1) as f64 / secs.max(1e-9)
        );
        if let Some(t) = self.scene.h.streamed().map(|s| s.totals) {
            eprintln!(
                "streaming: {} pages installed, {} evicted, {} faults, {} splits waiting, the \
                 pool's pressure scaling the tolerance by {:.2}",
                t.installs, t.evictions, t.faults, t.deferred, t.pressure
            );
            if let Some(warm) = self.resources.0 {
                eprintln!(
                    "caveclod's device resources: {warm} made by frame {WARM_UP}, {} by frame {}",
                    self.resources.1, self.drawn
                );
            }
        }
        for (i, c) in self.scene.cameras.iter().enumerate() {
            eprintln!(
                "camera {}: {} polygons, {} operations, refine {:.2} ms, emit {:.2} ms",
                i + 1,
                c.stats.polygons,
                c.stats.operations,
                c.stats.refine_ms,
                c.stats.emit_ms
            );
        }
    }

    /// Tears down the window and GPU, writes and checks the screenshot, reports the
    /// validation messages; the exit status.
    fn finish(mut self, looped: Result<(), String>) -> Result<ExitCode, String> {
        let (swapchains, reports) = self
            .viewer
            .as_ref()
            .map_or((0, 0), |v| (v.swapchains_made, v.swapchain_reports));
        let (messages, destroyed) = match self.viewer.take() {
            Some(v) => v.destroy(),
            None => (Vec::new(), Ok(())),
        };
        for m in &messages {
            eprintln!("validation: {m}");
        }
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        looped?;
        destroyed?;
        let mut ok = true;
        if let Some(path) = &self.args.screenshot {
            ok &= self.check_screenshot(path)?;
        }
        if let Some(storm) = &self.storm {
            eprintln!(
                "resize storm: {} sizes asked for, {swapchains} swapchains made, {reports} \
                 out of date or suboptimal at acquire or present",
                storm.requested
            );
            ok &= storm.requested > 0 && swapchains > storm.requested;
        }
        if self.args.frames.is_some() {
            eprintln!("{} validation messages", messages.len());
            ok &= messages.is_empty();
            let (warm, last) = self.resources;
            ok &= self.scene.h.streamed().is_none() || warm.is_none_or(|w| w == last);
        }
        Ok(if ok {
            ExitCode::SUCCESS
        } else {
            ExitCode::FAILURE
        })
    }

    /// Writes the screenshot; `false` if a viewport is below `--min-coverage`.
    fn check_screenshot(&self, path: &std::path::Path) -> Result<bool, String> {
        let capture = self
            .capture
            .as_ref()
            .ok_or("no frame was drawn, so there is no screenshot")?;
        screenshot::write(capture, path)?;
        let coverage = screenshot::coverage(capture);
        let shown: Vec<String> = coverage
            .iter()
            .map(|c| format!("{:.1}%", c * 1e2))
            .collect();
        eprintln!(
            "wrote {} ({}x{}); non-background per camera: {}",
            path.display(),
            capture.image.width,
            capture.image.height,
            shown.join(", ")
        );
        let Some(min) = self.args.min_coverage else {
            return Ok(true);
        };
        let low: Vec<usize> = (0..coverage.len()).filter(|&i| coverage[i] < min).collect();
        for i in &low {
            eprintln!(
                "camera {}: {:.1}% non-background, below {:.1}%",
                i + 1,
                coverage[*i] * 1e2,
                min * 1e2
            );
        }
        Ok(low.is_empty())
    }
}

impl ApplicationHandler for App<'_, '_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.viewer.is_some() {
            return;
        }
        let desc = WindowDesc {
            width: self.args.width,
            height: self.args.height,
            vsync: !self.args.no_vsync,
            validation: self.args.validation || cfg!(debug_assertions),
        };
        match Viewer::new(event_loop, &self.scene, desc) {
            Ok(v) => {
                eprintln!(
                    "{} on {} ({:?}, {:?})",
                    self.args.input.display(),
                    v.host.device_name(),
                    v.desc.format.format,
                    v.desc.present_mode
                );
                self.viewer = Some(v);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(viewer) = self.viewer.as_mut() else {
            return;
        };
        let egui_wants = viewer.on_window_event(&event);
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(_) | WindowEvent::ScaleFactorChanged { .. } => {
                viewer.stale = true;
                viewer.window.request_redraw();
            }
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            WindowEvent::Focused(false) => self.input.release_all(),
            WindowEvent::KeyboardInput { event, .. }
                if !egui_wants || !event.state.is_pressed() =>
            {
                if let PhysicalKey::Code(code) = event.physical_key {
                    if let Some(a) = self.input.key(code, event.state) {
                        if !event.repeat {
                            self.act(event_loop, a);
                        }
                    }
                }
            }
            WindowEvent::MouseInput { state, button, .. } if !egui_wants || !state.is_pressed() => {
                self.input.button(button, state);
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.input
                    .cursor(Vec2::new(position.x as f32, position.y as f32));
            }
            WindowEvent::MouseWheel { delta, .. } if !egui_wants => self.input.wheel(delta),
            _ => {}
        }
    }

    /// Draws continuously while there is something to draw into; a window without area
    /// waits for its next resize.
    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(v) = &self.viewer {
            let drawable = v.res.swapchain.is_some() || v.stale;
            event_loop.set_control_flow(if drawable {
                ControlFlow::Poll
            } else {
                ControlFlow::Wait
            });
            if drawable {
                v.window.request_redraw();
            }
        }
    }
}
