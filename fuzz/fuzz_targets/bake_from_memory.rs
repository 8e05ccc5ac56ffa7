//! Whatever imports, baked: the first byte picks the format (OBJ, PLY, glTF, GLB, DEM, npy),
//! the rest is the input (with a side file after a `#%side` line, as the reader targets);
//! a mesh that imports (at most 4,096 triangles, to keep runs fast) goes through the welder,
//! surface groups and hierarchy builder, is written as `.clod` bytes and loaded back with
//! `Hierarchy::from_bytes`. The bake may refuse the mesh with a typed error; it must never
//! panic, and what it makes must load.
#![no_main]

mod readers;

use caveclod_bake::import::ImportOptions;
use caveclod_bake::pipeline::{bake_mesh, BakeError};
use caveclod_core::Hierarchy;
use libfuzzer_sys::fuzz_target;

const FORMATS: [&str; 6] = ["obj", "ply", "gltf", "glb", "dem", "npy"];
const MOST_TRIANGLES: usize = 4096;

fuzz_target!(|data: &[u8]| {
    let Some((&first, body)) = data.split_first() else {
        return;
    };
    let format = FORMATS[usize::from(first) % FORMATS.len()];
    let options = ImportOptions {
        spacing: matches!(format, "npy").then_some(1.0),
    };
    let Ok((mesh, _)) = readers::import(&format!("fuzz.{format}"), body, &options) else {
        return;
    };
    if mesh.triangles.len() > MOST_TRIANGLES {
        return;
    }
    let baked = match bake_mesh(&mesh, "fuzz", &mut |_| {}) {
        Ok((baked, _)) => baked,
        Err(BakeError::Invalid(e)) => panic!("the baked hierarchy does not validate: {e}"),
        Err(_) => return,
    };
    let bytes = baked.to_bytes(&[]).expect("writing the baked hierarchy");
    let mut words = vec![0u64; bytes.len().div_ceil(8)];
    bytemuck::cast_slice_mut::<u64, u8>(&mut words)[..bytes.len()].copy_from_slice(&bytes);
    let aligned = &bytemuck::cast_slice::<u64, u8>(&words)[..bytes.len()];
    if let Err(e) = Hierarchy::from_bytes(aligned) {
        panic!("the baked file does not load: {e:?}");
    }
});
