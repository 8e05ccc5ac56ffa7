//! The C entry points allocate nothing: with a counting global allocator, opening a
//! hierarchy, sizing and initialising cameras (full, budgeted, morphing), refining from
//! several views, per-surface and packed emission (plain and morphed), the morph list and
//! the refusals of bad input leave the count unchanged once the caller's memory exists.
//!
//! Allocations are counted per thread (the test harness allocates on its own threads), and
//! the test shows the counter works by watching one `Vec::with_capacity(1)` change it.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::hint::black_box;
use std::mem::MaybeUninit;

use caveclod::*;

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

fn allocations() -> u64 {
    ALLOCATIONS.with(Cell::get)
}

// SAFETY: every method forwards to `System` with the caller's arguments unchanged; the
// counter is a thread-local `Cell` with a const initialiser, which never allocates.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        // SAFETY: forwarded; the caller upholds `alloc`'s contract.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded; `ptr` came from this allocator, hence from `System`.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

const FILE: &[u8] = include_bytes!("../../core/tests/data/terrain6.clod");

fn view(eye: [f32; 3], target: [f32; 3]) -> CaveclodView {
    CaveclodView {
        eye,
        target,
        up: [0.0, 1.0, 0.0],
        fov_y: std::f32::consts::FRAC_PI_3,
        aspect: 1280.0 / 720.0,
        near: 0.1,
        far: 1e5,
        viewport_height: 720,
    }
}

/// Checks a status.
fn ok(s: CaveclodStatus) {
    assert_eq!(s, CaveclodStatus::Ok);
}

#[test]
fn the_c_entry_points_do_not_allocate() {
    // Set-up: the caller's memory, made before counting.
    let mut aligned = vec![0u64; FILE.len().div_ceil(8)];
    let bytes: &mut [u8] = bytemuck_bytes(&mut aligned);
    bytes[..FILE.len()].copy_from_slice(FILE);
    let mut cam_memory = vec![0u64; 1 << 16];
    let mut morph_memory = vec![0u64; 1 << 16];
    let mut packed = vec![0u32; 1 << 14];
    let mut offsets = vec![0u32; 8];
    let mut lists: Vec<Vec<u32>> = (0..8).map(|_| vec![0u32; 1 << 14]).collect();
    let pointers: Vec<*mut u32> = lists.iter_mut().map(|l| l.as_mut_ptr()).collect();
    let capacities: Vec<usize> = lists.iter().map(Vec::len).collect();
    let mut written = vec![0u32; 8];
    let mut edits = vec![CaveclodIndexEdit::default(); 1 << 14];
    let mut draws = vec![CaveclodSurfaceDraw::default(); 8];
    let mut h = MaybeUninit::<CaveclodHierarchy>::uninit();
    let mut cam = MaybeUninit::<CaveclodCamera>::uninit();
    let mut morph_cam = MaybeUninit::<CaveclodCamera>::uninit();

    let probe: Vec<u8> = Vec::with_capacity(1);
    black_box(&probe);
    let before = allocations();
    let probe2: Vec<u8> = Vec::with_capacity(1);
    black_box(&probe2);
    assert!(allocations() > before, "the counting allocator saw nothing");

    let before = allocations();
    let mut polygons = 0u64;
    // SAFETY: every pointer is valid for what it is passed as, and outlives the calls.
    unsafe {
        ok(caveclod_hierarchy_open(
            bytes.as_ptr(),
            FILE.len(),
            h.as_mut_ptr(),
        ));
        let h = h.as_ptr();
        let mut hc = CaveclodHierarchyCounts::default();
        ok(caveclod_hierarchy_counts(h, &mut hc));
        let mut config = MaybeUninit::<CaveclodCameraConfig>::uninit();
        ok(caveclod_camera_config_full(h, config.as_mut_ptr()));
        let mut config = config.assume_init();
        let mut size = 0usize;
        ok(caveclod_camera_memory_size(h, &config, &mut size));
        assert!(size <= 8 * cam_memory.len());
        ok(caveclod_camera_init(
            h,
            &config,
            cam_memory.as_mut_ptr().cast(),
            8 * cam_memory.len(),
            cam.as_mut_ptr(),
        ));
        config.max_morphs = 64;
        ok(caveclod_camera_init_edited(
            h,
            &config,
            256,
            morph_memory.as_mut_ptr().cast(),
            8 * morph_memory.len(),
            morph_cam.as_mut_ptr(),
        ));
        let (cam, morph_cam) = (cam.as_mut_ptr(), morph_cam.as_mut_ptr());
        let centre = [0.0f32, 0.0, 0.0];
        for k in 0..8 {
            let a = k as f32 * 0.8;
            let v = view([30.0 * a.cos(), 20.0, 30.0 * a.sin()], centre);
            let mut stats = CaveclodRefineStats::default();
            ok(caveclod_camera_refine(
                cam,
                h,
                &v,
                std::ptr::null(),
                &mut stats,
            ));
            ok(caveclod_camera_refine(
                morph_cam,
                h,
                &v,
                std::ptr::null(),
                std::ptr::null_mut(),
            ));
            let mut total = 0usize;
            ok(caveclod_camera_emit_packed(
                cam,
                h,
                packed.as_mut_ptr(),
                packed.len(),
                offsets.as_mut_ptr(),
                offsets.len(),
                false,
                &mut total,
            ));
            let mut per_surface = 0usize;
            ok(caveclod_camera_emit(
                cam,
                h,
                pointers.as_ptr(),
                capacities.as_ptr(),
                written.as_mut_ptr(),
                pointers.len(),
                false,
                &mut per_surface,
            ));
            assert_eq!(total, per_surface);
            assert_eq!(total, 3 * stats.active_polygons as usize);
            polygons += u64::from(stats.active_polygons);
            ok(caveclod_camera_emit_packed(
                morph_cam,
                h,
                packed.as_mut_ptr(),
                packed.len(),
                offsets.as_mut_ptr(),
                offsets.len(),
                true,
                std::ptr::null_mut(),
            ));
            let mut result = CaveclodIndexEdits::default();
            ok(caveclod_camera_index_edits(
                morph_cam,
                h,
                32,
                edits.as_mut_ptr(),
                edits.len(),
                draws.as_mut_ptr(),
                draws.len(),
                &mut result,
            ));
            let mut slots = std::ptr::null();
            let mut count = 0usize;
            ok(caveclod_camera_morph_vertices(
                morph_cam, &mut slots, &mut count,
            ));
            assert!(count <= 128);
        }
        // Refusals allocate nothing either.
        assert_eq!(
            caveclod_camera_emit_packed(
                cam,
                h,
                packed.as_mut_ptr(),
                0,
                offsets.as_mut_ptr(),
                offsets.len(),
                false,
                std::ptr::null_mut()
            ),
            CaveclodStatus::OutputTooSmall
        );
        assert_eq!(
            caveclod_hierarchy_open(bytes.as_ptr().add(1), FILE.len() - 1, std::ptr::null_mut()),
            CaveclodStatus::NullPointer
        );
        ok(caveclod_camera_reset(cam, h));
    }
    assert_eq!(allocations(), before, "a C entry point allocated");
    assert!(polygons > 0);
}

#[test]
fn every_status_has_its_message() {
    for s in 0..=19 {
        // SAFETY: `caveclod_status_message` returns a static NUL-terminated string.
        let m = unsafe { std::ffi::CStr::from_ptr(caveclod_status_message(s)) };
        assert!(!m.to_bytes().is_empty(), "status {s}");
    }
    // SAFETY: as above.
    let unknown = unsafe { std::ffi::CStr::from_ptr(caveclod_status_message(-3)) };
    assert_eq!(unknown, CaveclodStatus::InvalidArgument.message());
    // SAFETY: as above.
    let last = unsafe { std::ffi::CStr::from_ptr(caveclod_status_message(19)) };
    assert_eq!(last, CaveclodStatus::BadPage.message());
    assert_eq!(caveclod_abi_version() >> 16, CAVECLOD_ABI_VERSION >> 16);
}

/// The bytes of `words`.
fn bytemuck_bytes(words: &mut [u64]) -> &mut [u8] {
    // SAFETY: `u8` has no invalid values and alignment 1; the length covers the same bytes.
    unsafe { std::slice::from_raw_parts_mut(words.as_mut_ptr().cast(), 8 * words.len()) }
}
