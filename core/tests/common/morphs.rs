//! Helpers of the geomorph tests: cameras with morph memory, views along one approach,
//! emission in both forms, and the invariants every morph must keep.

use std::collections::HashMap;

use caveclod_core::glam::Vec3;
use caveclod_core::gpu::{morph_chain, morph_slot_vertex, MorphSlices, MAX_MORPH_CHAIN};
use caveclod_core::{
    CameraConfig, CameraState, Hierarchy, LookAt, MorphVertex, NodeId, RefineParams, RefineStats,
    View,
};

/// A camera that can reach full resolution with room for `max_morphs` morphs.
pub fn morph_config(h: &Hierarchy<'_>, max_morphs: u32) -> CameraConfig {
    CameraConfig::full(h).with_morphs(max_morphs)
}

/// Memory for a camera with room for `max_morphs` morphs, with the configuration
/// ([`morph_config`]) it is sized for.
pub struct MorphMemory {
    config: CameraConfig,
    words: Vec<u32>,
}

impl MorphMemory {
    /// Memory for [`morph_config`]`(h, max_morphs)`.
    pub fn new(h: &Hierarchy<'_>, max_morphs: u32) -> Self {
        let config = morph_config(h, max_morphs);
        let words = vec![0u32; CameraState::words_needed_for(h, &config)];
        Self { config, words }
    }

    /// A [`morphing_camera`] in this memory.
    pub fn camera(&mut self, h: &Hierarchy<'_>) -> CameraState<'_> {
        morphing_camera(h, &mut self.words, &self.config)
    }
}

/// A camera with `config`'s memory that has drawn a first picture: its first pass, which
/// never morphs, looked away from the terrain, so the camera stands at its base mesh and its
/// next pass morphs what it splits.
pub fn morphing_camera<'m>(
    h: &Hierarchy<'_>,
    memory: &'m mut [u32],
    config: &CameraConfig,
) -> CameraState<'m> {
    let mut cam = CameraState::with_config(h, memory, config).expect("memory");
    let towards = approach_look(h, 50.0);
    let away = LookAt {
        target: towards.eye + (towards.eye - towards.target),
        ..towards
    };
    let st = cam
        .refine(h, &away.view(1280, 720), &RefineParams::default())
        .expect("refine");
    assert_eq!(
        st.splits, 0,
        "the terrain lies behind the first picture's eye"
    );
    cam
}

/// Views along one line towards the terrain: `k` from 0 (close, much detail) to 1 (far).
pub fn approach(h: &Hierarchy<'_>, k: f32) -> View {
    approach_look(h, 0.4 + 20.0 * k).view(1280, 720)
}

/// The look at the terrain's centre along that line from `distance` times its size.
pub fn approach_look(h: &Hierarchy<'_>, distance: f32) -> LookAt {
    let m = h.meta();
    let lo = Vec3::from_array(m.bounds_min);
    let hi = Vec3::from_array(m.bounds_max);
    let centre = (lo + hi) * 0.5;
    let size = (hi - lo).length().max(1e-3);
    let dir = Vec3::new(0.3, 0.8, 0.6).normalize();
    LookAt {
        eye: centre + dir * size * distance,
        target: centre,
        up: Vec3::Y,
        fov_y: 1.2,
        near: size * 1e-3,
        far: size * 100.0,
    }
}

/// Fine enough that the golden terrain refines deeply from close by, coarse enough that it
/// coarsens along the approach's far end.
pub fn fine() -> RefineParams {
    RefineParams {
        tolerance_px: 0.5,
        backface_culling: false,
        morph_speed_px_s: 0.0,
        // Cameras without morph memory, which the tests compare with, have no guard band.
        morph_guard_rad: 0.0,
        ..RefineParams::default()
    }
}

pub fn packed(h: &Hierarchy<'_>, cam: &CameraState<'_>, morphed: bool) -> (Vec<u32>, Vec<u32>) {
    let mut out = vec![u32::MAX; cam.total_index_count()];
    let mut offsets = vec![0u32; h.surface_count() + 1];
    let n = if morphed {
        cam.emit_indices_packed_morphed(h, &mut out, &mut offsets)
    } else {
        cam.emit_indices_packed(h, &mut out, &mut offsets)
    }
    .expect("emit");
    assert_eq!(n, out.len());
    (out, offsets)
}

pub fn sorted_front(cam: &CameraState<'_>) -> Vec<NodeId> {
    let mut v: Vec<NodeId> = cam.active_nodes().collect();
    v.sort();
    v
}

/// Each surface's triangles, sorted: the front's picture, whatever the slot order.
pub fn triangles(h: &Hierarchy<'_>, cam: &CameraState<'_>) -> Vec<Vec<[u32; 3]>> {
    surface_triangles(h, cam, false)
}

/// Each surface's triangles of packed emission (`morphed` or plain), sorted.
pub fn surface_triangles(
    h: &Hierarchy<'_>,
    cam: &CameraState<'_>,
    morphed: bool,
) -> Vec<Vec<[u32; 3]>> {
    let (out, offsets) = packed(h, cam, morphed);
    (0..h.surface_count())
        .map(|s| {
            let r = &out[offsets[s] as usize..offsets[s + 1] as usize];
            let mut t: Vec<[u32; 3]> = r.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
            t.sort_unstable();
            t
        })
        .collect()
}

/// The position each vertex stands at (from the vertex table).
pub fn position_of_vertex(h: &Hierarchy<'_>) -> Vec<u32> {
    let mut pos = vec![u32::MAX; h.vertices().len()];
    let parts = h.parts();
    for (p, w) in parts.vertex_table_offsets.windows(2).enumerate() {
        for key in &parts.vertex_table[w[0] as usize..w[1] as usize] {
            pos[key.vertex as usize] = p as u32;
        }
    }
    pos
}

/// What must hold of a camera's morphs after any pass:
/// - every live slot has `t` in [0, 1], its blend at `t` on the segment between where its
///   `from` is drawn and its `to`, `to` at the position of an active node, `coarse` at the
///   position of the parent whose split made that position's floating child, and `from`
///   naming `coarse`'s slot while `coarse` morphs (a chain within the limit), else `coarse`;
/// - morphed emission is the plain emission with exactly the morphing corners replaced by
///   `vertex_count + slot`.
///
/// Returns the number of morphs moving two vertices (a floating child on a seam).
pub fn check_morphs(h: &Hierarchy<'_>, cam: &CameraState<'_>, pos: &[u32]) -> usize {
    let vc = h.vertices().len();
    let slots = cam.morph_vertices();
    assert!(slots.len() <= 2 * cam.max_morphs() as usize);
    let live: Vec<(usize, &MorphVertex)> = slots
        .iter()
        .enumerate()
        .filter(|(_, m)| !m.is_idle())
        .collect();
    assert!(live.len() >= cam.morph_count() as usize);
    assert!(live.len() <= 2 * cam.morph_count() as usize);
    assert_eq!(cam.morph_count() == 0, slots.is_empty());
    let active_at: HashMap<u32, NodeId> = cam
        .active_nodes()
        .map(|n| (h.nodes()[n.index()].position.0, n))
        .collect();
    let mut slot_of = HashMap::new();
    for &(s, m) in &live {
        assert!(
            slot_of.insert(m.to, s).is_none(),
            "vertex {} in two slots",
            m.to
        );
    }
    let inputs = MorphSlices {
        vertices: h.vertices(),
        slots,
    };
    for &(s, m) in &live {
        assert!((0.0..=1.0).contains(&m.t), "slot {s}: t {}", m.t);
        assert!(
            (m.coarse as usize) < vc && (m.to as usize) < vc,
            "slot {s}: {m:?}"
        );
        // `from` is `coarse`, or the slot of `coarse` while that vertex morphs too.
        match slot_of.get(&m.coarse) {
            Some(&k) => assert_eq!(m.from as usize, vc + k, "slot {s}: {m:?}"),
            None => assert_eq!(m.from, m.coarse, "slot {s}: {m:?}"),
        }
        let chain = morph_chain(&inputs, s as u32).expect("a live slot").0;
        assert!(chain <= MAX_MORPH_CHAIN, "slot {s}: a chain of {chain}");
        // The blend lies on the segment from where `from` is drawn to `to`, at `t`.
        let start = if (m.from as usize) < vc {
            h.vertices()[m.from as usize]
        } else {
            morph_slot_vertex(&inputs, m.from - vc as u32).expect("a live slot")
        };
        let b = h.vertices()[m.to as usize];
        let p = Vec3::from_array(morph_slot_vertex(&inputs, s as u32).expect("live").position);
        let (pa, pb) = (
            Vec3::from_array(start.position),
            Vec3::from_array(b.position),
        );
        let ab = pb - pa;
        let along = if ab.length_squared() > 0.0 {
            ((p - pa).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let off = (p - (pa + ab * along)).length();
        assert!(
            off <= 1e-5 * (1.0 + pa.length().max(pb.length())),
            "slot {s}: {off}"
        );
        assert!((along - m.t).abs() <= 1e-4 || ab.length_squared() <= 1e-12);
        // `to` stands where an active node stands; walking up that node's stationary
        // ancestors (which share the position) reaches the floating child, whose parent
        // stands at `from`.
        let u = *active_at
            .get(&pos[m.to as usize])
            .unwrap_or_else(|| panic!("slot {s}: no active node at vertex {}", m.to));
        let mut child = u;
        let parent = loop {
            let p = h.nodes()[child.index()].parent;
            assert!(p != NodeId::NONE, "slot {s}: a root does not morph");
            if h.nodes()[p.index()].position != h.nodes()[u.index()].position {
                break p;
            }
            child = p;
        };
        assert_eq!(h.split(parent).map(|sp| sp.floating), Some(child));
        assert_eq!(pos[m.coarse as usize], h.nodes()[parent.index()].position.0);
        assert!(cam.is_split(parent));
    }
    let (plain, offsets) = packed(h, cam, false);
    let (morphed, morphed_offsets) = packed(h, cam, true);
    assert_eq!(offsets, morphed_offsets);
    for (k, (&i, &j)) in plain.iter().zip(&morphed).enumerate() {
        match slot_of.get(&i) {
            Some(&s) => assert_eq!(j as usize, vc + s, "index {k}"),
            None => assert_eq!(j, i, "index {k}"),
        }
    }
    slots
        .chunks_exact(2)
        .filter(|pair| pair.iter().all(|m| !m.is_idle()))
        .count()
}

/// Refines at `view` until a pass changes nothing and nothing morphs; returns the morphs
/// that finished on the way.
pub fn settle(h: &Hierarchy<'_>, cam: &mut CameraState<'_>, view: &View, p: &RefineParams) -> u32 {
    let mut finished = 0;
    for _ in 0..10_000 {
        let st = cam.refine(h, view, p).expect("refine");
        finished += st.morphs_finished;
        if st.operations() == 0 && st.morphing == 0 {
            return finished;
        }
    }
    panic!("refinement did not settle");
}

/// The stats without the morph counters.
pub fn without_morph_counts(s: RefineStats) -> RefineStats {
    RefineStats {
        morphs_started: 0,
        morphs_finished: 0,
        morphs_aborted: 0,
        morphs_dropped: 0,
        morphing: 0,
        ..s
    }
}

/// The parent whose split made the floating child that vertex `to` belongs to, and that
/// child (see `check_morphs`).
pub fn morph_pair(
    h: &Hierarchy<'_>,
    cam: &CameraState<'_>,
    pos: &[u32],
    to: u32,
) -> (NodeId, NodeId) {
    let u = cam
        .active_nodes()
        .find(|n| h.nodes()[n.index()].position.0 == pos[to as usize])
        .expect("an active node at the morphing vertex");
    let mut child = u;
    loop {
        let p = h.nodes()[child.index()].parent;
        if h.nodes()[p.index()].position != h.nodes()[u.index()].position {
            return (p, child);
        }
        child = p;
    }
}
