//! `caveclod bake` on generated CAD-style assemblies (separate parts touching without
//! sharing vertices, many materials, instanced meshes: the traits of one that once hung the
//! baker) ends, and with stderr not a terminal reports progress as plain lines, at most one
//! per `CAVECLOD_PROGRESS_INTERVAL` seconds.

mod common;

use std::path::Path;
use std::process::Output;

use caveclod_tests::parts::{PartSoup, SoupShape};
use caveclod_tests::AlignedBytes;
use serde_json::Value;

/// `caveclod bake <input> -o <output> --json` with the interval `interval` (stderr piped).
fn bake(input: &Path, output: &Path, interval: &str) -> Output {
    common::command()
        .arg("bake")
        .arg(input)
        .arg("-o")
        .arg(output)
        .arg("--json")
        .env("CAVECLOD_PROGRESS_INTERVAL", interval)
        .output()
        .expect("run caveclod")
}

/// `(done, most)` of a line `bake: hierarchy 1,234/5,678 collapses (21%)`, checking its
/// percentage.
fn collapse_count(line: &str) -> Option<(u64, u64)> {
    let rest = line.strip_prefix("bake: hierarchy ")?;
    let (counts, percent) = rest.split_once(" collapses (")?;
    let (done, most) = counts.split_once('/')?;
    let number = |s: &str| s.replace(',', "").parse::<u64>().ok();
    let (done, most) = (number(done)?, number(most)?);
    let percent: u64 = percent.strip_suffix("%)")?.parse().ok()?;
    assert_eq!(percent, done * 100 / most.max(1), "{line}");
    Some((done, most))
}

#[test]
fn a_cad_assembly_bakes_with_a_progress_line_per_update() {
    let soup = PartSoup::generate(&SoupShape::CAD_ASSEMBLY, 1);
    let dir = tempfile::tempdir().unwrap();
    let input = soup.write_gltf(dir.path(), "assembly").unwrap();
    let output = dir.path().join("assembly.clod");
    let out = bake(&input, &output, "0");
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(out.status.success(), "{stderr}");
    let report: Value = serde_json::from_slice(&out.stdout).expect("one JSON report");
    assert_eq!(report["input_triangles"], soup.triangle_count() as u64);
    // Every line a progress line: the steps, then the collapses after each pass.
    let lines: Vec<&str> = stderr.lines().collect();
    assert!(lines.iter().all(|l| l.starts_with("bake: ")), "{stderr}");
    for step in ["bake: importing", "bake: welding", "bake: assembling"] {
        assert!(lines.contains(&step), "{step}: {stderr}");
    }
    let counts: Vec<(u64, u64)> = lines.iter().filter_map(|l| collapse_count(l)).collect();
    assert!(counts.len() > 2, "{stderr}");
    assert!(counts
        .windows(2)
        .all(|w| w[0].0 <= w[1].0 && w[0].1 == w[1].1));
    let (done, most) = counts[counts.len() - 1];
    assert!(done > most / 2 && done <= most, "{done}/{most}");
    let file = AlignedBytes::from_slice(&std::fs::read(&output).unwrap());
    assert!(file.hierarchy().is_ok());
}

#[test]
fn plain_lines_wait_for_their_interval() {
    let shape = SoupShape {
        meshes: 3,
        parts: 4,
        instances: 6,
        materials: 4,
        cells: 2,
    };
    let soup = PartSoup::generate(&shape, 7);
    let dir = tempfile::tempdir().unwrap();
    let input = soup.write_gltf(dir.path(), "small").unwrap();
    let output = dir.path().join("small.clod");
    // An hour between lines: the bake ends before the first.
    let out = bake(&input, &output, "3600");
    assert!(out.status.success());
    assert_eq!(String::from_utf8_lossy(&out.stderr), "");
    // An interval that is not a number is refused before anything is baked.
    let out = bake(&input, &dir.path().join("never.clod"), "soon");
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("CAVECLOD_PROGRESS_INTERVAL"), "{stderr}");
    assert!(!dir.path().join("never.clod").exists());
}
