//! Running the tools: the workspace root, commands started from it and their outcomes, and
//! the pinned toolchain and target the steps name.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The nightly that miri runs on; pinned so a miri or nightly change cannot break CI.
pub const NIGHTLY: &str = "nightly-2026-08-15";
/// A target without `std`: building the core crate for it proves it is `no_std`.
pub const NO_STD_TARGET: &str = "thumbv7em-none-eabihf";

/// The workspace root: the parent of this package's directory.
pub fn workspace_root() -> PathBuf {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().unwrap_or(manifest).to_path_buf()
}

/// `cargo`'s arguments that run caveclod's example `name` (debug build), before the
/// example's own.
pub fn example_args(name: &str) -> [&str; 7] {
    [
        "run",
        "--quiet",
        "-p",
        "caveclod-examples",
        "--example",
        name,
        "--",
    ]
}

/// A command run from the workspace root, with the variables that `cargo run` and the
/// rustup proxy set for this process removed, so a nested `cargo +toolchain` picks its own
/// toolchain and tools.
pub fn cmd(program: &str, args: &[&str]) -> Command {
    let mut c = Command::new(program);
    c.args(args).current_dir(workspace_root());
    for var in [
        "RUSTUP_TOOLCHAIN",
        "RUSTC",
        "RUSTDOC",
        "CARGO",
        "RUSTC_WRAPPER",
    ] {
        c.env_remove(var);
    }
    c
}

/// Runs a command, echoing it; `Err` names it if it cannot start or exits non-zero.
pub fn run(mut c: Command) -> Result<(), String> {
    let shown = show(&c);
    println!("$ {shown}");
    let status = c
        .status()
        .map_err(|e| format!("could not start `{shown}`: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("`{shown}` failed ({status})"))
    }
}

/// `true` if the command starts and exits 0; its output is discarded.
pub fn succeeds(mut c: Command) -> bool {
    c.stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

pub fn show(c: &Command) -> String {
    let mut s = c.get_program().to_string_lossy().into_owned();
    for a in c.get_args() {
        s.push(' ');
        s.push_str(&a.to_string_lossy());
    }
    s
}
