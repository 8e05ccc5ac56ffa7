//! Shared by the integration tests of the `caveclod` binary: running it, paths as its
//! arguments, what it prints when it succeeds, and one camera refined to rest in the core
//! with the commands' defaults (what the commands that refine are checked against).

#![allow(dead_code)] // each test binary uses a part of this module

use std::path::Path;
use std::process::{Command, Output};

use caveclod_core::glam::Vec3;
use caveclod_core::{CameraState, Hierarchy, LookAt, RefineParams};
use serde_json::Value;

/// The core's golden file (a small terrain), relative to the package's directory, where the
/// tests run.
pub const TERRAIN6: &str = "../core/tests/data/terrain6.clod";

/// The binary under test, for a run that needs more than arguments (an environment).
pub fn command() -> Command {
    Command::new(env!("CARGO_BIN_EXE_caveclod"))
}

/// `caveclod ARGS`, its output captured.
pub fn caveclod(args: &[&str]) -> Output {
    command().args(args).output().expect("run caveclod")
}

/// A path as an argument.
pub fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Asserts that a run succeeded, with its stderr as the failure's message.
pub fn succeeded(out: &Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The standard output of a run that must succeed.
pub fn stdout(out: &Output) -> String {
    succeeded(out);
    String::from_utf8(out.stdout.clone()).expect("UTF-8 output")
}

/// The one JSON report of a run that must succeed.
pub fn json(out: &Output) -> Value {
    succeeded(out);
    serde_json::from_slice(&out.stdout).expect("one JSON report")
}

/// The centre of a hierarchy's bounding box and the length of its diagonal.
pub fn centre_and_size(h: &Hierarchy<'_>) -> (Vec3, f32) {
    let (lo, hi) = (
        Vec3::from_array(h.meta().bounds_min),
        Vec3::from_array(h.meta().bounds_max),
    );
    ((lo + hi) * 0.5, (hi - lo).length())
}

/// Active polygons once one camera at `eye` looking at `target` settles with the commands'
/// defaults (1280 × 720, 60° vertical fov, +Y up, near 0.1, far 1e5, the default refinement
/// parameters), and how many refinement passes did something.
pub fn settled(h: &Hierarchy<'_>, eye: Vec3, target: Vec3) -> (u32, u32) {
    let mut memory = vec![0u32; CameraState::words_needed(h)];
    let mut cam = CameraState::new(h, &mut memory).expect("camera");
    let look = LookAt {
        eye,
        target,
        up: Vec3::Y,
        fov_y: 60f32.to_radians(),
        near: 0.1,
        far: 1e5,
    };
    let view = look.view(1280, 720);
    let mut passes = 0;
    while cam
        .refine(h, &view, &RefineParams::default())
        .expect("refine")
        .operations()
        > 0
    {
        passes += 1;
    }
    (cam.active_polygon_count(), passes)
}
