//! The streaming out-of-core readers (PLY when the first byte is even, OBJ when odd) and the
//! whole out-of-core simplification after them, with a small budget: a typed error or a mesh
//! that validates, never a panic.
#![no_main]

use std::path::PathBuf;

use caveclod_bake::ooc::{simplify, MultiresOptions, OocOptions};
use libfuzzer_sys::fuzz_target;

/// A file of this process's own under the temporary directory, rewritten for each input.
fn input_path(extension: &str) -> PathBuf {
    std::env::temp_dir().join(format!(
        "caveclod-fuzz-ooc-{}.{extension}",
        std::process::id()
    ))
}

fuzz_target!(|data: &[u8]| {
    let Some((&first, body)) = data.split_first() else {
        return;
    };
    let path = input_path(if first & 1 == 0 { "ply" } else { "obj" });
    std::fs::write(&path, body).expect("writing the input file");
    let options = OocOptions {
        threads: 1,
        leaf_triangles: 64,
        max_depth: 6,
        target_triangles: Some(32),
        octree: (first & 2 == 0).then(MultiresOptions::default),
        ..OocOptions::with_budget(1 << 20)
    };
    if let Ok(s) = simplify(&path, &options, &mut |_| {}) {
        if let Err(e) = s.mesh.validate() {
            panic!("the simplified mesh does not validate: {e}");
        }
    }
    let _ = std::fs::remove_file(&path);
});
