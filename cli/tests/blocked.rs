//! `caveclod bake --blocked` on a generated terrain: a hierarchy of every input triangle
//! (less the counted repairs) built in several levels of blocks sized from the memory budget,
//! which `caveclod info` validates and the fly-over flies over from the memory map.

mod common;

use common::{caveclod, json, s};

#[test]
fn a_blocked_bake_holds_every_triangle_and_validates() {
    let dir = tempfile::tempdir().unwrap();
    let (ply, clod) = (dir.path().join("t.ply"), dir.path().join("t.clod"));
    let generated = caveclod(&["generate", "--triangles", "20000", "-o", s(&ply)]);
    assert!(generated.status.success());
    // 2 MiB over the threads sizes blocks of at most about a thousand triangles.
    let report = json(&caveclod(&[
        "bake",
        "--blocked",
        "--memory-budget",
        "2M",
        s(&ply),
        "-o",
        s(&clod),
        "--json",
    ]));
    let levels = report["blocked"]["levels"].as_array().expect("levels");
    assert!(levels.len() >= 3, "{report}");
    assert_eq!(levels.last().unwrap()["blocks"], 1);
    assert!(levels[0]["blocks"].as_u64().unwrap() >= 16, "{report}");
    let repaired: u64 = ["degenerate_triangles", "duplicate_triangles"]
        .iter()
        .map(|k| report["repairs"][k].as_u64().unwrap_or(0))
        .sum();
    let input = report["input_triangles"].as_u64().unwrap();
    assert!(input >= 20_000);
    assert_eq!(report["polygons"].as_u64().unwrap(), input - repaired);

    let info = json(&caveclod(&["info", "--json", s(&clod)]));
    assert_eq!(info["valid"], true);
    assert_eq!(info["polygons"], report["polygons"]);
    let flown = json(&caveclod(&[
        "flyover",
        s(&clod),
        "--cameras",
        "4",
        "--frames",
        "20",
        "--json",
    ]));
    assert!(flown.is_object());
}
