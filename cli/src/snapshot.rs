//! One-shot renders of a hierarchy from cameras orbiting it (the `caveclod render` CLI):
//! each camera refines its own front for its own viewport, then all of them are drawn in
//! one frame, into one split-screen target or one target each, and read back. The same for
//! the multiresolution octree of an out-of-core bake (`caveclod render --octree`), each
//! camera drawing its own cut.
//!
//! Surfaces draw with the file's materials where asked and it has them, else with colours
//! from caveclod-host's fixed palette: distinct hues, so surface boundaries show.

use std::path::{Path, PathBuf};

use caveclod_core::LookAt;
use caveclod_core::{CameraConfig, CameraState, Hierarchy, Octree, OctreeCut, RefineParams};
use caveclod_host::{orbit, orbit_box, palette, GpuMaterials};
use caveclod_vulkan::{
    CameraIndices, Context, Error, FrameStats, IndexSource, RecordCamera, Renderer, RendererDesc,
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
        let slot = renderer.begin_frame(ctx)?;
        for (ind, source) in indices.iter_mut().zip(sources) {
            ind.fill(ctx, slot, source)?;
        }
        let draws: Vec<(usize, RecordCamera<'_>)> = indices
            .iter()
            .enumerate()
            .map(|(i, ind)| {
                let (target, viewport) = viewports[i];
                let view_proj = looks[i].view_projection(viewport.aspect());
                let camera = RecordCamera::new(viewport, view_proj, &vertices, ind);
                let camera = match &gpu {
                    Some(g) => camera.materials(&g.set),
                    None => camera.colours(&colours),
                };
                (target, camera)
            })
            .collect();
        let stats = renderer.render(ctx, &draws)?;
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
