//! Pictures of a crowd run on the Vulkan device: each g-mesh level is one instanced draw
//! through the geomorph vertex stage, every visible instance morphing by its own factor.

use std::path::{Path, PathBuf};

use caveclod_core::glam::Vec3;
use caveclod_core::gmesh::{t_from_distance, GMesh};
use caveclod_core::gpu::MorphInstance;
use caveclod_core::{Hierarchy, LookAt, View};
use caveclod_vulkan::{
    CameraIndices, Context, HeadlessDesc, IndexSource, Morph, MorphInstances, RecordCamera,
    Renderer, RendererDesc, VertexBuffer, Viewport,
};

use crate::flight::{CameraPath, Run, D_FAR, D_NEAR};

/// The pictures' size in pixels.
const WIDTH: u32 = 1280;
/// The pictures' height in pixels.
const HEIGHT: u32 = 720;

/// A g-mesh level on the device: both attribute streams and the per-surface lists.
struct LevelBuffers {
    a: VertexBuffer,
    b: VertexBuffer,
    lists: Vec<Vec<u32>>,
}

/// What every frame of a run draws from.
struct Scene<'a, 'g> {
    gm: &'a GMesh<'g>,
    levels: &'a [LevelBuffers],
    colours: &'a [[f32; 4]],
    path: CameraPath,
    places: &'a [Vec3],
    run: &'a Run,
    total_frames: usize,
    /// The mesh's centre: instances are placed at radius 1 around their point.
    centre: Vec3,
    /// Scales the mesh to radius 1.
    scale: f32,
}

/// Draws `frames` of a run to PNG on a headless device (lavapipe by default); returns the
/// files written.
#[allow(clippy::too_many_arguments)]
pub fn render_run(
    h: &Hierarchy<'_>,
    gm: &GMesh<'_>,
    path: CameraPath,
    places: &[Vec3],
    run: &Run,
    total_frames: usize,
    frames: &[usize],
    out: &Path,
) -> Result<Vec<PathBuf>, String> {
    let ctx = Context::headless(&HeadlessDesc {
        validation: false,
        prefer_lavapipe: true,
        synchronization_validation: false,
    })
    .map_err(|e| e.to_string())?;
    let result = render_with(&ctx, h, gm, path, places, run, total_frames, frames, out);
    let destroyed = ctx.destroy().map_err(|e| e.to_string());
    let files = result?;
    destroyed?;
    Ok(files)
}

/// Uploads the levels, draws each frame in turn (stopping at the first failure), then frees
/// the device's resources.
#[allow(clippy::too_many_arguments)]
fn render_with(
    ctx: &Context,
    h: &Hierarchy<'_>,
    gm: &GMesh<'_>,
    path: CameraPath,
    places: &[Vec3],
    run: &Run,
    total_frames: usize,
    frames: &[usize],
    out: &Path,
) -> Result<Vec<PathBuf>, String> {
    let e = |e: caveclod_vulkan::Error| e.to_string();
    let m = h.meta();
    let (lo, hi) = (
        Vec3::from_array(m.bounds_min),
        Vec3::from_array(m.bounds_max),
    );
    let levels = upload_levels(ctx, h, gm)?;
    let mut renderer = Renderer::new(
        ctx,
        RendererDesc {
            targets: vec![(WIDTH, HEIGHT)],
            frames_in_flight: 1,
            readback: true,
            clear_colour: [0.55, 0.7, 0.9, 1.0],
            geomorph: true,
            refine_morphs: false,
        },
    )
    .map_err(e)?;
    let colours: Vec<[f32; 4]> = (0..gm.surfaces()).map(caveclod_host::palette).collect();
    let scene = Scene {
        gm,
        levels: &levels,
        colours: &colours,
        path,
        places,
        run,
        total_frames,
        centre: (lo + hi) * 0.5,
        scale: 1.0 / ((hi - lo).length() * 0.5).max(1e-6),
    };
    let mut written = Vec::new();
    let mut outcome = Ok(());
    for &f in frames {
        let file = out.join(format!("crowd-{}-{f:03}.png", path.name()));
        match draw_frame(ctx, &mut renderer, &scene, f, &file) {
            Ok(()) => written.push(file),
            Err(err) => {
                outcome = Err(err);
                break;
            }
        }
    }
    let mut cleanup = renderer.destroy(ctx);
    for l in levels {
        cleanup = cleanup
            .and_then(|()| l.a.destroy(ctx))
            .and_then(|()| l.b.destroy(ctx));
    }
    outcome?;
    cleanup.map_err(e)?;
    Ok(written)
}

/// Each g-mesh level's two vertex streams (`a_i` coarse, `a'_i` fine) and surface lists.
fn upload_levels(
    ctx: &Context,
    h: &Hierarchy<'_>,
    gm: &GMesh<'_>,
) -> Result<Vec<LevelBuffers>, String> {
    let e = |e: caveclod_vulkan::Error| e.to_string();
    let mut levels = Vec::new();
    for i in 0..gm.levels() {
        let level = gm.level(i).ok_or("missing level")?;
        let gather = |side: usize| -> Vec<caveclod_core::format::Vertex> {
            level
                .vertices
                .iter()
                .map(|p| h.vertices()[p[side] as usize])
                .collect()
        };
        levels.push(LevelBuffers {
            a: VertexBuffer::from_vertices(ctx, "a_i", &gather(0)).map_err(e)?,
            b: VertexBuffer::from_vertices(ctx, "a'_i", &gather(1)).map_err(e)?,
            lists: (0..gm.surfaces())
                .map(|s| level.surface_indices(s).to_vec())
                .collect(),
        });
    }
    Ok(levels)
}

/// Draws frame `f` of the run and writes it to `file`. The frame's instance buffers and index
/// lists are freed whatever happens; the last failure is the one returned.
fn draw_frame(
    ctx: &Context,
    renderer: &mut Renderer,
    scene: &Scene<'_, '_>,
    f: usize,
    file: &Path,
) -> Result<(), String> {
    let look = scene.path.look_at(f as f32 / scene.total_frames as f32);
    let viewport = Viewport::full(WIDTH, HEIGHT);
    let view = look.view(viewport.width, viewport.height);
    let bias = scene.run.bias.get(f).copied().unwrap_or(0.0);
    let per_level = morph_instances(scene, &view, look.eye, bias);
    let (inst_buffers, mut outcome) = upload_instances(ctx, &per_level);
    let mut indices: Vec<CameraIndices> = inst_buffers
        .iter()
        .map(|_| CameraIndices::new("level", scene.gm.surfaces(), 1))
        .collect();
    if outcome.is_ok() {
        outcome = draw_levels(
            ctx,
            renderer,
            scene,
            &look,
            viewport,
            &inst_buffers,
            &mut indices,
            file,
        );
    }
    for ind in indices {
        if let Err(err) = ind.destroy(ctx) {
            outcome = Err(err.to_string());
        }
    }
    for (_, b) in inst_buffers {
        if let Err(err) = b.destroy(ctx) {
            outcome = Err(err.to_string());
        }
    }
    outcome
}

/// The visible instances sorted by the level their morph factor falls in, each with its
/// placement and its factor within that level.
fn morph_instances(
    scene: &Scene<'_, '_>,
    view: &View,
    eye: Vec3,
    bias: f32,
) -> Vec<Vec<MorphInstance>> {
    let mut per_level: Vec<Vec<MorphInstance>> = vec![Vec::new(); scene.levels.len()];
    for &p in scene.places {
        if !view.sphere_visible(p, 1.0) {
            continue;
        }
        let lm = scene
            .gm
            .partitions()
            .level_morph(t_from_distance(eye.distance(p), D_NEAR, D_FAR) + bias);
        let o = p - scene.centre * scene.scale;
        per_level[lm.level].push(MorphInstance {
            offset_scale: [o.x, o.y, o.z, scene.scale],
            t: lm.t,
            _pad: [0.0; 3],
        });
    }
    per_level
}

/// An instance buffer per level that has instances; stops at the first failure and returns
/// the buffers made so far with it.
fn upload_instances(
    ctx: &Context,
    per_level: &[Vec<MorphInstance>],
) -> (Vec<(usize, MorphInstances)>, Result<(), String>) {
    let mut inst_buffers = Vec::new();
    for (i, list) in per_level.iter().enumerate() {
        if !list.is_empty() {
            match MorphInstances::new(ctx, "instances", list) {
                Ok(b) => inst_buffers.push((i, b)),
                Err(err) => return (inst_buffers, Err(err.to_string())),
            }
        }
    }
    (inst_buffers, Ok(()))
}

/// One instanced geomorph draw per level with instances, read back and written as PNG.
#[allow(clippy::too_many_arguments)]
fn draw_levels(
    ctx: &Context,
    renderer: &mut Renderer,
    scene: &Scene<'_, '_>,
    look: &LookAt,
    viewport: Viewport,
    inst_buffers: &[(usize, MorphInstances)],
    indices: &mut [CameraIndices],
    file: &Path,
) -> Result<(), String> {
    let levels = scene.levels;
    let refs: Vec<Vec<&[u32]>> = inst_buffers
        .iter()
        .map(|(i, _)| levels[*i].lists.iter().map(Vec::as_slice).collect())
        .collect();
    let slot = renderer.begin_frame(ctx).map_err(|err| err.to_string())?;
    for (ind, lists) in indices.iter_mut().zip(&refs) {
        ind.fill(ctx, slot, IndexSource::Lists(lists))
            .map_err(|err| err.to_string())?;
    }
    let view_proj = look.view_projection(viewport.aspect());
    let draws: Vec<(usize, RecordCamera<'_>)> = inst_buffers
        .iter()
        .zip(indices.iter())
        .map(|((i, inst), ind)| {
            let camera = RecordCamera::new(viewport, view_proj, &levels[*i].a, ind)
                .colours(scene.colours)
                .morph(Morph {
                    fine: &levels[*i].b,
                    instances: inst,
                });
            (0, camera)
        })
        .collect();
    let image = renderer
        .render(ctx, &draws)
        .and_then(|_| renderer.read_target(ctx, 0))
        .map_err(|err| err.to_string())?;
    caveclod_host::write_png(&image, file).map_err(|err| err.to_string())
}
