//! A `.clod` file read through a memory map gives what the same file read into the heap
//! gives: the same report, the same refined cuts, and `caveclod info` (which maps the file)
//! prints that report.

mod common;

use std::path::Path;

use caveclod_cli::aligned::AlignedBytes;
use caveclod_cli::mapped::ClodBytes;
use caveclod_core::glam::Vec3;
use common::{caveclod, centre_and_size, json, s, settled, TERRAIN6};

#[test]
fn a_mapped_file_reports_and_refines_as_a_read_one() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(TERRAIN6);
    let mapped = ClodBytes::open(&path).expect("map");
    assert!(mapped.is_mapped());
    let read = AlignedBytes::read(&path).expect("read");
    assert_eq!(mapped.bytes(), read.bytes());
    let (hm, hr) = (
        mapped.hierarchy().expect("valid"),
        read.hierarchy().expect("valid"),
    );
    assert_eq!(
        caveclod_cli::info::report(&hm, None),
        caveclod_cli::info::report(&hr, None)
    );
    let (centre, size) = centre_and_size(&hm);
    for eye in [
        centre + Vec3::new(0.1 * size, 0.4 * size, 0.6 * size),
        centre + Vec3::new(-0.3 * size, 0.05 * size, 0.1 * size),
    ] {
        let a = settled(&hm, eye, centre);
        assert!(a.0 > 0);
        assert_eq!(a, settled(&hr, eye, centre));
    }

    let printed = json(&caveclod(&["info", "--json", s(&path)]));
    for (key, value) in caveclod_cli::info::report(&hr, None) {
        assert_eq!(printed[&key], value, "{key}");
    }
    assert_eq!(printed["valid"], true);
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
