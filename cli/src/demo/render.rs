//! The demo's pictures: the four fly-over cameras drawn into the quadrants of one 1280 x 720
//! image on the Vulkan device (lavapipe unless a GPU is preferred), at a few frames of the
//! flight. Each camera refines its own front every frame for its own quadrant's view, exactly
//! as in the measured flights, with geomorphs (blended by the compute stage); only the
//! sampled frames are drawn and read back.

use std::path::{Path, PathBuf};

use caveclod_core::glam::Vec3;
use caveclod_core::{CameraConfig, CameraState, Hierarchy, RefineParams, COMPACT_STEP};
use caveclod_host::{terrain_colours, write_png};
use caveclod_vulkan::{
    CameraIndices, CameraMorphs, Context, HeadlessDesc, IndexSource, LookAt, MaterialSet,
    MorphStage, RecordCamera, Renderer, RendererDesc, RgbaImage, SurfaceMaterial, VertexBuffer,
    Viewport,
};

use crate::flyover::{clip, eye_at, routes, Ground, FOV_Y_DEG};

/// Image size of a split-screen frame.
pub const SIZE: (u32, u32) = (1280, 720);

/// Morphs each drawn camera holds at once.
const MAX_MORPHS: u32 = 8192;

/// Renders `frames` frames of the 4-camera fly-over and writes `frame-NNN.png` into `out` at
/// each of `shots` (frame numbers). Returns the files and the device's name.
pub fn render_flight(
    h: &Hierarchy<'_>,
    frames: usize,
    shots: &[usize],
    out: &Path,
) -> Result<(Vec<PathBuf>, String), String> {
    let ctx = Context::headless(&HeadlessDesc {
        validation: false,
        prefer_lavapipe: true,
        synchronization_validation: false,
    })
    .map_err(|e| e.to_string())?;
    let device = ctx.device_name().to_string();
    let result = draw(&ctx, h, frames, shots, out);
    let destroyed = ctx.destroy().map_err(|e| e.to_string());
    let files = result?;
    destroyed?;
    Ok((files, device))
}

/// Flies the four cameras for `frames` frames and draws the frames in `shots`.
fn draw(
    ctx: &Context,
    h: &Hierarchy<'_>,
    frames: usize,
    shots: &[usize],
    out: &Path,
) -> Result<Vec<PathBuf>, String> {
    let ground = Ground::new(h);
    let speed = ground.size / 600.0;
    let (near, far) = clip(&ground);
    let all = routes();
    let viewports = Viewport::split_screen(SIZE.0, SIZE.1, 4).map_err(|e| e.to_string())?;
    let config = CameraConfig::full(h).with_morphs(MAX_MORPHS);
    let words = CameraState::words_needed_for(h, &config);
    let mut memories: Vec<Vec<u32>> = (0..4).map(|_| vec![0u32; words]).collect();
    let mut cams = Vec::with_capacity(4);
    for m in memories.iter_mut() {
        cams.push(CameraState::with_config(h, m, &config).map_err(|e| e.to_string())?);
    }
    let mut gpu = Drawing::new(ctx, h).map_err(|e| e.to_string())?;
    let params = RefineParams::default();
    let mut written = Vec::new();
    let mut outcome = Ok(());
    for f in 0..frames {
        let looks: Vec<LookAt> = (0..4)
            .map(|i| {
                let (eye, dir) = eye_at(&all[i], f, speed, &ground);
                LookAt {
                    eye,
                    target: eye + dir,
                    up: Vec3::Y,
                    fov_y: FOV_Y_DEG.to_radians(),
                    near,
                    far,
                }
            })
            .collect();
        // The first frame refines without morphs (`CameraState::refine`): there is no
        // picture before it to morph from.
        for (i, cam) in cams.iter_mut().enumerate() {
            let view = looks[i].view(viewports[i].width, viewports[i].height);
            cam.compact_as_needed(h, COMPACT_STEP);
            if let Err(e) = cam.refine(h, &view, &params) {
                outcome = Err(format!("camera {i}, frame {f}: {e}"));
            }
        }
        if outcome.is_err() {
            break;
        }
        if !shots.contains(&f) {
            continue;
        }
        let path = out.join(format!("frame-{f:03}.png"));
        let shot = gpu
            .shot(ctx, h, &cams, &looks, &viewports)
            .map_err(|e| e.to_string())
            .and_then(|image| write_png(&image, &path).map_err(|e| e.to_string()));
        if let Err(e) = shot {
            outcome = Err(e);
            break;
        }
        written.push(path);
    }
    let cleanup = gpu.destroy(ctx);
    outcome?;
    cleanup.map_err(|e| e.to_string())?;
    Ok(written)
}

/// What the shots draw with: the terrain's vertices tinted by height and slope, a white
/// material per surface (lit vertex colours, no texture pattern), the renderer, and per
/// camera its index ring and morph slots (blended by the compute stage).
struct Drawing {
    vertices: VertexBuffer,
    renderer: Renderer,
    materials: MaterialSet,
    indices: Vec<CameraIndices>,
    morphs: Vec<CameraMorphs>,
}

impl Drawing {
    /// Uploads `h`'s vertices and makes the renderer (one frame in flight, read back) and
    /// each camera's ring and morph slots; what was made is destroyed on an error.
    fn new(ctx: &Context, h: &Hierarchy<'_>) -> caveclod_vulkan::Result<Self> {
        let tint = terrain_colours(h.vertices());
        let vertices = VertexBuffer::coloured(ctx, "terrain", h.vertices(), Some(&tint))?;
        let desc = RendererDesc {
            targets: vec![SIZE],
            frames_in_flight: 1,
            readback: true,
            clear_colour: [0.55, 0.7, 0.9, 1.0],
            geomorph: false,
            refine_morphs: true,
        };
        let renderer = match Renderer::new(ctx, desc) {
            Ok(r) => r,
            Err(e) => {
                let _ = vertices.destroy(ctx);
                return Err(e);
            }
        };
        let white = vec![SurfaceMaterial::plain([1.0; 4]); h.surface_count()];
        let materials = match MaterialSet::new(ctx, renderer.recorder(), &white) {
            Ok(m) => m,
            Err(e) => {
                let _ = renderer.destroy(ctx);
                let _ = vertices.destroy(ctx);
                return Err(e);
            }
        };
        let mut gpu = Self {
            vertices,
            renderer,
            materials,
            indices: Vec::with_capacity(4),
            morphs: Vec::with_capacity(4),
        };
        for i in 0..4 {
            let name = format!("camera {i}");
            gpu.indices
                .push(CameraIndices::new(&name, h.surface_count(), 1));
            let recorder = gpu.renderer.recorder();
            let stage = MorphStage::Compute;
            match CameraMorphs::new(ctx, recorder, &name, &gpu.vertices, stage, MAX_MORPHS, 1) {
                Ok(m) => gpu.morphs.push(m),
                Err(e) => {
                    let _ = gpu.destroy(ctx);
                    return Err(e);
                }
            }
        }
        Ok(gpu)
    }

    /// One frame of the cameras, each filling its ring and morph slots from its morphed
    /// front, drawn into its quadrant and read back.
    fn shot(
        &mut self,
        ctx: &Context,
        h: &Hierarchy<'_>,
        cams: &[CameraState<'_>],
        looks: &[LookAt],
        viewports: &[Viewport],
    ) -> caveclod_vulkan::Result<RgbaImage> {
        let slot = self.renderer.begin_frame(ctx)?;
        for ((ind, morphs), cam) in self.indices.iter_mut().zip(&mut self.morphs).zip(cams) {
            ind.fill(
                ctx,
                slot,
                IndexSource::MorphedCamera {
                    hierarchy: h,
                    camera: cam,
                },
            )?;
            morphs.fill(slot, h.vertices(), cam)?;
        }
        let draws: Vec<(usize, RecordCamera<'_>)> = self
            .indices
            .iter()
            .zip(&self.morphs)
            .enumerate()
            .map(|(i, (ind, morphs))| {
                let view_proj = looks[i].view_projection(viewports[i].aspect());
                let camera = RecordCamera::new(viewports[i], view_proj, &self.vertices, ind)
                    .materials(&self.materials)
                    .refine_morphs(morphs);
                (0, camera)
            })
            .collect();
        self.renderer.render(ctx, &draws)?;
        self.renderer.read_target(ctx, 0)
    }

    /// Destroys the morph slots and rings, the renderer (after its frames) and the
    /// vertices.
    fn destroy(self, ctx: &Context) -> caveclod_vulkan::Result<()> {
        let waited = self.renderer.wait(ctx);
        let morphs = self.morphs.into_iter().try_for_each(|m| m.destroy(ctx));
        let indices = self.indices.into_iter().try_for_each(|i| i.destroy(ctx));
        self.materials.destroy(ctx);
        let renderer = self.renderer.destroy(ctx);
        let vertices = self.vertices.destroy(ctx);
        waited.and(morphs).and(indices).and(renderer).and(vertices)
    }
}
