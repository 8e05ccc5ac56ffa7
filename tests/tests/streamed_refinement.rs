//! Refinement over a paged file: a camera reads a [`StreamedHierarchy`] (the root and the
//! pages resident in a pool) as it reads a whole file.
//!
//! - With every page resident, the same flight gives the same front, slot by slot, as over
//!   the whole file it was paged from.
//! - With pages absent, the splits that need them are deferred and their pages wanted;
//!   nothing reads an absent page, and once the wanted pages arrive the front is the whole
//!   file's.
//! - The pool counts, per page, the front nodes standing on it, and never evicts such a page:
//!   a flight through a pool a third of the file evicts what the front left.
//! - With a device vertex pool beside it, emission, the index edits and the morph slots name
//!   vertices in that pool: an index buffer patched by the edits draws the front, read
//!   through the pool's vertices, while its slots are reused.

use caveclod_core::format::paged::PagedRoot;
use caveclod_core::format::Vertex;
use caveclod_core::glam::Vec3;
use caveclod_core::stream::{
    FrameLists, PageKey, PageState, PoolConfig, Residency, StreamedHierarchy, VertexInstall, Want,
};
use caveclod_core::{
    CameraConfig, CameraState, HierarchyRecords, IndexEdit, LookAt, MorphVertex, OpError,
    RefineParams, RefineStats, SurfaceDraw, View,
};
use caveclod_io::PagedFile;
use caveclod_tests::check::check_front;
use caveclod_tests::paged::{self, paged_terrain, PoolMemory};
use caveclod_tests::soak::streamed::check_page_uses;
use caveclod_tests::BakedMesh;

/// The terrain the tests fly over, paged.
fn terrain() -> (BakedMesh, PagedFile, Vec<u8>) {
    let t = paged_terrain(48, 48, 11, 4096);
    (t.baked, t.file, t.bytes)
}

/// Frame `f` of a flight low over the terrain, turning.
fn view(f: u32) -> View {
    let a = f as f32 * 0.04;
    LookAt {
        eye: Vec3::new(24.0 + 20.0 * a.cos(), 4.0, 24.0 + 20.0 * a.sin()),
        target: Vec3::new(24.0 + 6.0 * (a * 1.3).sin(), 0.0, 24.0),
        up: Vec3::Y,
        fov_y: 1.0,
        near: 0.1,
        far: 500.0,
    }
    .view(640, 400)
}

/// Loads what `pool` schedules from the file's `bytes`, synchronously; the loads and the
/// evictions.
fn load(pool: &mut Residency<'_, '_>, root: &PagedRoot<'_>, bytes: &[u8]) -> (u32, u32) {
    let (installed, evictions) = paged::load(pool, root, bytes, 64);
    (installed.len() as u32, evictions)
}

/// [`load`], and each installed page's vertices copied into `device` (its slot's place
/// first filled with a vertex no page holds, so a stale read shows).
fn load_with_vertices(
    pool: &mut Residency<'_, '_>,
    root: &PagedRoot<'_>,
    bytes: &[u8],
    device: &mut [Vertex],
) -> (u32, u32) {
    let (installed, evictions) = paged::load(pool, root, bytes, 64);
    let slot_vertices = pool.vertex_pool().expect("vertex pool").slot_vertices as usize;
    for key in &installed {
        let install = pool.page_vertices(*key).expect("resident");
        let at = install.first as usize;
        device[at..at + slot_vertices].fill(STALE);
        copy_install(device, &install);
    }
    (installed.len() as u32, evictions)
}

/// A vertex no page holds.
const STALE: Vertex = Vertex {
    position: [f32::NAN; 3],
    normal: [0.0; 3],
    uv: [0.0; 2],
};

fn copy_install(device: &mut [Vertex], install: &VertexInstall<'_>) {
    let at = install.first as usize;
    device[at..at + install.vertices.len()].copy_from_slice(install.vertices);
}

/// Every streamed page's uses are the front nodes standing on it, over all `cameras`, and
/// each such page is resident.
fn assert_uses(pool: &Residency<'_, '_>, root: &PagedRoot<'_>, cameras: &[&CameraState<'_>]) {
    check_page_uses(pool, root, cameras).unwrap_or_else(|e| panic!("{e}"));
}

/// Lists for a frame over `pool`.
fn lists<'w>(
    config: &PoolConfig,
    wants: &'w mut [Want],
    words: &'w mut Vec<u32>,
) -> FrameLists<'w> {
    words.resize(FrameLists::words_needed(config), 0);
    FrameLists::new(config, wants, words).expect("lists")
}

/// The front slot by slot: each active polygon's corner points.
fn front(cam: &CameraState<'_>, h: &impl HierarchyRecords) -> Vec<[[f32; 3]; 3]> {
    cam.active_polygons(h)
        .map(|p| {
            let corners = cam.polygon_corners(h, p).expect("active");
            corners.map(|n| h.node_point(n).expect("resident"))
        })
        .collect()
}

/// The front as a surface: its triangles' corner points, each triangle from its least
/// corner, sorted.
fn surface(cam: &CameraState<'_>, h: &impl HierarchyRecords) -> Vec<[[u32; 3]; 3]> {
    let mut tris: Vec<[[u32; 3]; 3]> = front(cam, h)
        .into_iter()
        .map(|t| {
            let t = t.map(|p| p.map(f32::to_bits));
            let least = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
            [t[least], t[(least + 1) % 3], t[(least + 2) % 3]]
        })
        .collect();
    tris.sort_unstable();
    tris
}

/// What must agree between the two forms' passes (the counts of pages and certificates may
/// differ: the two forms number nodes differently).
fn ops(st: &RefineStats) -> [u32; 5] {
    [
        st.splits,
        st.collapses,
        st.active_nodes,
        st.active_polygons,
        st.morphs_started,
    ]
}

#[test]
fn a_flight_over_every_page_resident_gives_the_whole_files_fronts() {
    let (baked, file, bytes) = terrain();
    let whole = baked.hierarchy();
    let root = file.root().expect("root");
    let mut p = PoolMemory::new(&root, root.table().len() as u32);
    let config = p.config;
    let mut pool = p.residency(&root);
    // Every page, parents before children.
    for page in 0..root.table().len() as u32 {
        pool.begin_frame();
        pool.want(PageKey { file: 0, page }, 1.0).expect("want");
        load(&mut pool, &root, &bytes);
    }
    let resident = (0..root.table().len() as u32)
        .filter(|&page| pool.state(PageKey { file: 0, page }) == Some(PageState::Resident))
        .count();
    assert_eq!(resident, root.table().len());

    let (mut wants, mut words) = ([Want::default(); 256], Vec::new());
    let mut lists = lists(&config, &mut wants, &mut words);
    let mut whole_mem = vec![0u32; CameraState::words_needed(&whole)];
    let (camera_config, mut paged_mem) = {
        let streamed = StreamedHierarchy::new(&root, &pool, 0, &mut lists);
        let c = CameraConfig::full(&streamed);
        (c, vec![0u32; CameraState::words_needed_for(&streamed, &c)])
    };
    assert!(
        paged_mem.len() < whole_mem.len() * 2,
        "a camera over sparse ids keeps no per-id arrays: {} words against {}",
        paged_mem.len(),
        whole_mem.len()
    );
    let mut whole_cam = CameraState::new(&whole, &mut whole_mem).expect("camera");
    let mut paged_cam = {
        let streamed = StreamedHierarchy::new(&root, &pool, 0, &mut lists);
        CameraState::with_config(&streamed, &mut paged_mem, &camera_config).expect("camera")
    };
    let params = RefineParams::default();
    let mut operations = 0;
    for f in 0..240 {
        let v = view(f);
        let a = whole_cam.refine(&whole, &v, &params).expect("whole");
        let streamed = StreamedHierarchy::new(&root, &pool, 0, &mut lists);
        let b = paged_cam.refine(&streamed, &v, &params).expect("paged");
        assert_eq!(ops(&a), ops(&b), "frame {f}");
        assert_eq!(b.deferred_splits, 0);
        assert_eq!(
            front(&whole_cam, &whole),
            front(&paged_cam, &streamed),
            "frame {f}"
        );
        operations += a.operations();
        if f % 60 == 0 {
            check_front(&whole, &whole_cam).expect("whole front");
        }
        pool.apply(&mut lists).expect("apply");
        if f % 20 == 0 {
            assert_uses(&pool, &root, &[&paged_cam]);
        }
    }
    assert!(
        operations > 1000,
        "the flight changes the front: {operations}"
    );
    let reads = lists.reads();
    assert_eq!((reads.absent_reads, reads.untracked_uses), (0, 0));
    // A reset leaves every streamed page.
    let streamed = StreamedHierarchy::new(&root, &pool, 0, &mut lists);
    paged_cam.reset(&streamed);
    pool.apply(&mut lists).expect("apply");
    assert_uses(&pool, &root, &[&paged_cam]);
}

#[test]
fn splits_wait_for_their_pages_and_then_reach_the_whole_files_front() {
    let (baked, file, bytes) = terrain();
    let whole = baked.hierarchy();
    let root = file.root().expect("root");
    let mut p = PoolMemory::new(&root, root.table().len() as u32);
    let config = p.config;
    let mut pool = p.residency(&root);
    let (mut wants, mut words) = ([Want::default(); 256], Vec::new());
    let mut lists = lists(&config, &mut wants, &mut words);
    let mut paged_mem = Vec::new();
    let mut cam = {
        let streamed = StreamedHierarchy::new(&root, &pool, 0, &mut lists);
        let c = CameraConfig::full(&streamed);
        paged_mem.resize(CameraState::words_needed_for(&streamed, &c), 0);
        CameraState::with_config(&streamed, &mut paged_mem, &c).expect("camera")
    };
    let mut whole_mem = vec![0u32; CameraState::words_needed(&whole)];
    let mut whole_cam = CameraState::new(&whole, &mut whole_mem).expect("camera");
    let v = view(10);
    let params = RefineParams::default().without_morphs();
    while whole_cam
        .refine(&whole, &v, &params)
        .expect("whole")
        .operations()
        > 0
    {}

    let (mut deferred, mut frames, mut installs) = (0u32, 0u32, 0u32);
    loop {
        pool.begin_frame();
        let streamed = StreamedHierarchy::new(&root, &pool, 0, &mut lists);
        let st = cam.refine(&streamed, &v, &params).expect("paged");
        assert_eq!(streamed.reads().absent_reads, 0, "frame {frames}");
        deferred += st.deferred_splits;
        if frames == 0 {
            // A split asked for by hand waits as refinement's do.
            let nodes: Vec<_> = cam.active_nodes().collect();
            let absent = nodes
                .iter()
                .filter(|&&n| matches!(cam.split(&streamed, n), Err(OpError::Absent { .. })))
                .count();
            assert!(
                absent > 0,
                "{} deferred, none refused by hand",
                st.deferred_splits
            );
            assert_eq!(streamed.reads().absent_reads, 0);
        }
        if st.deferred_splits == 0 && st.operations() == 0 {
            // The same surface, in another slot order: the two got there by other paths.
            let (a, b) = (surface(&whole_cam, &whole), surface(&cam, &streamed));
            assert!(a == b, "{} triangles against {}", a.len(), b.len());
            break;
        }
        pool.apply(&mut lists).expect("apply");
        installs += load(&mut pool, &root, &bytes).0;
        frames += 1;
        assert!(frames < 500, "the front settles");
    }
    assert!(
        deferred > 0,
        "the root pages alone do not hold the wanted front"
    );
    assert!(
        installs > 0 && installs < root.table().len() as u32,
        "{installs} installs"
    );
    pool.apply(&mut lists).expect("apply");
    assert_uses(&pool, &root, &[&cam]);
}

#[test]
fn a_pool_a_third_of_the_file_evicts_only_what_the_fronts_left() {
    let (_, file, bytes) = terrain();
    let root = file.root().expect("root");
    let streamed_pages = root.table().len() as u32 - root.paged().root_pages;
    let mut p = PoolMemory::new(&root, streamed_pages / 3);
    let config = p.config;
    let mut pool = p.residency(&root);
    let (mut wants, mut words) = ([Want::default(); 256], Vec::new());
    let mut lists = lists(&config, &mut wants, &mut words);
    let (camera_config, words_needed) = {
        let streamed = StreamedHierarchy::new(&root, &pool, 0, &mut lists);
        let c = CameraConfig::with_polygon_budget(&streamed, 1500);
        (c, CameraState::words_needed_for(&streamed, &c))
    };
    let mut memories = vec![vec![0u32; words_needed]; 2];
    let mut cams: Vec<CameraState<'_>> = {
        let streamed = StreamedHierarchy::new(&root, &pool, 0, &mut lists);
        memories
            .iter_mut()
            .map(|m| CameraState::with_config(&streamed, m, &camera_config).expect("camera"))
            .collect()
    };
    let params = RefineParams::default();
    let (mut evictions, mut installs, mut deferred) = (0, 0, 0);
    for f in 0..600 {
        pool.begin_frame();
        let streamed = StreamedHierarchy::new(&root, &pool, 0, &mut lists);
        for (k, cam) in cams.iter_mut().enumerate() {
            let st = cam.refine(&streamed, &view(f * 2 + k as u32 * 80), &params);
            deferred += st.expect("refine").deferred_splits;
        }
        pool.apply(&mut lists).expect("apply");
        let (l, e) = load(&mut pool, &root, &bytes);
        installs += l;
        evictions += e;
        if f % 25 == 0 {
            let views: Vec<&CameraState<'_>> = cams.iter().collect();
            assert_uses(&pool, &root, &views);
        }
    }
    let reads = lists.reads();
    assert_eq!((reads.absent_reads, reads.untracked_uses), (0, 0));
    assert!(
        deferred > 0 && installs > streamed_pages / 3,
        "{installs} installs"
    );
    assert!(evictions > 0, "the fronts moved off pages, which made room");
}

#[test]
fn a_streamed_camera_draws_from_the_device_vertex_pool_while_its_slots_are_reused() {
    let (_, file, bytes) = terrain();
    let root = file.root().expect("root");
    let streamed_pages = root.table().len() as u32 - root.paged().root_pages;
    let mut p = PoolMemory::with_vertex_pool(&root, streamed_pages / 3);
    let config = p.config;
    let layout = config.vertex_pool.expect("layout");
    let mut pool = p.residency(&root);
    // The device pool as a renderer keeps it: the root pages' vertices once, then each
    // installed page's in its slot.
    let mut device = vec![STALE; layout.vertices as usize];
    for page in 0..root.paged().root_pages {
        copy_install(
            &mut device,
            &pool.root_vertices(0, &root, page).expect("root"),
        );
    }
    let (mut wants, mut words) = ([Want::default(); 256], Vec::new());
    let mut lists = lists(&config, &mut wants, &mut words);
    let mut memory = Vec::new();
    let mut cam = {
        let streamed = StreamedHierarchy::new(&root, &pool, 0, &mut lists);
        let c = CameraConfig::with_polygon_budget(&streamed, 1500)
            .with_morphs(256)
            .with_index_edits(512);
        memory.resize(CameraState::words_needed_for(&streamed, &c), 0);
        CameraState::with_config(&streamed, &mut memory, &c).expect("camera")
    };
    let mut places = vec![[u32::MAX - 1; 3]; cam.index_places()];
    let surfaces = root.meta().surface_count as usize;
    let (mut edits, mut draws) = (Vec::new(), vec![SurfaceDraw::default(); surfaces]);
    let (mut installs, mut evictions, mut morphing) = (0, 0, 0);
    let params = RefineParams::default();
    for f in 0..400 {
        pool.begin_frame();
        let h = StreamedHierarchy::new(&root, &pool, 0, &mut lists);
        cam.refine(&h, &view(f * 2), &params).expect("refine");
        edits.resize(cam.index_edits_needed(64), IndexEdit::default());
        let e = cam
            .index_edits(&h, 64, &mut edits, &mut draws)
            .expect("edits");
        for x in &edits[..e.edits] {
            places[x.place as usize] = x.indices;
        }
        let mut slots = vec![MorphVertex::IDLE; cam.morph_vertices().len()];
        cam.device_morph_vertices(&h, &mut slots).expect("morphs");
        check_morph_slots(&h, &cam, &slots, &device);
        morphing += slots.iter().filter(|m| !m.is_idle()).count();
        // The places drawn are the front, read through the device pool, a morphing corner
        // at its fine vertex (where its slot's blend ends).
        let drawn = draws
            .iter()
            .flat_map(|d| &places[d.first_index as usize / 3..][..d.index_count as usize / 3])
            .filter(|t| !(t[0] == t[1] && t[1] == t[2]))
            .map(|t| t.map(|i| device_point(&device, &slots, layout.vertices, i)));
        assert_eq!(sorted(drawn), fine_surface(&cam, &h), "frame {f}");
        pool.apply(&mut lists).expect("apply");
        let (l, e) = load_with_vertices(&mut pool, &root, &bytes, &mut device);
        installs += l;
        evictions += e;
    }
    assert!(
        installs > streamed_pages / 3 && evictions > 0,
        "{installs} installs, {evictions} evictions"
    );
    assert!(
        morphing > 100,
        "{morphing} morphing vertices over the flight"
    );
}

/// Each device morph slot names, in the device pool, the vertices its camera slot names by
/// id.
fn check_morph_slots(
    h: &StreamedHierarchy<'_, '_, '_, '_>,
    cam: &CameraState<'_>,
    device_slots: &[MorphVertex],
    device: &[Vertex],
) {
    let ids = h.vertex_id_bound() as u32;
    for (d, m) in device_slots.iter().zip(cam.morph_vertices()) {
        assert_eq!(d.is_idle(), m.is_idle());
        if m.is_idle() {
            continue;
        }
        assert_eq!(&device[d.to as usize], h.vertex(m.to).expect("to"));
        assert_eq!(
            &device[d.coarse as usize],
            h.vertex(m.coarse).expect("coarse")
        );
        match m.from.checked_sub(ids) {
            Some(slot) => assert_eq!(d.from, h.device_vertex_bound() as u32 + slot),
            None => assert_eq!(&device[d.from as usize], h.vertex(m.from).expect("from")),
        }
    }
}

/// The point index `i` names on the device: a pool vertex's, or a morph slot's fine vertex.
fn device_point(device: &[Vertex], slots: &[MorphVertex], vertices: u32, i: u32) -> [u32; 3] {
    let v = match i.checked_sub(vertices) {
        Some(s) => device[slots[s as usize].to as usize],
        None => device[i as usize],
    };
    v.position.map(f32::to_bits)
}

/// The front as its polygons' fine points: each corner at its node's point, sorted as
/// [`sorted`] sorts.
fn fine_surface(cam: &CameraState<'_>, h: &impl HierarchyRecords) -> Vec<[[u32; 3]; 3]> {
    sorted(
        front(cam, h)
            .into_iter()
            .map(|t| t.map(|p| p.map(f32::to_bits))),
    )
}

/// Triangles each from its least corner, sorted.
fn sorted(tris: impl Iterator<Item = [[u32; 3]; 3]>) -> Vec<[[u32; 3]; 3]> {
    let mut tris: Vec<[[u32; 3]; 3]> = tris
        .map(|t| {
            let least = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
            [t[least], t[(least + 1) % 3], t[(least + 2) % 3]]
        })
        .collect();
    tris.sort_unstable();
    tris
}
