//! `caveclod info`, which reads the file through a memory map, prints the file's counts, and
//! ends quietly when its reader goes away. (That a mapped file reports and refines as a read
//! one is checked by the `info` command's unit test and caveclod-io's tests.)

mod common;

use std::path::Path;

use caveclod_io::ClodFile;
use common::{caveclod, json, s, TERRAIN6};

#[test]
fn info_prints_the_files_counts() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(TERRAIN6);
    let file = ClodFile::open(&path).expect("map");
    let m = *file.hierarchy().expect("valid").meta();
    let printed = json(&caveclod(&["info", "--json", s(&path)]));
    assert_eq!(printed["valid"], true);
    assert_eq!(printed["nodes"], m.node_count);
    assert_eq!(printed["polygons"], m.polygon_count);
    assert_eq!(printed["positions"], m.position_count);
    assert_eq!(printed["vertices"], m.vertex_count);
    assert_eq!(printed["surfaces"], m.surface_count);
    assert_eq!(printed["base_polygons"], m.base_polygon_count);
    assert_eq!(printed["depth"], m.max_depth);
}

#[cfg(unix)]
#[test]
fn info_ends_quietly_when_its_reader_closes_early() {
    use std::process::Stdio;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(TERRAIN6);
    let mut child = common::command()
        .args(["info", s(&path)])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run caveclod");
    // The reader goes away before the report is printed, as `| head -0` would.
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("wait");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_ne!(out.status.code(), Some(101), "{stderr}");
}
