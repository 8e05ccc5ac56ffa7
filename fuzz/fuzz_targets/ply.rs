//! The in-memory importer of Stanford PLY, ascii and binary on arbitrary bytes: a typed error or a mesh that
//! validates, never a panic (the import's own panic guard does not hide one: the fuzzer's
//! panic hook aborts first).
#![no_main]

mod readers;

use caveclod_bake::import::ImportOptions;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = readers::import("fuzz.ply", data, &ImportOptions::default());
});
