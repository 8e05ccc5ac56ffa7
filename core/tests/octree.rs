//! The multiresolution octree: validation of hand-built octrees (a 2-level and a 3-level
//! strip of quads over two surfaces) and of their sections in a `.clod` file, each broken
//! invariant refused with its own error; per-camera selection (far, near, looking away, many
//! views against the criterion), emission against the selected nodes' ranges, entered/left
//! across frames, independent cameras, and no allocation in select + emit.

mod common;
mod counting;

use std::hint::black_box;

use caveclod_core::format::{serialized_len, write_into, ExtraSection, HierarchyParts, Vertex};
use caveclod_core::glam::Vec3;
use caveclod_core::octree::{octree_tags, OctreeMeta, OctreeNode, OctreeParts, OctreeRange};
use caveclod_core::{
    CutError, Hierarchy, LookAt, Octree, OctreeCut, OctreeFormatError, ParamField, ParamsError,
    SelectStats, SurfaceId, View,
};
use common::{golden, AlignedBytes};
use counting::{allocations, assert_counting};

/// An owned octree: a strip of quads along x in the plane z = 0, `y` in `0..1`, a complete
/// binary tree of `levels` levels. Level-0 nodes are 16 wide; every node holds two quads,
/// its left half on surface 0 and its right half on surface 1, with six vertices of its own.
/// Errors are 0 at level 0 and `2^(l - 1)` at level `l`.
#[derive(Clone, Debug)]
struct Strip {
    meta: OctreeMeta,
    nodes: Vec<OctreeNode>,
    ranges: Vec<OctreeRange>,
    vertices: Vec<Vertex>,
    indices: Vec<u32>,
}

impl Strip {
    fn new(levels: u32) -> Self {
        let width = 16.0 * (1u32 << (levels - 1)) as f32;
        let mut s = Strip {
            meta: OctreeMeta::default(),
            nodes: Vec::new(),
            ranges: Vec::new(),
            vertices: Vec::new(),
            indices: Vec::new(),
        };
        // Breadth first: (level, x0, x1).
        let mut queue = vec![(levels - 1, 0.0f32, width)];
        let mut head = 0;
        while head < queue.len() {
            let (level, x0, x1) = queue[head];
            head += 1;
            let xm = 0.5 * (x0 + x1);
            let first_child = queue.len() as u32;
            if level > 0 {
                queue.push((level - 1, x0, xm));
                queue.push((level - 1, xm, x1));
            }
            let v0 = s.vertices.len() as u32;
            for x in [x0, xm, x1] {
                for y in [0.0, 1.0] {
                    s.vertices.push(Vertex {
                        position: [x, y, 0.0],
                        normal: [0.0, 0.0, 1.0],
                        uv: [x / width, y],
                    });
                }
            }
            let first_range = s.ranges.len() as u32;
            for (surface, left) in [(0u32, v0), (1, v0 + 2)] {
                let first_index = s.indices.len() as u32;
                // Vertices `left`, `left + 1` at the quad's left edge, `+ 2`, `+ 3` right.
                s.indices
                    .extend([left, left + 2, left + 3, left, left + 3, left + 1]);
                s.ranges.push(OctreeRange {
                    surface,
                    first_index,
                    index_count: 6,
                });
            }
            s.nodes.push(OctreeNode {
                min: [x0, 0.0, 0.0],
                max: [x1, 1.0, 0.0],
                error: if level == 0 {
                    0.0
                } else {
                    (1u32 << (level - 1)) as f32
                },
                level,
                first_child: if level > 0 { first_child } else { 0 },
                child_count: if level > 0 { 2 } else { 0 },
                first_range,
                range_count: 2,
            });
        }
        s.meta = OctreeMeta {
            node_count: s.nodes.len() as u32,
            level_count: levels,
            vertex_count: s.vertices.len() as u32,
            index_count: s.indices.len() as u32,
            range_count: s.ranges.len() as u32,
            surface_count: 2,
            reserved: [0; 2],
        };
        s
    }

    fn parts(&self) -> OctreeParts<'_> {
        OctreeParts {
            meta: self.meta,
            nodes: &self.nodes,
            ranges: &self.ranges,
            vertices: &self.vertices,
            indices: &self.indices,
        }
    }

    fn octree(&self) -> Octree<'_> {
        Octree::new(self.parts()).expect("a valid strip")
    }
}

/// A perspective view with a 100-pixel viewport (about 91.5 pixels per radian).
fn look(eye: Vec3, target: Vec3) -> View {
    let look = LookAt {
        eye,
        target,
        up: Vec3::Y,
        fov_y: 1.0,
        near: 0.1,
        far: 1e6,
    };
    look.view(100, 100)
}

fn far() -> View {
    look(Vec3::new(32.0, 0.5, 1e5), Vec3::new(32.0, 0.5, 0.0))
}

/// Near x = 0, looking along the strip.
fn near() -> View {
    look(Vec3::new(-1.0, 0.5, 2.0), Vec3::new(64.0, 0.5, 0.0))
}

/// Above the middle of the strip, no frustum.
fn middle() -> View {
    View::without_frustum(Vec3::new(32.0, 0.5, 2.0), near().pixels_per_radian)
}

fn away() -> View {
    look(Vec3::new(-1.0, 0.5, 2.0), Vec3::new(-100.0, 0.5, 2.0))
}

const TOLERANCE: f32 = 4.0;

/// The selected nodes' ranges of each surface, concatenated in node order.
fn expected_indices(o: &Octree<'_>, nodes: &[u32]) -> Vec<Vec<u32>> {
    let mut out = vec![Vec::new(); o.surface_count()];
    for &n in nodes {
        for r in o.node_ranges(n) {
            out[r.surface as usize].extend_from_slice(o.range_indices(r));
        }
    }
    out
}

/// Emits in both forms into exactly sized buffers; both must equal `expected_indices`.
fn emit_checked(o: &Octree<'_>, cut: &OctreeCut<'_>) -> Vec<Vec<u32>> {
    let expected = expected_indices(o, cut.selected());
    let mut packed = vec![u32::MAX; cut.total_index_count()];
    let mut offsets = vec![u32::MAX; o.surface_count() + 1];
    let n = cut
        .emit_indices_packed(o, &mut packed, &mut offsets)
        .expect("packed");
    assert_eq!(n, packed.len());
    let mut lists: Vec<Vec<u32>> = (0..o.surface_count())
        .map(|s| vec![u32::MAX; cut.index_count(s)])
        .collect();
    let mut slices: Vec<&mut [u32]> = lists.iter_mut().map(|l| l.as_mut_slice()).collect();
    let mut written = vec![u32::MAX; o.surface_count()];
    assert_eq!(
        cut.emit_indices(o, &mut slices, &mut written)
            .expect("lists"),
        n
    );
    for s in 0..o.surface_count() {
        let range = &packed[offsets[s] as usize..offsets[s + 1] as usize];
        assert_eq!(range, expected[s].as_slice(), "surface {s}, packed");
        assert_eq!(lists[s], expected[s], "surface {s}, lists");
        assert_eq!(written[s] as usize, expected[s].len());
        assert_eq!(cut.index_count(s), expected[s].len());
    }
    expected
}

#[test]
fn hand_built_octrees_validate() {
    for levels in [1, 2, 3] {
        let s = Strip::new(levels);
        let o = s.octree();
        assert_eq!(o.node_count(), (1 << levels) - 1);
        assert_eq!(o.level_count(), levels);
        assert_eq!(o.surface_count(), 2);
        assert_eq!(o.node_ranges(0).len(), 2);
        assert_eq!(o.node_ranges(o.node_count() as u32), &[]);
    }
}

/// Breaks one invariant of the 3-level strip at a time.
#[test]
fn every_broken_invariant_is_refused() {
    type Break = fn(&mut Strip);
    let cases: Vec<(&str, Break, OctreeFormatError)> = vec![
        (
            "a child past the last node",
            |s| s.nodes[2].first_child = 6,
            OctreeFormatError::ChildOutOfRange { node: 2 },
        ),
        (
            "a node with two parents",
            |s| s.nodes[2].first_child = 4,
            OctreeFormatError::SharedChild { node: 2 },
        ),
        (
            "a node that is its own child",
            |s| s.nodes[1].first_child = 1,
            OctreeFormatError::SharedChild { node: 1 },
        ),
        (
            "a node with no parent",
            |s| s.nodes[1].child_count = 1,
            OctreeFormatError::Orphan { node: 4 },
        ),
        (
            "children ranges with a gap",
            |s| s.nodes[0].first_child = 2,
            OctreeFormatError::Orphan { node: 1 },
        ),
        (
            "a child's error above its parent's",
            |s| s.nodes[3].error = 1.5,
            OctreeFormatError::ErrorAboveParent { node: 3 },
        ),
        (
            "a child's box outside its parent's",
            |s| s.nodes[4].max[2] = 0.5,
            OctreeFormatError::ChildOutsideParent { node: 4 },
        ),
        (
            "a NaN bound",
            |s| s.nodes[4].min[1] = f32::NAN,
            OctreeFormatError::NotFinite { node: 4 },
        ),
        (
            "an infinite error",
            |s| s.nodes[0].error = f32::INFINITY,
            OctreeFormatError::NotFinite { node: 0 },
        ),
        (
            "min above max",
            |s| s.nodes[5].min[0] = 100.0,
            OctreeFormatError::EmptyBox { node: 5 },
        ),
        (
            "a negative error",
            |s| s.nodes[6].error = -1.0,
            OctreeFormatError::NegativeError { node: 6 },
        ),
        (
            "children at level 0",
            |s| s.nodes[1].level = 0,
            OctreeFormatError::BadLevel { node: 1 },
        ),
        (
            "a child two levels down",
            |s| {
                s.nodes[0].level = 3;
                s.meta.level_count = 4;
            },
            OctreeFormatError::BadLevel { node: 1 },
        ),
        (
            "a root below the top level",
            |s| s.meta.level_count = 4,
            OctreeFormatError::BadLevel { node: 0 },
        ),
        (
            "no levels",
            |s| s.meta.level_count = 0,
            OctreeFormatError::LevelCount { levels: 0 },
        ),
        (
            "too many levels",
            |s| s.meta.level_count = 33,
            OctreeFormatError::LevelCount { levels: 33 },
        ),
        (
            "an index past the vertex buffer",
            |s| s.indices[5] = s.meta.vertex_count,
            OctreeFormatError::VertexOutOfRange {
                index: 5,
                vertex: 42,
            },
        ),
        (
            "an index count not a multiple of 3",
            |s| s.ranges[0].index_count = 4,
            OctreeFormatError::BadIndexCount { range: 0 },
        ),
        (
            "an empty range",
            |s| s.ranges[7].index_count = 0,
            OctreeFormatError::BadIndexCount { range: 7 },
        ),
        (
            "surfaces not ascending",
            |s| {
                s.ranges[2].surface = 1;
                s.ranges[3].surface = 0;
            },
            OctreeFormatError::SurfacesNotAscending { node: 1 },
        ),
        (
            "the same surface twice",
            |s| s.ranges[13].surface = 0,
            OctreeFormatError::SurfacesNotAscending { node: 6 },
        ),
        (
            "a surface past the surface count",
            |s| s.ranges[1].surface = 2,
            OctreeFormatError::SurfaceOutOfRange { range: 1 },
        ),
        (
            "a range past the last index",
            |s| s.ranges[13].first_index = s.meta.index_count - 3,
            OctreeFormatError::IndicesOutOfRange { range: 13 },
        ),
        (
            "a node's ranges past the last range",
            |s| s.nodes[6].range_count = 3,
            OctreeFormatError::RangesOutOfRange { node: 6 },
        ),
        (
            "a NaN vertex",
            |s| s.vertices[9].uv[1] = f32::NAN,
            OctreeFormatError::VertexNotFinite { vertex: 9 },
        ),
        (
            "a node count that does not match",
            |s| s.meta.node_count = 8,
            OctreeFormatError::CountMismatch {
                tag: octree_tags::NODES,
                expected: 8,
                got: 7,
            },
        ),
        (
            "a truncated index section",
            |s| {
                s.indices.pop();
            },
            OctreeFormatError::CountMismatch {
                tag: octree_tags::INDICES,
                expected: 84,
                got: 83,
            },
        ),
        (
            "no node",
            |s| {
                s.nodes.clear();
                s.meta.node_count = 0;
            },
            OctreeFormatError::Empty,
        ),
    ];
    let good = Strip::new(3);
    assert_eq!(good.vertices.len(), 42);
    assert_eq!(good.indices.len(), 84);
    for (what, brk, expected) in cases {
        let mut s = good.clone();
        brk(&mut s);
        let got = Octree::new(s.parts());
        assert_eq!(got.err(), Some(expected), "{what}");
        // Every error names what is wrong.
        assert!(!expected.to_string().is_empty());
    }
}

/// A root over many leaves, every node naming one range of 65,535 indices: with 65,536
/// leaves exactly `u32::MAX` indices together, with one more leaf more than any cut's
/// counts could hold.
#[test]
#[cfg_attr(miri, ignore = "65,537 nodes are slow to validate under miri")]
fn index_totals_past_u32_are_refused() {
    let per_range = 65_535u32;
    let ranges = [OctreeRange {
        surface: 0,
        first_index: 0,
        index_count: per_range,
    }];
    let vertices = [Vertex {
        position: [0.0; 3],
        normal: [0.0, 0.0, 1.0],
        uv: [0.0; 2],
    }];
    let indices = vec![0u32; per_range as usize];
    let check = |leaves: u32| {
        let leaf = OctreeNode {
            min: [0.0; 3],
            max: [1.0; 3],
            range_count: 1,
            ..OctreeNode::default()
        };
        let mut nodes = vec![leaf; leaves as usize + 1];
        nodes[0].level = 1;
        nodes[0].first_child = 1;
        nodes[0].child_count = leaves;
        let parts = OctreeParts {
            meta: OctreeMeta {
                node_count: nodes.len() as u32,
                level_count: 2,
                vertex_count: 1,
                index_count: per_range,
                range_count: 1,
                surface_count: 1,
                reserved: [0; 2],
            },
            nodes: &nodes,
            ranges: &ranges,
            vertices: &vertices,
            indices: &indices,
        };
        Octree::new(parts).err()
    };
    assert_eq!(check(1 << 16), None);
    assert_eq!(
        check((1 << 16) + 1),
        Some(OctreeFormatError::TooManyIndices)
    );
}

/// `base` (the golden hierarchy's arrays) with `surfaces` surfaces, written with `extra`
/// sections.
fn file_with(base: &HierarchyParts<'_>, surfaces: u32, extra: &[ExtraSection<'_>]) -> AlignedBytes {
    let mut parts = *base;
    parts.surface_count = surfaces;
    let mut out = vec![0u8; serialized_len(&parts, extra)];
    write_into(&parts, extra, &mut out).expect("write");
    AlignedBytes::from_slice(&out)
}

#[test]
fn sections_in_a_file_round_trip_and_are_checked() {
    let s = Strip::new(3);
    let parts = s.parts();
    let sections = parts.sections();
    let g = golden();
    let golden = Hierarchy::from_bytes(g.bytes()).expect("golden");
    let base = golden.parts();

    let file = file_with(base, 2, &sections);
    let h = Hierarchy::from_bytes(file.bytes()).expect("hierarchy");
    let o = Octree::from_hierarchy(&h).expect("valid").expect("present");
    assert_eq!(o.nodes(), s.nodes.as_slice());
    assert_eq!(o.ranges(), s.ranges.as_slice());
    assert_eq!(o.vertices(), s.vertices.as_slice());
    assert_eq!(o.indices(), s.indices.as_slice());
    assert_eq!(*o.meta(), s.meta);
    // The file's checksum is part of the identity: a cut of the in-memory octree is refused.
    let mem = s.octree();
    assert_ne!(o.identity(), mem.identity());
    let mut words = vec![0u32; OctreeCut::words_needed(&mem)];
    let mut cut = OctreeCut::new(&mem, &mut words).expect("memory");
    assert_eq!(cut.select(&o, &far(), 1.0), Err(CutError::WrongOctree));

    // No octree sections (the golden file): none.
    assert!(Octree::from_hierarchy(&golden)
        .expect("nothing to refuse")
        .is_none());

    // Broken files: (surfaces of the hierarchy, sections, expected error). Under miri, where
    // every section look-up (a checksum of the file) takes about a second, only the first.
    let node_bytes: &[u8] = bytemuck::cast_slice(&s.nodes);
    let nodes_cut_to = |len: usize| {
        let mut cut_short = sections;
        cut_short[1] = ExtraSection {
            tag: octree_tags::NODES,
            record_size: 4,
            bytes: &node_bytes[..len],
        };
        cut_short
    };
    let metas = [s.meta, s.meta];
    let mut two_metas = sections;
    two_metas[0] = ExtraSection {
        tag: octree_tags::META,
        record_size: 32,
        bytes: bytemuck::cast_slice(&metas),
    };
    let broken: [(u32, &[ExtraSection<'_>], OctreeFormatError); 5] = [
        (
            3,
            &sections,
            OctreeFormatError::SurfaceCount {
                octree: 2,
                hierarchy: 3,
            },
        ),
        (
            2,
            &sections[..4],
            OctreeFormatError::MissingSection(octree_tags::INDICES),
        ),
        (
            2,
            &nodes_cut_to(node_bytes.len() - 4),
            OctreeFormatError::BadSection(octree_tags::NODES),
        ),
        (
            2,
            &nodes_cut_to(node_bytes.len() - 48),
            OctreeFormatError::CountMismatch {
                tag: octree_tags::NODES,
                expected: 7,
                got: 6,
            },
        ),
        (
            2,
            &two_metas,
            OctreeFormatError::CountMismatch {
                tag: octree_tags::META,
                expected: 1,
                got: 2,
            },
        ),
    ];
    let take = if cfg!(miri) { 1 } else { broken.len() };
    for (surfaces, extra, expected) in broken.into_iter().take(take) {
        let file = file_with(base, surfaces, extra);
        let h = Hierarchy::from_bytes(file.bytes()).expect("hierarchy");
        assert_eq!(Octree::from_hierarchy(&h).err(), Some(expected));
    }
}

#[test]
fn a_far_camera_takes_the_root_only() {
    for levels in [2, 3] {
        let s = Strip::new(levels);
        let o = s.octree();
        let mut words = vec![0u32; OctreeCut::words_needed(&o)];
        let mut cut = OctreeCut::new(&o, &mut words).expect("memory");
        let stats = cut.select(&o, &far(), 1.0).expect("select");
        assert_eq!(cut.selected(), &[0]);
        assert_eq!(
            stats,
            SelectStats {
                selected: 1,
                triangles: 4,
                entered: 1,
                left: 0,
                culled: 0,
                visited: 1,
            }
        );
        let emitted = emit_checked(&o, &cut);
        assert_eq!(emitted[0], &s.indices[0..6]);
        assert_eq!(emitted[1], &s.indices[6..12]);
    }
}

#[test]
fn a_near_camera_takes_fine_nodes_near_and_coarse_ones_far() {
    let s = Strip::new(3);
    let o = s.octree();
    let mut words = vec![0u32; OctreeCut::words_needed(&o)];
    let mut cut = OctreeCut::new(&o, &mut words).expect("memory");
    let stats = cut.select(&o, &near(), TOLERANCE).expect("select");
    // Node 2 (level 1, x 32..64) is 33 away: 91.5 px/rad × 1 / 33 ≈ 2.8 px, taken; node 1
    // (level 1, x 0..32) is 2.2 away: refined into the level-0 nodes 3 and 4.
    assert_eq!(cut.selected(), &[2, 3, 4]);
    assert_eq!(stats.selected, 3);
    assert_eq!(stats.triangles, 12);
    assert_eq!(stats.visited, 5);
    assert_eq!(stats.culled, 0);
    assert_eq!(o.node(2).map(|n| n.level), Some(1));
    emit_checked(&o, &cut);

    // A finer tolerance refines node 2 too.
    cut.select(&o, &near(), 1.0).expect("select");
    assert_eq!(cut.selected(), &[3, 4, 5, 6]);
    emit_checked(&o, &cut);
}

#[test]
fn a_camera_looking_away_selects_nothing() {
    let s = Strip::new(3);
    let o = s.octree();
    let mut words = vec![0u32; OctreeCut::words_needed(&o)];
    let mut cut = OctreeCut::new(&o, &mut words).expect("memory");
    cut.select(&o, &near(), TOLERANCE).expect("select");
    let stats = cut.select(&o, &away(), TOLERANCE).expect("select");
    assert_eq!(cut.selected(), &[] as &[u32]);
    assert_eq!(
        stats,
        SelectStats {
            selected: 0,
            triangles: 0,
            entered: 0,
            left: 3,
            culled: 1,
            visited: 1,
        }
    );
    assert_eq!(cut.total_index_count(), 0);
    let mut offsets = [u32::MAX; 3];
    assert_eq!(cut.emit_indices_packed(&o, &mut [], &mut offsets), Ok(0));
    assert_eq!(offsets, [0, 0, 0]);
}

#[test]
fn entered_and_left_follow_the_frames() {
    let s = Strip::new(3);
    let o = s.octree();
    let mut words = vec![0u32; OctreeCut::words_needed(&o)];
    let mut cut = OctreeCut::new(&o, &mut words).expect("memory");
    // View, cut, entered, left.
    type Frame = (View, &'static [u32], &'static [u32], &'static [u32]);
    let frames: [Frame; 5] = [
        (far(), &[0], &[0], &[]),
        (near(), &[2, 3, 4], &[2, 3, 4], &[0]),
        (near(), &[2, 3, 4], &[], &[]),
        (middle(), &[3, 4, 5, 6], &[5, 6], &[2]),
        (far(), &[0], &[0], &[3, 4, 5, 6]),
    ];
    for (i, (view, selected, entered, left)) in frames.iter().enumerate() {
        let stats = cut.select(&o, view, TOLERANCE).expect("select");
        assert_eq!(cut.selected(), *selected, "frame {i}");
        assert_eq!(cut.entered().collect::<Vec<_>>(), *entered, "frame {i}");
        assert_eq!(cut.left().collect::<Vec<_>>(), *left, "frame {i}");
        assert_eq!(stats.entered as usize, entered.len(), "frame {i}");
        assert_eq!(stats.left as usize, left.len(), "frame {i}");
        emit_checked(&o, &cut);
    }
    cut.reset();
    assert_eq!(cut.selected(), &[] as &[u32]);
    let stats = cut.select(&o, &far(), TOLERANCE).expect("select");
    assert_eq!((stats.entered, stats.left), (1, 0));
}

#[test]
fn two_cameras_keep_independent_cuts() {
    let s = Strip::new(3);
    let o = s.octree();
    let mut wa = vec![0u32; OctreeCut::words_needed(&o)];
    let mut wb = vec![0u32; OctreeCut::words_needed(&o)];
    let mut a = OctreeCut::new(&o, &mut wa).expect("memory");
    let mut b = OctreeCut::new(&o, &mut wb).expect("memory");
    a.select(&o, &far(), TOLERANCE).expect("select");
    b.select(&o, &near(), TOLERANCE).expect("select");
    let sa = a.select(&o, &far(), TOLERANCE).expect("select");
    assert_eq!(a.selected(), &[0]);
    assert_eq!(b.selected(), &[2, 3, 4]);
    assert_eq!((sa.entered, sa.left), (0, 0));
    let sb = b.select(&o, &middle(), TOLERANCE).expect("select");
    assert_eq!((sb.entered, sb.left), (2, 1));
    assert_eq!(a.selected(), &[0]);
    assert_ne!(emit_checked(&o, &a), emit_checked(&o, &b));
}

/// Many views: each cut takes at most one node per root-to-leaf path, exactly one on every
/// path without frustum planes; every taken node above level 0 meets the tolerance and every
/// node above a taken one does not.
#[test]
fn cuts_meet_the_criterion_from_many_views() {
    let s = Strip::new(3);
    let o = s.octree();
    let mut words = vec![0u32; OctreeCut::words_needed(&o)];
    let mut cut = OctreeCut::new(&o, &mut words).expect("memory");
    let nodes = o.nodes();
    let mut parent = vec![u32::MAX; nodes.len()];
    for (i, n) in nodes.iter().enumerate() {
        for c in n.children() {
            parent[c as usize] = i as u32;
        }
    }
    let projected = |view: &View, n: &OctreeNode| {
        let q = view
            .eye
            .max(Vec3::from_array(n.min))
            .min(Vec3::from_array(n.max));
        n.error * view.pixels_per_radian / (view.eye - q).length()
    };
    let count = if cfg!(miri) { 6 } else { 60 };
    let mut seen = [false; 7];
    for i in 0..count {
        let t = i as f32 / count as f32;
        let eye = Vec3::new(
            -20.0 + 100.0 * t,
            0.5 + 30.0 * (t * 7.0).sin(),
            1.0 + 40.0 * t,
        );
        let target = Vec3::new(64.0 * (t * 3.0).fract(), 0.5, 0.0);
        let tolerance = [0.5, 2.0, 8.0][i % 3];
        let view = if i % 4 == 3 {
            View::without_frustum(eye, 91.5)
        } else {
            look(eye, target)
        };
        cut.select(&o, &view, tolerance).expect("select");
        let sel = cut.selected().to_vec();
        assert!(sel.windows(2).all(|w| w[0] < w[1]));
        for &n in &sel {
            seen[n as usize] = true;
            let node = &nodes[n as usize];
            if node.level > 0 {
                assert!(projected(&view, node) <= tolerance, "view {i} node {n}");
            }
            let mut a = parent[n as usize];
            while a != u32::MAX {
                assert!(!sel.contains(&a), "view {i}: {n} and its ancestor {a}");
                assert!(projected(&view, &nodes[a as usize]) > tolerance);
                a = parent[a as usize];
            }
        }
        if view.plane_count == 0 {
            // Every leaf is covered exactly once.
            for leaf in 3..7u32 {
                let mut covered = 0;
                let mut a = leaf;
                while a != u32::MAX {
                    covered += usize::from(sel.contains(&a));
                    a = parent[a as usize];
                }
                assert_eq!(covered, 1, "view {i} leaf {leaf}");
            }
        }
        emit_checked(&o, &cut);
    }
    if !cfg!(miri) {
        assert!(
            seen.iter().all(|&x| x),
            "some node never selected: {seen:?}"
        );
    }
}

#[test]
fn small_buffers_and_wrong_octrees_are_errors() {
    let s = Strip::new(3);
    let o = s.octree();
    let needed = OctreeCut::words_needed(&o);
    assert_eq!(needed, 2 + 2 * 7);
    let mut small = vec![0u32; needed - 1];
    assert_eq!(
        OctreeCut::new(&o, &mut small).err(),
        Some(CutError::Capacity {
            needed,
            given: needed - 1
        })
    );
    let mut words = vec![0u32; needed + 5];
    let mut cut = OctreeCut::new(&o, &mut words).expect("more memory is fine");
    cut.select(&o, &near(), TOLERANCE).expect("select");
    let total = cut.total_index_count();
    assert_eq!(total, 36);

    let mut out = vec![0u32; total];
    let mut offsets = vec![0u32; 3];
    assert_eq!(
        cut.emit_indices_packed(&o, &mut out[..total - 1], &mut offsets),
        Err(CutError::OutputTooSmall {
            surface: None,
            needed: total,
            given: total - 1
        })
    );
    assert_eq!(
        cut.emit_indices_packed(&o, &mut out, &mut offsets[..2]),
        Err(CutError::TooFewOutputs {
            needed: 3,
            given: 2
        })
    );
    let mut l0 = vec![0u32; cut.index_count(0)];
    let mut l1 = vec![0u32; cut.index_count(1) - 3];
    let mut written = [0u32; 2];
    assert_eq!(
        cut.emit_indices(&o, &mut [&mut l0[..], &mut l1[..]], &mut written),
        Err(CutError::OutputTooSmall {
            surface: Some(SurfaceId(1)),
            needed: 18,
            given: 15
        })
    );
    assert_eq!(
        cut.emit_indices(&o, &mut [&mut l0[..]], &mut written),
        Err(CutError::TooFewOutputs {
            needed: 2,
            given: 1
        })
    );
    assert!(CutError::TooFewOutputs {
        needed: 2,
        given: 1
    }
    .to_string()
    .contains("2 needed"));

    // A cut of the 3-level octree on the 2-level one.
    let other = Strip::new(2);
    let o2 = other.octree();
    assert_eq!(cut.select(&o2, &far(), 1.0), Err(CutError::WrongOctree));
    assert_eq!(
        cut.emit_indices_packed(&o2, &mut out, &mut offsets),
        Err(CutError::WrongOctree)
    );
    assert_eq!(
        cut.emit_indices(&o2, &mut [&mut l0[..], &mut l1[..]], &mut written),
        Err(CutError::WrongOctree)
    );
}

#[test]
fn selection_bounds_and_odd_views() {
    let s = Strip::new(3);
    let o = s.octree();
    let mut words = vec![0u32; OctreeCut::words_needed(&o)];
    let mut cut = OctreeCut::new(&o, &mut words).expect("memory");
    // No pixel scale: nothing needs refining, as in the hierarchy's refinement.
    cut.select(&o, &View::without_frustum(Vec3::ZERO, 0.0), 1.0)
        .expect("select");
    assert_eq!(cut.selected(), &[0]);
    // Inside the root's box: distance 0, every error projects infinitely, finest level.
    cut.select(
        &o,
        &View::without_frustum(Vec3::new(1.0, 0.5, 0.0), 100.0),
        1.0,
    )
    .expect("select");
    assert_eq!(cut.selected(), &[3, 4, 5, 6]);
    // A tolerance that is not a finite number above 0 is refused, as refinement refuses
    // it, and the cut stays as it was.
    for bad in [f32::NAN, 0.0, -1.0, f32::INFINITY] {
        assert_eq!(
            cut.select(&o, &far(), bad),
            Err(CutError::InvalidParams(ParamsError {
                field: ParamField::TolerancePx,
                value: bad
            }))
        );
        assert_eq!(cut.selected(), &[3, 4, 5, 6]);
    }
}

// ---- No allocation in select + emit -------------------------------------------------

#[test]
fn select_and_emit_do_not_allocate() {
    let s = Strip::new(3);
    let views = [far(), near(), middle(), away(), near()];
    let mut words = vec![0u32; OctreeCut::words_needed(&s.octree())];
    let mut packed = vec![0u32; s.indices.len()];
    let mut offsets = vec![0u32; 3];
    let mut lists = vec![vec![0u32; s.indices.len()]; 2];
    let mut slices: Vec<&mut [u32]> = lists.iter_mut().map(|l| l.as_mut_slice()).collect();
    let mut written = vec![0u32; 2];

    assert_counting();

    let before = allocations();
    let o = Octree::new(s.parts()).expect("valid");
    let mut cut = OctreeCut::new(&o, &mut words).expect("memory");
    let mut work = 0u64;
    for view in &views {
        let stats = cut.select(&o, view, TOLERANCE).expect("select");
        work += u64::from(stats.visited);
        work += cut.entered().chain(cut.left()).count() as u64;
        let n = cut
            .emit_indices_packed(&o, &mut packed, &mut offsets)
            .expect("packed");
        let m = cut
            .emit_indices(&o, &mut slices, &mut written)
            .expect("lists");
        assert_eq!(n, m);
        work += n as u64;
    }
    let after = allocations();
    black_box(work);
    assert!(work > 0);
    assert_eq!(
        after,
        before,
        "select + emit allocated {} times",
        after - before
    );
}
