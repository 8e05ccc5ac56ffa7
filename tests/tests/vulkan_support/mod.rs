//! Shared set-up of the Vulkan tests: a headless lavapipe context with validation, baked
//! generated meshes, cameras, and the "no validation messages" check.
#![allow(dead_code)]

pub mod host_frame;

use caveclod_core::format::Vertex;
use caveclod_core::gpu::MorphInstance;
use caveclod_core::{
    CameraState, Hierarchy, HierarchyRecords, IndexEdit, RefineParams, SurfaceDraw,
};
use caveclod_host::{Host, HostDesc};
use caveclod_tests::meshes::TestMesh;
use caveclod_vulkan::{
    CameraIndices, Context, HeadlessDesc, IndexSource, LookAt, Morph, RecordCamera, Renderer,
    RendererDesc, RgbaImage, VertexBuffer, Viewport,
};
use glam::Vec3;

/// Colours of surfaces 0 and 1.
pub const COLOURS: [[f32; 4]; 2] = [[0.9, 0.6, 0.3, 1.0], [0.3, 0.7, 0.9, 1.0]];
/// The clear colour as RGBA8.
pub const BACKGROUND: [u8; 4] = [0, 0, 0, 255];

/// A headless context on lavapipe with the validation layer, which must be installed.
pub fn context() -> Context {
    context_with(false)
}

/// [`context`] with the layer's synchronization validation too: hazards between commands
/// and between frames in flight are messages.
pub fn sync_context() -> Context {
    context_with(true)
}

fn context_with(synchronization_validation: bool) -> Context {
    let ctx = match Context::headless(&HeadlessDesc {
        validation: true,
        prefer_lavapipe: true,
        synchronization_validation,
    }) {
        Ok(c) => c,
        Err(e) => panic!("no Vulkan context (install lavapipe: cargo xtask setup): {e}"),
    };
    assert!(
        ctx.validation_enabled(),
        "VK_LAYER_KHRONOS_validation is not installed (cargo xtask setup)"
    );
    ctx
}

/// The tests' host engine (caveclod-host): validation on (the layer must be installed),
/// lavapipe first, exactly the required features.
pub fn host() -> Host {
    ok(
        Host::headless(&HostDesc::default()),
        "host (install lavapipe and the validation layer: cargo xtask setup)",
    )
}

/// Tears `host` down, failing if it still held an allocation or the validation layer
/// reported anything (the teardown's messages included).
pub fn destroy_host(host: Host) {
    let log = host.log().clone();
    ok(host.destroy(), "host teardown");
    let messages = log.take();
    assert!(
        messages.is_empty(),
        "validation messages:\n{}",
        messages.join("\n")
    );
}

/// Panics with the messages if the validation layer reported anything.
pub fn assert_clean(ctx: &Context, when: &str) {
    let messages = ctx.take_validation_messages();
    assert!(
        messages.is_empty(),
        "{} validation message(s) {when}:\n{}",
        messages.len(),
        messages.join("\n")
    );
}

/// Unwraps a result of this crate, naming the step.
pub fn ok<T, E: std::fmt::Display>(r: Result<T, E>, what: &str) -> T {
    match r {
        Ok(x) => x,
        Err(e) => panic!("{what}: {e}"),
    }
}

/// Writes `image` as `name` (a PNG) into the directory `CAVECLOD_TEST_IMAGES` names, if it
/// names one (for looking at a test's pictures); does nothing otherwise.
pub fn save(image: &RgbaImage, name: &str) {
    let Some(dir) = std::env::var_os("CAVECLOD_TEST_IMAGES") else {
        return;
    };
    let dir = std::path::PathBuf::from(dir);
    ok(std::fs::create_dir_all(&dir), "image directory");
    ok(caveclod_host::write_png(image, &dir.join(name)), "png");
}

/// The four quadrants of a `size` × `size` target.
pub fn quadrants(size: u32) -> [Viewport; 4] {
    let half = size / 2;
    [(0, 0), (half, 0), (0, half), (half, half)].map(|(x, y)| Viewport {
        x,
        y,
        width: half,
        height: half,
    })
}

/// A camera looking at the middle of a `size` × `size` terrain from `angle` (radians around
/// the y axis) at distance `distance` (in terrain sizes) and height `height`.
pub fn terrain_camera(size: f32, angle: f32, distance: f32, height: f32) -> LookAt {
    let c = Vec3::new(size * 0.5, 0.0, size * 0.5);
    LookAt {
        eye: c + Vec3::new(
            angle.sin() * distance * size,
            height * size,
            angle.cos() * distance * size,
        ),
        target: c,
        up: Vec3::Y,
        fov_y: 60f32.to_radians(),
        near: 0.05,
        far: 10.0 * size,
    }
}

/// The input mesh as a vertex buffer (three vertices per triangle, attributes as given)
/// and one index list per surface: the mesh drawn directly, without the baker.
pub fn direct_mesh(t: &TestMesh) -> (Vec<Vertex>, Vec<Vec<u32>>) {
    let mut vertices = Vec::with_capacity(3 * t.triangles.len());
    let mut lists = vec![Vec::new(); t.surface_count() as usize];
    for tri in &t.triangles {
        for k in 0..3 {
            lists[tri.surface as usize].push(vertices.len() as u32);
            vertices.push(Vertex {
                position: t.positions[tri.p[k] as usize],
                normal: tri.normal[k],
                uv: tri.uv[k],
            });
        }
    }
    (vertices, lists)
}

/// Camera memory for full resolution.
pub fn camera_memory(h: &Hierarchy<'_>) -> Vec<u32> {
    vec![0u32; CameraState::words_needed(h)]
}

/// Refines `cam` for `look` in `viewport` at `tolerance_px`.
pub fn refine(
    h: &Hierarchy<'_>,
    cam: &mut CameraState<'_>,
    look: &LookAt,
    viewport: Viewport,
    tolerance_px: f32,
) {
    let params = RefineParams {
        tolerance_px,
        ..RefineParams::default()
    };
    ok(
        cam.refine(h, &look.view(viewport.width, viewport.height), &params),
        "refine",
    );
}

/// A camera drawing `indices` into `viewport`, seen from `look`, plain: in the tests'
/// colours, without materials or morphs (a draw that needs them adds them to this one).
pub fn plain_camera<'a>(
    viewport: Viewport,
    look: &LookAt,
    vertices: &'a VertexBuffer,
    indices: &'a CameraIndices,
) -> RecordCamera<'a> {
    let view_proj = look.view_projection(viewport.aspect());
    RecordCamera::new(viewport, view_proj, vertices, indices).colours(&COLOURS)
}

/// Renders one camera's indices from `source` alone into a fresh `w` × `h` renderer and
/// reads the image back; destroys what it made.
pub fn render_alone(
    ctx: &Context,
    vertices: &VertexBuffer,
    surfaces: usize,
    look: &LookAt,
    size: (u32, u32),
    source: IndexSource<'_, '_>,
) -> RgbaImage {
    render_one(ctx, vertices, None, surfaces, look, size, source)
}

/// [`render_alone`] through the geomorph vertex stage: `vertices` are the coarse ends,
/// `morph` the fine ends and the instances, drawn in one instanced draw.
pub fn render_morphed(
    ctx: &Context,
    vertices: &VertexBuffer,
    morph: Morph<'_>,
    surfaces: usize,
    look: &LookAt,
    size: (u32, u32),
    source: IndexSource<'_, '_>,
) -> RgbaImage {
    render_one(ctx, vertices, Some(morph), surfaces, look, size, source)
}

/// One camera drawn into a fresh renderer (with the geomorph pipelines where it morphs),
/// read back, and what was made destroyed.
fn render_one(
    ctx: &Context,
    vertices: &VertexBuffer,
    morph: Option<Morph<'_>>,
    surfaces: usize,
    look: &LookAt,
    (w, h): (u32, u32),
    source: IndexSource<'_, '_>,
) -> RgbaImage {
    let desc = RendererDesc {
        geomorph: morph.is_some(),
        ..RendererDesc::single(w, h)
    };
    let mut renderer = ok(Renderer::new(ctx, desc), "renderer");
    let mut indices = CameraIndices::new("alone", surfaces, renderer.desc().frames_in_flight);
    let viewport = Viewport::full(w, h);
    let slot = ok(renderer.begin_frame(ctx), "begin frame");
    ok(indices.fill(ctx, slot, source), "fill");
    let camera = plain_camera(viewport, look, vertices, &indices);
    let camera = match morph {
        Some(m) => camera.morph(m),
        None => camera,
    };
    ok(renderer.render(ctx, &[(0, camera)]), "render");
    let image = ok(renderer.read_target(ctx, 0), "read back");
    ok(renderer.destroy(ctx), "destroy renderer");
    ok(indices.destroy(ctx), "destroy indices");
    image
}

/// `v` placed as a morph instance places its vertices: scaled by `offset_scale[3]`, then
/// moved by `offset_scale[0..3]`.
pub fn place(mut v: Vertex, inst: &MorphInstance) -> Vertex {
    let [ox, oy, oz, s] = inst.offset_scale;
    v.position = [
        v.position[0] * s + ox,
        v.position[1] * s + oy,
        v.position[2] * s + oz,
    ];
    v
}

/// A twin camera's index buffer, kept in memory by applying its edits: the order a device
/// buffer edited alike holds.
pub struct EditCopy {
    pub places: Vec<[u32; 3]>,
    pub draws: Vec<SurfaceDraw>,
    edits: Vec<IndexEdit>,
}

impl EditCopy {
    /// An empty copy for `cam`'s places over `surfaces` surfaces.
    pub fn new(surfaces: usize, cam: &CameraState<'_>) -> Self {
        Self {
            places: vec![[0; 3]; cam.index_places()],
            draws: vec![SurfaceDraw::default(); surfaces],
            edits: Vec::new(),
        }
    }

    /// Takes the twin's edits (closing at most `moves` holes) and applies them.
    pub fn update(&mut self, h: &impl HierarchyRecords, twin: &mut CameraState<'_>, moves: u32) {
        self.edits
            .resize(twin.index_edits_needed(moves), IndexEdit::default());
        let e = ok(
            twin.index_edits(h, moves, &mut self.edits, &mut self.draws),
            "edits",
        );
        for x in &self.edits[..e.edits] {
            self.places[x.place as usize] = x.indices;
        }
    }

    /// Each surface's drawn places as an index list, holes included.
    pub fn lists(&self) -> Vec<Vec<u32>> {
        self.draws
            .iter()
            .map(|d| {
                let first = d.first_index as usize / 3;
                let n = d.index_count as usize / 3;
                self.places[first..first + n]
                    .iter()
                    .flatten()
                    .copied()
                    .collect()
            })
            .collect()
    }
}
