//! `cargo xtask test`'s miri step: the core crate's tests under miri, in two processes.
//!
//! Miri interprets one thread at a time, so one `cargo miri test` keeps one core busy. The
//! test targets are built once, then run as two groups side by side; each group's output is
//! held and printed whole when it ends, so the two logs do not interleave.

use std::ffi::OsStr;
use std::fs;
use std::process::{Command, Output};
use std::thread;

use crate::process::{cmd, run, show, workspace_root, NIGHTLY};
use crate::setup::{install_miri, miri_installed};

/// Features for the miri run. libm (through glam) computes `sqrtf` with inline `sqrtss` on
/// x86, which miri cannot interpret; its `force-soft-floats` feature selects the portable
/// implementation. Only the miri build uses it.
const MIRI_FEATURES: &str = "libm/force-soft-floats";

/// The integration tests that take about half of the interpreter's time between them; the
/// library's unit tests and every other file of `core/tests` form the other group, so a new
/// test file joins that one.
const FIRST_GROUP: &[&str] = &["format_robustness", "geomorph", "budget"];

/// The step: install miri if needed, build every test target, run the two groups at once,
/// then the doc-tests (cargo runs those alone).
pub(crate) fn step() -> Result<(), String> {
    if !miri_installed() {
        install_miri()?;
    }
    run(miri(&["--no-run"]))?;
    let (first, second) = groups()?;
    let first = thread::spawn(move || captured(miri(&first)));
    let second = captured(miri(&second));
    let first = first
        .join()
        .map_err(|_| "the first miri group's thread panicked".to_string())?;
    let failures: Vec<String> = [first, second]
        .into_iter()
        .filter_map(Result::err)
        .collect();
    run(miri(&["--doc"]))?;
    if failures.is_empty() {
        Ok(())
    } else {
        Err(failures.join("; "))
    }
}

/// `cargo +NIGHTLY miri test -p caveclod-core` with the miri features and `args`.
fn miri<S: AsRef<OsStr>>(args: &[S]) -> Command {
    let nightly = format!("+{NIGHTLY}");
    let mut c = cmd(
        "cargo",
        &[
            &nightly,
            "miri",
            "test",
            "-p",
            "caveclod-core",
            "--no-fail-fast",
            "--features",
            MIRI_FEATURES,
        ],
    );
    c.args(args);
    c
}

/// The two groups' target arguments: [`FIRST_GROUP`], and the library with every other test
/// file of `core/tests`.
fn groups() -> Result<(Vec<String>, Vec<String>), String> {
    let dir = workspace_root().join("core/tests");
    let entries = fs::read_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut second = vec!["--lib".to_string()];
    for entry in entries {
        let path = entry.map_err(|e| format!("{}: {e}", dir.display()))?.path();
        let is_test = path.extension().is_some_and(|x| x == "rs");
        let Some(name) = path.file_stem().and_then(|s| s.to_str()) else {
            continue;
        };
        if is_test && !FIRST_GROUP.contains(&name) {
            second.extend(["--test".to_string(), name.to_string()]);
        }
    }
    let first = FIRST_GROUP
        .iter()
        .flat_map(|t| ["--test".to_string(), t.to_string()])
        .collect();
    Ok((first, second))
}

/// Runs a command with its output held, then prints it whole; `Err` names it if it could
/// not start or failed.
fn captured(mut c: Command) -> Result<(), String> {
    let shown = show(&c);
    let output: Output = c
        .output()
        .map_err(|e| format!("could not start `{shown}`: {e}"))?;
    println!("$ {shown}");
    print!("{}", String::from_utf8_lossy(&output.stdout));
    print!("{}", String::from_utf8_lossy(&output.stderr));
    if output.status.success() {
        Ok(())
    } else {
        Err(format!("`{shown}` failed ({})", output.status))
    }
}
