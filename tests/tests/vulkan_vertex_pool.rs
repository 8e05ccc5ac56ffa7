//! The device vertex pool on lavapipe: four geomorphing cameras fly a paged terrain through
//! a page pool an eighth of the file, their vertices in a `VertexPool` whose slots are
//! reused as pages come and go (installs recorded into each frame's command buffer, at most
//! a cap a frame), drawn from edited index buffers with one, two and three frames in flight,
//! the validation layer and its synchronization validation silent. Every few frames the frame is drawn again from
//! a vertex buffer holding what the pool must hold (each page's vertices copied on the CPU
//! where the pool's installs copy them), with the same indices in the same order: the same
//! image, pixel for pixel.

mod vulkan_support;

use caveclod_core::format::Vertex;
use caveclod_core::glam::Vec3;
use caveclod_core::stream::{FrameLists, StreamedHierarchy, VertexInstall, Want};
use caveclod_core::{CameraConfig, CameraState, LookAt, RefineParams};
use caveclod_tests::paged::{load, paged_terrain, PoolMemory};
use caveclod_vulkan::{
    CameraIndices, CameraMorphs, Context, IndexSource, MorphStage, RecordCamera, Renderer,
    RendererDesc, RgbaImage, VertexBuffer, VertexPool,
};
use vulkan_support::{assert_clean, ok, plain_camera, quadrants, save, sync_context, EditCopy};

const SIZE: u32 = 256;
const FRAMES: usize = 240;
const CHECK_EVERY: usize = 12;
const MAX_INSTALLS: usize = 8;
const MAX_MORPHS: u32 = 1024;
const MOVES: u32 = 64;

/// A vertex no page holds.
const STALE: Vertex = Vertex {
    position: [f32::NAN; 3],
    normal: [0.0; 3],
    uv: [0.0; 2],
};

/// Camera `c`'s look in frame `f`: flying low round the terrain, looking ahead, so that its
/// front leaves the pages behind it.
fn look(size: f32, c: usize, f: usize) -> LookAt {
    let t = f as f32 / FRAMES as f32;
    let angle = 1.6 * c as f32 + t * (1.0 + 0.25 * c as f32) * std::f32::consts::TAU;
    let centre = Vec3::new(0.5 * size, 0.0, 0.5 * size);
    let radius = (0.2 + 0.03 * c as f32) * size;
    let eye = centre + Vec3::new(angle.cos() * radius, 0.06 * size, angle.sin() * radius);
    let ahead = Vec3::new(-angle.sin(), -0.25, angle.cos());
    LookAt {
        eye,
        target: eye + ahead * size * 0.1,
        up: Vec3::Y,
        fov_y: 1.0,
        near: 0.01 * size,
        far: 2.0 * size,
    }
}

/// The frame drawn again from `mirror`: per camera its copy's lists and its morph slots.
struct Reference {
    vertices: VertexBuffer,
    indices: Vec<CameraIndices>,
    morphs: Vec<CameraMorphs>,
}

impl Reference {
    fn destroy(self, ctx: &Context) {
        for i in self.indices {
            ok(i.destroy(ctx), "destroy indices");
        }
        for m in self.morphs {
            ok(m.destroy(ctx), "destroy morphs");
        }
        ok(self.vertices.destroy(ctx), "destroy vertices");
    }
}

fn copy_install(mirror: &mut [Vertex], i: &VertexInstall<'_>) {
    mirror[i.first as usize..][..i.vertices.len()].copy_from_slice(i.vertices);
}

#[test]
fn a_vertex_pool_one_frame_in_flight() {
    fly(1);
}

#[test]
fn a_vertex_pool_two_frames_in_flight() {
    fly(2);
}

#[test]
fn a_vertex_pool_three_frames_in_flight() {
    fly(3);
}

/// Flies the cameras over the pool with `in_flight` frames in flight (see the module docs).
fn fly(in_flight: usize) {
    let ctx = sync_context();
    let terrain = paged_terrain(128, 128, 11, 2048);
    let root = ok(terrain.file.root(), "root");
    let streamed_pages = root.table().len() as u32 - root.paged().root_pages;
    let mut memory = PoolMemory::with_vertex_pool(&root, streamed_pages / 8);
    let config = memory.config;
    let layout = config.vertex_pool.expect("layout");
    let mut pool = memory.residency(&root);
    let made = VertexPool::new(
        &ctx,
        "terrain",
        (layout, config.slots),
        false,
        MAX_INSTALLS as u32,
        in_flight,
    );
    let mut vertex_pool = ok(made, "vertex pool");
    let mut mirror = vec![STALE; layout.vertices as usize];
    let roots: Vec<VertexInstall<'_>> = (0..root.paged().root_pages)
        .map(|p| pool.root_vertices(0, &root, p).expect("root page"))
        .collect();
    ok(vertex_pool.upload_roots(&ctx, &roots), "roots");
    roots.iter().for_each(|r| copy_install(&mut mirror, r));

    let (mut wants, mut list_words) = (vec![Want::default(); 1024], Vec::new());
    list_words.resize(FrameLists::words_needed(&config), 0);
    let mut lists = ok(
        FrameLists::new(&config, &mut wants, &mut list_words),
        "lists",
    );
    let (camera_config, words) = {
        let h = StreamedHierarchy::new(&root, &pool, 0, &mut lists);
        let c = CameraConfig::with_polygon_budget(&h, 20_000)
            .with_morphs(MAX_MORPHS)
            .with_index_edits(8192);
        (c, CameraState::words_needed_for(&h, &c))
    };
    let mut memories = vec![vec![0u32; words]; 8];
    let (mut cams, mut twins): (Vec<CameraState<'_>>, Vec<CameraState<'_>>) = {
        let h = StreamedHierarchy::new(&root, &pool, 0, &mut lists);
        let mut all: Vec<CameraState<'_>> = memories
            .iter_mut()
            .map(|m| ok(CameraState::with_config(&h, m, &camera_config), "camera"))
            .collect();
        let twins = all.split_off(4);
        (all, twins)
    };
    let surfaces = root.meta().surface_count as usize;
    let mut copies: Vec<EditCopy> = twins.iter().map(|t| EditCopy::new(surfaces, t)).collect();
    let desc = |frames_in_flight| RendererDesc {
        refine_morphs: true,
        frames_in_flight,
        ..RendererDesc::single(SIZE, SIZE)
    };
    let mut renderer = ok(Renderer::new(&ctx, desc(in_flight)), "renderer");
    let mut reference_renderer = ok(Renderer::new(&ctx, desc(1)), "reference renderer");
    let mut indices: Vec<CameraIndices> = cams
        .iter()
        .enumerate()
        .map(|(c, cam)| {
            let name = format!("camera {c}");
            let made = CameraIndices::edited(&ctx, &name, surfaces, cam.index_places(), in_flight);
            ok(made, "edited indices")
        })
        .collect();
    let morphs_over = |vertices: &VertexBuffer, r: &Renderer, frames| -> Vec<CameraMorphs> {
        (0..4)
            .map(|c| {
                let name = format!("camera {c}");
                let made = CameraMorphs::new(
                    &ctx,
                    r.recorder(),
                    &name,
                    vertices,
                    MorphStage::Vertex,
                    MAX_MORPHS,
                    frames,
                );
                ok(made, "camera morphs")
            })
            .collect()
    };
    let mut morphs = morphs_over(vertex_pool.vertices(), &renderer, in_flight);

    let size = root.meta().bounds_max[0] - root.meta().bounds_min[0];
    let params = RefineParams {
        tolerance_px: 0.5,
        dt_s: 1.0 / 60.0,
        ..RefineParams::default()
    };
    let (mut installs, mut evictions, mut morphing, mut checked) = (0, 0, 0, 0);
    for f in 0..FRAMES {
        let looks: Vec<LookAt> = (0..4).map(|c| look(size, c, f)).collect();
        pool.begin_frame();
        let slot = ok(renderer.begin_frame(&ctx), "begin frame");
        let reference = {
            let h = StreamedHierarchy::new(&root, &pool, 0, &mut lists);
            for (c, (l, v)) in looks.iter().zip(quadrants(SIZE)).enumerate() {
                let view = l.view(v.width, v.height);
                ok(cams[c].refine(&h, &view, &params), "refine");
                ok(twins[c].refine(&h, &view, &params), "refine twin");
                copies[c].update(&h, &mut twins[c], MOVES);
                ok(
                    indices[c].fill_edits(&ctx, slot, &h, &mut cams[c], MOVES),
                    "fill edits",
                );
                morphing += ok(morphs[c].fill_device(slot, &h, &cams[c]), "fill morphs");
            }
            (f % CHECK_EVERY == CHECK_EVERY - 1).then(|| {
                // What frame `f` draws names no page installed after its refinement, so the
                // mirror before this frame's installs is what it reads.
                let vertices = ok(
                    VertexBuffer::from_vertices(&ctx, "mirror", &mirror),
                    "mirror",
                );
                let mut morphs = morphs_over(&vertices, &reference_renderer, 1);
                let mut lists_of = Vec::new();
                for (c, m) in morphs.iter_mut().enumerate() {
                    ok(m.fill_device(0, &h, &cams[c]), "reference morphs");
                    let mut ind = CameraIndices::new(&format!("reference {c}"), surfaces, 1);
                    let lists = copies[c].lists();
                    let lists: Vec<&[u32]> = lists.iter().map(Vec::as_slice).collect();
                    ok(
                        ind.fill(&ctx, 0, IndexSource::MorphedLists(&lists)),
                        "reference fill",
                    );
                    lists_of.push(ind);
                }
                Reference {
                    vertices,
                    indices: lists_of,
                    morphs,
                }
            })
        };
        ok(pool.apply(&mut lists), "apply");
        let (installed, evicted) = load(&mut pool, &root, &terrain.bytes, MAX_INSTALLS);
        let pages: Vec<VertexInstall<'_>> = installed
            .iter()
            .map(|k| pool.page_vertices(*k).expect("installed"))
            .collect();
        ok(vertex_pool.fill(slot, &pages), "fill pool");
        for p in &pages {
            let at = p.first as usize;
            mirror[at..at + layout.slot_vertices as usize].fill(STALE);
            copy_install(&mut mirror, p);
        }
        installs += pages.len();
        evictions += evicted;
        let draws: Vec<(usize, RecordCamera<'_>)> = indices
            .iter()
            .zip(&morphs)
            .zip(quadrants(SIZE))
            .zip(&looks)
            .map(|(((ind, m), viewport), look)| {
                let camera = plain_camera(viewport, look, vertex_pool.vertices(), ind);
                (0, camera.refine_morphs(m))
            })
            .collect();
        let stats = ok(
            renderer.render_with_pools(&ctx, &[&vertex_pool], &draws),
            "render",
        );
        assert_eq!(
            stats.vertex_install_bytes > 0,
            !pages.is_empty(),
            "frame {f}"
        );
        if let Some(r) = reference {
            let image = ok(renderer.read_slot_target(&ctx, slot, 0), "read back");
            let expected = draw_reference(&ctx, &mut reference_renderer, &r, &looks);
            if image.pixels != expected.pixels {
                save(&image, &format!("pool-{f}.png"));
                save(&expected, &format!("mirror-{f}.png"));
                panic!(
                    "frame {f}: the pool's image {:?}",
                    ok(image.diff(&expected), "diff")
                );
            }
            drawn_everywhere(&image, f);
            if f + CHECK_EVERY >= FRAMES {
                save(&image, &format!("vertex-pool-{in_flight}.png"));
            }
            r.destroy(&ctx);
            checked += 1;
        }
    }
    println!(
        "{installs} page installs into {} slots, {evictions} evictions, {morphing} morph slots \
         filled, {checked} frames checked",
        config.slots
    );
    assert!(
        installs > config.slots as usize && evictions > 0,
        "slots are reused"
    );
    assert!(morphing > 1000, "the cameras morph: {morphing}");
    ok(ctx.wait_idle(), "idle");
    ok(renderer.destroy(&ctx), "destroy renderer");
    ok(
        reference_renderer.destroy(&ctx),
        "destroy reference renderer",
    );
    for i in indices {
        ok(i.destroy(&ctx), "destroy indices");
    }
    for m in morphs {
        ok(m.destroy(&ctx), "destroy morphs");
    }
    ok(vertex_pool.destroy(&ctx), "destroy pool");
    assert_clean(&ctx, "flying a vertex pool");
    ok(ctx.destroy(), "destroy context");
}

/// Draws `r`'s cameras, from the mirror's vertices, and reads the image back.
fn draw_reference(
    ctx: &Context,
    renderer: &mut Renderer,
    r: &Reference,
    looks: &[LookAt],
) -> RgbaImage {
    ok(renderer.begin_frame(ctx), "begin reference frame");
    let draws: Vec<(usize, RecordCamera<'_>)> = r
        .indices
        .iter()
        .zip(&r.morphs)
        .zip(quadrants(SIZE))
        .zip(looks)
        .map(|(((ind, m), viewport), look)| {
            (
                0,
                plain_camera(viewport, look, &r.vertices, ind).refine_morphs(m),
            )
        })
        .collect();
    ok(renderer.render(ctx, &draws), "render reference");
    ok(renderer.read_slot_target(ctx, 0, 0), "read reference")
}

/// Every quadrant shows terrain.
fn drawn_everywhere(image: &RgbaImage, f: usize) {
    let half = SIZE / 2;
    for (q, v) in quadrants(SIZE).iter().enumerate() {
        let mut drawn = 0;
        for y in v.y..v.y + half {
            for x in v.x..v.x + half {
                let at = 4 * (y * SIZE + x) as usize;
                drawn += usize::from(image.pixels[at..at + 3] != [0, 0, 0]);
            }
        }
        assert!(
            drawn * 10 > (half * half) as usize,
            "frame {f}: quadrant {q} drawn on {drawn} pixels"
        );
    }
}
