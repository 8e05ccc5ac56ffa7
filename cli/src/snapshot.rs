//! One-shot renders of a hierarchy from cameras orbiting it (the `caveclod render` CLI):
//! each camera refines its own front for its own viewport, then all of them are drawn in
//! one frame, into one split-screen target or one target each, and read back. The same for
//! the multiresolution octree of an out-of-core bake (`caveclod render --octree`), each
//! camera drawing its own cut.
//!
//! A `.clod` file stores no materials, so surfaces get colours from a fixed palette
//! ([`palette`]): distinct hues, so surface boundaries show. [`write_png`] writes a
//! read-back image.

use std::path::{Path, PathBuf};

use caveclod_core::{CameraConfig, CameraState, Hierarchy, Octree, OctreeCut, RefineParams};
use glam::Vec3;

use crate::materials::GpuMaterials;
use caveclod_core::LookAt;
use caveclod_vulkan::{
    CameraDraw, CameraIndices, Context, Error, FrameStats, IndexSource, Renderer, RendererDesc,
    Result, RgbaImage, VertexBuffer, Viewport,
};

/// How the cameras share the output.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// One image, one viewport per camera ([`Viewport::split_screen`]).
    SplitScreen,
    /// One image per camera.
    Separate,
}

/// What to render.
#[derive(Clone, Debug, PartialEq)]
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
    /// Draw the hierarchy's materials, their texture paths relative to this directory
    /// (the `.clod` file's); `None`, or a file without materials, draws the palette.
    pub materials_dir: Option<PathBuf>,
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
    orbit_box(m.bounds_min, m.bounds_max, n)
}

/// [`orbit`] around a box.
pub fn orbit_box(min: [f32; 3], max: [f32; 3], n: usize) -> Vec<LookAt> {
    let (lo, hi) = (Vec3::from_array(min), Vec3::from_array(max));
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

/// Per camera its target and viewport; per target its size.
type Placement = (Vec<(usize, Viewport)>, Vec<(u32, u32)>);

/// Checks `desc` and places its cameras.
fn placement(desc: &SnapshotDesc) -> Result<Placement> {
    if !(1..=4).contains(&desc.cameras) {
        return Err(Error::InvalidArgument(format!(
            "{} cameras: 1 to 4 supported",
            desc.cameras
        )));
    }
    Ok(match desc.layout {
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
    })
}

/// Renders `h` from [`orbit`] cameras as described, destroying everything it made.
pub fn render_snapshot(ctx: &Context, h: &Hierarchy<'_>, desc: &SnapshotDesc) -> Result<Snapshot> {
    let (viewports, targets) = placement(desc)?;
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
        cam.refine(
            h,
            &looks[i].view(viewports[i].1.width, viewports[i].1.height),
            &params,
        )
        .map_err(|e| Error::InvalidArgument(format!("camera {i}: refinement: {e}")))?;
        cams.push(cam);
    }
    let vertices = VertexBuffer::from_hierarchy(ctx, "snapshot mesh", h)?;
    let sources = cams
        .iter()
        .map(|camera| IndexSource::Camera {
            hierarchy: h,
            camera,
        })
        .collect();
    let active = cams.iter().map(CameraState::active_polygon_count).collect();
    draw(
        ctx,
        vertices,
        h.surface_count(),
        (viewports, targets),
        &looks,
        sources,
        active,
        desc.materials_dir.as_deref().map(|dir| (h, dir)),
    )
}

/// Renders the multiresolution octree of an out-of-core bake from [`orbit_box`] cameras
/// around its root: each camera selects its own cut ([`OctreeCut`]) at the tolerance and
/// draws the cut's per-surface index lists from the octree's vertex buffer. `active_polygons`
/// are the cuts' triangles.
pub fn render_octree_snapshot(
    ctx: &Context,
    octree: &Octree<'_>,
    desc: &SnapshotDesc,
) -> Result<Snapshot> {
    let (viewports, targets) = placement(desc)?;
    let root = octree.nodes().first().copied().unwrap_or_default();
    let looks = orbit_box(root.min, root.max, desc.cameras);
    let surfaces = octree.surface_count();
    let mut lists: Vec<Vec<Vec<u32>>> = Vec::with_capacity(desc.cameras);
    let mut active = Vec::with_capacity(desc.cameras);
    let mut memory = vec![0u32; OctreeCut::words_needed(octree)];
    for (i, look) in looks.iter().enumerate() {
        let mut cut = OctreeCut::new(octree, &mut memory)
            .map_err(|e| Error::InvalidArgument(format!("camera {i}: {e}")))?;
        let stats = cut
            .select(
                octree,
                &look.view(viewports[i].1.width, viewports[i].1.height),
                desc.tolerance_px,
            )
            .map_err(|e| Error::InvalidArgument(format!("camera {i}: selection: {e}")))?;
        let mut camera_lists: Vec<Vec<u32>> = (0..surfaces)
            .map(|s| vec![0u32; cut.index_count(s)])
            .collect();
        let mut written = vec![0u32; surfaces];
        let mut outs: Vec<&mut [u32]> = camera_lists.iter_mut().map(Vec::as_mut_slice).collect();
        cut.emit_indices(octree, &mut outs, &mut written)
            .map_err(|e| Error::InvalidArgument(format!("camera {i}: emission: {e}")))?;
        lists.push(camera_lists);
        active.push(stats.triangles);
    }
    let vertices = VertexBuffer::from_vertices(ctx, "octree", octree.vertices())?;
    let refs: Vec<Vec<&[u32]>> = lists
        .iter()
        .map(|l| l.iter().map(Vec::as_slice).collect())
        .collect();
    let sources = refs.iter().map(|r| IndexSource::Lists(r)).collect();
    draw(
        ctx,
        vertices,
        surfaces,
        (viewports, targets),
        &looks,
        sources,
        active,
        None,
    )
}

/// Draws one source per camera in one frame and reads the targets back; destroys the
/// renderer, the index buffers and `vertices`, also on error.
#[allow(clippy::too_many_arguments)]
fn draw(
    ctx: &Context,
    vertices: VertexBuffer,
    surfaces: usize,
    (viewports, targets): Placement,
    looks: &[LookAt],
    sources: Vec<IndexSource<'_, '_>>,
    active_polygons: Vec<u32>,
    materials: Option<(&Hierarchy<'_>, &Path)>,
) -> Result<Snapshot> {
    let colours: Vec<[f32; 4]> = (0..surfaces).map(palette).collect();
    let renderer = Renderer::new(
        ctx,
        RendererDesc {
            targets,
            frames_in_flight: 1,
            readback: true,
            clear_colour: [0.02, 0.02, 0.03, 1.0],
            geomorph: false,
            refine_morphs: false,
        },
    );
    let mut renderer = match renderer {
        Ok(r) => r,
        Err(e) => {
            vertices.destroy(ctx)?;
            return Err(e);
        }
    };
    let gpu = match materials.map(|(h, dir)| GpuMaterials::load(ctx, renderer.recorder(), h, dir)) {
        Some(Err(e)) => {
            let _ = renderer.destroy(ctx);
            vertices.destroy(ctx)?;
            return Err(e);
        }
        Some(Ok(g)) => g,
        None => None,
    };
    let mut indices: Vec<CameraIndices> = (0..sources.len())
        .map(|i| CameraIndices::new(&format!("camera {i}"), surfaces, 1))
        .collect();
    let result = (|| -> Result<Snapshot> {
        let mut draws: Vec<CameraDraw<'_, '_>> = indices
            .iter_mut()
            .zip(sources)
            .enumerate()
            .map(|(i, (ind, source))| CameraDraw {
                target: viewports[i].0,
                viewport: viewports[i].1,
                view_proj: looks[i].view_projection(viewports[i].1.aspect()),
                vertices: &vertices,
                indices: ind,
                source,
                colours: &colours,
                materials: gpu.as_ref().map(|g| &g.set),
                refine_morphs: None,
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
            active_polygons,
        })
    })();
    let destroyed = renderer
        .destroy(ctx)
        .and_then(|()| gpu.map_or(Ok(()), |g| g.destroy(ctx)))
        .and_then(|()| indices.into_iter().try_for_each(|i| i.destroy(ctx)))
        .and_then(|()| vertices.destroy(ctx));
    let snapshot = result?;
    destroyed?;
    Ok(snapshot)
}

/// Why [`write_png`] failed: the file, and the encoder's error (which carries I/O errors).
#[derive(Debug)]
pub struct PngWriteError {
    /// The file being written.
    pub path: PathBuf,
    /// Why.
    pub source: png::EncodingError,
}

impl std::fmt::Display for PngWriteError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.path.display(), self.source)
    }
}

impl std::error::Error for PngWriteError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.source)
    }
}

/// Writes `image` as an RGBA PNG at `path`, through a temporary file renamed into place, so
/// a reader never sees a partial image.
pub fn write_png(image: &RgbaImage, path: &Path) -> std::result::Result<(), PngWriteError> {
    let mut tmp_name = path.file_name().unwrap_or_default().to_os_string();
    tmp_name.push(".tmp");
    let tmp = path.with_file_name(tmp_name);
    let result = encode_png(image, &tmp).and_then(|()| Ok(std::fs::rename(&tmp, path)?));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(|source| PngWriteError {
        path: path.to_path_buf(),
        source,
    })
}

/// Encodes `image` into a new file at `path` and syncs it.
fn encode_png(image: &RgbaImage, path: &Path) -> std::result::Result<(), png::EncodingError> {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    {
        let mut enc = png::Encoder::new(&mut w, image.width, image.height);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header()?;
        writer.write_image_data(&image.pixels)?;
        writer.finish()?;
    }
    let file = w.into_inner().map_err(|e| e.into_error())?;
    file.sync_all()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trip_through_a_temp_file() {
        let mut pixels = Vec::new();
        for y in 0..2u8 {
            for x in 0..3u8 {
                pixels.extend_from_slice(&[x * 80, y * 100, 7, 255]);
            }
        }
        let a = RgbaImage {
            width: 3,
            height: 2,
            pixels,
        };
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        let path = dir.path().join("a.png");
        write_png(&a, &path).unwrap_or_else(|e| panic!("{e}"));
        let decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(&path).unwrap_or_else(|e| panic!("{e}")),
        ));
        let mut reader = decoder.read_info().unwrap_or_else(|e| panic!("{e}"));
        let mut buf = vec![0; reader.output_buffer_size().unwrap_or(0)];
        let info = reader
            .next_frame(&mut buf)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((info.width, info.height), (3, 2));
        assert_eq!(&buf[..info.buffer_size()], &a.pixels[..]);
        assert!(!dir.path().join("a.png.tmp").exists());
    }

    #[test]
    fn a_png_into_a_missing_directory_names_the_file() {
        let a = RgbaImage {
            width: 1,
            height: 1,
            pixels: vec![0, 0, 0, 255],
        };
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        let path = dir.path().join("missing").join("a.png");
        let e = write_png(&a, &path).err();
        assert!(e.as_ref().is_some_and(|e| e.path == path), "{e:?}");
        assert!(e.is_some_and(|e| e.to_string().contains("a.png")));
    }
}
