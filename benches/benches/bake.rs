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
//!   1%, medians of a few runs, and the bake's stages from one extra run.
//!
//! Prints the figures with ratios (ours / meshopt) and writes them to `bake-quality.csv` in
//! the target directory. `cargo bench -p caveclod-benches --bench bake` (about a minute; a
//! filter argument such as `-- bake/lucy` picks inputs); without `--bench` (as
//! `cargo test --benches` runs it) it runs once on spot with fewer samples. Inputs that are
//! absent are skipped with a note.

use std::collections::BinaryHeap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use caveclod_bake::baked::Baked;
use caveclod_bake::hierarchy::{self, AttributeWeights};
use caveclod_bake::import::{self, ImportOptions};
use caveclod_bake::mesh::Mesh;
use caveclod_bake::pipeline::bake_mesh;
use caveclod_bake::weld::{self, Welded};
use caveclod_core::{CameraState, Hierarchy, NodeId};

type P3 = [f64; 3];

fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: P3, b: P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: P3, b: P3) -> P3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn axpy(a: P3, s: f64, d: P3) -> P3 {
    [a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2]]
}
fn d2(a: P3, b: P3) -> f64 {
    let d = sub(a, b);
    dot(d, d)
}
fn wide(p: [f32; 3]) -> P3 {
    p.map(f64::from)
}

/// SplitMix64: deterministic samples, so runs compare.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// A triangle soup: three corners per triangle.
type Soup = Vec<[[f32; 3]; 3]>;

/// Squared distance from `p` to the segment `a`–`b`.
fn segment_d2(p: P3, a: P3, b: P3) -> f64 {
    let ab = sub(b, a);
    let l = dot(ab, ab);
    let t = if l > 0.0 {
        (dot(sub(p, a), ab) / l).clamp(0.0, 1.0)
    } else {
        0.0
    };
    d2(p, axpy(a, t, ab))
}

/// Squared distance from `p` to the triangle `t` (Ericson, Real-Time Collision Detection,
/// 5.1.5), falling back to the edges for a degenerate triangle.
fn triangle_d2(p: P3, t: &[[f32; 3]; 3]) -> f64 {
    let (a, b, c) = (wide(t[0]), wide(t[1]), wide(t[2]));
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2_) = (dot(ab, ap), dot(ac, ap));
    if d1 <= 0.0 && d2_ <= 0.0 {
        return dot(ap, ap);
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return dot(bp, bp);
    }
    let vc = d1 * d4 - d3 * d2_;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return d2(p, axpy(a, d1 / (d1 - d3), ab));
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return dot(cp, cp);
    }
    let vb = d5 * d2_ - d1 * d6;
    if vb <= 0.0 && d2_ >= 0.0 && d6 <= 0.0 {
        return d2(p, axpy(a, d2_ / (d2_ - d6), ac));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return d2(p, axpy(b, w, sub(c, b)));
    }
    let denom = va + vb + vc;
    let r = if denom != 0.0 {
        let (v, w) = (vb / denom, vc / denom);
        d2(p, axpy(axpy(a, v, ab), w, ac))
    } else {
        f64::NAN
    };
    if r.is_finite() {
        r
    } else {
        segment_d2(p, a, b)
            .min(segment_d2(p, b, c))
            .min(segment_d2(p, c, a))
    }
}

/// A bounding-volume hierarchy over a triangle soup, for nearest-point queries.
struct Bvh {
    /// `(lo, hi, first, count)`: a leaf if `count > 0`, else the right child is node
    /// `first` and the left child follows its parent.
    nodes: Vec<([f32; 3], [f32; 3], u32, u32)>,
    tris: Soup,
}

const LEAF: usize = 4;

impl Bvh {
    fn new(tris: &[[[f32; 3]; 3]]) -> Self {
        let boxes: Vec<([f32; 3], [f32; 3])> = tris
            .iter()
            .map(|t| {
                let mut lo = t[0];
                let mut hi = t[0];
                for p in &t[1..] {
                    for k in 0..3 {
                        lo[k] = lo[k].min(p[k]);
                        hi[k] = hi[k].max(p[k]);
                    }
                }
                (lo, hi)
            })
            .collect();
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let mut bvh = Self {
            nodes: Vec::with_capacity(2 * tris.len() / LEAF + 1),
            tris: Vec::new(),
        };
        bvh.build(&mut order, &boxes, 0);
        bvh.tris = order.iter().map(|&i| tris[i as usize]).collect();
        bvh
    }

    fn build(&mut self, order: &mut [u32], boxes: &[([f32; 3], [f32; 3])], first: usize) {
        let id = self.nodes.len();
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        let (mut clo, mut chi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for &i in order.iter() {
            let (a, b) = boxes[i as usize];
            for k in 0..3 {
                lo[k] = lo[k].min(a[k]);
                hi[k] = hi[k].max(b[k]);
                let c = 0.5 * (a[k] + b[k]);
                clo[k] = clo[k].min(c);
                chi[k] = chi[k].max(c);
            }
        }
        if order.len() <= LEAF {
            self.nodes.push((lo, hi, first as u32, order.len() as u32));
            return;
        }
        self.nodes.push((lo, hi, 0, 0));
        let axis = (0..3)
            .max_by(|&a, &b| (chi[a] - clo[a]).total_cmp(&(chi[b] - clo[b])))
            .unwrap_or(0);
        let mid = order.len() / 2;
        let centre = |i: &u32| {
            let (a, b) = boxes[*i as usize];
            a[axis] + b[axis]
        };
        order.select_nth_unstable_by(mid, |x, y| centre(x).total_cmp(&centre(y)));
        let (left, right) = order.split_at_mut(mid);
        self.build(left, boxes, first);
        self.nodes[id].2 = self.nodes.len() as u32;
        self.build(right, boxes, first + mid);
    }

    fn box_d2(&self, n: usize, p: P3) -> f64 {
        let (lo, hi, _, _) = &self.nodes[n];
        let mut s = 0.0;
        for k in 0..3 {
            let d = (lo[k] as f64 - p[k]).max(p[k] - hi[k] as f64).max(0.0);
            s += d * d;
        }
        s
    }

    /// Squared distance from `p` to the nearest point of the soup.
    fn nearest_d2(&self, p: P3, stack: &mut Vec<u32>) -> f64 {
        let mut best = f64::INFINITY;
        stack.clear();
        stack.push(0);
        while let Some(n) = stack.pop() {
            let n = n as usize;
            if self.box_d2(n, p) >= best {
                continue;
            }
            let (_, _, first, count) = self.nodes[n];
            if count > 0 {
                for t in &self.tris[first as usize..(first + count) as usize] {
                    best = best.min(triangle_d2(p, t));
                }
                continue;
            }
            let (l, r) = (n + 1, first as usize);
            let (dl, dr) = (self.box_d2(l, p), self.box_d2(r, p));
            let (near, far, dfar) = if dl <= dr { (l, r, dr) } else { (r, l, dl) };
            if dfar < best {
                stack.push(far as u32);
            }
            stack.push(near as u32);
        }
        best
    }
}

/// Points of a soup: `count` uniform by area (seeded), then its distinct corners.
struct Samples {
    area: Vec<P3>,
    corners: Vec<P3>,
}

fn sample(tris: &[[[f32; 3]; 3]], count: usize, seed: u64) -> Samples {
    let mut cumulative = Vec::with_capacity(tris.len());
    let mut total = 0.0;
    for t in tris {
        let (a, b, c) = (wide(t[0]), wide(t[1]), wide(t[2]));
        let n = cross(sub(b, a), sub(c, a));
        total += 0.5 * dot(n, n).sqrt();
        cumulative.push(total);
    }
    let mut rng = Rng(seed);
    let area = (0..count)
        .map(|_| {
            let x = rng.unit() * total;
            let i = cumulative.partition_point(|&c| c <= x).min(tris.len() - 1);
            let t = &tris[i];
            let (a, b, c) = (wide(t[0]), wide(t[1]), wide(t[2]));
            let s = rng.unit().sqrt();
            let r = rng.unit();
            axpy(axpy(a, s * (1.0 - r), sub(b, a)), s * r, sub(c, a))
        })
        .collect();
    let mut corners: Vec<[u32; 3]> = tris
        .iter()
        .flat_map(|t| t.iter().map(|p| p.map(f32::to_bits)))
        .collect();
    corners.sort_unstable();
    corners.dedup();
    Samples {
        area,
        corners: corners
            .iter()
            .map(|p| p.map(f32::from_bits))
            .map(wide)
            .collect(),
    }
}

/// One direction: `(largest distance over all samples, sum of squares over the area samples)`.
fn one_way(samples: &Samples, target: &Bvh) -> (f64, f64) {
    let mut stack = Vec::with_capacity(64);
    let (mut max, mut sum) = (0.0f64, 0.0f64);
    for &p in &samples.area {
        let d = target.nearest_d2(p, &mut stack);
        max = max.max(d);
        sum += d;
    }
    for &p in &samples.corners {
        max = max.max(target.nearest_d2(p, &mut stack));
    }
    (max.sqrt(), sum)
}

/// The input, ready for comparisons.
struct Reference {
    bvh: Bvh,
    samples: Samples,
    diagonal: f64,
}

/// `(Hausdorff, RMS)` of `result` against the reference, both over the diagonal.
fn distances(r: &Reference, result: &[[[f32; 3]; 3]], count: usize, seed: u64) -> (f64, f64) {
    let s = sample(result, count, seed);
    let bvh = Bvh::new(result);
    let (h1, s1) = one_way(&s, &r.bvh);
    let (h2, s2) = one_way(&r.samples, &bvh);
    let n = (s.area.len() + r.samples.area.len()) as f64;
    (h1.max(h2) / r.diagonal, ((s1 + s2) / n).sqrt() / r.diagonal)
}

/// Splits `node` would force (itself, its missing ancestors, and the creators of missing
/// neighbours, recursively) into `out`; returns the polygons they add.
fn forced(
    h: &Hierarchy<'_>,
    cam: &CameraState<'_>,
    node: NodeId,
    out: &mut Vec<NodeId>,
    seen: &mut [u32],
    epoch: u32,
) -> usize {
    out.clear();
    let mut todo = vec![node];
    let mut added = 0;
    while let Some(u) = todo.pop() {
        if cam.is_split(u) || seen[u.index()] == epoch {
            continue;
        }
        seen[u.index()] = epoch;
        out.push(u);
        let s = h.split(u).expect("a creator or an ancestor has a split");
        added += 1 + usize::from(s.f_r.is_some());
        let parent = h.node(u).expect("node").parent;
        if parent.is_some() {
            todo.push(parent);
        }
        for f in s.neighbours {
            if let Some(c) = f.get().and_then(|f| h.polygons()[f.index()].creator.node()) {
                todo.push(c);
            }
        }
    }
    added
}

/// Total order on `f32` for the heap.
#[derive(Clone, Copy)]
struct Ordered(f32);
impl PartialEq for Ordered {
    fn eq(&self, o: &Self) -> bool {
        self.0.total_cmp(&o.0).is_eq()
    }
}
impl Eq for Ordered {}
impl PartialOrd for Ordered {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Ordered {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}

/// Our view-independent cut with at most `target` triangles: its triangles.
fn our_cut(h: &Hierarchy<'_>, target: usize) -> Soup {
    let mut memory = vec![0u32; CameraState::words_needed(h)];
    let mut cam = CameraState::new(h, &mut memory).expect("camera");
    let mut heap: BinaryHeap<(Ordered, NodeId)> = cam
        .active_nodes()
        .filter_map(|v| Some((Ordered(h.split_bounds(v)?.uni_error), v)))
        .collect();
    let mut stack = vec![NodeId::NONE; 1 << 16];
    let (mut out, mut seen, mut epoch) = (Vec::new(), vec![0u32; h.node_count()], 0u32);
    while let Some((_, v)) = heap.pop() {
        if cam.is_split(v) {
            continue;
        }
        epoch += 1;
        let before = cam.active_polygon_count() as usize;
        let added = forced(h, &cam, v, &mut out, &mut seen, epoch);
        if before + added > target {
            continue;
        }
        cam.force_split(h, v, &mut stack).expect("force_split");
        assert_eq!(cam.active_polygon_count() as usize, before + added);
        for &u in &out {
            let s = h.split(u).expect("split");
            for c in [s.stationary, s.floating] {
                if let Some(b) = h.split_bounds(c) {
                    if !cam.is_split(c) {
                        heap.push((Ordered(b.uni_error), c));
                    }
                }
            }
        }
        if before + added == target {
            break;
        }
    }
    let ns = h.surface_count();
    let mut indices = vec![0u32; (0..ns).map(|s| cam.index_count(s)).sum()];
    let mut offsets = vec![0u32; ns + 1];
    cam.emit_indices_packed(h, &mut indices, &mut offsets)
        .expect("emit");
    let v = h.vertices();
    indices
        .chunks_exact(3)
        .map(|t| [0, 1, 2].map(|k| v[t[k] as usize].position))
        .collect()
}

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
}

fn run(name: &str, path: &Path, s: &Settings, csv: &mut Csv) {
    let mesh: Mesh = import::import(path, &ImportOptions::default()).expect("import");
    let w = weld::weld(&mesh).expect("weld");
    let n = mesh.triangles.len();
    let indices: Vec<u32> = w.triangles.iter().flat_map(|t| t.p).collect();
    let input: Soup = w
        .triangles
        .iter()
        .map(|t| t.p.map(|p| w.positions[p as usize]))
        .collect();
    println!(
        "\n## {name}: {n} input triangles ({} welded, {} positions); load average {}",
        w.triangles.len(),
        w.positions.len(),
        load()
    );

    // Speed.
    let mut bake_times = Vec::new();
    let mut baked = None;
    for _ in 0..s.bake_runs {
        let t = Instant::now();
        let (b, _) = bake_mesh(&mesh, name, &mut |_| {}).expect("bake");
        bake_times.push(t.elapsed().as_secs_f64());
        baked = Some(b);
    }
    let baked = baked.expect("at least one run");
    let t = Instant::now();
    let w2 = weld::weld(&mesh).expect("weld");
    let t_weld = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let hier = hierarchy::build(&w2, &AttributeWeights::default(), &mut |_, _| {});
    let t_build = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let b2 = Baked::new(&w2, &hier);
    b2.hierarchy().expect("valid");
    let t_assemble = t.elapsed().as_secs_f64();
    drop((b2, hier, w2));
    let one = n.div_ceil(100);
    let mut meshopt_times = Vec::new();
    for _ in 0..s.meshopt_runs {
        let t = Instant::now();
        let (soup, _) = meshopt_cut(&w, &indices, one);
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
    csv.row(name, "seconds_bake_vs_simplify_1pct", one, ours_t, mo_t);
    csv.row(
        name,
        "seconds_hierarchy_vs_simplify_1pct",
        one,
        t_build,
        mo_t,
    );

    // Quality.
    let h = baked.hierarchy().expect("valid");
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in &w.positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k] as f64);
            hi[k] = hi[k].max(p[k] as f64);
        }
    }
    let t = Instant::now();
    let reference = Reference {
        bvh: Bvh::new(&input),
        samples: sample(&input, s.samples, 1),
        diagonal: d2(lo, hi).sqrt(),
    };
    println!(
        "reference: {} area samples + {} corners, BVH of {} nodes, in {:.2} s; diagonal {:.4}",
        reference.samples.area.len(),
        reference.samples.corners.len(),
        reference.bvh.nodes.len(),
        t.elapsed().as_secs_f64(),
        reference.diagonal
    );
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
        let (mo, mo_err) = meshopt_cut(&w, &indices, target);
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

/// The target directory: this executable lives in `<target>/<profile>/deps/`.
fn target_dir() -> Option<PathBuf> {
    let exe = std::env::current_exe().ok()?;
    exe.ancestors().nth(3).map(Path::to_path_buf)
}

fn main() {
    let benchmarking = std::env::args().any(|a| a == "--bench");
    // Like criterion, a filter among the arguments picks benchmarks by substring of their
    // names, `bake/lucy` and `bake/st_helens` (`bake/spot` without `--bench`).
    let filters: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let wanted = |name: &str| {
        let id = format!("bake/{name}");
        filters.is_empty() || filters.iter().any(|f| id.contains(f.as_str()))
    };
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data");
    let (inputs, settings): (&[(&str, &str)], _) = if benchmarking {
        (
            &[
                ("lucy", "scans/lucy.ply"),
                ("st_helens", "terrain/SainteHelens.dem"),
            ],
            Settings {
                samples: 200_000,
                bake_runs: 3,
                meshopt_runs: 7,
            },
        )
    } else {
        (
            &[("spot", "spot/spot_triangulated.obj")],
            Settings {
                samples: 20_000,
                bake_runs: 1,
                meshopt_runs: 1,
            },
        )
    };
    println!(
        "# Bake quality and speed against meshoptimizer ({} build, load average {})",
        if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        },
        load()
    );
    let mut csv = Csv("input,metric,target_triangles,ours,meshopt,ratio\n".into());
    let mut ran = 0;
    for &(name, relative) in inputs {
        if !wanted(name) {
            continue;
        }
        let path = data.join(relative);
        if !path.exists() {
            println!("note: {relative} not found under ../shared/data; skipping {name}");
            continue;
        }
        run(name, &path, &settings, &mut csv);
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
