//! The welded store: a welded mesh stored in block order reads back as the same mesh
//! renumbered (its origins say how), every block of every level is one range of triangles
//! whose centroids lie in the block's tiles, and positions are numbered by first use.

use caveclod_bake::weld::WeldInfo;
use caveclod_bake::weld::{self, Welded};
use caveclod_bake::weld_store::{StoreWriter, StoredTri, WeldedStore};
use caveclod_core::format::PositionClass;
use caveclod_tests::{meshes, to_mesh};

fn welded(nx: u32) -> Welded {
    weld::weld(&to_mesh(&meshes::holed_terrain(nx, nx, 5))).expect("weld")
}

#[test]
fn a_stored_mesh_reads_back_as_the_same_mesh_renumbered() {
    let w = welded(40);
    let store = WeldedStore::from_welded(w.clone(), 200, true).expect("store");
    assert!(store.side() >= 4, "{} tiles a side", store.side());
    assert_eq!(store.triangles(), w.triangles.len());
    let origins = store.origins().expect("kept").clone();
    let back = store.into_welded().expect("read back");
    assert_eq!(back.positions.len(), w.positions.len());
    assert_eq!(back.attributes.len(), w.attributes.len());
    assert_eq!(back.group_ids, w.group_ids);
    for (f, t) in back.triangles.iter().enumerate() {
        let o = &w.triangles[origins.triangles[f] as usize];
        assert_eq!(t.p.map(|x| origins.positions[x as usize]), o.p);
        assert_eq!((back.surface_of(t), t.group), (w.surface_of(o), o.group));
        let (at, ao) = (back.corner_attributes(t), w.corner_attributes(o));
        for k in 0..3 {
            assert_eq!(
                back.attributes[at[k] as usize],
                w.attributes[ao[k] as usize]
            );
        }
    }
    for (x, &o) in origins.positions.iter().enumerate() {
        assert_eq!(back.positions[x], w.positions[o as usize]);
        assert_eq!(back.classes[x], w.classes[o as usize]);
        let lists = |v: &Welded, p: usize| -> Vec<_> {
            v.vertices[p]
                .iter()
                .map(|&(g, a)| (g, v.attributes[a as usize].normal))
                .collect()
        };
        assert_eq!(lists(&back, x), lists(&w, o as usize));
    }
    // Positions by first use in triangle order.
    let mut next = 0;
    for t in &back.triangles {
        for x in t.p {
            assert!(x <= next, "position {x} used before {next}");
            next = next.max(x + 1);
        }
    }
}

#[test]
fn every_block_of_every_level_is_one_range_of_its_tiles_triangles() {
    let w = welded(48);
    let store = WeldedStore::from_welded(w, 150, false).expect("store");
    let side = store.side();
    assert!(side >= 8, "{side} tiles a side");
    let (lo, hi) = store.bounds();
    // The tiles divide the two widest axes, the wider first.
    let mut axes = [0usize, 1, 2];
    axes.sort_by(|&a, &b| (hi[b] - lo[b]).total_cmp(&(hi[a] - lo[a])));
    let all = store
        .read_triangles(0..store.triangles() as u32)
        .expect("read");
    let xyz = store
        .read_positions(0..store.positions() as u32)
        .expect("read");
    for level in 0..=side.trailing_zeros() {
        let s = side >> level;
        let mut covered = 0;
        for code in 0..store.blocks(level) {
            let r = store.block(level, code);
            assert_eq!(r.start, covered, "level {level} block {code}");
            covered = r.end;
            // The block's tile `(x, y)` from its Z-order code.
            let (mut x, mut y) = (0, 0);
            for bit in 0..16 {
                x |= ((code >> (2 * bit)) & 1) << bit;
                y |= ((code >> (2 * bit + 1)) & 1) << bit;
            }
            for t in &all[r.start as usize..r.end as usize] {
                let c = |a: usize| {
                    let m = t.p.iter().map(|&p| xyz[p as usize][a]).sum::<f32>() / 3.0;
                    ((m - lo[a]) / (hi[a] - lo[a]) * s as f32)
                        .floor()
                        .min(s as f32 - 1.0) as u32
                };
                assert_eq!(
                    (c(axes[0]), c(axes[1])),
                    (x, y),
                    "level {level} block {code}"
                );
            }
        }
        assert_eq!(covered as usize, all.len());
    }
}

#[test]
fn a_triangle_naming_a_missing_position_is_refused_with_its_index() {
    let mut out = StoreWriter::new().expect("writer");
    out.push_position([0.0; 3], PositionClass::Free, &[[0, 0]])
        .expect("push");
    out.push_triangles(&[StoredTri {
        p: [0, 0, 7],
        ..StoredTri::default()
    }])
    .expect("push");
    let info = WeldInfo {
        group_count: 1,
        surface_count: 1,
        ..WeldInfo::default()
    };
    let e = out.finish(info, 100, false).expect_err("invalid");
    assert!(
        e.to_string().contains("triangle 0 names position 7 of 1"),
        "{e}"
    );
}
