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

/// Generates a terrain of `triangles` and bakes it paged in 4 KiB pages; the file's path.
fn paged_terrain(dir: &Path, triangles: u32) -> std::path::PathBuf {
    let (ply, paged) = (dir.join("t.ply"), dir.join("paged.clod"));
    let n = triangles.to_string();
    succeeded(&caveclod(&["generate", "--triangles", &n, "-o", s(&ply)]));
    succeeded(&caveclod(&[
        "bake",
        s(&ply),
        "-o",
        s(&paged),
        "--page-size",
        "4K",
    ]));
    paged
}

/// Flies `file` streamed, two cameras for `frames` frames; the JSON report.
fn fly_streamed(file: &Path, frames: usize) -> serde_json::Value {
    let out = caveclod(&[
        "flyover",
        s(file),
        "--pool",
        "4M",
        "--io-latency",
        "2",
        "--io-bandwidth",
        "100",
        "--cameras",
        "4",
        "--frames",
        &frames.to_string(),
        "--json",
    ]);
    let report = json(&out);
    assert_eq!(
        report["frames"].as_array().map(Vec::len),
        Some(frames),
        "the flight goes on to the end"
    );
    assert_eq!(report["absent_reads"], 0);
    report
}

/// The pages the report names as bad, each checked to be named once.
fn reported_pages(report: &serde_json::Value) -> Vec<u32> {
    let faults = report["faults"].as_array().expect("faults");
    let mut pages: Vec<u32> = faults
        .iter()
        .map(|f| {
            let f = f.as_str().expect("a fault is a line");
            let at = f.find("page ").expect("names the page") + 5;
            let digits: String = f[at..].chars().take_while(char::is_ascii_digit).collect();
            digits.parse().expect("a page number")
        })
        .collect();
    let named = pages.len();
    pages.sort_unstable();
    pages.dedup();
    assert_eq!(pages.len(), named, "a page was reported twice: {faults:?}");
    pages
}

#[test]
fn damaged_pages_and_a_cut_file_are_reported_once_and_the_flight_goes_on() {
    let dir = tempfile::tempdir().expect("dir");
    let paged = paged_terrain(dir.path(), 120_000);
    let bytes = std::fs::read(&paged).expect("read");
    let file = caveclod_io::PagedFile::open(&paged).expect("open");
    let root = file.root().expect("root");
    let table = root.table();
    let first = root.paged().root_pages;
    let pages = table.len() as u32;
    assert!(pages > 3000, "{pages} pages");

    // A byte flipped in each of 1,000 random pages, past the first quarter (a bad page
    // takes its subtree with it: the top pages' loss would leave nothing to fly).
    let mut rng = caveclod_tests::generate::SplitMix64::new(0xBAD_9A6E);
    let mut damaged: Vec<u32> = Vec::new();
    let from = first.max(pages / 4);
    while damaged.len() < 1000 {
        let p = from + rng.below((pages - from) as usize) as u32;
        if !damaged.contains(&p) {
            damaged.push(p);
        }
    }
    let mut flipped = bytes.clone();
    for &p in &damaged {
        let e = table.entry(p).expect("entry");
        let at = e.offset as usize + rng.below(e.size as usize);
        flipped[at] ^= 1 << rng.below(8);
    }
    let copy = dir.path().join("damaged.clod");
    std::fs::write(&copy, &flipped).expect("write");
    let report = fly_streamed(&copy, 120);
    let bad = reported_pages(&report);
    assert!(bad.len() >= 10, "{} bad pages met", bad.len());
    assert!(bad.iter().all(|p| damaged.contains(p)), "{bad:?}");
    let installs: u64 = report["frames"]
        .as_array()
        .expect("frames")
        .iter()
        .filter_map(|f| f["installs"].as_u64())
        .sum();
    assert!(installs > 50, "the good pages stream: {installs}");
    eprintln!(
        "{} of the damaged pages met, each reported once; {installs} installs",
        bad.len()
    );

    // The file cut short: the pages past the cut are reported, the rest flies.
    let cut = table
        .entry(first + (pages - first) / 2)
        .expect("entry")
        .offset as usize;
    let short = dir.path().join("short.clod");
    std::fs::write(&short, &bytes[..cut]).expect("write");
    let report = fly_streamed(&short, 120);
    let bad = reported_pages(&report);
    assert!(!bad.is_empty(), "the flight met the cut");
    eprintln!("{} pages past the cut met", bad.len());
    for p in bad {
        let e = table.entry(p).expect("entry");
        assert!(
            e.offset + u64::from(e.size) > cut as u64,
            "page {p} lies before the cut"
        );
    }
}
