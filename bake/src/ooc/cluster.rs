//! Vertex clustering with generalized quadrics over position, normal, UV and colour.
//!
//! Every corner falls in a cell of a grid of `resolution` cells per axis over the input's
//! bounding cube (at a power of two, the octree's cells at that depth; in between, so that
//! the output size can be aimed closer than a factor of four). Inside a cell, corners are grouped into *clusters* that
//! never mix surfaces and never join the two sides of a UV seam: a corner joins the cell's
//! cluster of its surface whose UV, predicted at the cell centre, is close to its own
//! prediction (the prediction extends the corner's triangle's affine UV map to the cell
//! centre, so corners of one chart agree and the sides of a seam, which map the same point to
//! different places of the texture, do not). Every triangle's generalized quadric
//! ([`super::quadric`]) is added to the clusters of its three corners.
//!
//! The representatives: a cell's position is the minimiser of the sum of its clusters'
//! quadrics (so the clusters of one cell, on different surfaces or seam sides, share their
//! position and the output has no cracks there), and each cluster's normal, UV and colour
//! minimise its own quadric with the position held there. Positions and attributes are in
//! cell units (the attributes scaled by [`Weights`]), so the weights mean the same at every
//! level. A triangle survives when its corners fall in three different cells, once per set
//! of three cells.
//!
//! Memory is proportional to the output (clusters and surviving triangles), never to the
//! input: the soup streams through [`Clusterer::add`] leaf by leaf.

use super::quadric::{Quadric, DIM};
use super::soup::{decode_normal, Cube, SoupTriangle, HAS_COLOR, HAS_NORMAL, HAS_UV};
use crate::base::colour::srgb8_table;
use crate::base::fxhash::{FxHashMap, FxHashSet};
use crate::mesh::{Mesh, Surface, Triangle, NO_ATTRIBUTE};

/// Attribute weights, in cell units per unit of the attribute.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weights {
    /// Normals (unit vectors).
    pub normal: f64,
    /// Texture coordinates.
    pub uv: f64,
    /// Linear RGBA in 0..=1.
    pub color: f64,
}

impl Default for Weights {
    fn default() -> Self {
        Self {
            normal: 0.5,
            uv: 4.0,
            color: 0.5,
        }
    }
}

/// How to cluster.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClusterOptions {
    /// Cells per axis of the bounding cube (1 to 2^21).
    pub resolution: u32,
    /// Attribute weights.
    pub weights: Weights,
    /// UV distance (in either coordinate) beyond which two corners' predictions are two sides
    /// of a seam. Predictions are exact for UV maps affine across the cell; a curved map
    /// splits a chart's corners into more clusters than needed at coarse resolutions (a few
    /// percent more vertices, no cracks: the clusters of a cell share its position).
    pub seam_tolerance: f32,
    /// Record each input corner's cluster ([`Clusterer::corner_clusters`]), for tests.
    pub record_corners: bool,
}

impl ClusterOptions {
    /// Defaults at `2^level` cells per axis.
    pub fn at_level(level: u32) -> Self {
        Self::at_resolution(1 << level.min(21))
    }

    /// Defaults at `resolution` cells per axis.
    pub fn at_resolution(resolution: u32) -> Self {
        Self {
            resolution,
            weights: Weights::default(),
            seam_tolerance: 0.05,
            record_corners: false,
        }
    }
}

/// One cluster: the corners of one surface (and one side of any UV seam) in one cell.
#[derive(Clone)]
pub(super) struct Cluster {
    /// Index of its cell.
    pub(super) cell: u32,
    /// Its surface.
    pub(super) surface: u16,
    /// Which attributes its corners carry (`HAS_*`).
    pub(super) flags: u16,
    /// Next cluster of the same cell (`u32::MAX` ends the list).
    pub(super) next: u32,
    /// The UV its corners predict at the cell centre.
    pub(super) uv_ref: [f32; 2],
    /// Sum of the quadrics of the triangles at its corners.
    pub(super) quadric: Quadric,
    /// Sum of its corners as points of R^n.
    pub(super) sum: [f64; DIM],
    /// Number of corners.
    pub(super) corners: f64,
    /// Box of its corners' positions, cell units.
    pub(super) lo: [f64; 3],
    /// Box of its corners' positions, cell units.
    pub(super) hi: [f64; 3],
}

impl Cluster {
    /// The mean of its corners.
    pub(super) fn mean(&self) -> [f64; DIM] {
        self.sum.map(|s| s / self.corners.max(1.0))
    }
}

/// The clusters of a cell's list starting at `first` (linked by [`Cluster::next`]).
pub(super) fn cluster_list(clusters: &[Cluster], first: u32) -> impl Iterator<Item = &Cluster> {
    let mut k = first;
    std::iter::from_fn(move || {
        let c = clusters.get(k as usize)?;
        k = c.next;
        Some(c)
    })
}

/// The representative position of a cell from its clusters' quadrics: the quadric optimum,
/// or the corners' mean where the optimum lies outside the cell by more than half a cell (a
/// poorly conditioned solve). `lo` is the cell's low corner and `size` its edge, in the
/// quadrics' units.
pub(super) fn cell_position<'a>(
    clusters: impl Iterator<Item = &'a Cluster>,
    lo: [f64; 3],
    size: f64,
) -> [f64; 3] {
    let mut q = Quadric::default();
    let mut sum = [0.0; DIM];
    let mut n = 0.0;
    for c in clusters {
        q.add_scaled(&c.quadric, 1.0);
        for a in 0..DIM {
            sum[a] += c.sum[a];
        }
        n += c.corners;
    }
    let mean = sum.map(|s| s / f64::max(n, 1.0));
    let x = q.minimize(&mean);
    let x = if (0..3).any(|a| (x[a] - (lo[a] + 0.5 * size)).abs() > size) {
        mean
    } else {
        x
    };
    [x[0], x[1], x[2]]
}

/// A cluster's normal, UV and colour: the minimiser of its quadric with the position held at
/// its cell's representative, unweighted (normal normalised; `+z` where it vanishes).
pub(super) fn cluster_attributes(
    c: &Cluster,
    position: [f64; 3],
    w: &Weights,
) -> ([f32; 3], [f32; 2], [f32; 4]) {
    let x = c.quadric.minimize_given(position, &c.mean());
    let n = [x[3], x[4], x[5]].map(|v| v / w.normal);
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let normal = if len > 1e-12 {
        n.map(|v| (v / len) as f32)
    } else {
        [0.0, 0.0, 1.0]
    };
    let uv = [(x[6] / w.uv) as f32, (x[7] / w.uv) as f32];
    let color = [8, 9, 10, 11].map(|a| ((x[a] / w.color).clamp(0.0, 1.0)) as f32);
    (normal, uv, color)
}

/// Accumulates clusters over a stream of triangles.
pub struct Clusterer {
    pub(super) cube: Cube,
    pub(super) options: ClusterOptions,
    /// Cells per unit of length.
    pub(super) scale: f64,
    cells: FxHashMap<u64, u32>,
    /// Each cell's first cluster.
    pub(super) cell_first: Vec<u32>,
    /// Each cell's integer coordinates.
    pub(super) cell_coords: Vec<[u32; 3]>,
    pub(super) clusters: Vec<Cluster>,
    /// Surviving triangles: cells, clusters, surface.
    pub(super) triangles: Vec<([u32; 3], [u32; 3], u16)>,
    seen: FxHashSet<[u32; 3]>,
    corner_clusters: Vec<u32>,
    srgb: [f32; 256],
    input: u64,
    degenerate: u64,
}

/// The cell id of integer cell coordinates (unique per level up to 21).
fn cell_id(c: [u32; 3]) -> u64 {
    u64::from(c[0]) | u64::from(c[1]) << 21 | u64::from(c[2]) << 42
}

impl Clusterer {
    /// A clusterer on `cube`.
    pub fn new(cube: Cube, options: ClusterOptions) -> Self {
        let resolution = options.resolution.clamp(1, 1 << 21);
        // A weight of zero would lose the attribute; a tiny one keeps it without influence.
        let w = options.weights;
        let weights = Weights {
            normal: w.normal.max(1e-6),
            uv: w.uv.max(1e-6),
            color: w.color.max(1e-6),
        };
        Self {
            cube,
            options: ClusterOptions {
                resolution,
                weights,
                ..options
            },
            scale: f64::from(resolution) / cube.size,
            cells: FxHashMap::default(),
            cell_first: Vec::new(),
            cell_coords: Vec::new(),
            clusters: Vec::new(),
            triangles: Vec::new(),
            seen: FxHashSet::default(),
            corner_clusters: Vec::new(),
            srgb: srgb8_table(),
            input: 0,
            degenerate: 0,
        }
    }

    /// The clusters of the cell whose first cluster is `first`.
    pub(super) fn cell_clusters(&self, first: u32) -> impl Iterator<Item = &Cluster> {
        cluster_list(&self.clusters, first)
    }

    /// Clusters so far.
    pub fn cluster_count(&self) -> usize {
        self.clusters.len()
    }

    /// Triangles kept so far.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Triangles added so far.
    pub fn input_triangles(&self) -> u64 {
        self.input
    }

    /// The cluster of every corner added, three per triangle in order (when
    /// [`ClusterOptions::record_corners`]).
    pub fn corner_clusters(&self) -> &[u32] {
        &self.corner_clusters
    }

    /// The corner as a point of R^n.
    fn point(&self, t: &SoupTriangle, k: usize) -> [f64; DIM] {
        let c = &t.corners[k];
        let w = &self.options.weights;
        let mut v = [0.0; DIM];
        for a in 0..3 {
            v[a] = (f64::from(c.position[a]) - self.cube.origin[a]) * self.scale;
        }
        if t.flags & HAS_NORMAL != 0 {
            let n = decode_normal(c.normal);
            for a in 0..3 {
                v[3 + a] = w.normal * f64::from(n[a]);
            }
        }
        if t.flags & HAS_UV != 0 {
            v[6] = w.uv * f64::from(c.uv[0]);
            v[7] = w.uv * f64::from(c.uv[1]);
        }
        if t.flags & HAS_COLOR != 0 {
            for a in 0..3 {
                v[8 + a] = w.color * f64::from(self.srgb[usize::from(c.color[a])]);
            }
            v[11] = w.color * f64::from(c.color[3]) / 255.0;
        }
        v
    }

    /// The cell of a point in cell units, and its id.
    fn cell_of(&self, p: &[f64; DIM]) -> [u32; 3] {
        // Truncation is the floor for the non-negative coordinates inside the cube.
        let top = self.options.resolution - 1;
        [0, 1, 2].map(|a| (p[a].max(0.0) as u32).min(top))
    }

    /// Adds one triangle.
    pub fn add(&mut self, t: &SoupTriangle) {
        self.input += 1;
        let p = [self.point(t, 0), self.point(t, 1), self.point(t, 2)];
        let cells = [
            self.cell_of(&p[0]),
            self.cell_of(&p[1]),
            self.cell_of(&p[2]),
        ];
        // UV prediction: the triangle's affine UV map at each corner's cell centre.
        let (d1, d2) = (sub3(&p[1], &p[0]), sub3(&p[2], &p[0]));
        let (g11, g12, g22) = (dot3(d1, d1), dot3(d1, d2), dot3(d2, d2));
        let det = g11 * g22 - g12 * g12;
        let uv = |k: usize| t.corners[k].uv.map(f64::from);
        let (u0, u1, u2) = (uv(0), uv(1), uv(2));
        let du1 = [u1[0] - u0[0], u1[1] - u0[1]];
        let du2 = [u2[0] - u0[0], u2[1] - u0[1]];
        let has_uv = t.flags & HAS_UV != 0;
        let affine = has_uv && det > 1e-12 * (g11 * g22).max(f64::MIN_POSITIVE);
        let mut ids = [0u32; 3];
        for k in 0..3 {
            let pred = if affine {
                let c = [0, 1, 2].map(|a| f64::from(cells[k][a]) + 0.5);
                let x = [c[0] - p[0][0], c[1] - p[0][1], c[2] - p[0][2]];
                let (r1, r2) = (dot3(d1, x), dot3(d2, x));
                let s = (g22 * r1 - g12 * r2) / det;
                let u = (g11 * r2 - g12 * r1) / det;
                [
                    (u0[0] + s * du1[0] + u * du2[0]) as f32,
                    (u0[1] + s * du1[1] + u * du2[1]) as f32,
                ]
            } else {
                t.corners[k].uv
            };
            ids[k] = self.cluster_for(cells[k], t.surface, t.flags, has_uv, pred);
        }
        if self.options.record_corners {
            self.corner_clusters.extend_from_slice(&ids);
        }
        match Quadric::triangle(&p) {
            Some(q) => {
                if ids[0] == ids[1] && ids[1] == ids[2] {
                    self.clusters[ids[0] as usize].quadric.add_scaled(&q, 3.0);
                } else {
                    for id in ids {
                        self.clusters[id as usize].quadric.add_scaled(&q, 1.0);
                    }
                }
            }
            None => self.degenerate += 1,
        }
        for k in 0..3 {
            let c = &mut self.clusters[ids[k] as usize];
            for a in 0..DIM {
                c.sum[a] += p[k][a];
            }
            for a in 0..3 {
                c.lo[a] = c.lo[a].min(p[k][a]);
                c.hi[a] = c.hi[a].max(p[k][a]);
            }
            c.corners += 1.0;
        }
        let cs = ids.map(|i| self.clusters[i as usize].cell);
        if cs[0] != cs[1] && cs[1] != cs[2] && cs[0] != cs[2] {
            let mut key = cs;
            key.sort_unstable();
            if self.seen.insert(key) {
                self.triangles.push((cs, ids, t.surface));
            }
        }
    }

    fn cluster_for(
        &mut self,
        cell: [u32; 3],
        surface: u16,
        flags: u16,
        has_uv: bool,
        uv: [f32; 2],
    ) -> u32 {
        let id = cell_id(cell);
        let next_cell = self.cell_first.len() as u32;
        let ci = *self.cells.entry(id).or_insert(next_cell);
        if ci == next_cell {
            self.cell_first.push(u32::MAX);
            self.cell_coords.push(cell);
        }
        let tol = self.options.seam_tolerance;
        let mut k = self.cell_first[ci as usize];
        while k != u32::MAX {
            let c = &mut self.clusters[k as usize];
            if c.surface == surface
                && (!has_uv
                    || c.flags & HAS_UV == 0
                    || ((c.uv_ref[0] - uv[0]).abs() <= tol && (c.uv_ref[1] - uv[1]).abs() <= tol))
            {
                c.flags |= flags;
                if has_uv && c.flags & HAS_UV == 0 {
                    c.uv_ref = uv;
                }
                return k;
            }
            k = c.next;
        }
        let k = self.clusters.len() as u32;
        self.clusters.push(Cluster {
            cell: ci,
            surface,
            flags,
            next: self.cell_first[ci as usize],
            uv_ref: uv,
            quadric: Quadric::default(),
            sum: [0.0; DIM],
            corners: 0.0,
            lo: [f64::MAX; 3],
            hi: [f64::MIN; 3],
        });
        self.cell_first[ci as usize] = k;
        k
    }

    /// Makes room for `clusters` more clusters (in as many cells) and `triangles` more
    /// triangles at once, before merging others: growing by doubling would leave the
    /// outgrown arrays' memory to the allocator at the peak.
    pub(super) fn reserve(&mut self, clusters: usize, triangles: usize) {
        self.clusters.reserve_exact(clusters);
        self.cell_first.reserve_exact(clusters);
        self.cell_coords.reserve_exact(clusters);
        self.cells.reserve(clusters);
        self.triangles.reserve_exact(triangles);
        self.seen.reserve(triangles);
    }

    /// Adds the clusters and triangles of `other` (same cube and options), which clustered
    /// other triangles: clusters of a cell and surface whose UV references agree are summed.
    pub fn merge(&mut self, other: &Clusterer) {
        let mut map = Vec::with_capacity(other.clusters.len());
        for c in &other.clusters {
            let cell = other.cell_coords[c.cell as usize];
            let has_uv = c.flags & HAS_UV != 0;
            let k = self.cluster_for(cell, c.surface, c.flags, has_uv, c.uv_ref);
            let d = &mut self.clusters[k as usize];
            d.quadric.add_scaled(&c.quadric, 1.0);
            for a in 0..DIM {
                d.sum[a] += c.sum[a];
            }
            d.corners += c.corners;
            for a in 0..3 {
                d.lo[a] = d.lo[a].min(c.lo[a]);
                d.hi[a] = d.hi[a].max(c.hi[a]);
            }
            map.push(k);
        }
        for &(_, ids, surface) in &other.triangles {
            let ids = ids.map(|i| map[i as usize]);
            let cs = ids.map(|i| self.clusters[i as usize].cell);
            let mut key = cs;
            key.sort_unstable();
            if self.seen.insert(key) {
                self.triangles.push((cs, ids, surface));
            }
        }
        self.corner_clusters
            .extend(other.corner_clusters.iter().map(|&i| map[i as usize]));
        self.input += other.input;
        self.degenerate += other.degenerate;
    }

    /// The clustered mesh: one position per cell, one normal / UV / colour per cluster.
    pub fn finish(&self, surfaces: &[Surface]) -> Mesh {
        let w = self.options.weights;
        let unit = 1.0 / self.scale;
        let mut mesh = Mesh {
            surfaces: surfaces.to_vec(),
            ..Default::default()
        };
        let mut cell_pos = Vec::with_capacity(self.cell_first.len());
        for (ci, &first) in self.cell_first.iter().enumerate() {
            let lo = self.cell_coords[ci].map(f64::from);
            let x = cell_position(self.cell_clusters(first), lo, 1.0);
            cell_pos.push(x);
            mesh.positions
                .push([0, 1, 2].map(|a| (self.cube.origin[a] + x[a] * unit) as f32));
        }
        for c in &self.clusters {
            let (normal, uv, color) = cluster_attributes(c, cell_pos[c.cell as usize], &w);
            mesh.normals.push(normal);
            mesh.uvs.push(uv);
            mesh.colors.push(color);
        }
        for &(cells, ids, surface) in &self.triangles {
            let attr = |flag: u16| {
                ids.map(|i| {
                    if self.clusters[i as usize].flags & flag != 0 {
                        i
                    } else {
                        NO_ATTRIBUTE
                    }
                })
            };
            let all = |a: [u32; 3]| {
                if a.contains(&NO_ATTRIBUTE) {
                    [NO_ATTRIBUTE; 3]
                } else {
                    a
                }
            };
            mesh.triangles.push(Triangle {
                position: cells,
                normal: all(attr(HAS_NORMAL)),
                uv: all(attr(HAS_UV)),
                color: all(attr(HAS_COLOR)),
                surface,
            });
        }
        if !self.clusters.iter().any(|c| c.flags & HAS_NORMAL != 0) {
            mesh.normals.clear();
        }
        if !self.clusters.iter().any(|c| c.flags & HAS_UV != 0) {
            mesh.uvs.clear();
        }
        if !self.clusters.iter().any(|c| c.flags & HAS_COLOR != 0) {
            mesh.colors.clear();
        }
        mesh
    }
}

fn sub3(a: &[f64; DIM], b: &[f64; DIM]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
