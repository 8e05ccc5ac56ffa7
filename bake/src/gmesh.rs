//! g-mesh levels (Southern & Gain) from a baked hierarchy: batches of independent collapses,
//! each level's connectivity `c_i` and geomorph pairs `(a_i, a'_i)`, normalised volumes and
//! volume-based partitions, stored as the `GM..` sections `caveclod_core::gmesh::GMesh` reads.
//!
//! # Batches
//! The paper's batched hierarchy collapses the cheapest queued edge, drops every queued edge
//! touching the retained vertex, and when the queue is empty writes a level and rebuilds the
//! queue. Over our vertex hierarchy a queued edge is a split node whose two children are both
//! on the current front; cost is its quadric-based error bound (`uni_error`). A batch walks
//! the nodes queued at its start in cost order and collapses each one that is legal at that
//! moment (Hoppe's preconditions, checked by caveclod-core's camera front); collapses made in
//! the batch create new front nodes, which never are children of queued nodes, so no vertex
//! moves twice in one batch — the paper's independence rule. Levels are the fronts between
//! batches, so every level is exactly a cut of the view-dependent hierarchy and its vertices
//! are vertices of the persistent vertex buffer.
//!
//! # Volume
//! `V = Σ A_⊥ · h̄` over triangles: the signed area projected along an axis times the mean
//! height of the corners above the lowest point on that axis. For a closed mesh this is the
//! enclosed volume whatever the axis (divergence theorem); for an open mesh — a terrain — with
//! the axis of least extent (up, for a terrain) it is the volume under the surface, the
//! substitute the paper's Section 5.3 needs for open meshes. `V_i = V(c_i) / V(c_0)`.

use caveclod_core::format::ExtraSection;
use caveclod_core::gmesh::{gmesh_tags, volume_boundaries, GMesh, GMeshError, GMeshParts};
use caveclod_core::{CameraState, Hierarchy, NodeId, PolyId};

use crate::base::fxhash::FxHashMap;

/// How far to simplify.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GMeshOptions {
    /// Stop once a level has at most this many polygons (0: `|c_0| / 64`).
    pub min_polygons: u32,
    /// At most this many levels (at least 2).
    pub max_levels: u32,
    /// Smallest share of the `T` range any level gets (see `volume_boundaries`).
    pub min_share: f32,
}

impl Default for GMeshOptions {
    fn default() -> Self {
        Self {
            min_polygons: 0,
            max_levels: 12,
            min_share: 0.02,
        }
    }
}

/// Why the g-mesh levels could not be built.
#[derive(Debug, thiserror::Error)]
pub enum GMeshBuildError {
    /// The hierarchy is invalid (a baker bug).
    #[error("internal error: the baked hierarchy does not validate: {0}")]
    Hierarchy(#[from] caveclod_core::FormatError),
    /// The camera front refused an operation (a baker bug).
    #[error("internal error while building g-mesh levels: {0}")]
    Front(String),
    /// A morph target has no vertex for its surface group (a baker bug).
    #[error("internal error: node {node} has no vertex for surface group {group}")]
    MissingVertex {
        /// The node.
        node: u32,
        /// The group.
        group: u16,
    },
    /// The mesh cannot be simplified at all, so there is no second level.
    #[error("the mesh has no legal collapse, so it has a single level; a g-mesh needs two")]
    SingleLevel,
    /// The partitions could not be made.
    #[error("g-mesh partitions: {0}")]
    Partitions(GMeshError),
}

/// The g-mesh arrays, owned.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GMeshData {
    /// `|c_i|` per level.
    pub level_polygons: Vec<u32>,
    /// `R_i` per level.
    pub boundaries: Vec<f32>,
    /// `V_i` per level.
    pub volumes: Vec<f32>,
    /// Offsets into `vertices` per level, plus one.
    pub vertex_offsets: Vec<u32>,
    /// Offsets into `indices` per (level, surface), plus one.
    pub index_offsets: Vec<u32>,
    /// `(from, to)` vertex-buffer indices.
    pub vertices: Vec<[u32; 2]>,
    /// Local indices.
    pub indices: Vec<u32>,
}

impl GMeshData {
    /// Borrowed arrays.
    pub fn parts(&self) -> GMeshParts<'_> {
        GMeshParts {
            level_polygons: &self.level_polygons,
            boundaries: &self.boundaries,
            volumes: &self.volumes,
            vertex_offsets: &self.vertex_offsets,
            index_offsets: &self.index_offsets,
            vertices: &self.vertices,
            indices: &self.indices,
        }
    }

    /// The extra sections to write beside the hierarchy.
    pub fn sections(&self) -> Vec<ExtraSection<'_>> {
        use gmesh_tags as t;
        let s = |tag, record_size, bytes| ExtraSection {
            tag,
            record_size,
            bytes,
        };
        vec![
            s(t::POLYGONS, 4, bytemuck::cast_slice(&self.level_polygons)),
            s(t::BOUNDARIES, 4, bytemuck::cast_slice(&self.boundaries)),
            s(t::VOLUMES, 4, bytemuck::cast_slice(&self.volumes)),
            s(
                t::VERTEX_OFFSETS,
                4,
                bytemuck::cast_slice(&self.vertex_offsets),
            ),
            s(
                t::INDEX_OFFSETS,
                4,
                bytemuck::cast_slice(&self.index_offsets),
            ),
            s(t::VERTICES, 8, bytemuck::cast_slice(&self.vertices)),
            s(t::INDICES, 4, bytemuck::cast_slice(&self.indices)),
        ]
    }

    /// Number of levels.
    pub fn levels(&self) -> usize {
        self.level_polygons.len()
    }
}

/// One recorded front polygon.
#[derive(Clone, Copy)]
struct FrontPoly {
    corners: [NodeId; 3],
    surface: u16,
    group: u16,
}

fn front_polygons(h: &Hierarchy<'_>, cam: &CameraState<'_>) -> Vec<FrontPoly> {
    let polys = h.polygons();
    cam.active_polygons(h)
        .filter_map(|f: PolyId| {
            let corners = cam.polygon_corners(h, f)?;
            let p = polys.get(f.index())?;
            Some(FrontPoly {
                corners,
                surface: p.surface.0,
                group: p.group.0,
            })
        })
        .collect()
}

/// `Σ A_⊥ · h̄` (see the module docs) along `axis` above `base`.
fn volume(h: &Hierarchy<'_>, polys: &[FrontPoly], axis: usize, base: f32) -> f64 {
    let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut v = 0.0f64;
    for p in polys {
        let q = p
            .corners
            .map(|n| h.node_point(n).unwrap_or([0.0; 3]).map(f64::from));
        let area = 0.5
            * ((q[1][a] - q[0][a]) * (q[2][b] - q[0][b])
                - (q[2][a] - q[0][a]) * (q[1][b] - q[0][b]));
        let height = (q[0][axis] + q[1][axis] + q[2][axis]) / 3.0 - f64::from(base);
        v += area * height;
    }
    v
}

/// Builds the g-mesh levels of a baked hierarchy.
///
/// The passes: the front at full detail, then level after level: the front's polygons
/// written with where each vertex moves, a batch of the cheapest legal collapses applied,
/// until no collapse is legal or the level budget is spent; then the volume boundaries and
/// the validation a reader applies.
pub fn build(h: &Hierarchy<'_>, options: &GMeshOptions) -> Result<GMeshData, GMeshBuildError> {
    let mut memory = vec![0u32; CameraState::words_needed(h)];
    let mut cam =
        CameraState::new(h, &mut memory).map_err(|e| GMeshBuildError::Front(e.to_string()))?;
    split_everything(h, &mut cam)?;
    let (axis, base) = volume_axis(h);
    let mut out = GMeshData::default();
    let surfaces = h.surface_count();
    out.vertex_offsets.push(0);
    out.index_offsets.push(0);
    let mut v0 = 0.0f64;
    let mut moved = vec![NodeId::NONE; h.node_count()];
    loop {
        let polys = front_polygons(h, &cam);
        let level = out.level_polygons.len();
        if level == 0 {
            v0 = volume(h, &polys, axis, base);
        }
        let min_polygons = if options.min_polygons == 0 {
            (polys.len() as u32 / 64).max(1)
        } else {
            options.min_polygons
        };
        let last_allowed = level + 1 >= options.max_levels.max(2) as usize;
        let batch = if polys.len() as u32 <= min_polygons || last_allowed {
            Vec::new()
        } else {
            collapse_batch(h, &mut cam)
        };
        // Where each node of this level goes: its parent if the batch collapsed it.
        mark_moved(h, &batch, &mut moved, true);
        write_level(h, &polys, &moved, &mut out)?;
        let v = volume(h, &polys, axis, base);
        out.volumes
            .push(if v0 != 0.0 { (v / v0) as f32 } else { 1.0 });
        mark_moved(h, &batch, &mut moved, false);
        if batch.is_empty() {
            break;
        }
    }
    if out.levels() < 2 {
        return Err(GMeshBuildError::SingleLevel);
    }
    out.boundaries = vec![0.0; out.levels()];
    volume_boundaries(&out.volumes, options.min_share, &mut out.boundaries)
        .map_err(GMeshBuildError::Partitions)?;
    // The same validation a reader applies.
    GMesh::new(out.parts(), h.vertices().len(), surfaces)
        .map_err(|e| GMeshBuildError::Front(e.to_string()))?;
    Ok(out)
}

/// Full detail: nodes are numbered parents first, so one pass splits everything.
fn split_everything(h: &Hierarchy<'_>, cam: &mut CameraState<'_>) -> Result<(), GMeshBuildError> {
    for i in 0..h.splits().len() {
        let v = NodeId(i as u32);
        if !cam.is_split(v) {
            cam.force_split_own_stack(h, v)
                .map_err(|e| GMeshBuildError::Front(e.to_string()))?;
        }
    }
    Ok(())
}

/// The volume axis: least extent (up for a terrain; any axis for a closed mesh), and the
/// lowest coordinate along it.
fn volume_axis(h: &Hierarchy<'_>) -> (usize, f32) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in h.positions() {
        for k in 0..3 {
            lo[k] = lo[k].min(p.xyz[k]);
            hi[k] = hi[k].max(p.xyz[k]);
        }
    }
    let axis = (0..3)
        .min_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
        .unwrap_or(2);
    (axis, lo[axis])
}

/// The batch: the splits whose children are both active leaves of the front, cheapest
/// first, each collapsed if legal; the collapsed ones.
fn collapse_batch(h: &Hierarchy<'_>, cam: &mut CameraState<'_>) -> Vec<NodeId> {
    let mut queue: Vec<(f32, NodeId)> = cam
        .active_nodes()
        .filter_map(|n| h.node(n).map(|node| node.parent))
        .filter(|&p| p != NodeId::NONE)
        .filter(|&p| {
            h.split(p).is_some_and(|s| {
                !cam.is_split(s.stationary)
                    && !cam.is_split(s.floating)
                    && cam.is_node_active(h, s.stationary)
                    && cam.is_node_active(h, s.floating)
            })
        })
        .filter_map(|p| h.split_bounds(p).map(|b| (b.uni_error, p)))
        .collect();
    queue.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1 .0.cmp(&b.1 .0)));
    queue.dedup_by_key(|e| e.1);
    // Sweeps until nothing more is legal: a collapse can make a neighbour's legal (its faces
    // get back the neighbours its split recorded).
    let mut batch: Vec<NodeId> = Vec::new();
    loop {
        let before = batch.len();
        queue.retain(|&(_, p)| {
            if cam.can_collapse(h, p) && cam.collapse(h, p).is_ok() {
                batch.push(p);
                false
            } else {
                true
            }
        });
        if batch.len() == before {
            break;
        }
    }
    batch
}

/// Records (or, with `set` false, clears) the batch's children as moving to their parent.
fn mark_moved(h: &Hierarchy<'_>, batch: &[NodeId], moved: &mut [NodeId], set: bool) {
    for &p in batch {
        if let Some(s) = h.split(p) {
            let to = if set { p } else { NodeId::NONE };
            moved[s.stationary.index()] = to;
            moved[s.floating.index()] = to;
        }
    }
}

/// One level: local vertices keyed by their vertex-buffer index (each with the vertex it
/// moves to), indices by surface.
fn write_level(
    h: &Hierarchy<'_>,
    polys: &[FrontPoly],
    moved: &[NodeId],
    out: &mut GMeshData,
) -> Result<(), GMeshBuildError> {
    let target = |n: NodeId| match moved.get(n.index()) {
        Some(&m) if m != NodeId::NONE => m,
        _ => n,
    };
    let mut local: FxHashMap<u32, u32> = FxHashMap::default();
    let mut by_surface: Vec<Vec<u32>> = vec![Vec::new(); h.surface_count()];
    let vertex_of = |n: NodeId, group: u16| -> Result<u32, GMeshBuildError> {
        let pos = h.node(n).map(|node| node.position);
        pos.and_then(|pos| h.vertex_index(caveclod_core::SurfaceGroupId(group), pos))
            .ok_or(GMeshBuildError::MissingVertex { node: n.0, group })
    };
    for p in polys {
        for &n in &p.corners {
            let from = vertex_of(n, p.group)?;
            let next = local.len() as u32;
            let idx = match local.get(&from) {
                Some(&i) => i,
                None => {
                    let to = vertex_of(target(n), p.group)?;
                    local.insert(from, next);
                    out.vertices.push([from, to]);
                    next
                }
            };
            if let Some(list) = by_surface.get_mut(usize::from(p.surface)) {
                list.push(idx);
            }
        }
    }
    for list in &by_surface {
        out.indices.extend_from_slice(list);
        out.index_offsets.push(out.indices.len() as u32);
    }
    out.vertex_offsets.push(out.vertices.len() as u32);
    out.level_polygons.push(polys.len() as u32);
    Ok(())
}
