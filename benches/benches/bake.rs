//! Bake quality and speed against meshoptimizer (`meshopt` crate), in one run.
//!
//! For each input (lucy and the St. Helens terrain from `../shared/data`):
//!
//! - **Quality** at 10% and 1% of the input triangles. *Ours*: a view-independent cut of the
//!   baked hierarchy, chosen through caveclod-core's public API only: from the base mesh,
//!   repeatedly force-split the active node with the largest `uni_error` (a max-heap over the
//!   front); a node whose forced split would take the front past the target is skipped with
//!   its subtree, and the selection goes on with smaller errors, so the cut has exactly or
//!   just under the target count. Its triangles are those `emit_indices_packed` writes.
//!   *meshopt*: `meshopt::simplify` of the same welded mesh to the same target index count,
//!   default options, target error 1.0 (the whole extent), so only the count stops it.
//!   Both are measured against the input by the same sampled symmetric distances: 200,000
//!   points uniform by area on each surface (same seeds for both methods), each one's distance
//!   to the nearest point of the other surface (a BVH over its triangles, exact
//!   point-triangle distance). Hausdorff: the largest distance in either direction, the
//!   vertices of each surface included as extra samples. RMS: the root mean square over the
//!   area samples of both directions. Both divided by the input's bounding-box diagonal.
//! - **Speed**: the whole bake (`pipeline::bake_mesh`: weld, hierarchy, assembly and
//!   validation; the import is not timed) against `meshopt::simplify` of the welded mesh to
//!   1%, medians of a few runs, and the bake's stages from one extra run; input triangles
//!   per second of the bake.
//! - **Memory**: the peak resident set of a bake measured from outside: this executable runs
//!   itself as a child (`--peak-rss-child FILE`: `pipeline::bake_file`, the import included,
//!   as `caveclod bake` runs it) under `/usr/bin/time -v` and reads its "Maximum resident set
//!   size"; divided by the input triangles. Without `/usr/bin/time` the row says so.
//!
//! The inputs are lucy and the St. Helens terrain from `../shared/data`, and a generated
//! 1200 × 1200 grid (`caveclod_bake::generate::terrain`, 2,875,202 triangles with normals,
//! colours and UVs, written to the temporary directory and removed after the run).
//!
//! Prints the figures with ratios (ours / meshopt) and writes them to `bake-quality.csv` in
//! the target directory. `cargo bench -p caveclod-benches --bench bake` (a few minutes; a
//! filter argument such as `-- bake/lucy` picks inputs); without `--bench` (as
//! `cargo test --benches` runs it) it runs once on spot and a small generated grid with
//! fewer samples. Inputs that are absent are skipped with a note.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use caveclod_bake::baked::Baked;
use caveclod_bake::hierarchy::{self, AttributeWeights};
use caveclod_bake::import::{self, ImportOptions};
use caveclod_bake::mesh::Mesh;
use caveclod_bake::pipeline::{bake_file, bake_mesh};
use caveclod_bake::weld::{self, Welded};
use caveclod_benches::cut::our_cut;
use caveclod_benches::distance::{d2, distances, sample, Bvh, Reference, Soup};

/// `meshopt::simplify` of the welded mesh to `target` triangles: its triangles and the error
/// it reports (relative to the extent).
fn meshopt_cut(w: &Welded, indices: &[u32], target: usize) -> (Soup, f32) {
    let adapter = meshopt::VertexDataAdapter::new(meshopt::typed_to_bytes(&w.positions), 12, 0)
        .expect("adapter");
    let mut error = 0.0f32;
    let out = meshopt::simplify(
        indices,
        &adapter,
        3 * target,
        1.0,
        meshopt::SimplifyOptions::None,
        Some(&mut error),
    );
    let soup = out
        .chunks_exact(3)
        .map(|t| [0, 1, 2].map(|k| w.positions[t[k] as usize]))
        .collect();
    (soup, error)
}

/// What [`peak_rss`] measures of a child's bake.
struct Child {
    /// Its maximum resident set.
    bytes: u64,
    /// Its bake's wall time, as it measured it.
    seconds: f64,
    /// Its processor time, user and system, all threads (from `/usr/bin/time`): unlike the
    /// wall time, a busy host does not inflate it.
    cpu_seconds: f64,
}

/// Peak resident set of `bake_file` of `path` in a child process, read from
/// `/usr/bin/time -v`, or why it was not measured.
fn peak_rss(path: &Path) -> Result<Child, String> {
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let out = Command::new("/usr/bin/time")
        .arg("-v")
        .arg(exe)
        .arg("--peak-rss-child")
        .arg(path)
        .output()
        .map_err(|e| format!("/usr/bin/time: {e}"))?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        return Err(format!(
            "the child failed ({}): {}",
            out.status,
            stderr.lines().next().unwrap_or("")
        ));
    }
    let field = |name: &str| {
        stderr
            .lines()
            .find_map(|l| l.trim().strip_prefix(name))
            .and_then(|v| v.trim().parse::<f64>().ok())
            .ok_or(format!("no \"{name}\" in /usr/bin/time's report"))
    };
    let kbytes = field("Maximum resident set size (kbytes):")?;
    let cpu_seconds = field("User time (seconds):")? + field("System time (seconds):")?;
    let seconds = String::from_utf8_lossy(&out.stdout)
        .lines()
        .find_map(|l| l.strip_prefix("bake_seconds "))
        .and_then(|v| v.trim().parse::<f64>().ok())
        .ok_or("the child printed no bake time")?;
    Ok(Child {
        bytes: kbytes as u64 * 1024,
        seconds,
        cpu_seconds,
    })
}

/// The child of [`peak_rss`]: bakes `path` as `caveclod bake` does and prints its time.
fn peak_rss_child(path: &Path) {
    let t = Instant::now();
    let (baked, info) = bake_file(path, &ImportOptions::default(), &mut |_| {}).expect("bake");
    println!("bake_seconds {}", t.elapsed().as_secs_f64());
    assert!(info.input_triangles > 0 && baked.hierarchy().is_ok());
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_unstable_by(f64::total_cmp);
    v[v.len() / 2]
}

fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}

struct Settings {
    samples: usize,
    bake_runs: usize,
    meshopt_runs: usize,
}

#[derive(Default)]
struct Csv(String);

impl Csv {
    fn row(&mut self, input: &str, metric: &str, target: usize, ours: f64, meshopt: f64) {
        self.0.push_str(&format!(
            "{input},{metric},{target},{ours},{meshopt},{}\n",
            ours / meshopt
        ));
    }

    /// A figure of ours alone.
    fn single(&mut self, input: &str, metric: &str, target: usize, ours: f64) {
        self.0
            .push_str(&format!("{input},{metric},{target},{ours},,\n"));
    }
}

/// An input as both methods take it: the imported mesh, its weld, and the welded triangles
/// (as indices, for meshopt, and as a soup, for the distances).
struct Prepared {
    mesh: Mesh,
    w: Welded,
    indices: Vec<u32>,
    input: Soup,
}

/// Imports and welds `path`.
fn prepare(path: &Path) -> Prepared {
    let mesh: Mesh = import::import(path, &ImportOptions::default()).expect("import");
    let w = weld::weld(&mesh).expect("weld");
    let indices: Vec<u32> = w.triangles.iter().flat_map(|t| t.p).collect();
    let input: Soup = w
        .triangles
        .iter()
        .map(|t| t.p.map(|p| w.positions[p as usize]))
        .collect();
    Prepared {
        mesh,
        w,
        indices,
        input,
    }
}

fn run(name: &str, path: &Path, s: &Settings, csv: &mut Csv) {
    let p = prepare(path);
    println!(
        "\n## {name}: {} input triangles ({} welded, {} positions); load average {}",
        p.mesh.triangles.len(),
        p.w.triangles.len(),
        p.w.positions.len(),
        load()
    );
    let baked = speed(name, path, &p, s, csv);
    quality(name, &baked, &p, s, csv);
}

/// The bake's wall times (medians of `s.bake_runs`, its stages from one more run) against
/// meshopt's simplification to 1%, and the peak memory of a file bake of `path`; returns the
/// bake.
fn speed(name: &str, path: &Path, p: &Prepared, s: &Settings, csv: &mut Csv) -> Baked {
    let n = p.mesh.triangles.len();
    let mut bake_times = Vec::new();
    let mut baked = None;
    for _ in 0..s.bake_runs {
        let t = Instant::now();
        let (b, _) = bake_mesh(&p.mesh, name, &mut |_| {}).expect("bake");
        bake_times.push(t.elapsed().as_secs_f64());
        baked = Some(b);
    }
    let baked = baked.expect("at least one run");
    let (t_weld, t_build, t_assemble) = stage_times(&p.mesh);
    let one = n.div_ceil(100);
    let mut meshopt_times = Vec::new();
    for _ in 0..s.meshopt_runs {
        let t = Instant::now();
        let (soup, _) = meshopt_cut(&p.w, &p.indices, one);
        meshopt_times.push(t.elapsed().as_secs_f64());
        assert!(!soup.is_empty());
    }
    let (ours_t, mo_t) = (median(bake_times.clone()), median(meshopt_times.clone()));
    println!(
        "bake (weld + hierarchy + assembly): median {:.3} s of {:?}; stages of one more run: \
         weld {:.3} s, hierarchy {:.3} s, assembly + validation {:.3} s",
        ours_t,
        bake_times
            .iter()
            .map(|x| format!("{x:.3}"))
            .collect::<Vec<_>>(),
        t_weld,
        t_build,
        t_assemble
    );
    println!(
        "meshopt::simplify to 1% ({one} triangles): median {:.4} s of {} runs",
        mo_t, s.meshopt_runs
    );
    println!(
        "ratio bake / meshopt: {:.1}x (hierarchy stage alone: {:.1}x)",
        ours_t / mo_t,
        t_build / mo_t
    );
    println!(
        "input triangles per second: {:.3} M (bake), {:.3} M (hierarchy stage alone)",
        n as f64 / ours_t / 1e6,
        n as f64 / t_build / 1e6
    );
    csv.single(name, "triangles_per_second_bake", n, n as f64 / ours_t);
    memory(name, path, n, csv);
    csv.row(name, "seconds_bake_vs_simplify_1pct", one, ours_t, mo_t);
    csv.row(
        name,
        "seconds_hierarchy_vs_simplify_1pct",
        one,
        t_build,
        mo_t,
    );
    baked
}

/// The seconds of a bake's stages, one run each: weld, hierarchy, assembly with validation.
fn stage_times(mesh: &Mesh) -> (f64, f64, f64) {
    let t = Instant::now();
    let w = weld::weld(mesh).expect("weld");
    let t_weld = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let hier = hierarchy::build(&w, &AttributeWeights::default(), &mut |_, _| {}).expect("build");
    let t_build = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let b = Baked::new(&w, &hier);
    b.hierarchy().expect("valid");
    let t_assemble = t.elapsed().as_secs_f64();
    (t_weld, t_build, t_assemble)
}

/// The peak resident set of a file bake of `path` (`n` input triangles) in a child process.
fn memory(name: &str, path: &Path, n: usize, csv: &mut Csv) {
    match peak_rss(path) {
        Ok(Child {
            bytes,
            seconds,
            cpu_seconds,
        }) => {
            println!(
                "peak resident set of a file bake in a child (import included, {seconds:.3} s, \
                 {cpu_seconds:.2} s of processor time): {:.1} MB, {:.0} bytes per input triangle",
                bytes as f64 / 1e6,
                bytes as f64 / n as f64
            );
            csv.single(name, "child_cpu_seconds", n, cpu_seconds);
            csv.single(
                name,
                "peak_rss_bytes_per_triangle",
                n,
                bytes as f64 / n as f64,
            );
        }
        Err(why) => println!("peak resident set: not measured ({why})"),
    }
}

/// Our cut of `baked` and meshopt's simplification at 10% and 1% of the input, measured
/// against the input by the same sampled distances.
fn quality(name: &str, baked: &Baked, p: &Prepared, s: &Settings, csv: &mut Csv) {
    let n = p.mesh.triangles.len();
    let h = baked.hierarchy().expect("valid");
    let reference = reference(p, s.samples);
    println!(
        "| target | triangles ours / meshopt | Hausdorff ours | meshopt | ratio | RMS ours | \
         meshopt | ratio | meshopt's own error |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for (label, share) in [("10%", 10), ("1%", 1)] {
        let target = n * share / 100;
        let t = Instant::now();
        let ours = our_cut(&h, target);
        let t_cut = t.elapsed().as_secs_f64();
        let (mo, mo_err) = meshopt_cut(&p.w, &p.indices, target);
        let t = Instant::now();
        let (oh, or) = distances(&reference, &ours, s.samples, 2);
        let (mh, mr) = distances(&reference, &mo, s.samples, 2);
        let t_dist = t.elapsed().as_secs_f64();
        println!(
            "| {label} ({target}) | {} / {} | {oh:.3e} | {mh:.3e} | {:.2} | {or:.3e} | {mr:.3e} \
             | {:.2} | {mo_err:.3e} |",
            ours.len(),
            mo.len(),
            oh / mh,
            or / mr
        );
        eprintln!("   (our cut selected in {t_cut:.3} s; distances in {t_dist:.1} s)");
        csv.row(
            name,
            &format!("triangles_{label}"),
            target,
            ours.len() as f64,
            mo.len() as f64,
        );
        csv.row(name, &format!("hausdorff_{label}"), target, oh, mh);
        csv.row(name, &format!("rms_{label}"), target, or, mr);
    }
}

/// The input's samples, BVH and bounding-box diagonal, which both methods are measured
/// against.
fn reference(p: &Prepared, samples: usize) -> Reference {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for q in &p.w.positions {
        for k in 0..3 {
            lo[k] = lo[k].min(q[k] as f64);
            hi[k] = hi[k].max(q[k] as f64);
        }
    }
    let t = Instant::now();
    let reference = Reference {
        bvh: Bvh::new(&p.input),
        samples: sample(&p.input, samples, 1),
        diagonal: d2(lo, hi).sqrt(),
    };
    println!(
        "reference: {} area samples + {} corners, BVH of {} nodes, in {:.2} s; diagonal {:.4}",
        reference.samples.area.len(),
        reference.samples.corners.len(),
        reference.bvh.node_count(),
        t.elapsed().as_secs_f64(),
        reference.diagonal
    );
    reference
}

/// The target directory: this executable lives in `<target>/<profile>/deps/`.
fn target_dir() -> Option<PathBuf> {
    let exe = std::env::current_exe().ok()?;
    exe.ancestors().nth(3).map(Path::to_path_buf)
}

/// An input of the benchmark.
enum Source {
    /// A file under `shared/data`.
    Data(&'static str),
    /// A generated terrain of at least this many triangles.
    Grid(u64),
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--peak-rss-child") {
        peak_rss_child(Path::new(&args[i + 1]));
        return;
    }
    let benchmarking = args.iter().any(|a| a == "--bench");
    // Like criterion, a filter among the arguments picks benchmarks by substring of their
    // names, `bake/lucy`, `bake/st_helens` and `bake/grid1200` (`bake/spot` and
    // `bake/grid_small` without `--bench`).
    let filters: Vec<String> = args
        .iter()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .cloned()
        .collect();
    let wanted = |name: &str| {
        let id = format!("bake/{name}");
        filters.is_empty() || filters.iter().any(|f| id.contains(f.as_str()))
    };
    let data = caveclod_tests::shared_data::dir();
    let (inputs, settings): (&[(&str, Source)], _) = if benchmarking {
        (
            &[
                ("lucy", Source::Data("scans/lucy.ply")),
                ("st_helens", Source::Data("terrain/SainteHelens.dem")),
                // 1200 × 1200 vertices.
                ("grid1200", Source::Grid(2_875_202)),
            ],
            Settings {
                samples: 200_000,
                bake_runs: 3,
                meshopt_runs: 7,
            },
        )
    } else {
        (
            &[
                ("spot", Source::Data("spot/spot_triangulated.obj")),
                ("grid_small", Source::Grid(20_000)),
            ],
            Settings {
                samples: 20_000,
                bake_runs: 1,
                meshopt_runs: 1,
            },
        )
    };
    println!(
        "# Bake quality and speed against meshoptimizer ({} build, load average {}, {} threads)",
        if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        },
        load(),
        rayon::current_num_threads()
    );
    let mut csv = Csv("input,metric,target_triangles,ours,meshopt,ratio\n".into());
    let mut ran = 0;
    for (name, source) in inputs {
        if !wanted(name) {
            continue;
        }
        match source {
            Source::Data(relative) => {
                let path = data.join(relative);
                if !path.exists() {
                    println!("note: {relative} not found under ../shared/data; skipping {name}");
                    continue;
                }
                run(name, &path, &settings, &mut csv);
            }
            &Source::Grid(triangles) => {
                let path = std::env::temp_dir().join(format!(
                    "caveclod-bake-bench-{}-{name}.ply",
                    std::process::id()
                ));
                caveclod_bake::generate::terrain(&path, triangles, &mut |_, _| {})
                    .expect("generate the grid");
                run(name, &path, &settings, &mut csv);
                std::fs::remove_file(&path).expect("remove the generated grid");
            }
        }
        ran += 1;
    }
    println!("\nload average at the end: {}", load());
    if benchmarking && ran > 0 {
        if let Some(dir) = target_dir() {
            let file = dir.join("bake-quality.csv");
            match std::fs::write(&file, &csv.0) {
                Ok(()) => println!("wrote {}", file.display()),
                Err(e) => println!("could not write {}: {e}", file.display()),
            }
        }
    }
}
