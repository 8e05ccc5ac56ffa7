//! Times the test builder on a large terrain: `cargo run --release -p caveclod-tests --example build_timing -- 708`.
fn main() {
    let n: u32 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(256);
    let t0 = std::time::Instant::now();
    let mesh = caveclod_tests::meshes::terrain(n, n, 1);
    let t1 = std::time::Instant::now();
    let built = caveclod_tests::build(&mesh);
    let t2 = std::time::Instant::now();
    let h = built.hierarchy();
    let t3 = std::time::Instant::now();
    println!(
        "{} triangles: mesh {:.2}s build {:.2}s validate {:.3}s; nodes {} splits {} base polygons {} depth {}",
        mesh.triangles.len(),
        (t1 - t0).as_secs_f64(),
        (t2 - t1).as_secs_f64(),
        (t3 - t2).as_secs_f64(),
        h.node_count(),
        h.splits().len(),
        h.base_polygon_count(),
        h.meta().max_depth
    );
}
