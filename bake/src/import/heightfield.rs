//! Regular grids of heights (DEM, npy) to a triangle mesh, shared by both heightfield
//! importers.
//!
//! Axes: x east, y up, z **south**, origin at the north-west post of the grid (so every x and
//! z is ≥ 0), all in metres. Row 0 of a grid is its northern edge.
//!
//! A missing post (NaN height) removes the four cells around it: a cell becomes two triangles
//! only when all four of its posts exist, so irregular borders and voids become mesh borders
//! and holes, never spikes to a fill value. Each post that some emitted cell uses becomes one
//! position with its own normal (central differences of the grid, one-sided next to borders
//! and holes) and UV (`u` west to east, `v` north to south, both 0..=1 over the grid's extent);
//! posts that no cell uses are not emitted at all.

use super::error::{ImportError, Source};
use super::ids::{next_index, push_surface};
use super::options::{HeightfieldInfo, ImportReport};
use crate::mesh::{Mesh, Surface, Triangle, NO_ATTRIBUTE};

/// A grid of heights in metres.
pub(crate) struct Heightfield {
    /// Posts per row (along x, east).
    pub width: usize,
    /// Rows (along z, south).
    pub depth: usize,
    /// Metres between neighbouring posts along x and along z.
    pub spacing: [f32; 2],
    /// `width * depth` heights in metres, row-major, row 0 the northern edge; NaN marks a
    /// missing post. Infinite heights are errors.
    pub heights: Vec<f32>,
}

impl Heightfield {
    fn height(&self, col: usize, row: usize) -> Option<f32> {
        let h = self.heights[row * self.width + col];
        (!h.is_nan()).then_some(h)
    }

    fn cell_complete(&self, col: usize, row: usize) -> bool {
        self.height(col, row).is_some()
            && self.height(col + 1, row).is_some()
            && self.height(col, row + 1).is_some()
            && self.height(col + 1, row + 1).is_some()
    }

    /// Slope `dh/dx` (or `dh/dz` with `along_z`) at a post, from the neighbours that exist;
    /// in `f64`, where any two finite `f32` heights and spacing give a finite slope whose
    /// square is finite too (in `f32` the difference of heights near `f32::MAX` overflows).
    fn slope(&self, col: usize, row: usize, along_z: bool) -> f64 {
        let (len, i, step) = if along_z {
            (self.depth, row, f64::from(self.spacing[1]))
        } else {
            (self.width, col, f64::from(self.spacing[0]))
        };
        let at = |j: usize| {
            if along_z {
                self.height(col, j)
            } else {
                self.height(j, row)
            }
            .map(f64::from)
        };
        let here = at(i);
        let before = if i > 0 { at(i - 1) } else { None };
        let after = if i + 1 < len { at(i + 1) } else { None };
        match (before, here, after) {
            (Some(b), _, Some(a)) => (a - b) / (2.0 * step),
            (None, Some(h), Some(a)) => (a - h) / step,
            (Some(b), Some(h), None) => (h - b) / step,
            _ => 0.0,
        }
    }
}

/// Builds the mesh of `grid` with one surface named `surface_name`; notes missing posts in
/// `report`.
///
/// The passes: the grid checked and described in the report, the surface, the posts some
/// complete cell uses as vertices, then two triangles per complete cell.
pub(crate) fn heightfield_to_mesh(
    source: &Source,
    grid: &Heightfield,
    surface_name: &str,
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    let posts = check_grid(source, grid)?;
    let missing = grid.heights.iter().filter(|h| h.is_nan()).count();
    report.heightfield = Some(describe(grid, posts - missing));
    let mut mesh = Mesh::default();
    let surface = push_surface(source, &mut mesh, Surface::plain(surface_name))?;
    if grid.width < 2 || grid.depth < 2 {
        return Ok(mesh);
    }
    let index = push_posts(source, grid, &used_posts(grid), &mut mesh)?;
    let skipped_cells = push_cells(grid, &index, surface, &mut mesh);
    if missing > 0 {
        report.notes.push(format!(
            "{}: {missing} of {posts} grid posts are missing; the {skipped_cells} cells that \
             touch them are left out (holes and borders)",
            source.name
        ));
    }
    Ok(mesh)
}

/// The post count, which must match the heights; no height infinite (NaN marks a missing
/// post); a spacing that is a positive `f32` over a grid whose extent is one too (a header's
/// resolution can be anything an `f64` holds).
fn check_grid(source: &Source, grid: &Heightfield) -> Result<usize, ImportError> {
    let [sx, sz] = grid.spacing;
    let extent = [
        grid.width.saturating_sub(1) as f32 * sx,
        grid.depth.saturating_sub(1) as f32 * sz,
    ];
    let positive = |v: f32| v.is_finite() && v > 0.0;
    if !(positive(sx) && positive(sz) && extent.iter().all(|e| e.is_finite())) {
        return Err(source.unsupported(
            "grid",
            format!(
                "a spacing of {sx} x {sz} m over {} x {} posts is outside the range of 32-bit \
                 coordinates",
                grid.width, grid.depth
            ),
        ));
    }
    let posts = grid
        .width
        .checked_mul(grid.depth)
        .filter(|&n| n == grid.heights.len())
        .ok_or_else(|| {
            source.malformed(
                "grid",
                format!(
                    "{} x {} posts but {} heights",
                    grid.width,
                    grid.depth,
                    grid.heights.len()
                ),
            )
        })?;
    if let Some(i) = grid.heights.iter().position(|h| h.is_infinite()) {
        return Err(source.non_finite(
            format!("row {} column {}", i / grid.width, i % grid.width),
            "height",
            f64::from(grid.heights[i]),
        ));
    }
    Ok(posts)
}

/// The grid's size, spacing and height range, with `present` posts.
fn describe(grid: &Heightfield, present: usize) -> HeightfieldInfo {
    let (low, high) = grid
        .heights
        .iter()
        .filter(|h| !h.is_nan())
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
    HeightfieldInfo {
        columns: grid.width,
        rows: grid.depth,
        posts: present,
        spacing: grid.spacing,
        height_range: [low, high],
    }
}

/// Which posts some complete cell uses.
fn used_posts(grid: &Heightfield) -> Vec<bool> {
    let mut used = vec![false; grid.width * grid.depth];
    for row in 0..grid.depth - 1 {
        for col in 0..grid.width - 1 {
            if grid.cell_complete(col, row) {
                for (c, r) in [
                    (col, row),
                    (col + 1, row),
                    (col, row + 1),
                    (col + 1, row + 1),
                ] {
                    used[r * grid.width + c] = true;
                }
            }
        }
    }
    used
}

/// The used posts as vertices (position, normal from the slopes, UV over the grid); each
/// post's vertex index, `NO_ATTRIBUTE` where unused.
fn push_posts(
    source: &Source,
    grid: &Heightfield,
    used: &[bool],
    mesh: &mut Mesh,
) -> Result<Vec<u32>, ImportError> {
    let mut index = vec![NO_ATTRIBUTE; used.len()];
    let u_scale = 1.0 / (grid.width - 1) as f32;
    let v_scale = 1.0 / (grid.depth - 1) as f32;
    for row in 0..grid.depth {
        for col in 0..grid.width {
            let i = row * grid.width + col;
            if !used[i] {
                continue;
            }
            index[i] = next_index(source, mesh.positions.len(), "posts")?;
            let h = grid.heights[i];
            mesh.positions.push([
                col as f32 * grid.spacing[0],
                h,
                row as f32 * grid.spacing[1],
            ]);
            let n = [
                -grid.slope(col, row, false),
                1.0,
                -grid.slope(col, row, true),
            ];
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            mesh.normals.push(n.map(|c| (c / len) as f32));
            mesh.uvs.push([col as f32 * u_scale, row as f32 * v_scale]);
        }
    }
    Ok(index)
}

/// Two triangles per complete cell; the count of cells left out.
fn push_cells(grid: &Heightfield, index: &[u32], surface: u16, mesh: &mut Mesh) -> usize {
    let mut skipped_cells = 0usize;
    for row in 0..grid.depth - 1 {
        for col in 0..grid.width - 1 {
            if !grid.cell_complete(col, row) {
                skipped_cells += 1;
                continue;
            }
            let nw = index[row * grid.width + col];
            let ne = index[row * grid.width + col + 1];
            let sw = index[(row + 1) * grid.width + col];
            let se = index[(row + 1) * grid.width + col + 1];
            // Counter-clockwise seen from above (+y) with z pointing south.
            for corners in [[nw, sw, se], [nw, se, ne]] {
                mesh.triangles.push(Triangle {
                    position: corners,
                    normal: corners,
                    uv: corners,
                    color: [NO_ATTRIBUTE; 3],
                    surface,
                });
            }
        }
    }
    skipped_cells
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(width: usize, depth: usize, heights: Vec<f32>) -> Heightfield {
        Heightfield {
            width,
            depth,
            spacing: [2.0, 3.0],
            heights,
        }
    }

    fn source() -> Source {
        Source {
            name: "grid.test".to_owned(),
        }
    }

    #[test]
    fn full_grid_is_two_triangles_per_cell_facing_up() {
        let g = grid(3, 2, vec![0.0, 1.0, 2.0, 0.0, 1.0, 2.0]);
        let mut report = ImportReport::default();
        let mesh = heightfield_to_mesh(&source(), &g, "t", &mut report).unwrap();
        mesh.validate().unwrap();
        assert_eq!(mesh.positions.len(), 6);
        assert_eq!(mesh.triangles.len(), 4);
        assert!(report.notes.is_empty());
        assert_eq!(mesh.positions[5], [4.0, 2.0, 3.0]);
        assert_eq!(mesh.uvs[5], [1.0, 1.0]);
        let info = report.heightfield.unwrap();
        assert_eq!((info.columns, info.rows, info.posts), (3, 2, 6));
        assert_eq!(info.height_range, [0.0, 2.0]);
        for t in &mesh.triangles {
            let [a, b, c] = t.position.map(|i| mesh.positions[i as usize]);
            let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let ny = e1[2] * e2[0] - e1[0] * e2[2];
            assert!(ny > 0.0, "triangle {t:?} faces down");
        }
        // Height rises 1 m per 2 m east: the normal leans west.
        let n = mesh.normals[0];
        assert!((n[0] - (-0.5 / 1.25f32.sqrt())).abs() < 1e-6, "{n:?}");
        assert!(n[2].abs() < 1e-6);
    }

    #[test]
    fn missing_post_removes_its_cells_and_is_noted() {
        let nan = f32::NAN;
        // 3 x 3 posts, the centre missing: no complete cell remains.
        let g = grid(3, 3, vec![0.0, 0.0, 0.0, 0.0, nan, 0.0, 0.0, 0.0, 0.0]);
        let mut report = ImportReport::default();
        let mesh = heightfield_to_mesh(&source(), &g, "t", &mut report).unwrap();
        assert!(mesh.triangles.is_empty());
        assert!(mesh.positions.is_empty());
        assert_eq!(report.notes.len(), 1);
        assert!(report.notes[0].contains("1 of 9"), "{:?}", report.notes);

        // A missing corner removes only its cell.
        let g = grid(3, 3, vec![nan, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        let mesh = heightfield_to_mesh(&source(), &g, "t", &mut report).unwrap();
        assert_eq!(mesh.triangles.len(), 6);
        assert_eq!(mesh.positions.len(), 8);
        mesh.validate().unwrap();
    }

    /// Neighbouring heights near `f32::MAX` of opposite signs: their difference overflows
    /// `f32`, and the normals must still be finite unit vectors (found by the `npy` fuzz
    /// target, whose mesh had a NaN normal).
    #[test]
    fn extreme_heights_give_finite_normals() {
        let (max, min) = (f32::MAX, f32::MIN);
        let g = grid(3, 3, vec![max, min, max, min, max, min, max, min, max]);
        let mut report = ImportReport::default();
        let mesh = heightfield_to_mesh(&source(), &g, "t", &mut report).unwrap();
        mesh.validate().unwrap();
        assert_eq!(mesh.triangles.len(), 8);
        for n in &mesh.normals {
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            assert!((len - 1.0).abs() < 1e-5, "{n:?}");
        }
        // At the middle of the west edge the height rises from MIN to MAX going east: the
        // normal leans west, almost level.
        let n = mesh.normals[3];
        assert!(n[0] < -0.999 && n[1] > 0.0, "{n:?}");
    }

    /// A DEM header's resolution can round to 0 or infinity in `f32`, or give an extent
    /// past `f32::MAX`: typed errors, not NaN or infinite positions.
    #[test]
    fn spacing_outside_f32_is_an_error() {
        for spacing in [
            [0.0, 3.0],
            [f32::INFINITY, 3.0],
            [2.0, f32::NAN],
            [2e38, 2e38],
        ] {
            let g = Heightfield {
                spacing,
                ..grid(3, 2, vec![0.0; 6])
            };
            let err =
                heightfield_to_mesh(&source(), &g, "t", &mut ImportReport::default()).unwrap_err();
            assert!(matches!(err, ImportError::Unsupported { .. }), "{err}");
            assert!(err.to_string().contains("3 x 2 posts"), "{err}");
        }
    }

    #[test]
    fn infinite_height_is_an_error() {
        let g = grid(2, 2, vec![0.0, 0.0, f32::INFINITY, 0.0]);
        let err = heightfield_to_mesh(&source(), &g, "t", &mut ImportReport::default())
            .unwrap_err()
            .to_string();
        assert_eq!(err, "grid.test: row 1 column 0: height is inf");
    }
}
