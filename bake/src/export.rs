//! Exporting one level of a hierarchy as Wavefront OBJ, to inspect it in any viewer.

use std::fmt::Write as _;

use caveclod_core::{Hierarchy, NodeId};

/// Which level to export.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    /// Every full-resolution polygon.
    Full,
    /// The base mesh.
    Base,
}

/// The OBJ text of `level`: positions, normals and UVs of the vertices used, one `usemtl`
/// group per surface (named `surface<N>`).
pub fn obj(h: &Hierarchy<'_>, level: Level) -> String {
    let tris: Vec<(usize, [NodeId; 3])> = match level {
        Level::Full => h
            .polygons()
            .iter()
            .enumerate()
            .map(|(i, p)| (i, p.nodes))
            .collect(),
        Level::Base => h
            .base()
            .iter()
            .enumerate()
            .map(|(i, b)| (i, b.corners))
            .collect(),
    };
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# caveclod export: {} level, {} triangles",
        if level == Level::Full { "full" } else { "base" },
        tris.len()
    );
    let mut index = vec![0u32; h.vertices().len()];
    let mut next = 1u32;
    let mut faces: Vec<Vec<[u32; 3]>> = vec![Vec::new(); h.surface_count()];
    for &(poly, corners) in &tris {
        let p = &h.polygons()[poly];
        let mut f = [0u32; 3];
        for k in 0..3 {
            let pos = h.nodes()[corners[k].index()].position;
            // Validated at load: the group has a vertex at every corner of every level.
            let v = h.vertex_index(p.group, pos).unwrap_or(0) as usize;
            if index[v] == 0 {
                let x = h.vertices()[v];
                let _ = writeln!(
                    out,
                    "v {} {} {}",
                    x.position[0], x.position[1], x.position[2]
                );
                let _ = writeln!(out, "vn {} {} {}", x.normal[0], x.normal[1], x.normal[2]);
                let _ = writeln!(out, "vt {} {}", x.uv[0], x.uv[1]);
                index[v] = next;
                next += 1;
            }
            f[k] = index[v];
        }
        faces[p.surface.index()].push(f);
    }
    for (s, fs) in faces.iter().enumerate() {
        if fs.is_empty() {
            continue;
        }
        let _ = writeln!(out, "usemtl surface{s}");
        for f in fs {
            let _ = writeln!(
                out,
                "f {0}/{0}/{0} {1}/{1}/{1} {2}/{2}/{2}",
                f[0], f[1], f[2]
            );
        }
    }
    out
}
