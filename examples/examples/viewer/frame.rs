//! One frame, as named steps: wait for the slot, acquire an image, refine every camera,
//! emit its indices into the slot's ring, run egui, record (host barriers and rendering,
//! caveclod's cameras, egui on top), submit, present; for a screenshot also copy the image
//! out and read it back.

use std::time::Instant;

use caveclod_core::glam::Mat4;
use caveclod_core::stream::StreamedHierarchy;
use caveclod_core::CameraState;
use caveclod_host::{rendering, Acquired, ReadbackBuffer};
use caveclod_vulkan::ash::vk;
use caveclod_vulkan::{
    CameraMorphs, Context, IndexSource, MorphStage, RecordCamera, RgbaImage, Viewport,
};

use crate::scene::{ColourMode, Frozen, Scene};
use crate::ui::{self, PanelInfo};
use crate::viewer::{Rings, Vertices, Viewer};

/// Holes a streamed camera's index edits close a frame.
const EDIT_MOVES: u32 = 256;

/// The background, as stored in the image (sRGB bytes), so screenshots can tell it apart.
pub const BACKGROUND_SRGB: [u8; 3] = [28, 30, 36];

/// What a frame did.
pub enum Outcome {
    /// Nothing drawn: no area to draw in, or the swapchain had to be recreated.
    Skipped,
    /// Drawn and presented; with the read-back image when asked.
    Drawn(Option<Capture>),
}

/// A frame read back: its pixels (RGBA8, as stored), the cameras' viewports and the
/// rectangle egui's panel covered (pixels).
pub struct Capture {
    pub image: RgbaImage,
    pub viewports: Vec<Viewport>,
    pub panel: Option<egui::Rect>,
}

/// egui's output of a frame, ready to record.
struct EguiFrame {
    primitives: Vec<egui::ClippedPrimitive>,
    pixels_per_point: f32,
    /// The panel's rectangle in pixels.
    panel: Option<egui::Rect>,
}

impl Viewer {
    /// Draws one frame of `scene` (see the module docs); `capture` reads it back.
    pub fn frame(
        &mut self,
        scene: &mut Scene<'_>,
        info: &PanelInfo<'_>,
        capture: bool,
    ) -> Result<Outcome, String> {
        if self.stale || self.res.swapchain.is_none() {
            self.recreate_swapchain()?;
        }
        let Some(extent) = self.res.swapchain.as_ref().map(|s| s.extent()) else {
            return Ok(Outcome::Skipped);
        };
        let viewports = Viewport::split_screen(extent.width, extent.height, scene.cameras.len())
            .map_err(|e| e.to_string())?;
        if viewports.iter().any(|v| v.width == 0 || v.height == 0) {
            return Ok(Outcome::Skipped);
        }
        let slot = self.res.frames.slot_of(self.frame);
        self.res
            .frames
            .wait(&self.host, slot)
            .map_err(|e| e.to_string())?;
        self.free_pending_textures()?;
        let Some(image) = self.acquire(slot)? else {
            return Ok(Outcome::Skipped);
        };
        let stage = scene.settings.morphs.stage();
        let (ctx, rings) = (&self.ctx, &mut self.res.rings);
        scene.refine(&viewports, &mut |i, h, camera| {
            fill_streamed(ctx, &mut rings[i], slot, stage, h, camera)
                .map_err(|e| format!("camera {}: {e}", i + 1))
        })?;
        match (&mut self.res.vertices, scene.h.streamed()) {
            (Vertices::Pool(pool), Some(s)) => pool
                .fill(slot, &s.installed_vertices())
                .map(drop)
                .map_err(|e| format!("vertex pool: {e}"))?,
            _ => self.emit(scene, slot)?,
        }
        let views: Vec<(Viewport, Mat4)> = viewports
            .iter()
            .zip(&scene.cameras)
            .map(|(vp, c)| (*vp, c.control.look().view_projection(vp.aspect())))
            .collect();
        let egui_frame = self.run_egui(scene, info, &views)?;
        let readback = if capture {
            let size = 4 * u64::from(extent.width) * u64::from(extent.height);
            let buffer = ReadbackBuffer::new(&self.host, "screenshot", size);
            Some(buffer.map_err(|e| e.to_string())?)
        } else {
            None
        };
        let drawn = self
            .record_and_submit(scene, slot, image, &views, &egui_frame, readback.as_ref())
            .and_then(|()| self.present(image));
        self.frame += 1;
        let Some(buffer) = readback else {
            return drawn.map(|()| Outcome::Drawn(None));
        };
        let read = drawn.and_then(|()| {
            self.res
                .frames
                .wait(&self.host, slot)
                .and_then(|()| buffer.image(extent, self.desc.format.format))
                .map_err(|e| e.to_string())
        });
        buffer.destroy(&self.host).map_err(|e| e.to_string())?;
        Ok(Outcome::Drawn(Some(Capture {
            image: read?,
            viewports,
            panel: egui_frame.panel,
        })))
    }

    /// Acquires the next image with `slot`'s semaphore; `None` (and the swapchain marked
    /// stale) when it is out of date.
    fn acquire(&mut self, slot: usize) -> Result<Option<u32>, String> {
        let Some(chain) = &self.res.swapchain else {
            return Ok(None);
        };
        let available = self.res.frames.image_available(slot);
        match chain
            .acquire(available.map_err(|e| e.to_string())?)
            .map_err(|e| e.to_string())?
        {
            Acquired::OutOfDate => {
                self.stale = true;
                self.swapchain_reports += 1;
                Ok(None)
            }
            Acquired::Image { index, suboptimal } => {
                self.stale |= suboptimal;
                self.swapchain_reports += u64::from(suboptimal);
                Ok(Some(index))
            }
        }
    }

    /// Emits each camera's front into its ring's `slot`: per surface, or regrouped by depth.
    fn emit(&mut self, scene: &mut Scene<'_>, slot: usize) -> Result<(), String> {
        let Some(h) = scene.h.whole() else {
            return Ok(());
        };
        for (i, c) in scene.cameras.iter_mut().enumerate() {
            let rings = &mut self.res.rings[i];
            let start = Instant::now();
            match (scene.settings.colour, scene.settings.morphs.stage()) {
                (ColourMode::Materials | ColourMode::Surface, Some(stage)) => {
                    let source = IndexSource::MorphedCamera {
                        hierarchy: h,
                        camera: &c.state,
                    };
                    rings
                        .morphs_mut(stage)
                        .fill(slot, h.vertices(), &c.state)
                        .and_then(|_| rings.surfaces.fill(&self.ctx, slot, source))
                }
                (ColourMode::Materials | ColourMode::Surface, None) => {
                    let source = IndexSource::Camera {
                        hierarchy: h,
                        camera: &c.state,
                    };
                    rings.surfaces.fill(&self.ctx, slot, source)
                }
                (ColourMode::Depth, _) => {
                    self.bands.regroup(h, &c.state)?;
                    let lists = self.bands.lists();
                    rings
                        .bands
                        .fill(&self.ctx, slot, IndexSource::Lists(&lists))
                }
            }
            .map_err(|e| format!("camera {}: {e}", i + 1))?;
            c.stats.emit_ms = start.elapsed().as_secs_f64() * 1e3;
            c.stats.polygons = c.state.active_polygon_count();
        }
        Ok(())
    }

    /// Runs the panel and the frusta; uploads egui's new textures.
    fn run_egui(
        &mut self,
        scene: &Scene<'_>,
        info: &PanelInfo<'_>,
        views: &[(Viewport, Mat4)],
    ) -> Result<EguiFrame, String> {
        let input = self.egui_state.take_egui_input(&self.window);
        let frozen: Vec<Frozen> = scene.cameras.iter().filter_map(|c| c.frozen).collect();
        let mut panel = None;
        let out = self.egui_ctx.run_ui(input, |ui| {
            panel = ui::panel(ui.ctx(), scene, info);
            ui::frusta(ui.ctx(), &frozen, views, ui.ctx().pixels_per_point());
        });
        self.egui_state
            .handle_platform_output(&self.window, out.platform_output);
        self.upload_textures(out.textures_delta)?;
        let ppp = out.pixels_per_point;
        Ok(EguiFrame {
            primitives: self.egui_ctx.tessellate(out.shapes, ppp),
            pixels_per_point: ppp,
            panel: panel.map(|r: egui::Rect| {
                egui::Rect::from_min_max(
                    (r.min.to_vec2() * ppp).to_pos2(),
                    (r.max.to_vec2() * ppp).to_pos2(),
                )
            }),
        })
    }

    /// Applies egui's texture changes (after the GPU is done with every frame that may
    /// sample them); frees come later, see [`Viewer::free_pending_textures`].
    fn upload_textures(&mut self, mut delta: egui::TexturesDelta) -> Result<(), String> {
        // Taken out whole, so `delta` drops empty as egui asks, whatever happens below.
        let set = std::mem::take(&mut delta.set);
        self.pending_free.extend(std::mem::take(&mut delta.free));
        if !set.is_empty() {
            self.host.wait_idle().map_err(|e| e.to_string())?;
        }
        for (id, changes) in set {
            for change in changes {
                self.res
                    .egui
                    .set_texture(self.host.queue(), self.res.upload_pool, id, &change)
                    .map_err(|e| format!("egui texture: {e}"))?;
            }
        }
        Ok(())
    }

    /// Frees the textures egui let go of, once no frame in flight can use them.
    fn free_pending_textures(&mut self) -> Result<(), String> {
        if self.pending_free.is_empty() {
            return Ok(());
        }
        self.host.wait_idle().map_err(|e| e.to_string())?;
        for id in std::mem::take(&mut self.pending_free) {
            self.res
                .egui
                .free_texture(id)
                .map_err(|e| format!("egui texture: {e}"))?;
        }
        Ok(())
    }

    /// Records the frame into `slot`'s command buffer and submits it.
    fn record_and_submit(
        &mut self,
        scene: &Scene<'_>,
        slot: usize,
        image: u32,
        views: &[(Viewport, Mat4)],
        egui_frame: &EguiFrame,
        readback: Option<&ReadbackBuffer>,
    ) -> Result<(), String> {
        let chain = self
            .res
            .swapchain
            .as_ref()
            .ok_or("no swapchain to record into")?;
        let target = chain.attachments(image).map_err(|e| e.to_string())?;
        let render_finished = chain.render_finished(image).map_err(|e| e.to_string())?;
        let by_depth = scene.settings.colour == ColourMode::Depth;
        let wireframe = scene.settings.wireframe && self.res.recorder.desc().wireframe;
        // Depth bands regroup the plain front; the other colourings draw the morphs.
        let stage = scene.settings.morphs.stage().filter(|_| !by_depth);
        let morphs: Vec<&CameraMorphs> = match stage {
            Some(stage) => self.res.rings.iter().map(|r| r.morphs(stage)).collect(),
            None => Vec::new(),
        };
        let cameras: Vec<RecordCamera<'_>> = views
            .iter()
            .zip(&self.res.rings)
            .map(|(&(viewport, view_proj), rings)| RecordCamera {
                viewport,
                view_proj,
                vertices: self.res.vertices.buffer(),
                indices: if by_depth {
                    &rings.bands
                } else {
                    &rings.surfaces
                },
                colours: if by_depth {
                    &self.band_colours
                } else {
                    &self.surface_colours
                },
                materials: match scene.settings.colour {
                    ColourMode::Materials => self.res.materials.as_ref().map(|m| &m.set),
                    ColourMode::Surface | ColourMode::Depth => None,
                },
                refine_morphs: stage.map(|s| rings.morphs(s)),
                morph: None,
                wireframe,
            })
            .collect();
        let (host, frames) = (&self.host, &mut self.res.frames);
        let d = host.device();
        let cmd = frames.begin(host, slot).map_err(|e| e.to_string())?;
        // A paged file's page installs and edited index buffers: copies, before the draws.
        if let Vertices::Pool(pool) = &self.res.vertices {
            pool.record(&self.ctx, cmd, slot);
        }
        for r in &self.res.rings {
            r.surfaces.record_edits(&self.ctx, cmd, slot);
        }
        self.res
            .recorder
            .record_morph_blends(&self.ctx, cmd, slot, &morphs)
            .map_err(|e| format!("caveclod: {e}"))?;
        rendering::begin_dynamic(d, cmd, &target, clear_colour(self.desc.srgb()));
        self.res
            .recorder
            .record(&self.ctx, cmd, slot, &cameras)
            .map_err(|e| format!("caveclod: {e}"))?;
        self.res
            .egui
            .cmd_draw(
                cmd,
                target.extent,
                egui_frame.pixels_per_point,
                &egui_frame.primitives,
            )
            .map_err(|e| format!("egui: {e}"))?;
        rendering::end_dynamic(d, cmd);
        let colour = target.colour.0;
        let mut layout = vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL;
        if let Some(b) = readback {
            rendering::copy_out(d, cmd, colour, layout, target.extent, b.raw);
            layout = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
        }
        rendering::to_present(d, cmd, colour, layout);
        let available = frames.image_available(slot).map_err(|e| e.to_string())?;
        // The acquire's semaphore is waited for where the colour is first written; the
        // barrier `begin_dynamic` records chains to that stage.
        let wait = [(available, vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT)];
        frames
            .submit(host, slot, &wait, &[render_finished])
            .map_err(|e| e.to_string())
    }

    /// Presents `image`; marks the swapchain stale if presentation says so.
    fn present(&mut self, image: u32) -> Result<(), String> {
        let chain = self
            .res
            .swapchain
            .as_ref()
            .ok_or("no swapchain to present")?;
        let recreate = chain
            .present(&self.host, image)
            .map_err(|e| e.to_string())?;
        self.stale |= recreate;
        self.swapchain_reports += u64::from(recreate);
        Ok(())
    }
}

/// Fills a streamed camera's ring for `slot` while the frame's records `h` are at hand: its
/// index edits, and its morph slots in the vertex pool for the stage that blends them.
fn fill_streamed(
    ctx: &Context,
    rings: &mut Rings,
    slot: usize,
    stage: Option<MorphStage>,
    h: &StreamedHierarchy<'_, '_, '_, '_>,
    camera: &mut CameraState<'_>,
) -> Result<(), String> {
    rings
        .surfaces
        .fill_edits(ctx, slot, h, camera, EDIT_MOVES)
        .map_err(|e| e.to_string())?;
    if let Some(stage) = stage {
        rings
            .morphs_mut(stage)
            .fill_device(slot, h, camera)
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// The clear colour that is stored as [`BACKGROUND_SRGB`]: converted to linear for an
/// sRGB format, as it is for a UNORM one.
fn clear_colour(srgb: bool) -> [f32; 4] {
    let linear = |c: u8| {
        let c = f32::from(c) / 255.0;
        if !srgb {
            c
        } else if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let [r, g, b] = BACKGROUND_SRGB;
    [linear(r), linear(g), linear(b), 1.0]
}
