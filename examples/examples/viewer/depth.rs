//! Colour by hierarchy depth: a camera's active polygons regrouped on the CPU into bands of
//! depth (the deepest hierarchy level among each polygon's three active corner nodes), one
//! index list per band, drawn as if each band were a surface with a colour of its own.
//!
//! caveclod-core keeps no vertex→depth map: a vertex belongs to a (surface group, position)
//! and a position to a chain of nodes, so the depth is taken from the camera's front
//! instead (its polygons' active corner nodes) with node depths derived once at load from
//! the nodes' parent links.

use caveclod_core::{CameraState, Hierarchy, NodeId};

/// Bands of depth drawn (fewer when the hierarchy is shallower).
const MAX_BANDS: usize = 12;

/// Node depths and the per-band index lists of the last regrouping.
pub struct DepthBands {
    /// Per node: edges from its root.
    depth: Vec<u32>,
    /// One more than the largest depth.
    levels: u32,
    lists: Vec<Vec<u32>>,
}

impl DepthBands {
    /// Every node's depth, from the parent links (each chain walked once).
    pub fn new(h: &Hierarchy<'_>) -> Result<Self, String> {
        let nodes = h.nodes();
        const UNKNOWN: u32 = u32::MAX;
        let mut depth = vec![UNKNOWN; nodes.len()];
        let mut chain = Vec::new();
        for start in 0..nodes.len() {
            let mut at = start;
            // Up to the first node of known depth (or past the root).
            let base = loop {
                if depth[at] != UNKNOWN {
                    break depth[at];
                }
                chain.push(at);
                if chain.len() > nodes.len() {
                    return Err(format!("node {start}: its parent links form a cycle"));
                }
                match nodes[at].parent.get() {
                    Some(p) if p.index() < nodes.len() => at = p.index(),
                    Some(p) => return Err(format!("node {at}: parent {} out of range", p.0)),
                    None => break u32::MAX, // one above a root: the root gets depth 0
                }
            };
            for (k, &n) in chain.iter().rev().enumerate() {
                depth[n] = base.wrapping_add(1 + k as u32);
            }
            chain.clear();
        }
        let levels = depth.iter().copied().max().map_or(1, |d| d + 1);
        let bands = (levels as usize).clamp(1, MAX_BANDS);
        Ok(Self {
            depth,
            levels,
            lists: vec![Vec::new(); bands],
        })
    }

    /// No depths: for a file whose nodes are not all at hand (a paged one), which is not
    /// coloured by depth.
    pub fn none() -> Self {
        Self {
            depth: Vec::new(),
            levels: 1,
            lists: vec![Vec::new()],
        }
    }

    /// Bands (index lists) drawn.
    pub fn band_count(&self) -> usize {
        self.lists.len()
    }

    /// Hierarchy levels (longest root-to-leaf path plus one).
    pub fn levels(&self) -> u32 {
        self.levels
    }

    /// The band of a depth: levels spread evenly over the bands.
    fn band(&self, depth: u32) -> usize {
        let bands = self.lists.len() as u64;
        ((u64::from(depth) * bands / u64::from(self.levels.max(1))) as usize)
            .min(self.lists.len() - 1)
    }

    /// Regroups `cam`'s active polygons into the bands' index lists (vertex indices of the
    /// hierarchy's vertex buffer, in the polygons' corner order).
    pub fn regroup(&mut self, h: &Hierarchy<'_>, cam: &CameraState<'_>) -> Result<(), String> {
        for l in &mut self.lists {
            l.clear();
        }
        for poly in cam.active_polygons(h) {
            let corners = cam
                .polygon_corners(h, poly)
                .ok_or_else(|| format!("polygon {}: active but without corners", poly.0))?;
            let group = h
                .polygons()
                .get(poly.index())
                .ok_or_else(|| format!("polygon {}: out of range", poly.0))?
                .group;
            let mut tri = [0u32; 3];
            let mut deepest = 0;
            for (k, &node) in corners.iter().enumerate() {
                tri[k] = vertex_of(h, group, node)
                    .ok_or_else(|| format!("polygon {} corner {k}: no vertex", poly.0))?;
                deepest = deepest.max(self.depth.get(node.index()).copied().unwrap_or(0));
            }
            let band = self.band(deepest);
            self.lists[band].extend_from_slice(&tri);
        }
        Ok(())
    }

    /// The bands' index lists of the last [`regroup`](Self::regroup).
    pub fn lists(&self) -> Vec<&[u32]> {
        self.lists.iter().map(Vec::as_slice).collect()
    }

    /// A colour per band: blue for the coarsest, through green and yellow, to red for the
    /// finest.
    pub fn colours(&self) -> Vec<[f32; 4]> {
        let n = self.lists.len();
        (0..n)
            .map(|b| {
                let t = if n > 1 {
                    b as f32 / (n - 1) as f32
                } else {
                    0.0
                };
                caveclod_host::hue(240.0 * (1.0 - t), 0.15)
            })
            .collect()
    }
}

/// The vertex-buffer index of `node`'s position in surface group `group`.
fn vertex_of(h: &Hierarchy<'_>, group: caveclod_core::SurfaceGroupId, node: NodeId) -> Option<u32> {
    h.vertex_index(group, h.node(node)?.position)
}

#[cfg(test)]
mod tests {
    use super::*;
    use caveclod_core::RefineParams;

    /// A triangle with its smallest index first, winding kept.
    fn canonical(t: &[u32]) -> [u32; 3] {
        let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
        [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
    }

    #[test]
    fn bands_hold_the_emitted_triangles_and_depths_follow_parents() {
        let baked = caveclod_tests::bake(&caveclod_tests::meshes::terrain(24, 24, 7));
        let h = baked.hierarchy();
        let mut memory = vec![0u32; CameraState::words_needed(&h)];
        let mut cam = CameraState::new(&h, &mut memory).unwrap();
        let look = caveclod_host::orbit(&h, 1)[0];
        let params = RefineParams {
            tolerance_px: 0.5,
            ..RefineParams::default()
        };
        cam.refine(&h, &look.view(256, 256), &params).unwrap();
        let mut indices = vec![0u32; cam.total_index_count()];
        let mut offsets = vec![0u32; h.surface_count() + 1];
        cam.emit_indices_packed(&h, &mut indices, &mut offsets)
            .unwrap();

        let mut bands = DepthBands::new(&h).unwrap();
        bands.regroup(&h, &cam).unwrap();
        let mut emitted: Vec<[u32; 3]> = indices.chunks(3).map(canonical).collect();
        let mut grouped: Vec<[u32; 3]> = bands
            .lists()
            .iter()
            .flat_map(|l| l.chunks(3))
            .map(canonical)
            .collect();
        emitted.sort_unstable();
        grouped.sort_unstable();
        assert!(!emitted.is_empty());
        assert_eq!(grouped, emitted, "the bands are not the emitted front");
        let used = bands.lists().iter().filter(|l| !l.is_empty()).count();
        assert!(used > 1, "a refined front spans several bands, got {used}");

        for (i, n) in h.nodes().iter().enumerate() {
            let want = n.parent.get().map_or(0, |p| bands.depth[p.index()] + 1);
            assert_eq!(bands.depth[i], want, "node {i}");
        }
        assert_eq!(bands.levels(), h.meta().max_depth + 1);
    }
}
