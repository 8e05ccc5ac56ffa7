//! A procedural terrain of any size, streamed to binary PLY (`caveclod generate`).
//!
//! [`terrain`] writes a heightfield terrain (sums of sines: smooth, with analytic normals)
//! as a `binary_little_endian` PLY with per-vertex normals, 8-bit colours (by height) and
//! texture coordinates (the grid's), so out-of-core tests and benchmarks have inputs of tens
//! of millions of triangles without downloads. Nothing is held in memory but one row of the
//! grid at a time: vertices are written row by row, then faces row by row (the face element
//! needs no vertex data). The file is written to a temporary sibling and renamed once
//! complete, so an interrupted run never leaves a partial file under the requested name.

use std::io::{self, BufWriter, Write};
use std::path::Path;

/// Side of the terrain, in file units.
pub const TERRAIN_SIZE: f32 = 1000.0;

/// The grid a requested triangle count becomes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TerrainGrid {
    /// Quads along x.
    pub columns: u32,
    /// Quads along z.
    pub rows: u32,
}

impl TerrainGrid {
    /// The grid closest to square with at least `triangles` triangles (two per quad); at least
    /// one quad.
    pub fn for_triangles(triangles: u64) -> Result<Self, GenerateError> {
        let quads = triangles.div_ceil(2).max(1);
        let columns = ((quads as f64).sqrt().ceil() as u64).max(1);
        let rows = quads.div_ceil(columns);
        let vertices = (columns + 1) * (rows + 1);
        if vertices > u64::from(u32::MAX) || columns > u64::from(u32::MAX) {
            return Err(GenerateError::TooLarge { triangles });
        }
        Ok(Self {
            columns: columns as u32,
            rows: rows as u32,
        })
    }

    /// Vertices written: `(columns + 1) * (rows + 1)`.
    pub fn vertices(&self) -> u64 {
        (u64::from(self.columns) + 1) * (u64::from(self.rows) + 1)
    }

    /// Triangles written: two per quad.
    pub fn triangles(&self) -> u64 {
        2 * u64::from(self.columns) * u64::from(self.rows)
    }
}

/// Why generating failed.
#[derive(Debug, thiserror::Error)]
pub enum GenerateError {
    /// More vertices than 32-bit indices can name.
    #[error("{triangles} triangles need more than 2^32 - 1 vertices")]
    TooLarge {
        /// Requested.
        triangles: u64,
    },
    /// Writing failed.
    #[error("{path}: {source}")]
    Io {
        /// The output file.
        path: String,
        /// The operating-system error.
        #[source]
        source: io::Error,
    },
}

/// Height and its x and z derivatives at `(x, z)` in `0..=1`, in file units.
fn height(x: f32, z: f32) -> (f32, f32, f32) {
    use std::f32::consts::TAU;
    // (frequency x, frequency z, amplitude, phase)
    const WAVES: [(f32, f32, f32, f32); 4] = [
        (1.0, 0.5, 60.0, 0.3),
        (2.5, 3.0, 20.0, 1.1),
        (7.0, 5.0, 6.0, 2.0),
        (17.0, 23.0, 1.5, 0.7),
    ];
    let (mut h, mut dx, mut dz) = (0.0, 0.0, 0.0);
    for (fx, fz, a, p) in WAVES {
        let t = TAU * (fx * x + fz * z) + p;
        let (s, c) = t.sin_cos();
        h += a * s;
        dx += a * c * TAU * fx;
        dz += a * c * TAU * fz;
    }
    (h, dx / TERRAIN_SIZE, dz / TERRAIN_SIZE)
}

/// Writes the terrain's PLY to `out`; `progress(done, total)` counts triangles and vertices
/// written.
pub fn write_terrain(
    out: &mut dyn Write,
    grid: TerrainGrid,
    progress: &mut dyn FnMut(u64, u64),
) -> io::Result<()> {
    let (cols, rows) = (grid.columns, grid.rows);
    let total = grid.vertices() + grid.triangles();
    write!(
        out,
        "ply\nformat binary_little_endian 1.0\ncomment caveclod generate: terrain {cols}x{rows}\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n\
         property float u\nproperty float v\n\
         element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        grid.vertices(),
        grid.triangles()
    )?;
    let mut buf = Vec::with_capacity(35 * (cols as usize + 1));
    let mut done = 0u64;
    for j in 0..=rows {
        buf.clear();
        let zf = j as f32 / rows as f32;
        for i in 0..=cols {
            let xf = i as f32 / cols as f32;
            let (h, dx, dz) = height(xf, zf);
            let n = [-dx, 1.0, -dz];
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            let t = ((h + 90.0) / 180.0).clamp(0.0, 1.0);
            let rgb = [
                (60.0 + 180.0 * t) as u8,
                (140.0 - 40.0 * t) as u8,
                (60.0 + 150.0 * t * t) as u8,
            ];
            for v in [xf * TERRAIN_SIZE, h, zf * TERRAIN_SIZE] {
                buf.extend_from_slice(&v.to_le_bytes());
            }
            for v in n {
                buf.extend_from_slice(&(v / len).to_le_bytes());
            }
            buf.extend_from_slice(&rgb);
            for v in [xf, 1.0 - zf] {
                buf.extend_from_slice(&v.to_le_bytes());
            }
        }
        out.write_all(&buf)?;
        done += u64::from(cols) + 1;
        progress(done, total);
    }
    let stride = cols + 1;
    for j in 0..rows {
        buf.clear();
        for i in 0..cols {
            let a = j * stride + i;
            let (b, c, d) = (a + stride, a + 1, a + stride + 1);
            for tri in [[a, b, c], [c, b, d]] {
                buf.push(3);
                for v in tri {
                    buf.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
        out.write_all(&buf)?;
        done += 2 * u64::from(cols);
        progress(done, total);
    }
    Ok(())
}

/// Writes a terrain of at least `triangles` triangles to `path` (via a temporary sibling and
/// a rename). Returns the grid written.
pub fn terrain(
    path: &Path,
    triangles: u64,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<TerrainGrid, GenerateError> {
    let grid = TerrainGrid::for_triangles(triangles)?;
    crate::base::atomic::write_atomically_with(path, |f| {
        let mut w = BufWriter::with_capacity(1 << 20, f);
        write_terrain(&mut w, grid, progress)?;
        w.flush()
    })
    .map_err(|source| GenerateError::Io {
        path: path.display().to_string(),
        source,
    })?;
    Ok(grid)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_has_at_least_the_requested_triangles() {
        for n in [1, 2, 3, 100, 1001, 20_000_000] {
            let g = TerrainGrid::for_triangles(n).unwrap();
            assert!(g.triangles() >= n, "{n}: {g:?}");
            assert!(
                g.triangles() < n + 2 * u64::from(g.columns) + 2,
                "{n}: {g:?}"
            );
        }
    }

    #[cfg(feature = "ply")]
    #[test]
    fn small_terrain_imports_with_all_attributes() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.ply");
        let grid = terrain(&path, 200, &mut |_, _| {}).unwrap();
        let mesh = crate::import::import(&path, &Default::default()).unwrap();
        assert_eq!(mesh.triangles.len() as u64, grid.triangles());
        assert_eq!(mesh.positions.len() as u64, grid.vertices());
        assert_eq!(mesh.normals.len(), mesh.positions.len());
        assert_eq!(mesh.uvs.len(), mesh.positions.len());
        assert_eq!(mesh.colors.len(), mesh.positions.len());
        // Counter-clockwise seen from above: face normals agree with the vertex normals.
        for t in &mesh.triangles {
            let p = t.position.map(|i| mesh.positions[i as usize]);
            let e1 = [0, 1, 2].map(|k| p[1][k] - p[0][k]);
            let e2 = [0, 1, 2].map(|k| p[2][k] - p[0][k]);
            let ny = e1[2] * e2[0] - e1[0] * e2[2];
            assert!(ny > 0.0);
            assert!(mesh.normals[t.normal[0] as usize][1] > 0.5);
        }
        // Only the file itself is left in the directory.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
