//! Index edits on the golden hierarchy: a device index buffer patched each frame with only
//! the places that changed draws, after every frame, exactly the triangles of morphed
//! emission (with holes that draw nothing), over any flight, frame times, morph memory,
//! list size, compaction (whole or in steps), resets, finished morphs and hole moves; and a
//! frame that changes nothing hands out nothing.

mod common;

use caveclod_core::{
    CameraConfig, CameraError, CameraState, EmitError, Hierarchy, IndexEdit, RefineParams,
    SurfaceDraw,
};
use common::golden_hierarchy;
use common::morphs::{approach, surface_triangles};
use proptest::prelude::*;

/// A camera's device index buffer, as a host keeps it: one triangle per place.
struct Device {
    places: Vec<[u32; 3]>,
    draws: Vec<SurfaceDraw>,
    edits: Vec<IndexEdit>,
    written: usize,
}

impl Device {
    fn new(h: &Hierarchy<'_>, cam: &CameraState<'_>) -> Self {
        Self {
            // What a fresh buffer holds is never drawn: the first edits write every place.
            places: vec![[u32::MAX - 1; 3]; cam.index_places()],
            draws: vec![SurfaceDraw::default(); h.surface_count()],
            edits: Vec::new(),
            written: 0,
        }
    }

    /// Takes the camera's edits and applies them.
    fn update(&mut self, h: &Hierarchy<'_>, cam: &mut CameraState<'_>, moves: u32) -> usize {
        self.edits
            .resize(cam.index_edits_needed(moves), IndexEdit::default());
        let e = cam
            .index_edits(h, moves, &mut self.edits, &mut self.draws)
            .expect("edits");
        for x in &self.edits[..e.edits] {
            self.places[x.place as usize] = x.indices;
        }
        self.written += e.edits;
        e.edits
    }

    /// Each surface's drawn triangles, holes left out, sorted.
    fn drawn(&self) -> Vec<Vec<[u32; 3]>> {
        self.draws
            .iter()
            .map(|d| {
                let first = d.first_index as usize / 3;
                let mut t: Vec<[u32; 3]> = self.places[first..first + d.index_count as usize / 3]
                    .iter()
                    .filter(|t| !(t[0] == t[1] && t[1] == t[2]))
                    .copied()
                    .collect();
                t.sort_unstable();
                t
            })
            .collect()
    }
}

/// Morphed emission's triangles per surface, sorted.
fn emitted(h: &Hierarchy<'_>, cam: &CameraState<'_>) -> Vec<Vec<[u32; 3]>> {
    surface_triangles(h, cam, true)
}

fn edit_config(h: &Hierarchy<'_>, max_morphs: u32, list: u32) -> CameraConfig {
    CameraConfig::full(h)
        .with_morphs(max_morphs)
        .with_index_edits(list)
}

#[test]
fn edits_need_the_index_cache_and_memory_of_their_own() {
    let h = golden_hierarchy();
    let plain = CameraState::words_needed_for(&h, &CameraConfig::full(&h));
    let config = edit_config(&h, 0, 100);
    let slots = h.base_polygon_count() + 2 * h.splits().len();
    let places = slots * h.surface_count();
    assert_eq!(
        CameraState::words_needed_for(&h, &config) - plain,
        slots + places + 2 * places.div_ceil(32) + 100 + 3 * h.surface_count()
    );
    let uncached = CameraConfig {
        index_cache: false,
        ..config
    };
    let mut memory = vec![0u32; CameraState::words_needed_for(&h, &uncached)];
    assert!(matches!(
        CameraState::with_config(&h, &mut memory, &uncached).err(),
        Some(CameraError::IndexEdits {
            index_cache: false,
            ..
        })
    ));
    let mut memory = vec![0u32; plain];
    let mut cam = CameraState::new(&h, &mut memory).expect("memory");
    assert_eq!(cam.index_places(), 0);
    assert_eq!(
        cam.index_edits(&h, 0, &mut [], &mut []).err(),
        Some(EmitError::NoIndexEdits)
    );
}

#[test]
fn too_little_room_changes_nothing() {
    let h = golden_hierarchy();
    let config = edit_config(&h, 64, 4096);
    let mut memory = vec![0u32; CameraState::words_needed_for(&h, &config)];
    let mut cam = CameraState::with_config(&h, &mut memory, &config).expect("memory");
    let needed = cam.index_edits_needed(0);
    assert!(
        needed >= h.base_polygon_count(),
        "a new camera writes every place"
    );
    let mut short = vec![IndexEdit::default(); needed - 1];
    let mut draws = vec![SurfaceDraw::default(); h.surface_count()];
    assert!(matches!(
        cam.index_edits(&h, 0, &mut short, &mut draws),
        Err(EmitError::OutputTooSmall { .. })
    ));
    assert_eq!(cam.index_edits_needed(0), needed);
    let mut device = Device::new(&h, &cam);
    assert_eq!(device.update(&h, &mut cam, 0), h.base_polygon_count());
    assert_eq!(device.drawn(), emitted(&h, &cam));
    assert_eq!(device.update(&h, &mut cam, 16), 0, "nothing changed");
}

/// A flight whose frames change a few hundred polygons writes about as many places, not the
/// whole buffer, and what it draws stays exact.
#[test]
fn a_flight_writes_what_changed() {
    let h = golden_hierarchy();
    let config = edit_config(&h, 256, 4096);
    let mut memory = vec![0u32; CameraState::words_needed_for(&h, &config)];
    let mut cam = CameraState::with_config(&h, &mut memory, &config).expect("memory");
    let mut device = Device::new(&h, &cam);
    let p = RefineParams {
        tolerance_px: 0.5,
        dt_s: 1.0 / 60.0,
        ..RefineParams::default()
    };
    let frames = if cfg!(miri) { 4 } else { 120 };
    let (mut full, mut written) = (0usize, 0usize);
    for f in 0..frames {
        cam.refine(&h, &approach(&h, f as f32 / frames as f32), &p)
            .expect("refine");
        let n = device.update(&h, &mut cam, 8);
        if f > 0 {
            written += n;
            full += cam.active_polygon_count() as usize;
        }
        assert_eq!(device.drawn(), emitted(&h, &cam), "frame {f}");
    }
    assert!(
        cfg!(miri) || written * 4 < full,
        "{written} places written against {full} polygons emitted"
    );
}

fn frame() -> impl Strategy<Value = (usize, f32, f32, u8)> {
    (
        0usize..12,
        prop::sample::select(vec![0.0f32, 1.0 / 60.0, 1.0 / 20.0, 0.4]),
        prop::sample::select(vec![0.05f32, 0.3, 2.0]),
        0u8..16,
    )
}

proptest! {
    #![proptest_config(common::proptest_config(48, 2))]

    /// After every frame of any flight, the patched buffer draws what morphed emission
    /// writes, whatever the list's size (a small one overflows into full rewrites), the
    /// morph memory, the compactions, resets and hole moves between frames.
    #[test]
    fn edited_buffers_draw_what_emission_draws(
        max_morphs in 0u32..40,
        list in prop::sample::select(vec![1u32, 16, 4096]),
        frames in prop::collection::vec(frame(), 1..if cfg!(miri) { 4 } else { 30 }),
    ) {
        let h = golden_hierarchy();
        let mut views = common::views(&h, 6);
        views.extend((0..6).map(|k| approach(&h, k as f32 / 5.0)));
        let config = edit_config(&h, max_morphs, list);
        let mut memory = vec![0u32; CameraState::words_needed_for(&h, &config)];
        let mut cam = CameraState::with_config(&h, &mut memory, &config).expect("memory");
        let mut device = Device::new(&h, &cam);
        for &(v, dt_s, tolerance_px, action) in &frames {
            let p = RefineParams { dt_s, tolerance_px, ..RefineParams::default() };
            cam.refine(&h, &views[v], &p).expect("refine");
            match action {
                0 => cam.compact(&h),
                1 => cam.reset(&h),
                2..=5 => {
                    cam.compact_step(&h, u32::from(action) * 50);
                }
                6 => cam.finish_morphs(),
                _ => {}
            }
            device.update(&h, &mut cam, u32::from(action % 4) * 4);
            prop_assert_eq!(device.drawn(), emitted(&h, &cam));
            let drawn: u32 = device.draws.iter().map(|d| d.index_count / 3).sum();
            prop_assert!(drawn >= cam.active_polygon_count());
        }
        // Holes close at the moves' pace (no more a call than its list has room to mark):
        // enough calls leave none.
        let mut drawn = u32::MAX;
        for _ in 0..cam.index_places() {
            device.update(&h, &mut cam, u32::MAX / 2);
            drawn = device.draws.iter().map(|d| d.index_count / 3).sum();
            if drawn == cam.active_polygon_count() {
                break;
            }
        }
        prop_assert_eq!(drawn, cam.active_polygon_count());
        prop_assert_eq!(device.drawn(), emitted(&h, &cam));
    }
}
