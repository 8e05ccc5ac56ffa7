//! Index edits through the C entry points: a geomorphing camera circling the test terrain
//! keeps a copy of its index buffer by applying only the edits of each frame, and after
//! every frame the copy draws exactly the triangles of morphed packed emission; the calls
//! allocate nothing; bad configurations and outputs too small are refused.

use std::mem::MaybeUninit;

use caveclod::*;

const FILE: &[u8] = include_bytes!("../../core/tests/data/terrain6.clod");

fn ok(s: CaveclodStatus) {
    assert_eq!(s, CaveclodStatus::Ok);
}

/// Frame `k` of an orbit that closes in and backs away, so the front splits and collapses.
fn view(k: usize) -> CaveclodView {
    let (angle, r) = (k as f32 * 0.1, 4.0 + 2.0 * (k as f32 - 30.0).abs());
    CaveclodView {
        eye: [r * angle.cos(), 0.6 * r, r * angle.sin()],
        target: [0.0, 0.0, 0.0],
        up: [0.0, 1.0, 0.0],
        fov_y: std::f32::consts::FRAC_PI_3,
        aspect: 1280.0 / 720.0,
        near: 0.1,
        far: 1e5,
        viewport_height: 720,
    }
}

/// Sorted triangles of `indices`, holes (three equal indices) left out.
fn triangles(indices: &[u32]) -> Vec<[u32; 3]> {
    let mut t: Vec<[u32; 3]> = indices
        .chunks_exact(3)
        .filter(|t| !(t[0] == t[1] && t[1] == t[2]))
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    t.sort_unstable();
    t
}

#[test]
fn edits_keep_a_copy_equal_to_morphed_emission() {
    let mut aligned = vec![0u64; FILE.len().div_ceil(8)];
    // SAFETY: `u8` has no invalid values; the length covers the same bytes.
    let bytes: &mut [u8] =
        unsafe { std::slice::from_raw_parts_mut(aligned.as_mut_ptr().cast(), 8 * aligned.len()) };
    bytes[..FILE.len()].copy_from_slice(FILE);
    let mut h = MaybeUninit::<CaveclodHierarchy>::uninit();
    let mut cam = MaybeUninit::<CaveclodCamera>::uninit();
    // SAFETY: every pointer is valid for what it is passed as and outlives the calls.
    unsafe {
        ok(caveclod_hierarchy_open(
            bytes.as_ptr(),
            FILE.len(),
            h.as_mut_ptr(),
        ));
        let h = h.as_ptr();
        let mut hc = CaveclodHierarchyCounts::default();
        ok(caveclod_hierarchy_counts(h, &mut hc));
        let surfaces = hc.surfaces as usize;
        let mut config = MaybeUninit::<CaveclodCameraConfig>::uninit();
        ok(caveclod_camera_config_full(h, config.as_mut_ptr()));
        let mut config = config.assume_init();
        config.max_morphs = 256;
        let mut size = 0usize;
        assert_eq!(
            caveclod_camera_memory_size_edited(h, &config, 0, &mut size),
            CaveclodStatus::InvalidConfig
        );
        ok(caveclod_camera_memory_size_edited(
            h, &config, 512, &mut size,
        ));
        let mut plain = 0usize;
        ok(caveclod_camera_memory_size(h, &config, &mut plain));
        assert!(size > plain);
        let mut memory = vec![0u64; size.div_ceil(8)];
        ok(caveclod_camera_init_edited(
            h,
            &config,
            512,
            memory.as_mut_ptr().cast(),
            size,
            cam.as_mut_ptr(),
        ));
        let cam = cam.as_mut_ptr();
        let mut places = 0usize;
        ok(caveclod_camera_index_places(cam, &mut places));
        assert!(places > 0);
        let mut copy = vec![[0u32; 3]; places];
        let mut draws = vec![CaveclodSurfaceDraw::default(); surfaces];
        let mut edits = vec![CaveclodIndexEdit::default(); places];
        let mut packed = vec![0u32; 3 * places];
        let mut offsets = vec![0u32; surfaces + 1];
        let mut params = MaybeUninit::<CaveclodRefineParams>::uninit();
        ok(caveclod_refine_params_default(params.as_mut_ptr()));
        let mut params = params.assume_init();
        params.tolerance_px = 0.5;
        params.dt_s = 1.0 / 30.0;
        let mut result = CaveclodIndexEdits::default();
        assert_eq!(
            caveclod_camera_index_edits(
                cam,
                h,
                0,
                edits.as_mut_ptr(),
                0,
                draws.as_mut_ptr(),
                surfaces,
                &mut result,
            ),
            CaveclodStatus::OutputTooSmall
        );
        let mut changed = 0usize;
        for k in 0..60 {
            let v = view(k);
            ok(caveclod_camera_refine(
                cam,
                h,
                &v,
                &params,
                std::ptr::null_mut(),
            ));
            let mut needed = 0usize;
            ok(caveclod_camera_index_edits_needed(cam, 16, &mut needed));
            assert!(needed <= edits.len());
            ok(caveclod_camera_index_edits(
                cam,
                h,
                16,
                edits.as_mut_ptr(),
                edits.len(),
                draws.as_mut_ptr(),
                surfaces,
                &mut result,
            ));
            assert_eq!(result.everything, k == 0, "frame {k}");
            if k > 0 {
                changed += result.edits;
            }
            for e in &edits[..result.edits] {
                copy[e.place as usize] = e.indices;
            }
            let mut total = 0usize;
            ok(caveclod_camera_emit_packed(
                cam,
                h,
                packed.as_mut_ptr(),
                packed.len(),
                offsets.as_mut_ptr(),
                offsets.len(),
                true,
                &mut total,
            ));
            for (s, d) in draws.iter().enumerate() {
                let first = d.first_index as usize / 3;
                let drawn: Vec<u32> = copy[first..first + d.index_count as usize / 3]
                    .iter()
                    .flatten()
                    .copied()
                    .collect();
                let emitted = &packed[offsets[s] as usize..offsets[s + 1] as usize];
                assert_eq!(
                    triangles(&drawn),
                    triangles(emitted),
                    "frame {k}, surface {s}"
                );
            }
        }
        assert!(changed > 0, "the orbit changed nothing");
    }
}
