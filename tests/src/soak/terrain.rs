//! The soak's terrain: the St. Helens DEM the demo flies over (in the repository's `data/`),
//! imported and baked by `caveclod-bake` as `caveclod bake` does, whole or cropped to a
//! window round its centre (the crater) so a debug build bakes it in seconds; or a `.clod`
//! file baked before.

use std::path::{Path, PathBuf};

use caveclod_bake::import::{import, ImportOptions};
use caveclod_bake::mesh::{Mesh, NO_ATTRIBUTE};
use caveclod_bake::pipeline::bake_mesh;
use caveclod_io::AlignedBytes;

/// The St. Helens DEM in the repository's `data/terrain`.
pub fn st_helens() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/terrain/SainteHelens.dem")
}

/// Imports the heightfield or mesh at `path` and keeps the triangles inside the centred
/// window of `share` of its extent along x and z (1 keeps everything).
pub fn terrain_mesh(path: &Path, share: f32) -> Result<Mesh, String> {
    let mesh = import(path, &ImportOptions::default()).map_err(|e| e.to_string())?;
    if share >= 1.0 {
        return Ok(mesh);
    }
    let mut lo = [f32::INFINITY; 2];
    let mut hi = [f32::NEG_INFINITY; 2];
    for p in &mesh.positions {
        for (k, &c) in [p[0], p[2]].iter().enumerate() {
            lo[k] = lo[k].min(c);
            hi[k] = hi[k].max(c);
        }
    }
    let inside = |p: &[f32; 3]| {
        [p[0], p[2]].iter().enumerate().all(|(k, &c)| {
            let centre = 0.5 * (lo[k] + hi[k]);
            (c - centre).abs() <= 0.5 * share * (hi[k] - lo[k])
        })
    };
    Ok(crop(&mesh, |t| {
        t.position
            .iter()
            .all(|&i| inside(&mesh.positions[i as usize]))
    }))
}

/// The triangles `keep` accepts, with only the attributes they use.
fn crop(mesh: &Mesh, keep: impl Fn(&caveclod_bake::mesh::Triangle) -> bool) -> Mesh {
    let mut out = Mesh {
        surfaces: mesh.surfaces.clone(),
        ..Mesh::default()
    };
    let mut maps = [
        vec![NO_ATTRIBUTE; mesh.positions.len()],
        vec![NO_ATTRIBUTE; mesh.normals.len()],
        vec![NO_ATTRIBUTE; mesh.uvs.len()],
        vec![NO_ATTRIBUTE; mesh.colors.len()],
    ];
    for t in mesh.triangles.iter().filter(|t| keep(t)) {
        let mut t = *t;
        for k in 0..3 {
            t.position[k] = remap(
                &mut maps[0],
                t.position[k],
                &mesh.positions,
                &mut out.positions,
            );
            t.normal[k] = remap(&mut maps[1], t.normal[k], &mesh.normals, &mut out.normals);
            t.uv[k] = remap(&mut maps[2], t.uv[k], &mesh.uvs, &mut out.uvs);
            t.color[k] = remap(&mut maps[3], t.color[k], &mesh.colors, &mut out.colors);
        }
        out.triangles.push(t);
    }
    out
}

/// The new index of attribute `i` (copied on first use); `NO_ATTRIBUTE` stays.
fn remap<T: Copy>(map: &mut [u32], i: u32, from: &[T], to: &mut Vec<T>) -> u32 {
    if i == NO_ATTRIBUTE {
        return i;
    }
    let m = &mut map[i as usize];
    if *m == NO_ATTRIBUTE {
        *m = to.len() as u32;
        to.push(from[i as usize]);
    }
    *m
}

/// The `.clod` bytes of the terrain at `path` cropped to `share` (see [`terrain_mesh`]),
/// baked with the default options.
pub fn bake_terrain(path: &Path, share: f32) -> Result<AlignedBytes, String> {
    let mesh = terrain_mesh(path, share)?;
    let (baked, _) =
        bake_mesh(&mesh, &path.display().to_string(), &mut |_| {}).map_err(|e| e.to_string())?;
    let bytes = baked.to_bytes(&[]).map_err(|e| e.to_string())?;
    Ok(AlignedBytes::from_slice(&bytes))
}

/// A `.clod` file's bytes, aligned for [`caveclod_core::Hierarchy::from_bytes`].
pub fn load_clod(path: &Path) -> Result<AlignedBytes, String> {
    AlignedBytes::read(path).map_err(|e| e.to_string())
}
