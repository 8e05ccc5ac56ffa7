//! The in-memory importer of USGS ASCII DEM (with the header's spacing, or 30 m when the first byte is odd, for arc-second headers) on arbitrary bytes: a typed error or a mesh that
//! validates, never a panic (the import's own panic guard does not hide one: the fuzzer's
//! panic hook aborts first).
#![no_main]

mod readers;

use caveclod_bake::import::ImportOptions;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = readers::import(
        "fuzz.dem",
        data,
        &ImportOptions {
            spacing: (data.first().is_some_and(|b| b & 1 == 1)).then_some(30.0),
        },
    );
});
