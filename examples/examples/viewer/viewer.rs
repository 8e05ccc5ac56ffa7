//! The window and everything the GPU holds for it: the host's device (caveclod-host's
//! windowed [`Host`]), caveclod's context, recorder, vertex buffer and per-camera index
//! rings, the swapchain and frames in flight, and egui's renderer; made when the window
//! opens, destroyed explicitly on exit.

use caveclod_host::{Frames, GpuMaterials, Host, HostDesc, Swapchain, SwapchainDesc};
use caveclod_vulkan::ash::vk;
use caveclod_vulkan::{
    CameraIndices, CameraMorphs, Context, DeviceFeatures, MorphStage, Recorder, RecorderDesc,
    TargetFormats, VertexBuffer, VertexPool,
};
use egui_ash_renderer::allocator::GpuAllocator;
use egui_ash_renderer::{DynamicRendering, Options, RenderMode};
use winit::dpi::PhysicalSize;
use winit::event::WindowEvent;
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

use crate::depth::DepthBands;
use crate::scene::{Records, Scene};
use crate::stream::MAX_INSTALLS;

/// Frames the CPU records while the GPU still renders earlier ones.
pub const FRAMES_IN_FLIGHT: usize = 2;

/// egui's renderer, drawing with the host's allocator.
pub type EguiRenderer = egui_ash_renderer::Renderer<GpuAllocator>;

/// How to open the window.
#[derive(Clone, Copy, Debug)]
pub struct WindowDesc {
    pub width: u32,
    pub height: u32,
    pub vsync: bool,
    pub validation: bool,
}

/// A camera's index rings: one list per surface, and one per depth band; and its morph
/// slots for each stage that can blend them.
pub struct Rings {
    pub surfaces: CameraIndices,
    pub bands: CameraIndices,
    pub vertex_morphs: CameraMorphs,
    pub compute_morphs: CameraMorphs,
}

impl Rings {
    /// The morphs blended by `stage` (the vertex or the compute stage).
    pub fn morphs(&self, stage: MorphStage) -> &CameraMorphs {
        match stage {
            MorphStage::Compute => &self.compute_morphs,
            MorphStage::Vertex | MorphStage::Host => &self.vertex_morphs,
        }
    }

    /// As [`Rings::morphs`], to fill.
    pub fn morphs_mut(&mut self, stage: MorphStage) -> &mut CameraMorphs {
        match stage {
            MorphStage::Compute => &mut self.compute_morphs,
            MorphStage::Vertex | MorphStage::Host => &mut self.vertex_morphs,
        }
    }
}

/// The vertices the cameras draw: a whole file's, or a paged file's resident pages'.
pub enum Vertices {
    Whole(VertexBuffer),
    Pool(VertexPool),
}

impl Vertices {
    /// The buffer the draws read.
    pub fn buffer(&self) -> &VertexBuffer {
        match self {
            Self::Whole(v) => v,
            Self::Pool(p) => p.vertices(),
        }
    }

    /// The whole file's, or a pool with its root pages, over `scene`'s records.
    fn new(ctx: &Context, scene: &Scene<'_>) -> Result<Self, String> {
        match &scene.h {
            Records::Whole(h) => VertexBuffer::from_hierarchy(ctx, "mesh", h)
                .map(Self::Whole)
                .map_err(|e| format!("vertex buffer: {e}")),
            Records::Streamed(s) => {
                let layout = s.vertex_pool().ok_or("a page pool without a vertex pool")?;
                let made = VertexPool::new(
                    ctx,
                    "terrain",
                    layout,
                    false,
                    MAX_INSTALLS as u32,
                    FRAMES_IN_FLIGHT,
                );
                let mut pool = made.map_err(|e| format!("vertex pool: {e}"))?;
                match pool.upload_roots(ctx, &s.root_vertices()) {
                    Ok(()) => Ok(Self::Pool(pool)),
                    Err(e) => {
                        let _ = pool.destroy(ctx);
                        Err(format!("vertex pool: {e}"))
                    }
                }
            }
        }
    }

    fn destroy(self, ctx: &Context) -> Result<(), String> {
        match self {
            Self::Whole(v) => v.destroy(ctx),
            Self::Pool(p) => p.destroy(ctx),
        }
        .map_err(|e| format!("vertices: {e}"))
    }
}

/// What the frames draw with, besides the host's device.
pub struct Resources {
    pub recorder: Recorder,
    /// The file's materials for the recorder, if it has any.
    pub materials: Option<GpuMaterials>,
    pub vertices: Vertices,
    pub rings: Vec<Rings>,
    pub frames: Frames,
    /// Where egui's texture uploads allocate their command buffers.
    pub upload_pool: vk::CommandPool,
    pub egui: EguiRenderer,
    /// `None` while the window has no area (minimised).
    pub swapchain: Option<Swapchain>,
}

/// The window, the GPU side and the egui state.
pub struct Viewer {
    pub host: Host,
    pub ctx: Context,
    pub res: Resources,
    pub desc: SwapchainDesc,
    pub bands: DepthBands,
    pub surface_colours: Vec<[f32; 4]>,
    pub band_colours: Vec<[f32; 4]>,
    pub egui_ctx: egui::Context,
    pub egui_state: egui_winit::State,
    /// The swapchain no longer matches the window.
    pub stale: bool,
    /// Swapchains made so far (the first included).
    pub swapchains_made: u64,
    /// Times acquire or present reported the swapchain out of date or suboptimal.
    pub swapchain_reports: u64,
    /// Frames recorded so far (frame `n` uses slot `n % FRAMES_IN_FLIGHT`).
    pub frame: u64,
    /// egui textures to free once the GPU is done with the frames that drew them.
    pub pending_free: Vec<egui::TextureId>,
    // Last: the surface is destroyed (in `destroy`) before the window is dropped.
    pub window: Window,
}

impl Viewer {
    /// Opens the window and makes everything the frames need for `scene`.
    pub fn new(
        event_loop: &ActiveEventLoop,
        scene: &Scene<'_>,
        w: WindowDesc,
    ) -> Result<Self, String> {
        let attributes = Window::default_attributes()
            .with_title("caveclod viewer")
            .with_inner_size(PhysicalSize::new(w.width, w.height));
        let window = event_loop
            .create_window(attributes)
            .map_err(|e| format!("opening the window: {e}"))?;
        let desc = HostDesc {
            validation: w.validation,
            prefer_cpu: false,
            required: DeviceFeatures::REQUIRED,
            optional: DeviceFeatures::ALL,
        };
        let host = Host::windowed(&window, &desc).map_err(|e| e.to_string())?;
        let made = host.context().map_err(|e| e.to_string()).and_then(|ctx| {
            let ready = SwapchainDesc::choose(&host, w.vsync)
                .map_err(|e| e.to_string())
                .and_then(|desc| {
                    let bands = match scene.h.whole() {
                        Some(h) => DepthBands::new(h)?,
                        None => DepthBands::none(),
                    };
                    Ok((desc, bands))
                })
                .and_then(|(desc, bands)| {
                    let res = Resources::new(&host, &ctx, scene, desc, &bands, &window)?;
                    Ok((desc, bands, res))
                });
            match ready {
                Ok(r) => Ok((ctx, r)),
                Err(e) => {
                    let _ = ctx.destroy();
                    Err(e)
                }
            }
        });
        let (ctx, (desc, bands, res)) = match made {
            Ok(m) => m,
            Err(e) => {
                let _ = host.destroy();
                return Err(e);
            }
        };
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            None,
        );
        let surface_colours = (0..scene.h.surface_count())
            .map(caveclod_host::palette)
            .collect();
        let band_colours = bands.colours();
        let swapchains_made = u64::from(res.swapchain.is_some());
        Ok(Self {
            host,
            ctx,
            res,
            desc,
            bands,
            surface_colours,
            band_colours,
            egui_ctx,
            egui_state,
            stale: false,
            swapchains_made,
            swapchain_reports: 0,
            frame: 0,
            pending_free: Vec::new(),
            window,
        })
    }

    /// Passes a window event to egui; `true` if egui wants it for itself.
    pub fn on_window_event(&mut self, event: &WindowEvent) -> bool {
        self.egui_state
            .on_window_event(&self.window, event)
            .consumed
    }

    /// The window's drawable size.
    pub fn size(&self) -> vk::Extent2D {
        let s = self.window.inner_size();
        vk::Extent2D {
            width: s.width,
            height: s.height,
        }
    }

    /// Replaces the swapchain with one for the window's current size (none while the
    /// window has no area).
    pub fn recreate_swapchain(&mut self) -> Result<(), String> {
        self.host.wait_idle().map_err(|e| e.to_string())?;
        let old = self.res.swapchain.take();
        let made = Swapchain::new(&self.host, self.desc, self.size(), old.as_ref());
        if let Some(old) = old {
            old.destroy(&self.host);
        }
        self.res.swapchain = made.map_err(|e| e.to_string())?;
        self.swapchains_made += u64::from(self.res.swapchain.is_some());
        self.stale = false;
        Ok(())
    }

    /// Waits for the GPU, then destroys everything in reverse order of creation; returns
    /// the validation messages recorded (including the teardown's) and the first error.
    pub fn destroy(self) -> (Vec<String>, Result<(), String>) {
        let log = self.host.log().clone();
        let mut result = self.host.wait_idle().map_err(|e| e.to_string());
        let mut keep = |r: Result<(), String>| {
            if let (Ok(()), Err(e)) = (&result, r) {
                result = Err(e);
            }
        };
        keep(self.res.destroy(&self.host, &self.ctx));
        keep(self.ctx.destroy().map_err(|e| format!("caveclod: {e}")));
        keep(self.host.destroy().map_err(|e| format!("host: {e}")));
        drop(self.window);
        (log.take(), result)
    }
}

impl Resources {
    /// Recorder (for the swapchain's formats, wireframe where the device has it), vertex
    /// buffer, index rings, frame slots, egui's renderer and the swapchain, each step
    /// undoing the earlier ones if it fails.
    fn new(
        host: &Host,
        ctx: &Context,
        scene: &Scene<'_>,
        desc: SwapchainDesc,
        bands: &DepthBands,
        window: &Window,
    ) -> Result<Self, String> {
        let formats = TargetFormats {
            colour: desc.format.format,
            depth: desc.depth,
            samples: vk::SampleCountFlags::TYPE_1,
        };
        let recorder = Recorder::new(
            ctx,
            RecorderDesc {
                wireframe: ctx.features().fill_mode_non_solid,
                refine_morphs: true,
                ..RecorderDesc::dynamic(formats)
            },
        )
        .map_err(|e| format!("caveclod recorder: {e}"))?;
        let loaded = match scene.h.whole() {
            Some(h) => GpuMaterials::load(ctx, &recorder, h, &scene.texture_dir),
            None => Ok(None),
        };
        let materials = match loaded {
            Ok(m) => m,
            Err(e) => {
                let _ = recorder.destroy(ctx);
                return Err(format!("materials: {e}"));
            }
        };
        let undo = |materials: Option<GpuMaterials>, recorder: Recorder| {
            if let Some(m) = materials {
                let _ = m.destroy(ctx);
            }
            let _ = recorder.destroy(ctx);
        };
        let vertices = match Vertices::new(ctx, scene) {
            Ok(v) => v,
            Err(e) => {
                undo(materials, recorder);
                return Err(e);
            }
        };
        let rings = match rings(ctx, &recorder, vertices.buffer(), scene, bands) {
            Ok(r) => r,
            Err(e) => {
                let _ = vertices.destroy(ctx);
                undo(materials, recorder);
                return Err(e);
            }
        };
        let (frames, upload_pool) = match frames_and_pool(host) {
            Ok(s) => s,
            Err(e) => {
                let _ = destroy_rings(ctx, rings);
                let _ = vertices.destroy(ctx);
                undo(materials, recorder);
                return Err(e);
            }
        };
        let egui = match egui_renderer(host, desc) {
            Ok(r) => r,
            Err(e) => {
                destroy_frames(host, frames, upload_pool);
                let _ = destroy_rings(ctx, rings);
                let _ = vertices.destroy(ctx);
                undo(materials, recorder);
                return Err(e);
            }
        };
        let mut res = Self {
            recorder,
            materials,
            vertices,
            rings,
            frames,
            upload_pool,
            egui,
            swapchain: None,
        };
        let size = window.inner_size();
        let extent = vk::Extent2D {
            width: size.width,
            height: size.height,
        };
        match Swapchain::new(host, desc, extent, None) {
            Ok(s) => {
                res.swapchain = s;
                Ok(res)
            }
            Err(e) => {
                let _ = res.destroy(host, ctx);
                Err(e.to_string())
            }
        }
    }

    /// Destroys everything; the device must be idle.
    fn destroy(self, host: &Host, ctx: &Context) -> Result<(), String> {
        if let Some(s) = self.swapchain {
            s.destroy(host);
        }
        // egui's renderer frees its buffers, textures and pipeline when dropped (its only
        // way to be destroyed); before the allocator it draws from.
        drop(self.egui);
        destroy_frames(host, self.frames, self.upload_pool);
        let mut first = destroy_rings(ctx, self.rings);
        if let Err(e) = self.vertices.destroy(ctx) {
            first = first.and(Err(e));
        }
        if let Some(m) = self.materials {
            if let Err(e) = m.destroy(ctx) {
                first = first.and(Err(format!("materials: {e}")));
            }
        }
        if let Err(e) = self.recorder.destroy(ctx) {
            first = first.and(Err(format!("recorder: {e}")));
        }
        first
    }
}

/// The frames in flight (with the swapchain's acquire semaphores) and the pool egui's
/// uploads use.
fn frames_and_pool(host: &Host) -> Result<(Frames, vk::CommandPool), String> {
    let frames = Frames::new(host, FRAMES_IN_FLIGHT, true).map_err(|e| e.to_string())?;
    let info = vk::CommandPoolCreateInfo::default()
        .queue_family_index(host.queue_family())
        .flags(vk::CommandPoolCreateFlags::TRANSIENT);
    // SAFETY: valid create info.
    match unsafe { host.device().create_command_pool(&info, None) } {
        Ok(pool) => Ok((frames, pool)),
        Err(e) => {
            let _ = frames.destroy(host);
            Err(format!("vkCreateCommandPool: {e}"))
        }
    }
}

/// Destroys the frames in flight and egui's upload pool; the device must be idle.
fn destroy_frames(host: &Host, frames: Frames, pool: vk::CommandPool) {
    // The device is idle: nothing is left to wait for, so only a lost device could fail here,
    // and its objects are destroyed anyway.
    let _ = frames.destroy(host);
    // SAFETY: the device is idle (the callers' contract); a null pool is ignored.
    unsafe { host.device().destroy_command_pool(pool, None) };
}

/// egui's renderer for the swapchain's formats, drawing in the same dynamic rendering as
/// caveclod (no depth test), one vertex and index buffer per frame in flight.
fn egui_renderer(host: &Host, desc: SwapchainDesc) -> Result<EguiRenderer, String> {
    EguiRenderer::with_gpu_allocator(
        host.allocator().clone(),
        host.device().clone(),
        RenderMode::DynamicRendering(DynamicRendering {
            color_attachment_format: desc.format.format,
            depth_attachment_format: Some(desc.depth),
            stencil_attachment_format: None,
        }),
        Options {
            in_flight_frames: FRAMES_IN_FLIGHT,
            enable_depth_test: false,
            enable_depth_write: false,
            srgb_framebuffer: desc.srgb(),
        },
    )
    .map_err(|e| format!("egui renderer: {e}"))
}

/// Each camera's index rings (over a paged file, its index buffer edited in place) and morph
/// slots.
fn rings(
    ctx: &Context,
    recorder: &Recorder,
    vertices: &VertexBuffer,
    scene: &Scene<'_>,
    bands: &DepthBands,
) -> Result<Vec<Rings>, String> {
    let mut rings = Vec::with_capacity(scene.cameras.len());
    for (i, c) in scene.cameras.iter().enumerate() {
        let name = format!("camera {}", i + 1);
        let morphs = |stage| {
            let max = c.state.max_morphs();
            CameraMorphs::new(ctx, recorder, &name, vertices, stage, max, FRAMES_IN_FLIGHT)
                .map_err(|e| format!("{name}: morphs: {e}"))
        };
        let made = morphs(MorphStage::Vertex).and_then(|v| match morphs(MorphStage::Compute) {
            Ok(c) => Ok((v, c)),
            Err(e) => {
                let _ = v.destroy(ctx);
                Err(e)
            }
        });
        let (vertex_morphs, compute_morphs) = match made {
            Ok(m) => m,
            Err(e) => {
                let _ = destroy_rings(ctx, rings);
                return Err(e);
            }
        };
        let surfaces = match scene.h.streamed() {
            None => Ok(CameraIndices::new(
                &name,
                scene.h.surface_count(),
                FRAMES_IN_FLIGHT,
            )),
            Some(_) => {
                let places = c.state.index_places();
                CameraIndices::edited(
                    ctx,
                    &name,
                    scene.h.surface_count(),
                    places,
                    FRAMES_IN_FLIGHT,
                )
                .map_err(|e| format!("{name}: index buffer: {e}"))
            }
        };
        let surfaces = match surfaces {
            Ok(s) => s,
            Err(e) => {
                let _ = vertex_morphs.destroy(ctx);
                let _ = compute_morphs.destroy(ctx);
                let _ = destroy_rings(ctx, rings);
                return Err(e);
            }
        };
        rings.push(Rings {
            surfaces,
            bands: CameraIndices::new(
                &format!("{name} depth bands"),
                bands.band_count(),
                FRAMES_IN_FLIGHT,
            ),
            vertex_morphs,
            compute_morphs,
        });
    }
    Ok(rings)
}

/// Destroys every ring; the device must be done with them.
fn destroy_rings(ctx: &Context, rings: Vec<Rings>) -> Result<(), String> {
    let mut first = Ok(());
    for r in rings {
        for ring in [r.surfaces, r.bands] {
            if let Err(e) = ring.destroy(ctx) {
                first = first.and(Err(format!("index ring: {e}")));
            }
        }
        for m in [r.vertex_morphs, r.compute_morphs] {
            if let Err(e) = m.destroy(ctx) {
                first = first.and(Err(format!("morphs: {e}")));
            }
        }
    }
    first
}
