//! A blocked build's collapses spilled to disk and written from there, splits in reverse
//! creation order: the file validates and holds the same hierarchy as the same build read
//! back into memory and written depth-first, up to the numbering of the splits, and its bytes
//! do not depend on how many threads built the blocks.

use caveclod_bake::blocked::BlockedOptions;
use caveclod_bake::import::ImportOptions;
use caveclod_bake::pipeline::{build_file_spilled, SpilledBuild};
use caveclod_core::format::{Meta, SplitBounds};
use caveclod_core::{Hierarchy, NodeId, PolyId};
use caveclod_tests::{generate, AlignedBytes};
use std::path::Path;

fn build(input: &Path) -> SpilledBuild {
    let options = BlockedOptions {
        block_triangles: 2048,
    };
    let (built, levels) =
        build_file_spilled(input, &ImportOptions::default(), &options, &mut |_| {}).unwrap();
    assert!(levels.len() > 2, "too few levels: {levels:?}");
    built
}

/// A split as numbering leaves it: the positions of its children, its bounds, and the
/// leaves (numbered alike in both orders) of the polygons it creates.
type SplitKey = (u32, u32, Vec<u8>, [u32; 3], Option<[u32; 3]>);

/// The hierarchy of a file with its splits named by what they are rather than their ids.
#[derive(Debug, PartialEq)]
struct Renumbered {
    counts: [u32; 7],
    splits: Vec<SplitKey>,
    roots: Vec<u32>,
    base: Vec<[u32; 3]>,
}

fn renumbered(h: &Hierarchy<'_>) -> Renumbered {
    let m: &Meta = h.meta();
    let nodes = h.nodes();
    let position = |n: NodeId| nodes[n.index()].position.0;
    let polygon = |p: PolyId| {
        p.get()
            .map(|p| h.polygons()[p.index()].nodes.map(&position))
    };
    let mut splits: Vec<SplitKey> = h
        .splits()
        .iter()
        .zip(h.bounds())
        .map(|(s, b): (_, &SplitBounds)| {
            (
                position(s.stationary),
                position(s.floating),
                bytemuck::bytes_of(b).to_vec(),
                polygon(s.f_l).expect("every split creates f_l"),
                polygon(s.f_r),
            )
        })
        .collect();
    splits.sort();
    let mut roots: Vec<u32> = h.roots().iter().map(|&r| position(r)).collect();
    roots.sort();
    let mut base: Vec<[u32; 3]> = h.base().iter().map(|f| f.corners.map(position)).collect();
    base.sort();
    Renumbered {
        counts: [
            m.node_count,
            m.split_count,
            m.root_count,
            m.polygon_count,
            m.base_polygon_count,
            m.position_count,
            m.max_depth,
        ],
        splits,
        roots,
        base,
    }
}

fn read(path: &Path) -> AlignedBytes {
    AlignedBytes::from_slice(&std::fs::read(path).unwrap())
}

#[test]
fn a_spilled_blocked_bake_writes_the_in_memory_hierarchy_renumbered() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("terrain.ply");
    generate::terrain(&input, 20_000, &mut |_, _| {}).unwrap();

    let spilled_path = dir.path().join("spilled.clod");
    build(&input)
        .write(&spilled_path, &[])
        .expect("spilled write");
    let in_memory_path = dir.path().join("in_memory.clod");
    build(&input)
        .into_built("terrain")
        .unwrap()
        .write(&in_memory_path, &[])
        .expect("in-memory write");

    let (spilled, in_memory) = (read(&spilled_path), read(&in_memory_path));
    let spilled = Hierarchy::from_bytes(spilled.bytes()).expect("the spilled file validates");
    let in_memory = Hierarchy::from_bytes(in_memory.bytes()).expect("valid");
    assert!(spilled.splits().len() > 1000);
    // Not the same numbering: the orders differ, the hierarchies do not.
    assert_ne!(spilled.splits(), in_memory.splits());
    assert_eq!(renumbered(&spilled), renumbered(&in_memory));
}

#[test]
fn a_spilled_blocked_bake_writes_the_same_bytes_on_one_thread_and_on_two() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("terrain.ply");
    generate::terrain(&input, 20_000, &mut |_, _| {}).unwrap();
    let bytes = |threads: usize| {
        let path = dir.path().join(format!("on_{threads}.clod"));
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| build(&input).write(&path, &[]))
            .expect("spilled write");
        std::fs::read(&path).unwrap()
    };
    assert!(bytes(1) == bytes(2), "the files differ");
}
