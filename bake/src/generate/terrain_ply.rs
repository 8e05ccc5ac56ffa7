//! A procedural terrain of any size, streamed to binary PLY (`caveclod generate`).
//!
//! [`terrain_with`] writes a heightfield terrain as a `binary_little_endian` PLY with
//! per-vertex normals, 8-bit colours (by height) and texture coordinates (the grid's), so
//! out-of-core tests and benchmarks have inputs of tens of millions of triangles without
//! downloads. The surface is a sum of sines (smooth, with analytic normals) plus, unless the
//! [`TerrainStyle`]'s roughness is zero, fractal detail ([`noise`](super::noise)) down to two
//! grid cells, whose slopes come from central differences over the grid: a smooth terrain
//! simplifies to a few thousand polygons at a pixel's tolerance, a rough one keeps a camera
//! busy at every resolution. [`terrain`] is the smooth one.
//!
//! Nothing is held in memory but a few rows of the grid at a time: vertices are written row
//! by row (the detail of the rows either side kept for the slopes), then faces row by row
//! (the face element needs no vertex data). The file is written to a temporary sibling and
//! renamed once complete, so an interrupted run never leaves a partial file under the
//! requested name.

use std::io::{self, BufWriter, Write};
use std::path::Path;

use super::noise::Fractal;

/// Side of the terrain, in file units.
pub const TERRAIN_SIZE: f32 = 1000.0;

/// How a generated terrain looks: the sum of sines alone, or with fractal detail on top.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerrainStyle {
    /// How rough the fractal detail is: the relief of its octave at a sixty-fourth of the
    /// terrain's side (15.6 file units), over that scale. Its octaves run from a quarter of
    /// the side down to two grid cells, each one's relief its scale to the power 0.7
    /// ([`noise::HURST`](super::noise::HURST)), so the coarse octaves are gentler for their
    /// size and the fine ones rougher. 0 for the sum of sines alone.
    pub roughness: f32,
    /// Draws the detail: the same seed, roughness and grid give the same file.
    pub seed: u64,
}

impl TerrainStyle {
    /// The sum of sines alone: [`terrain`]'s surface.
    pub const SMOOTH: Self = Self {
        roughness: 0.0,
        seed: 0,
    };
    /// `caveclod generate`'s roughness: detail that keeps each of four cameras flying low
    /// over a grid of a few million triangles refining tens of thousands of polygons at a
    /// pixel's tolerance, on hills and valleys that still read as terrain.
    pub const DEFAULT_ROUGHNESS: f32 = 0.2;
    /// `caveclod generate`'s seed.
    pub const DEFAULT_SEED: u64 = 1;

    /// Whether the roughness is a finite number at least 0.
    fn valid(&self) -> bool {
        self.roughness.is_finite() && self.roughness >= 0.0
    }
}

impl Default for TerrainStyle {
    /// `caveclod generate`'s terrain: [`DEFAULT_ROUGHNESS`](Self::DEFAULT_ROUGHNESS) and
    /// [`DEFAULT_SEED`](Self::DEFAULT_SEED).
    fn default() -> Self {
        Self {
            roughness: Self::DEFAULT_ROUGHNESS,
            seed: Self::DEFAULT_SEED,
        }
    }
}

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
    /// A roughness that is negative or not a number.
    #[error("roughness {0} is not a finite number at least 0")]
    Roughness(f32),
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

/// Writes the smooth terrain's PLY to `out` ([`write_terrain_with`] of
/// [`TerrainStyle::SMOOTH`]).
pub fn write_terrain(
    out: &mut dyn Write,
    grid: TerrainGrid,
    progress: &mut dyn FnMut(u64, u64),
) -> io::Result<()> {
    write_terrain_with(out, grid, TerrainStyle::SMOOTH, progress)
}

/// Writes the terrain's PLY to `out`, with the detail `style` asks for; `progress(done,
/// total)` counts triangles and vertices written. A roughness that is negative or not a
/// number is an `InvalidInput` error, and nothing is written.
pub fn write_terrain_with(
    out: &mut dyn Write,
    grid: TerrainGrid,
    style: TerrainStyle,
    progress: &mut dyn FnMut(u64, u64),
) -> io::Result<()> {
    if !style.valid() {
        let e = GenerateError::Roughness(style.roughness);
        return Err(io::Error::new(io::ErrorKind::InvalidInput, e.to_string()));
    }
    let (cols, rows) = (grid.columns, grid.rows);
    let total = grid.vertices() + grid.triangles();
    let detail = DetailRows::new(grid, style);
    let comment = match &detail {
        None => String::new(),
        Some(_) => format!(", roughness {} seed {}", style.roughness, style.seed),
    };
    write!(
        out,
        "ply\nformat binary_little_endian 1.0\ncomment caveclod generate: terrain {cols}x{rows}\
         {comment}\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n\
         property float u\nproperty float v\n\
         element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        grid.vertices(),
        grid.triangles()
    )?;
    let mut buf = Vec::with_capacity(35 * (cols as usize + 1));
    let mut done = write_vertices(out, grid, detail, &mut buf, &mut |done| {
        progress(done, total)
    })?;
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

/// Writes the vertex element row by row; returns the vertices written.
fn write_vertices(
    out: &mut dyn Write,
    grid: TerrainGrid,
    mut detail: Option<DetailRows>,
    buf: &mut Vec<u8>,
    progress: &mut dyn FnMut(u64),
) -> io::Result<u64> {
    let (cols, rows) = (grid.columns, grid.rows);
    let mut done = 0u64;
    for j in 0..=rows {
        buf.clear();
        let zf = j as f32 / rows as f32;
        for i in 0..=cols {
            let xf = i as f32 / cols as f32;
            let (mut h, mut dx, mut dz) = height(xf, zf);
            if let Some(d) = &detail {
                let (dh, ddx, ddz) = d.at(i);
                (h, dx, dz) = (h + dh, dx + ddx, dz + ddz);
            }
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
        out.write_all(buf)?;
        done += u64::from(cols) + 1;
        progress(done);
        if let Some(d) = &mut detail {
            d.advance();
        }
    }
    Ok(done)
}

/// The fractal detail on the grid row being written and the rows either side (clamped at the
/// grid's edges), for its heights and, by central differences, its slopes: what the faces
/// around a vertex see, so the normals agree with them however fine the detail.
struct DetailRows {
    fractal: Fractal,
    grid: TerrainGrid,
    /// Rows `max(j - 1, 0)`, `j` and `min(j + 1, rows)` of the detail's heights.
    rows: [Vec<f64>; 3],
    /// The row being written.
    j: u32,
}

impl DetailRows {
    /// The detail on rows 0 and 1, or `None` for a smooth `style`.
    fn new(grid: TerrainGrid, style: TerrainStyle) -> Option<Self> {
        if style.roughness == 0.0 {
            return None;
        }
        let size = f64::from(TERRAIN_SIZE);
        let cell = size / f64::from(grid.columns.min(grid.rows));
        let fractal = Fractal::new(size, cell, f64::from(style.roughness), style.seed);
        let mut d = Self {
            fractal,
            grid,
            rows: Default::default(),
            j: 0,
        };
        let mut first = Vec::new();
        d.fill(0, &mut first);
        let mut second = Vec::new();
        d.fill(1, &mut second);
        d.rows = [first.clone(), first, second];
        Some(d)
    }

    /// Row `j`'s heights into `row`.
    fn fill(&self, j: u32, row: &mut Vec<f64>) {
        let size = f64::from(TERRAIN_SIZE);
        let z = f64::from(j) / f64::from(self.grid.rows) * size;
        let cols = f64::from(self.grid.columns);
        row.clear();
        row.extend((0..=self.grid.columns).map(|i| self.fractal.at(f64::from(i) / cols * size, z)));
    }

    /// Moves to the next row (past the last, a no-op).
    fn advance(&mut self) {
        if self.j == self.grid.rows {
            return;
        }
        self.j += 1;
        self.rows.rotate_left(1);
        let next = (self.j + 1).min(self.grid.rows);
        let mut row = std::mem::take(&mut self.rows[2]);
        self.fill(next, &mut row);
        self.rows[2] = row;
    }

    /// Height and its x and z slopes at column `i` of the row being written, in file units.
    fn at(&self, i: u32) -> (f32, f32, f32) {
        let (cols, rows) = (self.grid.columns, self.grid.rows);
        let (il, ir) = (i.saturating_sub(1), (i + 1).min(cols));
        let (jp, jn) = (self.j.saturating_sub(1), (self.j + 1).min(rows));
        let size = f64::from(TERRAIN_SIZE);
        let [p, c, n] = &self.rows;
        let (i, il, ir) = (i as usize, il as usize, ir as usize);
        let dx = (c[ir] - c[il]) / ((ir - il) as f64 * size / f64::from(cols));
        let dz = (n[i] - p[i]) / (f64::from(jn - jp) * size / f64::from(rows));
        (c[i] as f32, dx as f32, dz as f32)
    }
}

/// Writes the smooth terrain of at least `triangles` triangles to `path` ([`terrain_with`]
/// of [`TerrainStyle::SMOOTH`]). Returns the grid written.
pub fn terrain(
    path: &Path,
    triangles: u64,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<TerrainGrid, GenerateError> {
    terrain_with(path, triangles, TerrainStyle::SMOOTH, progress)
}

/// Writes a terrain of at least `triangles` triangles in `style` to `path` (via a temporary
/// sibling and a rename). Returns the grid written.
pub fn terrain_with(
    path: &Path,
    triangles: u64,
    style: TerrainStyle,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<TerrainGrid, GenerateError> {
    if !style.valid() {
        return Err(GenerateError::Roughness(style.roughness));
    }
    let grid = TerrainGrid::for_triangles(triangles)?;
    crate::base::atomic::write_atomically_with(path, |f| {
        let mut w = BufWriter::with_capacity(1 << 20, f);
        write_terrain_with(&mut w, grid, style, progress)?;
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

    /// FNV-1a, 64 bits.
    fn fnv(bytes: &[u8]) -> u64 {
        bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
            (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
        })
    }

    fn written(triangles: u64, style: TerrainStyle) -> Vec<u8> {
        let mut out = Vec::new();
        let grid = TerrainGrid::for_triangles(triangles).unwrap();
        write_terrain_with(&mut out, grid, style, &mut |_, _| {}).unwrap();
        out
    }

    #[test]
    fn roughness_zero_is_the_smooth_terrain_byte_for_byte() {
        let mut smooth = Vec::new();
        let grid = TerrainGrid::for_triangles(5000).unwrap();
        write_terrain(&mut smooth, grid, &mut |_, _| {}).unwrap();
        for seed in [0, 1, 99] {
            let style = TerrainStyle {
                roughness: 0.0,
                seed,
            };
            assert!(written(5000, style) == smooth, "seed {seed}");
        }
        // The smooth terrain's bytes are pinned (sines from the platform's libm: glibc's here).
        if cfg!(all(target_os = "linux", target_env = "gnu")) {
            let pinned = written(200, TerrainStyle::SMOOTH);
            assert_eq!((pinned.len(), fnv(&pinned)), (7198, 0xdf1d_e177_3647_1149));
            assert_eq!(fnv(&smooth), 0xb17d_b942_ff45_6a11);
        }
    }

    #[test]
    fn rough_terrain_is_deterministic_and_drawn_from_its_seed() {
        let style = TerrainStyle::default();
        let a = written(5000, style);
        assert!(a == written(5000, style));
        let other = written(5000, TerrainStyle { seed: 2, ..style });
        assert_eq!(a.len(), other.len());
        assert!(a != other);
        assert!(a != written(5000, TerrainStyle::SMOOTH));
        let header = String::from_utf8_lossy(&a[..200]).into_owned();
        assert!(header.contains("roughness 0.2 seed 1\n"), "{header}");
        let nan = TerrainStyle {
            roughness: f32::NAN,
            ..style
        };
        let bad = terrain_with(Path::new("x.ply"), 10, nan, &mut |_, _| {});
        assert!(matches!(bad, Err(GenerateError::Roughness(_))));
        let mut out = Vec::new();
        let grid = TerrainGrid::for_triangles(10).unwrap();
        let negative = TerrainStyle {
            roughness: -0.5,
            ..style
        };
        let bad = write_terrain_with(&mut out, grid, negative, &mut |_, _| {});
        assert_eq!(bad.unwrap_err().kind(), io::ErrorKind::InvalidInput);
        assert!(out.is_empty());
    }

    /// Every face is counter-clockwise seen from above (+y), and its corners' normals lean
    /// the same way as it does.
    #[cfg(feature = "ply")]
    fn assert_normals_agree_with_faces(mesh: &crate::mesh::Mesh) {
        for t in &mesh.triangles {
            let p = t.position.map(|i| mesh.positions[i as usize]);
            let e1 = [0, 1, 2].map(|k| p[1][k] - p[0][k]);
            let e2 = [0, 1, 2].map(|k| p[2][k] - p[0][k]);
            let face = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            assert!(face[1] > 0.0);
            for n in t.normal.map(|i| mesh.normals[i as usize]) {
                let dot: f32 = (0..3).map(|k| n[k] * face[k]).sum();
                assert!(dot > 0.0, "{n:?} against {face:?}");
            }
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
        assert_normals_agree_with_faces(&mesh);
        for t in &mesh.triangles {
            assert!(mesh.normals[t.normal[0] as usize][1] > 0.5);
        }
        // Only the file itself is left in the directory.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[cfg(feature = "ply")]
    #[test]
    fn rough_terrain_normals_agree_with_faces() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.ply");
        for roughness in [TerrainStyle::DEFAULT_ROUGHNESS, 0.6] {
            let style = TerrainStyle { roughness, seed: 5 };
            let grid = terrain_with(&path, 20_000, style, &mut |_, _| {}).unwrap();
            let mesh = crate::import::import(&path, &Default::default()).unwrap();
            assert_eq!(mesh.triangles.len() as u64, grid.triangles());
            assert_eq!(mesh.normals.len(), mesh.positions.len());
            assert_normals_agree_with_faces(&mesh);
        }
    }
}
