//! Out-of-core clustering against meshoptimizer's grid clustering, in one run.
//!
//! For each input (Stanford Lucy as PLY, Spot as OBJ, a generated terrain of 2 million
//! triangles as PLY) and each target size, `caveclod_bake::ooc::simplify_file` (streamed from
//! disk, generalized quadrics, 64 MiB budget) runs first; `meshopt::simplify_sloppy` then gets
//! the same mesh in memory with the index count ours produced as its target. Both results are
//! compared with the input by sampled distances: points spread over each surface by area
//! (deterministic seed), the distance from each to the nearest point of the other surface,
//! reported as the symmetric Hausdorff distance (the larger one-way maximum) and the RMS over
//! both directions, both relative to the input's bounding-box diagonal, plus each method's
//! wall time (one run each; ours includes reading and sorting the file, meshopt's input is
//! already in memory, so the time ratio favours meshopt). A third column group is our
//! clustering with the attribute weights near zero (geometry alone), to show what the
//! attribute terms cost in distance.
//!
//! `cargo bench -p caveclod-benches --bench ooc`; data from `../shared/data` (skipped when
//! absent). Output: one table on stdout.

use std::path::{Path, PathBuf};
use std::time::Instant;

use caveclod_bake::import;
use caveclod_bake::ooc::{self, OocOptions, Weights};

type P = [f64; 3];
type Tri = [P; 3];

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: P, b: P) -> P {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn lerp(a: P, s: f64, d: P) -> P {
    [a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2]]
}

/// Squared distance from `p` to triangle `t` (closest point by regions, Ericson 5.1.5).
fn tri_d2(p: P, t: &Tri) -> f64 {
    let (a, b, c) = (t[0], t[1], t[2]);
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    let q = if d1 <= 0.0 && d2 <= 0.0 {
        a
    } else {
        let bp = sub(p, b);
        let (d3, d4) = (dot(ab, bp), dot(ac, bp));
        let cp = sub(p, c);
        let (d5, d6) = (dot(ab, cp), dot(ac, cp));
        let vc = d1 * d4 - d3 * d2;
        let vb = d5 * d2 - d1 * d6;
        let va = d3 * d6 - d5 * d4;
        if d3 >= 0.0 && d4 <= d3 {
            b
        } else if d6 >= 0.0 && d5 <= d6 {
            c
        } else if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            lerp(a, d1 / (d1 - d3), ab)
        } else if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            lerp(a, d2 / (d2 - d6), ac)
        } else if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            lerp(b, (d4 - d3) / ((d4 - d3) + (d5 - d6)), sub(c, b))
        } else {
            let den = va + vb + vc;
            if den.abs() < 1e-300 {
                a
            } else {
                let (v, w) = (vb / den, vc / den);
                [0, 1, 2].map(|k| a[k] + ab[k] * v + ac[k] * w)
            }
        }
    };
    let d = sub(p, q);
    dot(d, d)
}

/// A uniform grid of triangles for nearest-point queries.
struct Grid {
    tris: Vec<Tri>,
    origin: P,
    cell: f64,
    dims: [i64; 3],
    cells: Vec<Vec<u32>>,
}

impl Grid {
    fn new(tris: Vec<Tri>) -> Self {
        let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
        for t in &tris {
            for p in t {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        let ext = sub(hi, lo).map(|e| e.max(1e-9));
        let vol = ext[0] * ext[1] * ext[2];
        let cell = (vol / tris.len().max(1) as f64)
            .cbrt()
            .max(ext.iter().fold(0.0, |a: f64, &b| a.max(b)) / 256.0);
        let dims = ext.map(|e| ((e / cell).ceil() as i64).max(1));
        let mut cells = vec![Vec::new(); (dims[0] * dims[1] * dims[2]) as usize];
        let at = |p: P, k: usize| (((p[k] - lo[k]) / cell).floor() as i64).clamp(0, dims[k] - 1);
        for (i, t) in tris.iter().enumerate() {
            let mut a = [i64::MAX; 3];
            let mut b = [i64::MIN; 3];
            for p in t {
                for k in 0..3 {
                    a[k] = a[k].min(at(*p, k));
                    b[k] = b[k].max(at(*p, k));
                }
            }
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        cells[((z * dims[1] + y) * dims[0] + x) as usize].push(i as u32);
                    }
                }
            }
        }
        Self {
            tris,
            origin: lo,
            cell,
            dims,
            cells,
        }
    }

    /// Distance from `p` to the nearest triangle.
    fn distance(&self, p: P) -> f64 {
        let c = [0, 1, 2].map(|k| {
            (((p[k] - self.origin[k]) / self.cell).floor() as i64).clamp(0, self.dims[k] - 1)
        });
        let mut best = f64::MAX;
        let max_r = self.dims.iter().copied().max().unwrap_or(1);
        for r in 0..=max_r {
            for z in (c[2] - r).max(0)..=(c[2] + r).min(self.dims[2] - 1) {
                for y in (c[1] - r).max(0)..=(c[1] + r).min(self.dims[1] - 1) {
                    for x in (c[0] - r).max(0)..=(c[0] + r).min(self.dims[0] - 1) {
                        let shell = (x - c[0]).abs().max((y - c[1]).abs()).max((z - c[2]).abs());
                        if shell != r {
                            continue;
                        }
                        for &t in &self.cells[((z * self.dims[1] + y) * self.dims[0] + x) as usize]
                        {
                            best = best.min(tri_d2(p, &self.tris[t as usize]));
                        }
                    }
                }
            }
            // Everything beyond this shell is at least r cells away (p may sit anywhere in
            // its own cell).
            let reach = r as f64 * self.cell;
            if best <= reach * reach {
                break;
            }
        }
        best.sqrt()
    }
}

/// `count` points spread over `tris` by area (xorshift, fixed seed).
fn sample(tris: &[Tri], count: usize, seed: u64) -> Vec<P> {
    let mut cdf = Vec::with_capacity(tris.len());
    let mut total = 0.0;
    for t in tris {
        let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
        total += 0.5 * dot(n, n).sqrt();
        cdf.push(total);
    }
    let mut s = seed | 1;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..count)
        .map(|_| {
            let x = rnd() * total;
            let i = cdf.partition_point(|&c| c < x).min(tris.len() - 1);
            let (mut u, mut v) = (rnd(), rnd());
            if u + v > 1.0 {
                u = 1.0 - u;
                v = 1.0 - v;
            }
            let t = &tris[i];
            [0, 1, 2].map(|k| t[0][k] + u * (t[1][k] - t[0][k]) + v * (t[2][k] - t[0][k]))
        })
        .collect()
}

/// (Hausdorff, RMS) between two soups, relative to `diag`.
fn distances(
    input: &[Tri],
    input_grid: &Grid,
    out: &[Tri],
    samples: usize,
    diag: f64,
) -> (f64, f64) {
    let out_grid = Grid::new(out.to_vec());
    let (mut max, mut sum, mut n) = (0.0f64, 0.0, 0.0);
    for p in sample(input, samples, 0x9e37_79b9) {
        let d = out_grid.distance(p);
        max = max.max(d);
        sum += d * d;
        n += 1.0;
    }
    for p in sample(out, samples, 0x7f4a_7c15) {
        let d = input_grid.distance(p);
        max = max.max(d);
        sum += d * d;
        n += 1.0;
    }
    (max / diag, (sum / n).sqrt() / diag)
}

fn soup(positions: &[[f32; 3]], tris: impl Iterator<Item = [u32; 3]>) -> Vec<Tri> {
    tris.map(|t| t.map(|i| positions[i as usize].map(f64::from)))
        .collect()
}

fn data(relative: &str) -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data")
        .join(relative);
    p.exists().then_some(p)
}

fn main() {
    let tmp = tempfile_dir();
    let terrain = tmp.join("terrain.ply");
    caveclod_bake::generate::terrain(&terrain, 2_000_000, &mut |_, _| {}).expect("generate");
    let mut inputs: Vec<(&str, PathBuf)> = Vec::new();
    if let Some(p) = data("scans/lucy.ply") {
        inputs.push(("lucy", p));
    }
    if let Some(p) = data("spot/spot_triangulated.obj") {
        inputs.push(("spot", p));
    }
    inputs.push(("terrain 2M", terrain.clone()));
    println!(
        "| input | triangles | target | ours: triangles | Hausdorff | RMS | seconds | sloppy: triangles | Hausdorff | RMS | seconds | ours, geometry only: triangles | Hausdorff | RMS |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for (name, path) in &inputs {
        let mesh = import::import(path, &Default::default()).expect("import");
        let input = soup(&mesh.positions, mesh.triangles.iter().map(|t| t.position));
        let grid = Grid::new(input.clone());
        let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
        for p in &mesh.positions {
            for k in 0..3 {
                lo[k] = lo[k].min(f64::from(p[k]));
                hi[k] = hi[k].max(f64::from(p[k]));
            }
        }
        let d = sub(hi, lo);
        let diag = dot(d, d).sqrt();
        let indices: Vec<u32> = mesh.triangles.iter().flat_map(|t| t.position).collect();
        for percent in [1.0, 5.0] {
            let target = ((mesh.triangles.len() as f64 * percent / 100.0) as u64).max(100);
            let options = OocOptions {
                target_triangles: Some(target),
                temp_dir: Some(tmp.clone()),
                ..OocOptions::with_budget(64 << 20)
            };
            let t0 = Instant::now();
            let (ours, _) = ooc::simplify_file(path, &options, &mut |_| {}).expect("ooc");
            let ours_s = t0.elapsed().as_secs_f64();
            let ours_soup = soup(&ours.positions, ours.triangles.iter().map(|t| t.position));
            // The same clustering with attribute weights near zero: geometry alone.
            let geometry = OocOptions {
                weights: Weights {
                    normal: 0.0,
                    uv: 0.0,
                    color: 0.0,
                },
                ..options.clone()
            };
            let (geo, _) = ooc::simplify_file(path, &geometry, &mut |_| {}).expect("ooc");
            let geo_soup = soup(&geo.positions, geo.triangles.iter().map(|t| t.position));
            let adapter =
                meshopt::VertexDataAdapter::new(meshopt::typed_to_bytes(&mesh.positions), 12, 0)
                    .expect("adapter");
            let t1 = Instant::now();
            let sloppy =
                meshopt::simplify_sloppy(&indices, &adapter, 3 * ours_soup.len(), 1.0, None);
            let sloppy_s = t1.elapsed().as_secs_f64();
            let sloppy_soup = soup(
                &mesh.positions,
                sloppy.chunks_exact(3).map(|t| [t[0], t[1], t[2]]),
            );
            let samples = 200_000;
            let (oh, or) = distances(&input, &grid, &ours_soup, samples, diag);
            let (sh, sr) = distances(&input, &grid, &sloppy_soup, samples, diag);
            let (gh, gr) = distances(&input, &grid, &geo_soup, samples, diag);
            println!(
                "| {name} | {} | {percent}% | {} | {oh:.5} | {or:.6} | {ours_s:.3} | {} | {sh:.5} | {sr:.6} | {sloppy_s:.3} | {} | {gh:.5} | {gr:.6} |",
                mesh.triangles.len(),
                ours_soup.len(),
                sloppy_soup.len(),
                geo_soup.len()
            );
        }
    }
    let _ = std::fs::remove_dir_all(&tmp);
}

/// A fresh directory for the generated input and the temporary files.
fn tempfile_dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("caveclod-ooc-bench-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}
