//! `cargo xtask test`: its steps in order, each timed, and the interactive viewer's check
//! under Xvfb.

use std::env;
use std::time::{Duration, Instant};

use crate::capi;
use crate::limits;
use crate::miri;
use crate::process::{cmd, example_args, run, workspace_root, NIGHTLY, NO_STD_TARGET};
use crate::setup::setup;
use crate::shaders::check_shaders;

/// The mesh the viewer check opens (baked on the fly; its material names its texture) and
/// the image it writes.
const VIEWER_INPUT: &str = "data/spot/spot_triangulated.obj";
const VIEWER_SCREENSHOT: &str = "caveclod-viewer-check.png";

type Step = Box<dyn Fn() -> Result<(), String>>;

/// The steps of `cargo xtask test`, in order.
fn test_steps() -> Vec<(String, Step)> {
    let step = |title: &str, args: &'static [&'static str]| -> (String, Step) {
        (title.to_string(), Box::new(move || run(cmd("cargo", args))))
    };
    vec![
        ("setup".to_string(), Box::new(|| setup(false))),
        (
            "check-shaders (manifest hash, spirv-val)".to_string(),
            Box::new(check_shaders),
        ),
        (
            "limits (README < 200 lines, ARCHITECTURE < 150, src files < 800, functions <= 120, \
             no figures or history in src comments, no import circle in any crate)"
                .to_string(),
            Box::new(|| limits::check(&workspace_root())),
        ),
        step(
            "cargo fmt --all -- --check",
            &["fmt", "--all", "--", "--check"],
        ),
        step(
            "cargo clippy --workspace --all-targets -- -D warnings",
            &[
                "clippy",
                "--workspace",
                "--all-targets",
                "--",
                "-D",
                "warnings",
            ],
        ),
        // The debug profile: the whole suite runs in well under a minute in debug, while a
        // release build of the workspace and its dev-dependencies takes longer to compile
        // than the tests take to run. `--no-fail-fast` reports every failing test binary.
        step(
            "cargo test --workspace",
            &["test", "--workspace", "--no-fail-fast"],
        ),
        // The owned forms of the core crate's optional `alloc` feature, which no workspace
        // crate enables, so the workspace's tests do not build them.
        step(
            "cargo test -p caveclod-core --features alloc --lib",
            &["test", "-p", "caveclod-core", "--features", "alloc", "--lib"],
        ),
        // Thousands of imports of megabyte inputs need an optimised build (the sweep is
        // ignored in debug builds).
        step(
            "reader sweep: truncations and byte flips of ../shared/data through the in-memory bake (release)",
            &[
                "test",
                "--release",
                "-p",
                "caveclod-bake",
                "--test",
                "reader_sweep",
            ],
        ),
        (
            "C interface: refine.c, arena.c and stream.c (C99), the C++17 test (sanitizers), against the Rust API"
                .to_string(),
            Box::new(capi::check),
        ),
        step(
            "cargo build -p caveclod-core --target thumbv7em-none-eabihf",
            &["build", "-p", "caveclod-core", "--target", NO_STD_TARGET],
        ),
        (
            "viewer under Xvfb (4 cameras, 300 frames, resize storm, screenshot coverage, no validation messages)"
                .to_string(),
            Box::new(viewer_check),
        ),
        (
            "viewer under Xvfb over a paged terrain (generated and baked paged; 4 cameras, \
             300 frames, its pages streaming through a small vertex pool, no validation \
             messages, no device resource made after the warm-up)"
                .to_string(),
            Box::new(viewer_streamed_check),
        ),
        // Without its default `prefetch` feature the core crate forbids `unsafe`.
        step(
            "cargo clippy -p caveclod-core --no-default-features -- -D warnings",
            &[
                "clippy",
                "-p",
                "caveclod-core",
                "--no-default-features",
                "--",
                "-D",
                "warnings",
            ],
        ),
        (
            format!(
                "cargo +{NIGHTLY} miri test -p caveclod-core (two groups side by side, then the doc-tests)"
            ),
            Box::new(miri::step),
        ),
    ]
}

/// Runs every step (a failure does not stop the others), timing each; `Err` if any failed.
pub(crate) fn test() -> Result<(), String> {
    let total = Instant::now();
    let mut results: Vec<(String, Duration, bool)> = Vec::new();
    for (title, step) in test_steps() {
        println!("\n==> {title}");
        let start = Instant::now();
        let outcome = step();
        let took = start.elapsed();
        match &outcome {
            Ok(()) => println!("<== ok in {}", secs(took)),
            Err(e) => println!("<== FAILED in {}: {e}", secs(took)),
        }
        results.push((title, took, outcome.is_ok()));
    }
    println!("\nsteps:");
    for (title, took, ok) in &results {
        let mark = if *ok { "ok    " } else { "FAILED" };
        println!("  {mark} {:>8}  {title}", secs(*took));
    }
    println!("  total  {:>8}", secs(total.elapsed()));
    let passed = results.iter().filter(|r| r.2).count();
    let failed = results.len() - passed;
    println!("{passed} passed, {failed} failed");
    if failed == 0 {
        Ok(())
    } else {
        Err(format!("{failed} step(s) failed"))
    }
}

fn secs(d: Duration) -> String {
    format!("{:.1}s", d.as_secs_f64())
}

/// Triangles of the terrain the paged viewer check flies, its page size, and the viewer's
/// vertex pool (MiB): a small pool, so that pages come and go.
const PAGED_TRIANGLES: &str = "300000";
const PAGED_PAGE_SIZE: &str = "16K";
const PAGED_VERTEX_POOL: &str = "1";

/// Generates a terrain, bakes it paged, and flies the viewer over it in a virtual X server on
/// lavapipe, its pages streaming into a small vertex pool; the viewer fails on a validation
/// message, an empty viewport, or a device resource made after its warm-up.
fn viewer_streamed_check() -> Result<(), String> {
    let dir = env::temp_dir().join("caveclod-viewer-paged");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let path = |name: &str| dir.join(name).to_string_lossy().into_owned();
    let (ply, clod, shot) = (path("terrain.ply"), path("terrain.clod"), path("shot.png"));
    let cli = [
        "run",
        "--quiet",
        "-p",
        "caveclod-cli",
        "--bin",
        "caveclod",
        "--",
    ];
    let generate = ["generate", "--triangles", PAGED_TRIANGLES, "-o", &ply];
    run(cmd("cargo", &[&cli[..], &generate[..]].concat()))?;
    let bake = ["bake", &ply, "-o", &clod, "--page-size", PAGED_PAGE_SIZE];
    run(cmd("cargo", &[&cli[..], &bake[..]].concat()))?;
    run_viewer(&[
        &clod,
        "--cameras",
        "4",
        "--frames",
        "300",
        "--validation",
        "--vertex-pool",
        PAGED_VERTEX_POOL,
        "--screenshot",
        &shot,
        "--min-coverage",
        "0.1",
    ])?;
    println!("paged viewer screenshot: {shot}");
    Ok(())
}

/// Runs the interactive viewer in a virtual X server on lavapipe: 4 cameras, 300 animated
/// frames, validation on, and a resize storm (the window resizes itself every 12 frames,
/// back to its size before the end). The viewer itself writes the last frame, checks that
/// every camera's viewport is at least 10% non-background outside its panel and that every
/// size asked for got a swapchain, and exits non-zero on a validation message (this tool
/// stays std-only, so it cannot decode the PNG).
fn viewer_check() -> Result<(), String> {
    let shot = env::temp_dir().join(VIEWER_SCREENSHOT);
    let shot = shot.to_string_lossy();
    run_viewer(&[
        VIEWER_INPUT,
        "--cameras",
        "4",
        "--frames",
        "300",
        "--validation",
        "--screenshot",
        &shot,
        "--min-coverage",
        "0.1",
        "--resize-every",
        "12",
    ])?;
    println!("viewer screenshot: {shot}");
    Ok(())
}

/// Runs the viewer (debug build) with `args` in a virtual X server.
fn run_viewer(args: &[&str]) -> Result<(), String> {
    let xvfb = ["-a", "-s", "-screen 0 1280x720x24", "cargo"];
    let viewer = example_args("viewer");
    run(cmd("xvfb-run", &[&xvfb[..], &viewer[..], args].concat()))
}
