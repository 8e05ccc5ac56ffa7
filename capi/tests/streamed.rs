//! Cameras over a paged file through the C entry points: the frame's lists, a camera sized,
//! made, refined and emitted over the streamed file, the lists applied, pages loaded from
//! the file's bytes and installed, and a pressure on the tolerance. Splits wait for their
//! pages at first, nothing reads an absent page, the front grows as pages arrive, emission
//! writes three indices per polygon, and the frame loop allocates nothing. A device vertex
//! pool beside the page pool, kept here as a renderer keeps it (the roots' vertices once,
//! each installed page's in its slot), holds every vertex that emission and the morph slots
//! name, and so does its device index buffer, patched each frame with the camera's edits.

#[path = "../../core/tests/counting/mod.rs"]
mod counting;

use std::mem::MaybeUninit;

use caveclod::*;
use caveclod_bake::paged::{write_paged, PageOptions};
use caveclod_tests::{bake, meshes};

use counting::allocations;

fn ok(s: CaveclodStatus) {
    assert_eq!(s, CaveclodStatus::Ok, "{s:?}");
}

/// `len` zeroed bytes on 64 bytes, in a vector of words that owns them.
fn aligned(len: usize) -> (Vec<u64>, *mut u8) {
    let mut v = vec![0u64; len / 8 + 9];
    let p = v.as_mut_ptr().cast::<u8>();
    let skip = p.align_offset(64);
    // SAFETY: `skip < 64` bytes into an allocation of at least `len + 72` bytes.
    (v, unsafe { p.add(skip) })
}

/// Changed places a camera lists between two edits, and holes closed a frame.
const EDIT_LIST: u32 = 1024;
const EDIT_MOVES: u32 = 16;

/// A device pool's vertex that no copy wrote.
const STALE: [u8; 32] = [0xff; 32];

/// Copies `install`'s vertices into `device` at their place.
///
/// # Safety
/// `install` is as a pool call wrote it, its vertices alive.
unsafe fn copy_install(device: &mut [[u8; 32]], install: &CaveclodVertexInstall) {
    // SAFETY: the caller's contract: `count` vertices of 32 bytes.
    let from = unsafe {
        std::slice::from_raw_parts(install.vertices.cast::<[u8; 32]>(), install.count as usize)
    };
    device[install.first as usize..][..from.len()].copy_from_slice(from);
}

/// Whether `device` holds a vertex a copy wrote at `i`.
fn written(device: &[[u8; 32]], i: u32) -> bool {
    device.get(i as usize).is_some_and(|v| *v != STALE)
}

/// A generated terrain's paged form: its bytes.
fn paged() -> Vec<u8> {
    let baked = bake(&meshes::terrain(40, 40, 9));
    let dir = tempfile::tempdir().expect("dir");
    let path = dir.path().join("terrain-paged.clod");
    write_paged(&baked.hierarchy(), &path, &PageOptions { page_bytes: 4096 }).expect("paged");
    std::fs::read(&path).expect("read")
}

#[test]
fn a_camera_refines_over_a_streamed_file_through_the_c_calls() {
    counting::assert_counting();
    let file = paged();
    let root_len = u64::from_le_bytes(file[16..24].try_into().expect("8 bytes")) as usize;
    let (_root_words, root_bytes) = aligned(root_len);
    // SAFETY: `root_bytes` holds `root_len` writable bytes.
    unsafe { root_bytes.copy_from_nonoverlapping(file.as_ptr(), root_len) };

    let mut root = MaybeUninit::<CaveclodPagedRoot>::uninit();
    // SAFETY: the root's bytes outlive the handle; `root` is writable.
    ok(unsafe { caveclod_paged_root_open(root_bytes, root_len, root.as_mut_ptr()) });
    let mut counts = CaveclodPagedCounts::default();
    // SAFETY: `root` was opened; `counts` is writable.
    ok(unsafe { caveclod_paged_root_counts(root.as_ptr(), &mut counts) });
    assert!(counts.pages > counts.root_pages + 4, "{counts:?}");

    let slots = (counts.pages - counts.root_pages) / 3 + 1;
    let config = CaveclodPoolConfig {
        slot_bytes: counts.largest_page.next_multiple_of(64),
        slots,
        files: 1,
        pages: counts.pages,
        max_requests: 256,
        slot_vertices: counts.most_page_vertices,
        vertex_pool_vertices: slots * counts.most_page_vertices + counts.root_vertices,
    };
    let mut memory_len = 0;
    // SAFETY: readable config, writable size.
    ok(unsafe { caveclod_pool_memory_size(&config, &mut memory_len) });
    let (_memory, memory) = aligned(memory_len);
    let pool_len = config.slots as usize * config.slot_bytes as usize;
    let (_pool_words, pool_bytes) = aligned(pool_len);
    let mut pool = MaybeUninit::<CaveclodPool>::uninit();
    // SAFETY: the memory and bytes outlive the pool; `pool` is writable.
    ok(unsafe {
        caveclod_pool_init(
            &config,
            memory.cast(),
            memory_len,
            pool_bytes,
            pool_len,
            pool.as_mut_ptr(),
        )
    });
    let mut file_index = 0;
    // SAFETY: initialised handles; writable index.
    ok(unsafe { caveclod_pool_add_file(pool.as_mut_ptr(), root.as_ptr(), &mut file_index) });
    // The device pool, each vertex a position no page holds until a copy writes it.
    let mut device = vec![STALE; config.vertex_pool_vertices as usize];
    for page in 0..counts.root_pages {
        let mut install = MaybeUninit::<CaveclodVertexInstall>::uninit();
        // SAFETY: initialised handles; writable install.
        ok(unsafe {
            caveclod_pool_root_vertices(pool.as_ptr(), root.as_ptr(), 0, page, install.as_mut_ptr())
        });
        // SAFETY: written above; its vertices lie in the root's bytes.
        unsafe { copy_install(&mut device, &install.assume_init()) };
    }

    let mut lists_len = 0;
    // SAFETY: initialised pool; writable size.
    ok(unsafe { caveclod_frame_lists_memory_size(pool.as_ptr(), 128, &mut lists_len) });
    let (_lists_words, lists_memory) = aligned(lists_len);
    let mut lists = MaybeUninit::<CaveclodFrameLists>::uninit();
    // SAFETY: the memory outlives the lists; `lists` is writable.
    ok(unsafe {
        caveclod_frame_lists_init(
            pool.as_ptr(),
            128,
            lists_memory.cast(),
            lists_len,
            lists.as_mut_ptr(),
        )
    });
    let streamed = CaveclodStreamedFile {
        root: root.as_ptr(),
        pool: pool.as_ptr(),
        file: file_index,
        lists: lists.as_mut_ptr(),
    };
    let mut camera_config = MaybeUninit::<CaveclodCameraConfig>::uninit();
    // SAFETY: initialised handles; writable config.
    ok(unsafe {
        caveclod_camera_config_polygon_budget_streamed(&streamed, 4000, camera_config.as_mut_ptr())
    });
    // SAFETY: written above.
    let budget = unsafe { camera_config.assume_init() };
    let camera_config = CaveclodCameraConfig {
        max_morphs: 512,
        ..budget
    };
    let mut camera_len = 0;
    // SAFETY: as above.
    ok(unsafe {
        caveclod_camera_memory_size_edited_streamed(
            &streamed,
            &camera_config,
            EDIT_LIST,
            &mut camera_len,
        )
    });
    let (_camera_words, camera_memory) = aligned(camera_len);
    let mut cam = MaybeUninit::<CaveclodCamera>::uninit();
    // SAFETY: the memory outlives the camera; `cam` is writable.
    ok(unsafe {
        caveclod_camera_init_edited_streamed(
            &streamed,
            &camera_config,
            EDIT_LIST,
            camera_memory.cast(),
            camera_len,
            cam.as_mut_ptr(),
        )
    });
    let mut pressure = MaybeUninit::<CaveclodPressure>::uninit();
    // SAFETY: writable.
    ok(unsafe { caveclod_pressure_init(8.0, pressure.as_mut_ptr()) });

    let view = CaveclodView {
        eye: [30.0, 12.0, 30.0],
        target: [0.0, 0.0, 0.0],
        up: [0.0, 1.0, 0.0],
        fov_y: std::f32::consts::FRAC_PI_3,
        aspect: 1280.0 / 720.0,
        near: 0.1,
        far: 1e5,
        viewport_height: 720,
    };
    let mut out = vec![0u32; 3 * 4100];
    let mut offsets = vec![0u32; counts.surfaces as usize + 1];
    let mut loads = [CaveclodLoadRequest::default(); 16];
    let mut evicted = [CaveclodPageKey::default(); 16];
    let idle = CaveclodMorphVertex {
        from: u32::MAX,
        to: u32::MAX,
        t: 0.0,
        coarse: u32::MAX,
    };
    let mut morphs = vec![idle; 2 * camera_config.max_morphs as usize];
    // The camera's device index buffer, patched with its edits.
    let mut places_len = 0;
    // SAFETY: an initialised camera; writable count.
    ok(unsafe { caveclod_camera_index_places(cam.as_mut_ptr(), &mut places_len) });
    let mut places = vec![[u32::MAX - 1; 3]; places_len];
    let mut edits = vec![CaveclodIndexEdit::default(); places_len + EDIT_MOVES as usize];
    let mut draws = vec![CaveclodSurfaceDraw::default(); counts.surfaces as usize];
    let (mut first_deferred, mut installs, mut polygons, mut morphing) = (0, 0, 0, 0);
    let before = allocations();
    for frame in 0..120 {
        // SAFETY: every handle is initialised and used by this thread alone; every pointer
        // is valid for what the call writes.
        unsafe {
            ok(caveclod_pool_begin_frame(pool.as_mut_ptr()));
            let mut stats = CaveclodRefineStats::default();
            let mut deferred = 0;
            let params = std::ptr::null();
            ok(caveclod_camera_refine_streamed(
                cam.as_mut_ptr(),
                &streamed,
                &view,
                params,
                &mut stats,
                &mut deferred,
            ));
            if frame == 0 {
                first_deferred = deferred;
            }
            polygons = stats.active_polygons;
            let mut total = 0;
            ok(caveclod_camera_emit_packed_streamed(
                cam.as_mut_ptr(),
                &streamed,
                out.as_mut_ptr(),
                out.len(),
                offsets.as_mut_ptr(),
                offsets.len(),
                false,
                &mut total,
            ));
            assert_eq!(total, 3 * stats.active_polygons as usize, "frame {frame}");
            for &i in &out[..total] {
                assert!(
                    written(&device, i),
                    "frame {frame}: index {i} names no vertex"
                );
            }
            let mut n = 0;
            ok(caveclod_camera_device_morph_vertices_streamed(
                cam.as_mut_ptr(),
                &streamed,
                morphs.as_mut_ptr(),
                morphs.len(),
                &mut n,
            ));
            for m in morphs[..n].iter().filter(|m| m.to != u32::MAX) {
                assert!(written(&device, m.to) && written(&device, m.coarse));
                morphing += 1;
            }
            let mut e = CaveclodIndexEdits::default();
            ok(caveclod_camera_index_edits_streamed(
                cam.as_mut_ptr(),
                &streamed,
                EDIT_MOVES,
                edits.as_mut_ptr(),
                edits.len(),
                draws.as_mut_ptr(),
                draws.len(),
                &mut e,
            ));
            for x in &edits[..e.edits] {
                places[x.place as usize] = x.indices;
            }
            // The patched buffer draws every polygon, at pool vertices or morph slots.
            let slots_end = config.vertex_pool_vertices + n as u32;
            let mut drawn = 0;
            for d in &draws {
                let first = d.first_index as usize / 3;
                for t in &places[first..first + d.index_count as usize / 3] {
                    if t[0] == t[1] && t[1] == t[2] {
                        continue;
                    }
                    drawn += 1;
                    for &i in t {
                        assert!(
                            written(&device, i)
                                || (config.vertex_pool_vertices..slots_end).contains(&i)
                        );
                    }
                }
            }
            assert_eq!(drawn, stats.active_polygons, "frame {frame}");
            ok(caveclod_pool_apply(pool.as_mut_ptr(), lists.as_mut_ptr()));
            let mut schedule = CaveclodScheduleStats::default();
            ok(caveclod_pool_schedule(
                pool.as_mut_ptr(),
                loads.as_mut_ptr(),
                4,
                evicted.as_mut_ptr(),
                16,
                &mut schedule,
            ));
            for l in &loads[..schedule.loads as usize] {
                let (mut slot, mut len) = (std::ptr::null_mut(), 0);
                ok(caveclod_pool_loading_slot(
                    pool.as_mut_ptr(),
                    l.slot,
                    &mut slot,
                    &mut len,
                ));
                let bytes = &file[l.offset as usize..l.offset as usize + l.size as usize];
                slot.copy_from_nonoverlapping(bytes.as_ptr(), bytes.len());
                let mut fault = CaveclodPageFault::default();
                ok(caveclod_pool_install(
                    pool.as_mut_ptr(),
                    l.slot,
                    root.as_ptr(),
                    &mut fault,
                ));
                installs += 1;
                let mut install = MaybeUninit::<CaveclodVertexInstall>::uninit();
                ok(caveclod_pool_page_vertices(
                    pool.as_ptr(),
                    l.file,
                    l.page,
                    install.as_mut_ptr(),
                ));
                let install = install.assume_init();
                let slot_places = config.slot_vertices as usize;
                device[install.first as usize..][..slot_places].fill(STALE);
                copy_install(&mut device, &install);
            }
            let mut scale = 1.0;
            ok(caveclod_pressure_update(
                pressure.as_mut_ptr(),
                pool.as_ptr(),
                &schedule,
                deferred,
                stats.active_nodes,
                &mut scale,
            ));
            assert!(scale >= 1.0);
        }
    }
    assert_eq!(allocations(), before, "the frame loop allocated");
    let mut reads = CaveclodStreamedReads::default();
    // SAFETY: initialised lists; writable reads.
    ok(unsafe { caveclod_frame_lists_reads(lists.as_mut_ptr(), &mut reads) });
    assert_eq!((reads.absent_reads, reads.untracked_uses), (0, 0));
    assert!(
        first_deferred > 0,
        "the root alone does not hold the wanted front"
    );
    assert!(
        installs > 0 && polygons > 100 && morphing > 0,
        "{installs} installs, {polygons} polygons, {morphing} morphing vertices"
    );

    // A pool that does not serve the root's file is refused.
    let wrong = CaveclodStreamedFile {
        file: 1,
        ..streamed
    };
    let mut stats = CaveclodRefineStats::default();
    // SAFETY: as above.
    let s = unsafe {
        caveclod_camera_refine_streamed(
            cam.as_mut_ptr(),
            &wrong,
            &view,
            std::ptr::null(),
            &mut stats,
            std::ptr::null_mut(),
        )
    };
    assert_eq!(s, CaveclodStatus::WrongHierarchy);
}
