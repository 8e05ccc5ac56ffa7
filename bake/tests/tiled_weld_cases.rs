//! The tiled weld against the in-core weld on small built meshes: every case at several
//! tilings, so borders cut through what each case repairs.

use caveclod_bake::mesh::{Mesh, Surface, Triangle, NO_ATTRIBUTE};
use caveclod_bake::weld::tiled::{weld_tiled, MeshTiles};
use caveclod_bake::weld::weld;

mod tiled_support;
use tiled_support::assert_same;

/// Builds test meshes: a height grid and extra pieces, one input vertex per corner use.
#[derive(Default)]
struct Builder {
    mesh: Mesh,
}

impl Builder {
    fn point(&mut self, p: [f32; 3]) -> u32 {
        self.mesh.positions.push(p);
        self.mesh.positions.len() as u32 - 1
    }

    fn triangle(&mut self, p: [u32; 3]) -> usize {
        self.mesh.triangles.push(Triangle {
            position: p,
            normal: [NO_ATTRIBUTE; 3],
            uv: [NO_ATTRIBUTE; 3],
            color: [NO_ATTRIBUTE; 3],
            surface: 0,
        });
        self.mesh.triangles.len() - 1
    }

    /// An `n × n` grid of cells over `0..n` on x and y, heights from `h`; returns the vertex
    /// ids by row. Corners get a normal unless `normal_every` says to skip them, a UV whose
    /// u jumps at `seam_x` (a seam: the vertex there has two UVs, one per side), and a
    /// colour when `colours`.
    fn grid(&mut self, n: u32, seam_x: Option<u32>, normal_every: u32, colours: bool) {
        let h = |x: u32, y: u32| ((x * 7 + y * 3) % 5) as f32 * 0.25 + (x as f32 * 0.3).sin();
        let at = |x: u32, y: u32| (y * (n + 1) + x) as usize;
        for y in 0..=n {
            for x in 0..=n {
                self.point([x as f32, y as f32, h(x, y)]);
            }
        }
        let s = self.mesh.surfaces.len().max(1);
        self.mesh.surfaces.resize(s, Surface::plain("grid"));
        for y in 0..n {
            for x in 0..n {
                let quad = [(x, y), (x + 1, y), (x + 1, y + 1), (x, y + 1)];
                for tri in [[0, 1, 2], [0, 2, 3]] {
                    let c = tri.map(|k| quad[k]);
                    let f = self.triangle(c.map(|(x, y)| at(x, y) as u32));
                    for k in 0..3 {
                        let (vx, vy) = c[k];
                        let corner = (f * 3 + k) as u32;
                        if normal_every == 0 || corner % normal_every != 0 {
                            let n = [(vx as f32 * 0.1).sin(), (vy as f32 * 0.1).cos(), 1.0];
                            self.mesh.triangles[f].normal[k] = self.mesh.normals.len() as u32;
                            self.mesh.normals.push(n);
                        }
                        if let Some(seam) = seam_x {
                            // The cell's side of the seam decides the u at the seam column.
                            let side = if x < seam { 0.0 } else { 10.0 };
                            self.mesh.triangles[f].uv[k] = self.mesh.uvs.len() as u32;
                            self.mesh
                                .uvs
                                .push([vx as f32 * 0.1 + side, vy as f32 * 0.1]);
                        }
                        if colours {
                            self.mesh.triangles[f].color[k] = self.mesh.colors.len() as u32;
                            self.mesh
                                .colors
                                .push([0.5, vx as f32 / n as f32, 0.25, 1.0]);
                        }
                    }
                }
            }
        }
    }
}

fn check(mesh: &Mesh, sides: &[u32]) {
    let reference = weld(mesh).expect("weld");
    for &side in sides {
        let mut tiles = MeshTiles::new(mesh, side).expect("tiles");
        let tiled = weld_tiled(&mut tiles).expect("tiled weld");
        assert_same(&reference, &tiled);
    }
}

#[test]
fn a_terrain_welds_as_in_core_at_every_tiling() {
    let mut b = Builder::default();
    b.grid(12, None, 0, false);
    check(&b.mesh, &[1, 2, 3, 4, 8]);
}

#[test]
fn missing_normals_are_computed_across_borders() {
    let mut b = Builder::default();
    b.grid(12, None, 4, true);
    check(&b.mesh, &[1, 2, 4, 5]);
    let mut b = Builder::default();
    b.grid(9, None, 1, false);
    check(&b.mesh, &[2, 3, 4]);
}

#[test]
fn a_uv_seam_across_tiles_splits_groups_as_in_core() {
    let mut b = Builder::default();
    b.grid(12, Some(5), 3, false);
    check(&b.mesh, &[1, 2, 3, 4, 8]);
}

#[test]
fn non_manifold_edges_and_bowties_on_borders_are_repaired_as_in_core() {
    let mut b = Builder::default();
    b.grid(8, None, 0, false);
    let at = |x: u32, y: u32| y * 9 + x;
    // Fins on the edge (4,3)–(4,4), on the border between the two halves: one the way the
    // grid's first triangle runs it, one the other way.
    let apex = b.point([4.2, 3.5, 3.0]);
    b.triangle([at(4, 3), at(4, 4), apex]);
    let apex2 = b.point([3.8, 3.5, 3.0]);
    b.triangle([at(4, 4), at(4, 3), apex2]);
    // A bowtie at (4, 6): two triangles touching the grid there only, their centroids on
    // either side of the border.
    let q = [
        b.point([5.0, 6.5, 4.0]),
        b.point([5.5, 6.0, 4.0]),
        b.point([3.0, 6.5, 4.0]),
        b.point([3.5, 6.0, 5.0]),
    ];
    b.triangle([at(4, 6), q[0], q[1]]);
    b.triangle([at(4, 6), q[2], q[3]]);
    // A duplicate (turned over) and a degenerate triangle on the border.
    b.triangle([at(4, 2), at(4, 1), at(3, 1)]);
    b.triangle([at(4, 2), at(4, 2), at(4, 1)]);
    b.mesh.positions.push([100.0, 100.0, 100.0]);
    let r = weld(&b.mesh).expect("weld").repairs;
    assert_eq!(
        (r.non_manifold_edges, r.non_manifold_vertices),
        (2, 2),
        "the fins on the grid's edge are cut; the bowtie's two extra fans split"
    );
    assert_eq!((r.duplicate_triangles, r.degenerate_triangles), (1, 1));
    check(&b.mesh, &[1, 2, 4]);
}

#[test]
fn several_surfaces_and_colours_join_across_borders() {
    let mut b = Builder::default();
    b.grid(10, Some(3), 5, true);
    b.mesh.surfaces.push(Surface::plain("other"));
    for (f, t) in b.mesh.triangles.iter_mut().enumerate() {
        if (f / 20) % 3 == 1 {
            t.surface = 1;
        }
    }
    check(&b.mesh, &[1, 2, 4, 8]);
}
