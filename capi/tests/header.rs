//! The committed header `include/caveclod.h` is what cbindgen generates from the sources:
//! this test fails on any drift (a signature, a struct, a doc comment). With
//! `CAVECLOD_BLESS_HEADER=1` it writes the generated header instead (`cargo xtask
//! capi-header` runs it so).

use std::path::Path;

fn generated() -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(root.join("cbindgen.toml"))
        .unwrap_or_else(|e| panic!("reading cbindgen.toml: {e}"));
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(root.join("src/lib.rs"))
        .generate()
        .unwrap_or_else(|e| panic!("cbindgen: {e}"));
    let mut out = Vec::new();
    bindings.write(&mut out);
    String::from_utf8(out).unwrap_or_else(|e| panic!("header is not UTF-8: {e}"))
}

#[test]
fn committed_header_matches_the_sources() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("include/caveclod.h");
    let fresh = generated();
    if std::env::var_os("CAVECLOD_BLESS_HEADER").is_some() {
        std::fs::write(&path, &fresh).unwrap_or_else(|e| panic!("writing {path:?}: {e}"));
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    if committed != fresh {
        let line = committed
            .lines()
            .zip(fresh.lines())
            .position(|(a, b)| a != b)
            .map_or(committed.lines().count().min(fresh.lines().count()), |i| i);
        panic!(
            "include/caveclod.h differs from the header the sources generate (first at line \
             {}):\n  committed: {:?}\n  generated: {:?}\nregenerate it with `cargo xtask \
             capi-header` and commit it",
            line + 1,
            committed.lines().nth(line).unwrap_or(""),
            fresh.lines().nth(line).unwrap_or("")
        );
    }
}
