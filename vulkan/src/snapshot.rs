//! One-shot renders of a hierarchy from cameras orbiting it (the `caveclod render` CLI):
//! each camera refines its own front for its own viewport, then all of them are drawn in
//! one frame, into one split-screen target or one target each, and read back.
//!
//! A `.clod` file stores no materials, so surfaces get colours from a fixed palette
//! ([`palette`]): distinct hues, so surface boundaries show.

use caveclod_core::{CameraConfig, CameraState, Hierarchy, RefineParams};
use glam::Vec3;

use crate::device::Context;
use crate::error::{Error, Result};
use crate::frame::{CameraDraw, FrameStats, Renderer, RendererDesc, Viewport};
use crate::indices::{CameraIndices, IndexSource};
use crate::mesh::VertexBuffer;
use crate::readback::RgbaImage;
use crate::view::LookAt;

/// How the cameras share the output.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// One image, one viewport per camera ([`Viewport::split_screen`]).
    SplitScreen,
    /// One image per camera.
    Separate,
}

/// What to render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SnapshotDesc {
    /// Cameras, 1 to 4.
    pub cameras: usize,
    /// Screen-space tolerance of refinement, pixels.
    pub tolerance_px: f32,
    /// Width of the output image(s).
    pub width: u32,
    /// Height of the output image(s).
    pub height: u32,
    /// Split screen or one image per camera.
    pub layout: Layout,
}

/// What was rendered.
#[derive(Clone, Debug, PartialEq)]
pub struct Snapshot {
    /// One image (split screen) or one per camera.
    pub images: Vec<RgbaImage>,
    /// The frame's figures (index bytes per camera, draws).
    pub stats: FrameStats,
    /// Active polygons of each camera's front.
    pub active_polygons: Vec<u32>,
}

/// Colour of surface `s`: hues a golden angle apart, fully opaque.
pub fn palette(s: usize) -> [f32; 4] {
    let h = (s as f32 * 0.618_034 + 0.08).fract() * 6.0;
    let x = 1.0 - ((h % 2.0) - 1.0).abs();
    let (r, g, b) = match h as u32 {
        0 => (1.0, x, 0.0),
        1 => (x, 1.0, 0.0),
        2 => (0.0, 1.0, x),
        3 => (0.0, x, 1.0),
        4 => (x, 0.0, 1.0),
        _ => (1.0, 0.0, x),
    };
    // Pastel: mix with white so lighting stays readable.
    [0.35 + 0.65 * r, 0.35 + 0.65 * g, 0.35 + 0.65 * b, 1.0]
}

/// `n` cameras around the hierarchy's bounding box, 30° above it, evenly spaced in angle,
/// far enough for a 60° field of view to see the whole box.
pub fn orbit(h: &Hierarchy<'_>, n: usize) -> Vec<LookAt> {
    let m = h.meta();
    let (lo, hi) = (
        Vec3::from_array(m.bounds_min),
        Vec3::from_array(m.bounds_max),
    );
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    let fov_y = 60f32.to_radians();
    let distance = radius / (fov_y * 0.5).sin() * 1.05;
    (0..n)
        .map(|i| {
            let angle = 0.6 + std::f32::consts::TAU * i as f32 / n.max(1) as f32;
            let elevation = 30f32.to_radians();
            let dir = Vec3::new(
                angle.sin() * elevation.cos(),
                elevation.sin(),
                angle.cos() * elevation.cos(),
            );
            LookAt {
                eye: centre + dir * distance,
                target: centre,
                up: Vec3::Y,
                fov_y,
                near: distance * 1e-3,
                far: distance + 2.0 * radius,
            }
        })
        .collect()
}

/// Renders `h` from [`orbit`] cameras as described, destroying everything it made.
pub fn render_snapshot(ctx: &Context, h: &Hierarchy<'_>, desc: &SnapshotDesc) -> Result<Snapshot> {
    if !(1..=4).contains(&desc.cameras) {
        return Err(Error::InvalidArgument(format!(
            "{} cameras: 1 to 4 supported",
            desc.cameras
        )));
    }
    if !(desc.tolerance_px.is_finite() && desc.tolerance_px > 0.0) {
        return Err(Error::InvalidArgument(format!(
            "tolerance {} px: must be positive",
            desc.tolerance_px
        )));
    }
    // Per camera its target and viewport; per target its size.
    type Placement = (Vec<(usize, Viewport)>, Vec<(u32, u32)>);
    let (viewports, targets): Placement = match desc.layout {
        Layout::SplitScreen => (
            Viewport::split_screen(desc.width, desc.height, desc.cameras)?
                .into_iter()
                .map(|v| (0, v))
                .collect(),
            vec![(desc.width, desc.height)],
        ),
        Layout::Separate => (
            (0..desc.cameras)
                .map(|i| (i, Viewport::full(desc.width, desc.height)))
                .collect(),
            vec![(desc.width, desc.height); desc.cameras],
        ),
    };
    let looks = orbit(h, desc.cameras);
    let config = CameraConfig::full(h);
    let words = CameraState::words_needed_for(h, &config);
    let mut memories: Vec<Vec<u32>> = (0..desc.cameras).map(|_| vec![0u32; words]).collect();
    let mut cams = Vec::with_capacity(desc.cameras);
    let params = RefineParams {
        tolerance_px: desc.tolerance_px,
        ..RefineParams::default()
    };
    for (i, m) in memories.iter_mut().enumerate() {
        let mut cam = CameraState::with_config(h, m, &config)
            .map_err(|e| Error::InvalidArgument(format!("camera {i}: {e}")))?;
        cam.refine(h, &looks[i].view(viewports[i].1), &params)
            .map_err(|e| Error::InvalidArgument(format!("camera {i}: refinement: {e}")))?;
        cams.push(cam);
    }
    let colours: Vec<[f32; 4]> = (0..h.surface_count()).map(palette).collect();

    let vertices = VertexBuffer::from_hierarchy(ctx, "snapshot mesh", h)?;
    let renderer = Renderer::new(
        ctx,
        RendererDesc {
            targets,
            frames_in_flight: 1,
            readback: true,
            clear_colour: [0.02, 0.02, 0.03, 1.0],
            geomorph: false,
        },
    );
    let mut renderer = match renderer {
        Ok(r) => r,
        Err(e) => {
            vertices.destroy(ctx)?;
            return Err(e);
        }
    };
    let mut indices: Vec<CameraIndices> = (0..desc.cameras)
        .map(|i| CameraIndices::new(&format!("camera {i}"), h.surface_count(), 1))
        .collect();
    let result = (|| -> Result<Snapshot> {
        let mut draws: Vec<CameraDraw<'_, '_>> = indices
            .iter_mut()
            .enumerate()
            .map(|(i, ind)| CameraDraw {
                target: viewports[i].0,
                viewport: viewports[i].1,
                view_proj: looks[i].view_proj(viewports[i].1),
                vertices: &vertices,
                indices: ind,
                source: IndexSource::Camera {
                    hierarchy: h,
                    camera: &cams[i],
                },
                colours: &colours,
                morph: None,
            })
            .collect();
        let stats = renderer.render(ctx, &mut draws)?;
        let images = (0..renderer.desc().targets.len())
            .map(|t| renderer.read_target(ctx, t))
            .collect::<Result<Vec<_>>>()?;
        Ok(Snapshot {
            images,
            stats,
            active_polygons: cams.iter().map(CameraState::active_polygon_count).collect(),
        })
    })();
    let destroyed = renderer
        .destroy(ctx)
        .and_then(|()| indices.into_iter().try_for_each(|i| i.destroy(ctx)))
        .and_then(|()| vertices.destroy(ctx));
    let snapshot = result?;
    destroyed?;
    Ok(snapshot)
}
