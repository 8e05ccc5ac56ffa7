//! The paged form: a baked terrain written paged reads back root first, every page passes
//! its checks against its parents, and walking both forms from the roots meets the same
//! positions, bounds, polygons and vertices through every split; a whole-file reader refuses
//! a paged file, a damaged page fails its checks, and the root opens on its own.

use std::collections::HashMap;

use caveclod_bake::paged::{write_paged, PageOptions};
use caveclod_core::format::checksum64;
use caveclod_core::format::paged::{PageView, PagedRoot};
use caveclod_core::{FormatError, Hierarchy, NodeId, PolyKey};
use caveclod_tests::{bake, meshes, AlignedBytes};

struct Paged {
    bytes: AlignedBytes,
    root_len: usize,
}

impl Paged {
    fn root(&self) -> PagedRoot<'_> {
        PagedRoot::from_bytes(&self.bytes.bytes()[..self.root_len]).expect("root")
    }
    fn page_bytes(&self, page: u32) -> &[u8] {
        let e = *self.root().table().entry(page).expect("page");
        &self.bytes.bytes()[e.offset as usize..][..e.size as usize]
    }
    fn view(&self, page: u32) -> PageView<'_> {
        let layout = self.root().table().layout(page).expect("layout");
        PageView::cast(self.page_bytes(page), &layout).expect("view")
    }
}

fn paged_terrain(page_bytes: u32) -> (caveclod_tests::BakedMesh, Paged, tempfile::TempDir) {
    let baked = bake(&meshes::terrain(32, 32, 3));
    let dir = tempfile::tempdir().expect("dir");
    let path = dir.path().join("t.clod");
    let summary =
        write_paged(&baked.hierarchy(), &path, &PageOptions { page_bytes }).expect("paged");
    let bytes = AlignedBytes::from_slice(&std::fs::read(&path).expect("read"));
    assert_eq!(bytes.bytes().len() as u64, summary.file_bytes);
    assert!(summary.largest_page <= page_bytes, "{summary:?}");
    let paged = Paged {
        bytes,
        root_len: summary.root_bytes as usize,
    };
    (baked, paged, dir)
}

#[test]
fn every_page_passes_its_checks_and_the_forms_agree() {
    let (baked, paged, _dir) = paged_terrain(4 * 1024);
    let h = baked.hierarchy();
    let root = paged.root();
    let pages = root.table().len() as u32;
    assert!(pages > 8, "{pages} pages");
    for page in 1..pages {
        let b = paged.page_bytes(page);
        assert_eq!(checksum64(b), root.table().entry(page).unwrap().checksum);
        root.check_page(page, b, |p| Some(paged.view(p)))
            .expect("page checks");
    }
    assert_same_hierarchy(&h, &paged);
}

/// Walks both forms from the roots, pairing nodes through the split records.
fn assert_same_hierarchy(h: &Hierarchy<'_>, paged: &Paged) {
    let root = paged.root();
    let ids = root.ids();
    let view = |id: u32| paged.view(ids.page(id));
    let at = |id: u32| ids.index(id) as usize;
    let point = |id: u32| {
        let v = view(id);
        let q = v.nodes[at(id)].position.0;
        paged.view(ids.page(q)).positions[at(q)].xyz
    };
    let mut by_point: HashMap<[u32; 3], u32> = HashMap::new();
    for &r in root.roots() {
        by_point.insert(point(r.0).map(f32::to_bits), r.0);
    }
    let mut map: HashMap<u32, u32> = HashMap::new();
    let mut stack: Vec<(u32, u32)> = h
        .roots()
        .iter()
        .map(|r| {
            let xyz = h.node_point(*r).unwrap().map(f32::to_bits);
            (r.0, by_point[&xyz])
        })
        .collect();
    while let Some((old, new)) = stack.pop() {
        map.insert(old, new);
        assert_eq!(h.node_point(NodeId(old)).unwrap(), point(new));
        let v = view(new);
        let Some(s) = h.split(NodeId(old)) else {
            assert!(at(new) >= v.splits.len(), "a leaf became splittable");
            continue;
        };
        let (ns, nb) = (v.splits[at(new)], v.bounds[at(new)]);
        assert_eq!(*h.split_bounds(NodeId(old)).unwrap(), nb);
        for (o, n) in [(s.f_l, ns.f_l), (s.f_r, ns.f_r)] {
            if let Some(o) = o.get() {
                let (op, np) = (h.polygons()[o.index()], view(n.0).polygons[at(n.0)]);
                assert_eq!((op.surface, op.group), (np.surface, np.group));
            }
        }
        stack.push((s.stationary.0, ns.stationary.0));
        stack.push((s.floating.0, ns.floating.0));
    }
    assert_eq!(map.len(), h.nodes().len());
    // Neighbour keys and polygon corners name the paired nodes.
    let base = h.base_polygon_count() as u32;
    for (old, s) in h.splits().iter().enumerate() {
        let new = map[&(old as u32)];
        let ns = view(new).splits[at(new)];
        for (o, n) in s.neighbours.iter().zip(ns.neighbours) {
            let want = match o.creator(base) {
                Some((c, right)) => PolyKey(base + 2 * map[&c.0] + u32::from(right)),
                None => *o,
            };
            assert_eq!(n, want);
        }
    }
}

#[test]
fn the_root_opens_alone_and_whole_file_readers_refuse_a_paged_file() {
    let (_baked, paged, _dir) = paged_terrain(4 * 1024);
    let root = paged.root();
    assert!(root.paged().file_len > paged.root_len as u64);
    assert_eq!(
        Hierarchy::from_bytes(&paged.bytes.bytes()[..paged.root_len]).err(),
        Some(FormatError::Paged)
    );
    assert!(root
        .root_page(0)
        .is_some_and(|v| v.polygons.len() >= root.base().len()));
}

#[test]
fn a_damaged_page_fails_its_checks() {
    let (_baked, paged, _dir) = paged_terrain(4 * 1024);
    let root = paged.root();
    let page = root.table().len() as u32 / 2;
    let mut bytes = paged.page_bytes(page).to_vec();
    // The first node's parent: a node of no parent page.
    let words: &mut [u32] = bytemuck::cast_slice_mut(&mut bytes[..8]);
    words[0] = u32::MAX - 1;
    let aligned = AlignedBytes::from_slice(&bytes);
    let err = root
        .check_page(page, aligned.bytes(), |p| Some(paged.view(p)))
        .expect_err("refused");
    assert!(err.to_string().contains("NODE record 0"), "{err}");
    assert_ne!(
        checksum64(&bytes),
        root.table().entry(page).unwrap().checksum
    );
}

/// A blocked bake numbers its splits in reverse creation order, not depth first; its pages
/// are still runs of subtrees: a page has a few parent pages, not one per block it touches.
#[test]
fn a_blocked_bake_pages_into_subtrees() {
    use caveclod_bake::blocked::BlockedOptions;
    use caveclod_bake::import::ImportOptions;
    use caveclod_bake::pipeline::build_file_spilled;
    let dir = tempfile::tempdir().expect("dir");
    let input = dir.path().join("terrain.ply");
    caveclod_tests::generate::terrain(&input, 20_000, &mut |_, _| {}).expect("generate");
    let options = BlockedOptions {
        block_triangles: 2048,
    };
    // As `caveclod bake --blocked` writes it: splits in reverse creation order.
    let (built, levels) =
        build_file_spilled(&input, &ImportOptions::default(), &options, &mut |_| {})
            .expect("blocked bake");
    assert!(levels[0].blocks > 4, "{levels:?}");
    let whole = dir.path().join("whole.clod");
    built.write(&whole, &[]).expect("write");
    let bytes = AlignedBytes::from_slice(&std::fs::read(&whole).expect("read"));
    let h = Hierarchy::from_bytes(bytes.bytes()).expect("valid");
    let path = dir.path().join("paged.clod");
    let summary = write_paged(
        &h,
        &path,
        &PageOptions {
            page_bytes: 8 * 1024,
        },
    )
    .expect("paged");
    let file = AlignedBytes::from_slice(&std::fs::read(&path).expect("read"));
    let root = PagedRoot::from_bytes(&file.bytes()[..summary.root_bytes as usize]).expect("root");
    let table = root.table();
    assert!(table.len() > 20, "{} pages", table.len());
    let most = (0..table.len() as u32)
        .map(|p| table.parents(p).len())
        .max()
        .unwrap_or(0);
    assert!(most <= 4, "a page with {most} parent pages");
}

/// The root's record of the largest streamed page (what a pool's slots must hold) is the
/// page table's, or the root is refused.
#[test]
fn a_root_that_misstates_its_largest_page_is_refused() {
    use caveclod_core::format::FileHeader;
    let (_baked, paged, _dir) = paged_terrain(4 * 1024);
    let mut root = paged.bytes.bytes()[..paged.root_len].to_vec();
    // The section table's second entry is PGMT; `largest_page` is its 24th byte on.
    let entry = &root[64 + 24..64 + 48];
    assert_eq!(&entry[..4], b"PGMT");
    let at = u64::from_le_bytes(entry[8..16].try_into().expect("offset")) as usize + 24;
    root[at] ^= 1;
    let mut header: FileHeader = bytemuck::pod_read_unaligned(&root[..64]);
    header.checksum = checksum64(&root[64..]);
    root[..64].copy_from_slice(bytemuck::bytes_of(&header));
    let root = AlignedBytes::from_slice(&root);
    let err = PagedRoot::from_bytes(root.bytes()).expect_err("refused");
    assert!(err.to_string().contains("largest_page"), "{err}");
}
