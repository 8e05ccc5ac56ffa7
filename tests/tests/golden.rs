//! The golden file `core/tests/data/terrain6.clod`, which the core crate's integration tests
//! use, and its copy `fuzz/seeds/from_bytes/terrain6.clod`, the fuzzer's seed, are exactly
//! what `caveclod-bake` makes of `terrain(6, 6, 1)`.
//!
//! After an intended change to the baker or the format, regenerate both with
//! `CAVECLOD_UPDATE_GOLDEN=1 cargo test -p caveclod-tests --test golden` and commit them.

use std::path::PathBuf;

use caveclod_core::Hierarchy;
use caveclod_tests::{bake, meshes};

/// The golden file and its copies, relative to the workspace root.
const GOLDEN_FILES: [&str; 2] = [
    "core/tests/data/terrain6.clod",
    "fuzz/seeds/from_bytes/terrain6.clod",
];

fn workspace_path(relative: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(relative)
}

fn updating() -> bool {
    std::env::var_os("CAVECLOD_UPDATE_GOLDEN").is_some_and(|v| v == "1")
}

#[test]
fn terrain6_matches_the_golden_file() {
    let baked = bake(&meshes::terrain(6, 6, 1));
    let bytes = baked.to_bytes();
    // Whatever is committed must load.
    Hierarchy::from_bytes(&bytes).expect("the baked bytes are a valid hierarchy");

    for relative in GOLDEN_FILES {
        let path = workspace_path(relative);
        if updating() {
            std::fs::create_dir_all(path.parent().expect("a parent directory")).expect("mkdir");
            let tmp = path.with_extension("clod.tmp");
            std::fs::write(&tmp, &bytes[..]).expect("write the golden file");
            std::fs::rename(&tmp, &path).expect("rename the golden file");
            eprintln!("wrote {relative} ({} bytes)", bytes.len());
            continue;
        }
        let golden = std::fs::read(&path).unwrap_or_else(|e| {
            panic!("cannot read {relative}: {e}; create it with CAVECLOD_UPDATE_GOLDEN=1")
        });
        if golden[..] != bytes[..] {
            let first = golden
                .iter()
                .zip(bytes.iter())
                .position(|(a, b)| a != b)
                .unwrap_or(golden.len().min(bytes.len()));
            panic!(
                "the baked output of terrain(6, 6, 1) differs from {relative}: {} bytes \
                 baked, {} golden, first difference at byte {first}. If the change is \
                 intended, rerun with CAVECLOD_UPDATE_GOLDEN=1 and commit the files.",
                bytes.len(),
                golden.len()
            );
        }
    }
}

#[test]
fn the_bake_is_deterministic() {
    let a = bake(&meshes::terrain(6, 6, 1)).to_bytes();
    let b = bake(&meshes::terrain(6, 6, 1)).to_bytes();
    assert!(a[..] == b[..], "two bakes of the same mesh differ");
}
