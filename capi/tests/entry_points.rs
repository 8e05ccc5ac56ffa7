//! What the C entry points report: the model's bounds, a file with bytes after its end, and
//! views and refinement parameters the core refuses (the camera left as it was).

use std::mem::MaybeUninit;

use caveclod::*;
use caveclod_core::Hierarchy;

const FILE: &[u8] = include_bytes!("../../core/tests/data/terrain6.clod");

/// `FILE` in 8-byte-aligned memory with `extra` zero bytes after it.
fn aligned(extra: usize) -> Vec<u64> {
    let mut words = vec![0u64; (FILE.len() + extra).div_ceil(8)];
    // SAFETY: `u8` has no invalid values and alignment 1; the length covers the same bytes.
    let bytes: &mut [u8] =
        unsafe { std::slice::from_raw_parts_mut(words.as_mut_ptr().cast(), 8 * words.len()) };
    bytes[..FILE.len()].copy_from_slice(FILE);
    words
}

/// Opens the first `len` bytes of `words` as a hierarchy.
fn open(words: &[u64], len: usize) -> (CaveclodStatus, MaybeUninit<CaveclodHierarchy>) {
    let mut h = MaybeUninit::<CaveclodHierarchy>::uninit();
    // SAFETY: `words` holds at least `len` bytes and outlives every use of the handle in
    // these tests; `h` is writable.
    let status = unsafe { caveclod_hierarchy_open(words.as_ptr().cast(), len, h.as_mut_ptr()) };
    (status, h)
}

fn view() -> CaveclodView {
    CaveclodView {
        eye: [30.0, 20.0, 10.0],
        target: [0.0, 0.0, 0.0],
        up: [0.0, 1.0, 0.0],
        fov_y: std::f32::consts::FRAC_PI_3,
        aspect: 1280.0 / 720.0,
        near: 0.1,
        far: 1e5,
        viewport_height: 720,
    }
}

#[test]
fn the_bounds_are_the_files() {
    let words = aligned(0);
    let (status, h) = open(&words, FILE.len());
    assert_eq!(status, CaveclodStatus::Ok);
    let mut bounds = CaveclodBounds::default();
    // SAFETY: `h` was opened over `words`, which lives; `bounds` is writable.
    let status = unsafe { caveclod_hierarchy_bounds(h.as_ptr(), &mut bounds) };
    assert_eq!(status, CaveclodStatus::Ok);
    // SAFETY: the words hold `FILE` and are 8-byte aligned.
    let bytes = unsafe { std::slice::from_raw_parts(words.as_ptr().cast::<u8>(), FILE.len()) };
    let core = Hierarchy::from_bytes(bytes).expect("the test file is valid");
    assert_eq!(bounds.min, core.meta().bounds_min);
    assert_eq!(bounds.max, core.meta().bounds_max);
    assert!((0..3).all(|k| bounds.min[k] < bounds.max[k]), "{bounds:?}");
    // SAFETY: a null output is refused before anything is written.
    let status = unsafe { caveclod_hierarchy_bounds(h.as_ptr(), std::ptr::null_mut()) };
    assert_eq!(status, CaveclodStatus::NullPointer);
    let never = MaybeUninit::<CaveclodHierarchy>::zeroed();
    // SAFETY: a zeroed handle is initialised memory the library refuses; `bounds` is
    // writable.
    let status = unsafe { caveclod_hierarchy_bounds(never.as_ptr(), &mut bounds) };
    assert_eq!(status, CaveclodStatus::InvalidHandle);
}

#[test]
fn bytes_after_the_end_have_their_own_status() {
    let words = aligned(16);
    assert_eq!(
        open(&words, FILE.len() + 16).0,
        CaveclodStatus::TrailingBytes
    );
    assert_eq!(
        open(&words, FILE.len() + 1).0,
        CaveclodStatus::TrailingBytes
    );
    assert_eq!(open(&words, FILE.len() - 1).0, CaveclodStatus::Truncated);
    assert_eq!(open(&words, FILE.len()).0, CaveclodStatus::Ok);
    let message = CaveclodStatus::TrailingBytes.message().to_string_lossy();
    assert!(message.contains("after the end"), "{message}");
    assert_ne!(
        CaveclodStatus::TrailingBytes.message(),
        CaveclodStatus::Truncated.message()
    );
}

/// A view or parameters out of range are refused with `INVALID_ARGUMENT`, and the camera
/// is left as it was; the same camera then refines.
#[test]
fn views_and_parameters_out_of_range_are_refused() {
    let words = aligned(0);
    let (status, h) = open(&words, FILE.len());
    assert_eq!(status, CaveclodStatus::Ok);
    let h = h.as_ptr();
    let mut memory = vec![0u64; 1 << 16];
    let mut cam = MaybeUninit::<CaveclodCamera>::uninit();
    let mut defaults = MaybeUninit::<CaveclodRefineParams>::uninit();
    // SAFETY: every pointer is valid for what it is passed as and outlives the calls.
    unsafe {
        let mut config = MaybeUninit::<CaveclodCameraConfig>::uninit();
        assert_eq!(
            caveclod_camera_config_full(h, config.as_mut_ptr()),
            CaveclodStatus::Ok
        );
        let status = caveclod_camera_init(
            h,
            config.as_ptr(),
            memory.as_mut_ptr().cast(),
            8 * memory.len(),
            cam.as_mut_ptr(),
        );
        assert_eq!(status, CaveclodStatus::Ok);
        assert_eq!(
            caveclod_refine_params_default(defaults.as_mut_ptr()),
            CaveclodStatus::Ok
        );
    }
    let cam = cam.as_mut_ptr();
    // SAFETY: filled by `caveclod_refine_params_default`.
    let defaults = unsafe { defaults.assume_init() };
    let refine = |v: &CaveclodView, p: &CaveclodRefineParams| {
        let mut stats = CaveclodRefineStats::default();
        // SAFETY: the camera, hierarchy and arguments are valid for the call.
        let status = unsafe { caveclod_camera_refine(cam, h, v, p, &mut stats) };
        (status, stats.splits)
    };
    let base = [
        CaveclodRefineParams {
            tolerance_px: 0.0,
            ..defaults
        },
        CaveclodRefineParams {
            tolerance_px: -1.0,
            ..defaults
        },
        CaveclodRefineParams {
            tolerance_px: f32::NAN,
            ..defaults
        },
        CaveclodRefineParams {
            tolerance_px: f32::INFINITY,
            ..defaults
        },
        CaveclodRefineParams {
            dt_s: -0.1,
            ..defaults
        },
        CaveclodRefineParams {
            refine_morph_s: f32::INFINITY,
            ..defaults
        },
        CaveclodRefineParams {
            coarsen_morph_s: f32::NAN,
            ..defaults
        },
        CaveclodRefineParams {
            morph_speed_px_s: -1.0,
            ..defaults
        },
        CaveclodRefineParams {
            morph_radius_tolerances: f32::NAN,
            ..defaults
        },
        CaveclodRefineParams {
            morph_guard_rad: 2.0,
            ..defaults
        },
    ];
    for p in &base {
        assert_eq!(
            refine(&view(), p),
            (CaveclodStatus::InvalidArgument, 0),
            "{p:?}"
        );
    }
    let views = [
        CaveclodView {
            fov_y: 0.0,
            ..view()
        },
        CaveclodView {
            aspect: 0.0,
            ..view()
        },
        CaveclodView {
            viewport_height: 0,
            ..view()
        },
        CaveclodView {
            target: view().eye,
            ..view()
        },
        CaveclodView {
            up: [30.0, 20.0, 10.0],
            ..view()
        },
        CaveclodView {
            far: 0.05,
            ..view()
        },
        CaveclodView {
            eye: [f32::NAN, 0.0, 0.0],
            ..view()
        },
    ];
    for v in &views {
        assert_eq!(
            refine(v, &defaults),
            (CaveclodStatus::InvalidArgument, 0),
            "{v:?}"
        );
    }
    let mut counts = CaveclodCameraCounts::default();
    // SAFETY: the camera is initialised; `counts` is writable.
    let status = unsafe { caveclod_camera_counts(cam, &mut counts) };
    assert_eq!(status, CaveclodStatus::Ok);
    assert_eq!(counts.splits, 0, "a refused pass changed the camera");
    // Zero and infinity both mean "none" for the speed limit and the radius bound.
    let off = CaveclodRefineParams {
        morph_speed_px_s: 0.0,
        morph_radius_tolerances: f32::INFINITY,
        ..defaults
    };
    let (status, splits) = refine(&view(), &off);
    assert_eq!(status, CaveclodStatus::Ok);
    assert!(splits > 0);
}
