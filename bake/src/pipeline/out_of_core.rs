//! The bake of a file of any size: simplified out of core ([`crate::ooc::simplify`]) to a mesh
//! that fits the memory budget, then baked in core.

use std::path::Path;
use std::time::Instant;

use super::built::{source_dir, Built};
use super::error::BakeError;
use super::in_core::build_mesh;
use crate::baked::Baked;
use crate::base::progress::Stage;
use crate::ooc::{self, MultiresOctree, OocOptions, OocStage, OocStats};
use crate::report::BakeInfo;

/// What [`bake_out_of_core`] makes.
#[derive(Debug)]
pub struct OutOfCoreBake {
    /// The view-dependent hierarchy over the clustered mesh.
    pub baked: Baked,
    /// About the bake (`input_triangles` counts the file's triangles).
    pub info: BakeInfo,
    /// About the out-of-core simplification.
    pub stats: OocStats,
    /// The multiresolution octree over every clustering level, when the options ask for it.
    pub octree: Option<MultiresOctree>,
}

/// What [`build_out_of_core`] makes: [`OutOfCoreBake`] up to the arrays.
#[derive(Debug)]
pub struct OutOfCoreBuild {
    /// The clustered mesh's bake up to its arrays (`info.input_triangles` counts the file's
    /// triangles).
    pub built: Built,
    /// About the out-of-core simplification.
    pub stats: OocStats,
    /// The multiresolution octree over every clustering level, when the options ask for it.
    pub octree: Option<MultiresOctree>,
}

/// Simplifies a file of any size out of core ([`crate::ooc::simplify`]) to a mesh that fits
/// the memory budget, then bakes that mesh in core; `bake_seconds` covers both. The
/// multiresolution octree (if [`crate::ooc::OocOptions::octree`]) describes the same surfaces
/// as the hierarchy.
pub fn bake_out_of_core(
    path: &Path,
    options: &OocOptions,
    ooc_progress: &mut dyn FnMut(OocStage),
    progress: &mut dyn FnMut(Stage),
) -> Result<OutOfCoreBake, BakeError> {
    let o = build_out_of_core(path, options, ooc_progress, progress)?;
    let (baked, info) = o.built.assemble(progress)?;
    Ok(OutOfCoreBake {
        baked,
        info,
        stats: o.stats,
        octree: o.octree,
    })
}

/// [`bake_out_of_core`] up to the arrays.
pub fn build_out_of_core(
    path: &Path,
    options: &OocOptions,
    ooc_progress: &mut dyn FnMut(OocStage),
    progress: &mut dyn FnMut(Stage),
) -> Result<OutOfCoreBuild, BakeError> {
    let start = Instant::now();
    let s = ooc::simplify(path, options, ooc_progress)?;
    let mut built = build_mesh(&s.mesh, &path.display().to_string(), progress)?;
    built.start = start;
    built.texture_dir = source_dir(path);
    drop(s.mesh);
    let mut octree = s.octree;
    if let Some(o) = &mut octree {
        o.surface_count = built.welded.surface_count;
    }
    let info = &mut built.info;
    info.input_triangles = s.stats.input_triangles;
    info.repairs.skipped_primitives = s.stats.skipped_primitives;
    if s.stats.skipped_primitives > 0 {
        info.notes.push(format!(
            "{}: {} faces with fewer than 3 corners skipped",
            path.display(),
            s.stats.skipped_primitives
        ));
    }
    info.bake_seconds = start.elapsed().as_secs_f64();
    Ok(OutOfCoreBuild {
        built,
        stats: s.stats,
        octree,
    })
}
