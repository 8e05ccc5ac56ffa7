//! Quick refine timing on a large terrain (scratch; see benches/ for the real benchmarks).
use caveclod_core::glam::Vec3;
use caveclod_core::{CameraState, LookAt, RefineParams};
fn main() {
    let n: u32 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(512);
    let tol: f32 = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1.0);
    let baked = caveclod_tests::bake(&caveclod_tests::meshes::terrain(n, n, 1));
    let h = baked.hierarchy();
    let mut mem = vec![0u32; CameraState::words_needed(&h)];
    let mut cam = CameraState::new(&h, &mut mem).unwrap();
    let s = n as f32;
    let view = |t: f32| {
        let eye = Vec3::new(
            s * 0.5 + s * 0.3 * t.cos(),
            s * 0.08,
            s * 0.5 + s * 0.3 * t.sin(),
        );
        let look = Vec3::new(
            s * 0.5 + s * 0.3 * (t + 0.2).cos(),
            0.0,
            s * 0.5 + s * 0.3 * (t + 0.2).sin(),
        );
        LookAt {
            eye,
            target: look,
            up: Vec3::Y,
            fov_y: 1.047,
            near: 0.1,
            far: s * 2.0,
        }
        .view(1280, 720)
    };
    let p = RefineParams {
        tolerance_px: tol,
        ..Default::default()
    };
    let t0 = std::time::Instant::now();
    let st = cam.refine(&h, &view(0.0), &p).unwrap();
    println!(
        "first refine {:.1} ms {:?}",
        t0.elapsed().as_secs_f64() * 1e3,
        st
    );
    let t0 = std::time::Instant::now();
    cam.refine(&h, &view(0.0), &p).unwrap();
    println!(
        "settled pass before compaction {:.3} ms",
        t0.elapsed().as_secs_f64() * 1e3
    );
    let t0 = std::time::Instant::now();
    cam.compact(&h);
    println!("compaction {:.3} ms", t0.elapsed().as_secs_f64() * 1e3);
    let t0 = std::time::Instant::now();
    let st = cam.refine(&h, &view(0.0), &p).unwrap();
    println!(
        "settled pass {:.3} ms {:?}",
        t0.elapsed().as_secs_f64() * 1e3,
        st
    );
    let mut ops = 0;
    let t0 = std::time::Instant::now();
    for f in 0..100 {
        ops += cam
            .refine(&h, &view(f as f32 * 0.01), &p)
            .unwrap()
            .operations();
    }
    println!(
        "moving: {:.3} ms/frame, {} ops/frame, active {}",
        t0.elapsed().as_secs_f64() * 10.0,
        ops / 100,
        cam.active_polygon_count()
    );
    let mut out = vec![0u32; 3 * cam.active_polygon_count() as usize];
    let mut off = vec![0u32; h.surface_count() + 1];
    let t0 = std::time::Instant::now();
    for _ in 0..20 {
        cam.emit_indices_packed(&h, &mut out, &mut off).unwrap();
    }
    println!("emit {:.3} ms", t0.elapsed().as_secs_f64() * 1e3 / 20.0);
}
