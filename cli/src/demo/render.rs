//! The demo's pictures: the four fly-over cameras drawn into the quadrants of one 1280 x 720
//! image on the Vulkan device (lavapipe unless a GPU is preferred), at a few frames of the
//! flight. Each camera refines its own front every frame for its own quadrant's view, exactly
//! as in the measured flights, with geomorphs (blended by the compute stage); only the
//! sampled frames are drawn and read back.

use std::path::{Path, PathBuf};

use caveclod_core::glam::Vec3;
use caveclod_core::{CameraConfig, CameraState, Hierarchy, RefineParams};
use caveclod_host::{palette, write_png};
use caveclod_vulkan::{
    CameraDraw, CameraIndices, CameraMorphs, Context, HeadlessDesc, IndexSource, LookAt,
    MorphStage, Renderer, RendererDesc, VertexBuffer, Viewport,
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
    })
    .map_err(|e| e.to_string())?;
    let device = ctx.device_name().to_string();
    let result = draw(&ctx, h, frames, shots, out);
    let destroyed = ctx.destroy().map_err(|e| e.to_string());
    let files = result?;
    destroyed?;
    Ok((files, device))
}

fn draw(
    ctx: &Context,
    h: &Hierarchy<'_>,
    frames: usize,
    shots: &[usize],
    out: &Path,
) -> Result<Vec<PathBuf>, String> {
    let err = |e: caveclod_vulkan::Error| e.to_string();
    let ground = Ground::new(h);
    let speed = ground.size / 600.0;
    let (near, far) = clip(&ground);
    let all = routes();
    let viewports = Viewport::split_screen(SIZE.0, SIZE.1, 4).map_err(err)?;
    let config = CameraConfig::full(h).with_morphs(MAX_MORPHS);
    let words = CameraState::words_needed_for(h, &config);
    let mut memories: Vec<Vec<u32>> = (0..4).map(|_| vec![0u32; words]).collect();
    let mut cams = Vec::with_capacity(4);
    for m in memories.iter_mut() {
        cams.push(CameraState::with_config(h, m, &config).map_err(|e| e.to_string())?);
    }
    let colours: Vec<[f32; 4]> = (0..h.surface_count()).map(palette).collect();
    let vertices = VertexBuffer::from_hierarchy(ctx, "terrain", h).map_err(err)?;
    let mut renderer = match Renderer::new(
        ctx,
        RendererDesc {
            targets: vec![SIZE],
            frames_in_flight: 1,
            readback: true,
            clear_colour: [0.55, 0.7, 0.9, 1.0],
            geomorph: false,
            refine_morphs: true,
        },
    ) {
        Ok(r) => r,
        Err(e) => {
            vertices.destroy(ctx).map_err(err)?;
            return Err(e.to_string());
        }
    };
    let mut indices: Vec<CameraIndices> = (0..4)
        .map(|i| CameraIndices::new(&format!("camera {i}"), h.surface_count(), 1))
        .collect();
    let mut morphs = Vec::with_capacity(4);
    for i in 0..4 {
        let name = format!("camera {i}");
        let stage = MorphStage::Compute;
        match CameraMorphs::new(
            ctx,
            renderer.recorder(),
            &name,
            &vertices,
            stage,
            MAX_MORPHS,
            1,
        ) {
            Ok(m) => morphs.push(m),
            Err(e) => {
                let _ = renderer.destroy(ctx);
                let _ = vertices.destroy(ctx);
                morphs
                    .into_iter()
                    .for_each(|m: CameraMorphs| drop(m.destroy(ctx)));
                return Err(e.to_string());
            }
        }
    }
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
        let params = &params;
        for (i, cam) in cams.iter_mut().enumerate() {
            if let Err(e) = cam.refine(
                h,
                &looks[i].view(viewports[i].width, viewports[i].height),
                params,
            ) {
                outcome = Err(format!("camera {i}, frame {f}: {e}"));
            }
        }
        if outcome.is_err() || !shots.contains(&f) {
            if outcome.is_err() {
                break;
            }
            continue;
        }
        let mut draws: Vec<CameraDraw<'_, '_>> = indices
            .iter_mut()
            .zip(morphs.iter_mut())
            .enumerate()
            .map(|(i, (ind, morphs))| CameraDraw {
                target: 0,
                viewport: viewports[i],
                view_proj: looks[i].view_projection(viewports[i].aspect()),
                vertices: &vertices,
                indices: ind,
                source: IndexSource::MorphedCamera {
                    hierarchy: h,
                    camera: &cams[i],
                },
                colours: &colours,
                materials: None,
                refine_morphs: Some(morphs),
                morph: None,
            })
            .collect();
        let image = renderer
            .render(ctx, &mut draws)
            .and_then(|_| renderer.read_target(ctx, 0));
        match image {
            Ok(image) => {
                let path = out.join(format!("frame-{f:03}.png"));
                if let Err(e) = write_png(&image, &path) {
                    outcome = Err(e.to_string());
                    break;
                }
                written.push(path);
            }
            Err(e) => {
                outcome = Err(e.to_string());
                break;
            }
        }
    }
    let cleanup = renderer
        .destroy(ctx)
        .and_then(|()| morphs.into_iter().try_for_each(|m| m.destroy(ctx)))
        .and_then(|()| vertices.destroy(ctx))
        .and_then(|()| indices.into_iter().try_for_each(|i| i.destroy(ctx)));
    outcome?;
    cleanup.map_err(err)?;
    Ok(written)
}
