//! Out-of-core clustering against meshoptimizer's grid clustering, in one run.
//!
//! For each input (Stanford Lucy as PLY, Spot as OBJ, a generated terrain of 2 million
//! triangles as PLY) and each target size, `caveclod_bake::ooc::simplify_file` (streamed from
//! disk, generalized quadrics, 64 MiB budget) runs first; `meshopt::simplify_sloppy` then gets
//! the same mesh in memory with the index count ours produced as its target. Both results are
//! compared with the input by the same sampled distances as the bake benchmark
//! (`caveclod_benches::distance`: 200,000 points by area on each surface plus its corners,
//! exact nearest-point distances through a BVH; symmetric Hausdorff and RMS over both
//! directions, relative to the input's bounding-box diagonal), plus each method's
//! wall time (one run each; ours includes reading and sorting the file, meshopt's input is
//! already in memory, so the time ratio favours meshopt). A third column group is our
//! clustering with the attribute weights near zero (geometry alone), to show what the
//! attribute terms cost in distance.
//!
//! `cargo bench -p caveclod-benches --bench ooc`; data from `../shared/data` (skipped when
//! absent). Output: one table on stdout.

use std::path::PathBuf;
use std::time::Instant;

use caveclod_bake::import;
use caveclod_bake::ooc::{self, OocOptions, Weights};
use caveclod_benches::distance::{distances, Reference, Soup};

/// A triangle soup from positions and index triples.
fn soup(positions: &[[f32; 3]], tris: impl Iterator<Item = [u32; 3]>) -> Soup {
    tris.map(|t| t.map(|i| positions[i as usize])).collect()
}

fn data(relative: &str) -> Option<PathBuf> {
    let p = caveclod_tests::shared_data::dir().join(relative);
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
        let samples = 200_000;
        let reference = Reference::new(&input, samples, 1);
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
            let (oh, or) = distances(&reference, &ours_soup, samples, 2);
            let (sh, sr) = distances(&reference, &sloppy_soup, samples, 2);
            let (gh, gr) = distances(&reference, &geo_soup, samples, 2);
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
