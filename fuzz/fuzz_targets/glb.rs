//! The in-memory importer of binary glTF (GLB) (and an external buffer after a `#%side` line) on arbitrary bytes: a typed error or a mesh that
//! validates, never a panic (the import's own panic guard does not hide one: the fuzzer's
//! panic hook aborts first).
#![no_main]

mod readers;

use caveclod_bake::import::ImportOptions;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = readers::import("fuzz.glb", data, &ImportOptions::default());
});
