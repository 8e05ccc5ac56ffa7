//! What the tiled weld's tests share: the check that two welded meshes are one up to
//! numbering.

use std::collections::HashMap;

use caveclod_bake::weld::{Welded, WeldedTri};

/// Each triangle of `a` with the triangle of `b` at the same corner coordinates (unique once
/// duplicates are dropped); panics if `b` has none there.
pub fn matched_triangles<'w>(
    a: &'w Welded,
    b: &'w Welded,
) -> impl Iterator<Item = (&'w WeldedTri, &'w WeldedTri)> {
    let coords = |w: &Welded, p: [u32; 3]| p.map(|x| w.positions[x as usize].map(f32::to_bits));
    let by_coords: HashMap<_, usize> = b
        .triangles
        .iter()
        .enumerate()
        .map(|(f, t)| (coords(b, t.p), f))
        .collect();
    a.triangles.iter().map(move |ta| {
        let at = by_coords.get(&coords(a, ta.p)).expect("triangle in both");
        (ta, &b.triangles[*at])
    })
}

/// Checks that `b` is `a` up to numbering: triangles matched by their corners' coordinates
/// (unique once duplicates are dropped), positions and groups mapped one to one, the same
/// attribute sets per corner, classes, vertices, repairs and group ids (so the colouring too).
pub fn assert_same(a: &Welded, b: &Welded) {
    assert_eq!(a.triangles.len(), b.triangles.len(), "triangles");
    assert_eq!(a.positions.len(), b.positions.len(), "positions");
    assert_eq!(a.attributes.len(), b.attributes.len(), "attribute sets");
    assert_eq!(a.repairs, b.repairs, "repairs");
    assert_eq!(a.group_count, b.group_count, "groups");
    assert_eq!(a.group_id_count, b.group_id_count, "group ids");
    assert_eq!(a.has_colors, b.has_colors);
    assert_eq!(a.surface_count, b.surface_count);
    let mut pos = vec![u32::MAX; a.positions.len()];
    let mut group = vec![u32::MAX; a.group_count as usize];
    let map = |m: &mut Vec<u32>, x: u32, y: u32, what: &str| {
        assert!(
            m[x as usize] == u32::MAX || m[x as usize] == y,
            "{what} {x} maps twice"
        );
        m[x as usize] = y;
    };
    for (ta, tb) in matched_triangles(a, b) {
        assert_eq!(a.surface_of(ta), b.surface_of(tb));
        map(&mut group, ta.group, tb.group, "group");
        let (aa, ab) = (a.corner_attributes(ta), b.corner_attributes(tb));
        for k in 0..3 {
            map(&mut pos, ta.p[k], tb.p[k], "position");
            assert_eq!(a.attributes[aa[k] as usize], b.attributes[ab[k] as usize]);
        }
    }
    let mut images: Vec<u32> = pos.iter().copied().filter(|&x| x != u32::MAX).collect();
    images.sort_unstable();
    images.dedup();
    assert_eq!(
        images.len(),
        pos.iter().filter(|&&x| x != u32::MAX).count(),
        "two positions map to one"
    );
    for (x, &y) in pos.iter().enumerate() {
        if y == u32::MAX {
            continue;
        }
        assert_eq!(a.classes[x], b.classes[y as usize], "class of position {x}");
        let attrs = |w: &Welded, at: u32| format!("{:?}", w.attributes[at as usize]);
        let mut va: Vec<_> = a.vertices[x]
            .iter()
            .map(|&(g, at)| (group[g as usize], attrs(a, at)))
            .collect();
        let mut vb: Vec<_> = b.vertices[y as usize]
            .iter()
            .map(|&(g, at)| (g, attrs(b, at)))
            .collect();
        va.sort();
        vb.sort();
        assert_eq!(va, vb, "vertices at position {x}");
    }
    for (g, &h) in group.iter().enumerate() {
        assert_eq!(a.group_ids[g], b.group_ids[h as usize], "id of group {g}");
    }
}
