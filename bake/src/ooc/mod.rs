//! Out-of-core simplification: inputs of any size down to a mesh that fits a memory budget.
//!
//! The method is Lindstrom's out-of-core vertex clustering (OoCS) organised around an octree,
//! with Garland & Heckbert's 1998 generalized quadrics so that normals, colours and texture
//! coordinates are preserved along with the shape:
//!
//! 1. [`stream`]: the input (PLY, OBJ) is opened and its vertices read once (binary PLY
//!    vertices stay in the input, others go to a temporary file), looked up through a bounded
//!    cache; its faces can then be streamed as a triangle soup ([`soup`]) as often as needed,
//!    each triangle carrying everything later stages need and a spatial key (the Morton code
//!    of its centroid);
//! 2. [`sort`]: a first pass over the faces sorts only the keys into runs (a thread sorts and
//!    writes one chunk while the reader fills the next) and merges them into one file,
//!    counting the occupied octree cells at every depth;
//! 3. [`octree`]: the sorted keys are the octree's storage: each node is a range of them;
//!    nodes split until a leaf holds at most a set number of triangles or the maximum depth;
//! 4. [`pass`], [`cluster`]: a second pass over the faces clusters the triangles as they
//!    come, dealt out by key to fixed parts of the octree's leaves, a thread per group of
//!    parts; corners are clustered on a grid whose resolution the occupied-cell counts say
//!    will make the output fit the target, with one quadric per cluster ([`quadric`]);
//!    clusters never span surfaces or UV seams; representatives are quadric optima;
//! 5. [`multires`]: every coarser level is derived from the finest clustering by summing its
//!    clusters' quadrics into the parent cells' clusters (exactly what clustering the input on
//!    the coarser grid would give, without reading it again), and the levels are cut into
//!    octree nodes stored as `OC..` sections of the `.clod` file, which
//!    `caveclod_core::octree` selects per camera by projected error.
//!
//! Two passes over the faces with keys alone on disk, rather than one pass that writes every
//! triangle's record to sorted runs: writing temporary files is what a large bake spends its
//! time on (fresh pages of the page cache), while reading the input again is cheap, and a key
//! is 8 bytes where a triangle's record is 96 ([`soup`]).
//!
//! The finest level is an ordinary [`Mesh`], which [`crate::pipeline::bake_out_of_core`] hands
//! to the in-core pipeline for the view-dependent hierarchy. The target size comes from the
//! budget ([`target_triangles_for_budget`]): the in-core hierarchy build needs about a
//! kilobyte per triangle. Memory: the two key chunks (half the budget), the vertex cache (an
//! eighth), the merge buffers (a quarter, after the chunks are freed), then the clusters
//! (proportional to the output). Every temporary file lives in one [`TempSpace`] directory,
//! removed when the simplification returns, with an error or without.
//!
//! In-memory meshes (glTF, which is not streamed) take the same clustering through
//! [`cluster_mesh`].

pub mod cluster;
mod error;
pub mod multires;
pub mod octree;
mod options;
pub mod pass;
pub mod quadric;
pub mod sort;
pub mod soup;
pub mod stream;

use std::path::Path;
use std::time::Instant;

pub use crate::base::memory::peak_rss_bytes;
pub use crate::base::temp::{self, parse_size, TempSpace};
pub use cluster::{ClusterOptions, Clusterer, Weights};
pub use error::OocError;
pub use multires::{MultiresOctree, MultiresOptions};
pub use options::{OocOptions, OocStage};

use crate::base::colour::encode_colour;
use crate::mesh::{Mesh, NO_ATTRIBUTE};
pub use soup::Cube;
use soup::{encode_normal, Corner, SoupTriangle, KEY_LEVELS};

/// Output triangles whose in-core hierarchy build fits `budget`: 1,600 bytes a triangle,
/// the in-core build's peak per triangle with room for the clustering beside it.
pub fn target_triangles_for_budget(budget: u64) -> u64 {
    (budget / 1600).max(16)
}

/// What a run did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OocStats {
    /// Triangles read.
    pub input_triangles: u64,
    /// Vertices read.
    pub input_vertices: u64,
    /// Triangles of the clustered mesh.
    pub output_triangles: u64,
    /// Clusters (output vertices).
    pub clusters: u64,
    /// Grid cells per axis clustered at.
    pub resolution: u32,
    /// Target the level was chosen for.
    pub target_triangles: u64,
    /// Octree nodes and leaves.
    pub octree_nodes: u64,
    /// Leaves.
    pub octree_leaves: u64,
    /// Sorted runs.
    pub runs: u64,
    /// Bytes written to temporary files.
    pub temp_bytes: u64,
    /// Seconds reading (and making runs), merging, clustering.
    pub seconds: [f64; 3],
    /// Levels of the multiresolution octree (0 when not built).
    pub lod_levels: u32,
    /// Nodes of the multiresolution octree.
    pub lod_nodes: u64,
    /// Seconds building it (included in the clustering seconds).
    pub lod_seconds: f64,
    /// Faces with fewer than three corners, skipped while reading.
    pub skipped_primitives: u64,
}

/// What [`simplify`] makes.
#[derive(Clone, Debug)]
pub struct Simplified {
    /// The clustered mesh at the target size (the finest level).
    pub mesh: Mesh,
    /// The multiresolution octree over every level, if asked for.
    pub octree: Option<MultiresOctree>,
    /// What the run did.
    pub stats: OocStats,
}

/// Simplifies the mesh in `path` (`.ply` or `.obj`) out of core.
pub fn simplify_file(
    path: &Path,
    options: &OocOptions,
    progress: &mut dyn FnMut(OocStage),
) -> Result<(Mesh, OocStats), OocError> {
    let options = OocOptions {
        octree: None,
        ..options.clone()
    };
    simplify(path, &options, progress).map(|s| (s.mesh, s.stats))
}

/// Simplifies the mesh in `path` (`.ply` or `.obj`) out of core, with the multiresolution
/// octree when [`OocOptions::octree`] asks for it.
///
/// The passes: the input's vertices read, its keys streamed into sorted runs, the octree over
/// the sorted keys, a first grid resolution from the occupied-cell counts, the faces read again
/// and clustered by parts of the leaves on the threads (again on a coarser grid while the
/// output is far above the target), then the finest level's mesh and the coarser levels.
pub fn simplify(
    path: &Path,
    options: &OocOptions,
    progress: &mut dyn FnMut(OocStage),
) -> Result<Simplified, OocError> {
    let budget = options.memory_budget;
    check_leaf_budget(options)?;
    let temp = TempSpace::new(options.temp_dir.as_deref(), options.temp_quota)
        .map_err(|e| OocError::temp("creating the temporary directory", e))?;
    let mut stats = OocStats::default();
    let name = path.display().to_string();
    let mut input = stream::open(path, &name, &temp, (budget / 8) as usize)?;
    let (report, sorted) = sort_keys(&mut input, &temp, budget, progress, &mut stats)?;
    let file = std::fs::File::open(&sorted.keys)
        .map_err(|e| OocError::temp("reading the sorted keys", e))?;
    let tree = octree::Octree::build(
        &file,
        sorted.triangles,
        options.leaf_triangles,
        options.max_depth,
    )?;
    let leaves = tree.leaves();
    stats.octree_nodes = tree.nodes.len() as u64;
    stats.octree_leaves = leaves.len() as u64;
    let target = options
        .target_triangles
        .unwrap_or_else(|| target_triangles_for_budget(budget));
    stats.target_triangles = target;
    let mut resolution = first_resolution(&sorted, target);
    let t1 = Instant::now();
    let clustering = pass::Clustering::new(sorted.cube, &leaves, sorted.triangles, options);
    let c = loop {
        let c = clustering.cluster(&mut input, resolution, progress)?;
        // The occupancy of centroids only estimates the output: go coarser when it came out
        // far above the target.
        if c.triangle_count() as u64 > 2 * target && resolution > 2 {
            resolution = resolution * 7 / 10;
            continue;
        }
        break c;
    };
    drop(input);
    stats.clusters = c.cluster_count() as u64;
    let mesh = c.finish(&report.surfaces);
    let t2 = Instant::now();
    let octree = options
        .octree
        .map(|o| multires::build(c, report.surfaces.len() as u32, &o));
    if let Some(o) = &octree {
        stats.lod_levels = o.level_count;
        stats.lod_nodes = o.nodes.len() as u64;
        stats.lod_seconds = t2.elapsed().as_secs_f64();
    }
    stats.resolution = resolution;
    stats.output_triangles = mesh.triangles.len() as u64;
    stats.seconds[2] = t1.elapsed().as_secs_f64();
    stats.temp_bytes = temp.used();
    drop(file);
    drop(temp);
    Ok(Simplified {
        mesh,
        octree,
        stats,
    })
}

/// An octree leaf, with the sort chunk and caches around it, must fit the budget.
fn check_leaf_budget(options: &OocOptions) -> Result<(), OocError> {
    let budget = options.memory_budget;
    let leaf_bytes = options.leaf_triangles * soup::RECORD_BYTES as u64;
    if leaf_bytes * 8 > budget {
        return Err(OocError::Budget {
            budget,
            what: format!(
                "an octree leaf of {} triangles (with the sort chunk and caches around it)",
                options.leaf_triangles
            ),
            needed: leaf_bytes * 8,
            hint: " or lower --leaf-triangles",
        });
    }
    Ok(())
}

/// The first pass: the input's keys streamed into sorted runs (the sort chunks: half the
/// budget; the vertex cache: an eighth) and merged (a quarter); the input counts and stage
/// times in `stats`.
fn sort_keys(
    input: &mut stream::Input<'_>,
    temp: &TempSpace,
    budget: u64,
    progress: &mut dyn FnMut(OocStage),
    stats: &mut OocStats,
) -> Result<(stream::StreamReport, sort::SortedSoup), OocError> {
    let t0 = Instant::now();
    let (report, sorted) = {
        let mut sort_progress = |merging, d, n| {
            progress(if merging {
                OocStage::Merge(d, n)
            } else {
                OocStage::Read(d, n)
            })
        };
        let mut runs =
            sort::RunBuilder::<u64>::new(temp, (budget / 2) as usize, &mut sort_progress);
        let report = input.faces(&mut runs)?;
        stats.seconds[0] = t0.elapsed().as_secs_f64();
        let sorted = runs.finish((budget / 4) as usize)?;
        (report, sorted)
    };
    stats.seconds[1] = t0.elapsed().as_secs_f64() - stats.seconds[0];
    if sorted.triangles == 0 {
        return Err(OocError::Empty {
            file: input.name().to_string(),
        });
    }
    stats.input_triangles = sorted.triangles;
    stats.input_vertices = report.vertices;
    stats.skipped_primitives = report.skipped_faces;
    stats.runs = sorted.runs.len() as u64;
    Ok((report, sorted))
}

/// The grid resolution to cluster at first: the finest octree depth whose occupied cells
/// (about half the output triangles) fit the target, then a resolution between it and the
/// next depth by the surface's square law; the finest grid when the input already fits.
fn first_resolution(sorted: &sort::SortedSoup, target: u64) -> u32 {
    if sorted.triangles <= target {
        return 1 << KEY_LEVELS;
    }
    let l = (1..=KEY_LEVELS)
        .rev()
        .find(|&l| 2 * sorted.occupied[l as usize] <= target)
        .unwrap_or(1);
    let f = (target as f64 / (2 * sorted.occupied[l as usize]).max(1) as f64).sqrt();
    ((f64::from(1u32 << l) * f.min(2.0)) as u32).max(2)
}

/// The bounding cube of a mesh's positions.
pub fn mesh_cube(mesh: &Mesh) -> Cube {
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for p in &mesh.positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    Cube::around(lo, hi)
}

/// The soup of an in-memory mesh, keyed on `cube` (the adapter for formats that are not
/// streamed).
pub fn mesh_soup(mesh: &Mesh, cube: &Cube) -> Vec<SoupTriangle> {
    mesh.triangles
        .iter()
        .map(|t| {
            let has = |i: [u32; 3]| !i.contains(&NO_ATTRIBUTE);
            let mut flags = 0;
            if has(t.normal) {
                flags |= soup::HAS_NORMAL;
            }
            if has(t.uv) {
                flags |= soup::HAS_UV;
            }
            if has(t.color) {
                flags |= soup::HAS_COLOR;
            }
            let corners: [Corner; 3] = std::array::from_fn(|k| {
                let mut c = Corner {
                    position: mesh.positions[t.position[k] as usize],
                    color: [255; 4],
                    ..Default::default()
                };
                if flags & soup::HAS_NORMAL != 0 {
                    c.normal = encode_normal(mesh.normals[t.normal[k] as usize]);
                }
                if flags & soup::HAS_UV != 0 {
                    c.uv = mesh.uvs[t.uv[k] as usize];
                }
                if flags & soup::HAS_COLOR != 0 {
                    c.color = encode_colour(mesh.colors[t.color[k] as usize]);
                }
                c
            });
            SoupTriangle {
                key: cube.key(&corners.map(|c| c.position)),
                surface: t.surface,
                flags,
                corners,
            }
        })
        .collect()
}

/// Clusters an in-memory mesh (glTF and other formats that are not streamed) with the same
/// clustering as [`simplify_file`], triangles in their order; returns the clustered mesh
/// and the clusterer (for [`Clusterer::corner_clusters`]).
pub fn cluster_mesh(mesh: &Mesh, options: ClusterOptions) -> (Mesh, Clusterer) {
    cluster_mesh_in(mesh, mesh_cube(mesh), options)
}

/// [`cluster_mesh`] on a given cube (which should contain the mesh).
pub fn cluster_mesh_in(mesh: &Mesh, cube: Cube, options: ClusterOptions) -> (Mesh, Clusterer) {
    let soup = mesh_soup(mesh, &cube);
    let mut c = Clusterer::new(cube, options);
    for t in &soup {
        c.add(t);
    }
    (c.finish(&mesh.surfaces), c)
}
