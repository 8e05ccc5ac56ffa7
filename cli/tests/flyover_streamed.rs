//! `caveclod flyover --pool`: cameras fly over paged files whose pages stream into a pool,
//! through a simulated slow disk; two files share one pool, a fraction of their size.

mod common;

use std::path::Path;

use common::{caveclod, json, s, succeeded, TERRAIN6};

#[test]
fn a_streamed_flight_reports_every_frame_and_reads_no_absent_page() {
    let dir = tempfile::tempdir().expect("dir");
    let (ply, paged) = (dir.path().join("t.ply"), dir.path().join("paged.clod"));
    succeeded(&caveclod(&[
        "generate",
        "--triangles",
        "20000",
        "-o",
        s(&ply),
    ]));
    succeeded(&caveclod(&[
        "bake",
        s(&ply),
        "-o",
        s(&paged),
        "--page-size",
        "8K",
    ]));
    let frames = 90;
    let out = caveclod(&[
        "flyover",
        s(&paged),
        s(&paged),
        "--pool",
        "256K",
        "--io-latency",
        "8",
        "--io-bandwidth",
        "20",
        "--cameras",
        "2",
        "--frames",
        &frames.to_string(),
        "--json",
    ]);
    let report = json(&out);
    assert_eq!(report["files"].as_array().map(Vec::len), Some(2));
    let per_frame = report["frames"].as_array().expect("frames");
    assert_eq!(per_frame.len(), frames);
    let sum = |field: &str| -> u64 { per_frame.iter().filter_map(|f| f[field].as_u64()).sum() };
    assert!(sum("installs") > 0 && sum("bytes_read") > 0, "{report}");
    assert!(
        sum("deferred") > 0,
        "the slow disk makes splits wait: {report}"
    );
    assert!(sum("evictions") > 0, "a 256 KiB pool evicts: {report}");
    assert_eq!(report["absent_reads"], 0);
    assert_eq!(report["untracked_uses"], 0);
    assert!(report["faults"].as_array().is_some_and(Vec::is_empty));
    assert!(report["peak_rss_bytes"].as_u64().is_some_and(|b| b > 0));
}

#[test]
fn a_whole_file_is_refused_with_the_pool() {
    let whole = Path::new(env!("CARGO_MANIFEST_DIR")).join(TERRAIN6);
    let out = caveclod(&["flyover", s(&whole), "--pool", "1M"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("flags"), "{err}");
}
