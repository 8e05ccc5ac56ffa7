//! A view-independent cut of a baked hierarchy with a polygon budget, chosen through
//! caveclod-core's public API only: from the base mesh, repeatedly force-split the active node
//! with the largest `uni_error` (a max-heap over the front); a node whose forced split would
//! take the front past the target is skipped with its subtree, and the selection goes on with
//! smaller errors, so the cut has exactly or just under the target count. Its triangles are
//! those `emit_indices_packed` writes.

use std::collections::BinaryHeap;

use caveclod_core::{CameraState, Hierarchy, NodeId};

use crate::distance::Soup;

/// Splits `node` would force (itself, its missing ancestors, and the creators of missing
/// neighbours, recursively) into `out`; returns the polygons they add.
fn forced(
    h: &Hierarchy<'_>,
    cam: &CameraState<'_>,
    node: NodeId,
    out: &mut Vec<NodeId>,
    seen: &mut [u32],
    epoch: u32,
) -> usize {
    out.clear();
    let mut todo = vec![node];
    let mut added = 0;
    while let Some(u) = todo.pop() {
        if cam.is_split(u) || seen[u.index()] == epoch {
            continue;
        }
        seen[u.index()] = epoch;
        out.push(u);
        let s = h.split(u).expect("a creator or an ancestor has a split");
        added += 1 + usize::from(s.f_r.is_some());
        let parent = h.node(u).expect("node").parent;
        if parent.is_some() {
            todo.push(parent);
        }
        for f in s.neighbours {
            if let Some((c, _)) = f.creator(h.base_polygon_count() as u32) {
                todo.push(c);
            }
        }
    }
    added
}

/// Total order on `f32` for the heap.
#[derive(Clone, Copy)]
struct Ordered(f32);
impl PartialEq for Ordered {
    fn eq(&self, o: &Self) -> bool {
        self.0.total_cmp(&o.0).is_eq()
    }
}
impl Eq for Ordered {}
impl PartialOrd for Ordered {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Ordered {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}

/// The view-independent cut of `h` with at most `target` triangles: its triangles.
pub fn our_cut(h: &Hierarchy<'_>, target: usize) -> Soup {
    let mut memory = vec![0u32; CameraState::words_needed(h)];
    let mut cam = CameraState::new(h, &mut memory).expect("camera");
    let mut heap: BinaryHeap<(Ordered, NodeId)> = cam
        .active_nodes()
        .filter_map(|v| Some((Ordered(h.split_bounds(v)?.uni_error), v)))
        .collect();
    let mut stack = vec![NodeId::NONE; 1 << 16];
    let (mut out, mut seen, mut epoch) = (Vec::new(), vec![0u32; h.node_count()], 0u32);
    while let Some((_, v)) = heap.pop() {
        if cam.is_split(v) {
            continue;
        }
        epoch += 1;
        let before = cam.active_polygon_count() as usize;
        let added = forced(h, &cam, v, &mut out, &mut seen, epoch);
        if before + added > target {
            continue;
        }
        cam.force_split(h, v, &mut stack).expect("force_split");
        assert_eq!(cam.active_polygon_count() as usize, before + added);
        for &u in &out {
            let s = h.split(u).expect("split");
            for c in [s.stationary, s.floating] {
                if let Some(b) = h.split_bounds(c) {
                    if !cam.is_split(c) {
                        heap.push((Ordered(b.uni_error), c));
                    }
                }
            }
        }
        if before + added == target {
            break;
        }
    }
    let ns = h.surface_count();
    let mut indices = vec![0u32; (0..ns).map(|s| cam.index_count(s)).sum()];
    let mut offsets = vec![0u32; ns + 1];
    cam.emit_indices_packed(h, &mut indices, &mut offsets)
        .expect("emit");
    let v = h.vertices();
    indices
        .chunks_exact(3)
        .map(|t| [0, 1, 2].map(|k| v[t[k] as usize].position))
        .collect()
}
