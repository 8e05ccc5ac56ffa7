//! Project tasks, run as `cargo xtask <command>` (the alias lives in `.cargo/config.toml`).
//!
//! - `setup [--with-miri]`: checks for, and installs when running as root, what the tests
//!   and the Vulkan side need (lavapipe, the Vulkan loader, the validation layers,
//!   `spirv-val`, and for the viewer's window Xvfb, xauth and the X client libraries), adds the `thumbv7em-none-eabihf` target, and with `--with-miri` installs
//!   the pinned nightly with miri.
//! - `test`: setup, then the shader check, formatting, clippy, the workspace tests (the
//!   runtime's 5,000-frame soak among them: `tests/tests/soak.rs`), the reader sweep
//!   (truncations and byte flips of the shared real inputs through the in-memory bake, in
//!   release), the no_std build for a microcontroller target, the interactive viewer under
//!   Xvfb (a resize storm, its screenshot's coverage and no validation message), clippy on the core crate without its
//!   `prefetch` feature (where it forbids `unsafe`), the core crate's tests under miri, and
//!   the C interface (`capi`): the C examples and the C++ test built with the system's
//!   compilers, run, and compared with the Rust API's numbers.
//!   Every step prints a header and its wall time; the run ends with `N passed, M failed`.
//! - `check-shaders`: the committed SPIR-V (`vulkan/spirv`) is up to date and valid: the
//!   manifest's source hash equals the hash of the current shader sources (computed by
//!   [`shader_manifest`], the same file the shader builder includes), its entry points are
//!   those of the module, and `spirv-val --target-env vulkan1.2` accepts every `.spv` there.
//!   It never builds shaders (that needs the rust-gpu toolchain); it says how to.
//! - `demo [ARGS..]`: `caveclod demo` in release mode, with `ARGS` forwarded.
//! - `capi-header`: writes the C interface's header `capi/include/caveclod.h` from the
//!   `caveclod-capi` sources (cbindgen; a test fails while the committed one differs).
//! - `capi-check`: the C interface's step of `test` alone (see [`capi`]).
//!
//! Only std: the tool must build before anything else is installed.

mod capi;
mod setup;
mod shader_manifest;
mod test;

use setup::{find_in_path, install_vulkan_packages, setup};
use test::test;

use std::env;
use std::ffi::OsStr;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

/// The nightly that miri runs on; pinned so a miri or nightly change cannot break CI.
const NIGHTLY: &str = "nightly-2026-08-15";
/// A target without `std`: building the core crate for it proves it is `no_std`.
const NO_STD_TARGET: &str = "thumbv7em-none-eabihf";

const USAGE: &str = "\
usage: cargo xtask <command>

commands:
  setup [--with-miri]   check/install lavapipe, the Vulkan loader, validation layers,
                        spirv-val, Xvfb and the thumbv7em-none-eabihf target; --with-miri also
                        installs the pinned nightly with miri
  test                  setup, then shader check, fmt, clippy, tests, the reader sweep
                        (release), the C interface (C examples, C++ test), no_std build,
                        the viewer under Xvfb, clippy without prefetch, miri
  check-shaders         the committed SPIR-V matches the shader sources and passes spirv-val
  capi-header           write capi/include/caveclod.h from the caveclod-capi sources
  capi-check            test's C interface step alone
  demo [ARGS..]         setup's Vulkan packages, then
                        cargo run --release -p caveclod-cli --bin caveclod -- demo ARGS
";

fn main() -> ExitCode {
    let args: Vec<String> = env::args().skip(1).collect();
    let Some((cmd, rest)) = args.split_first() else {
        eprint!("{USAGE}");
        return ExitCode::FAILURE;
    };
    let result = match cmd.as_str() {
        "setup" => {
            parse_flags(rest, &["--with-miri"]).and_then(|f| setup(f.contains(&"--with-miri")))
        }
        "test" => parse_flags(rest, &[]).and_then(|_| test()),
        "check-shaders" => parse_flags(rest, &[]).and_then(|_| check_shaders()),
        "capi-header" => parse_flags(rest, &[]).and_then(|_| capi::write_header()),
        "capi-check" => parse_flags(rest, &[]).and_then(|_| capi::check()),
        "demo" => demo(rest),
        "help" | "--help" | "-h" => {
            print!("{USAGE}");
            Ok(())
        }
        other => Err(format!("unknown command `{other}`\n{USAGE}")),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The flags given, each checked against `known`.
fn parse_flags<'a>(args: &'a [String], known: &[&str]) -> Result<Vec<&'a str>, String> {
    args.iter()
        .map(|a| {
            if known.contains(&a.as_str()) {
                Ok(a.as_str())
            } else {
                Err(format!("unknown argument `{a}`\n{USAGE}"))
            }
        })
        .collect()
}

/// The workspace root: the parent of this package's directory.
fn workspace_root() -> PathBuf {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().unwrap_or(manifest).to_path_buf()
}

/// A command run from the workspace root, with the variables that `cargo run` and the
/// rustup proxy set for this process removed, so a nested `cargo +toolchain` picks its own
/// toolchain and tools.
fn cmd(program: &str, args: &[&str]) -> Command {
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
fn run(mut c: Command) -> Result<(), String> {
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
fn succeeds(mut c: Command) -> bool {
    c.stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

fn show(c: &Command) -> String {
    let mut s = c.get_program().to_string_lossy().into_owned();
    for a in c.get_args() {
        s.push(' ');
        s.push_str(&a.to_string_lossy());
    }
    s
}

// ---------------------------------------------------------------------------------------
// check-shaders

/// Checks the committed shader module against the sources and `spirv-val` (see the module
/// docs); every problem found is reported, not just the first.
fn check_shaders() -> Result<(), String> {
    use shader_manifest::{
        entry_points, manifest_field, manifest_json, source_hash, MANIFEST_FILE, MODULE_FILE,
        REBUILD_COMMAND, SPIRV_DIR,
    };
    let root = workspace_root();
    let dir = root.join(SPIRV_DIR);
    let manifest_path = format!("{SPIRV_DIR}/{MANIFEST_FILE}");
    let module_path = format!("{SPIRV_DIR}/{MODULE_FILE}");
    let rebuild = format!("run `{REBUILD_COMMAND}` and commit {SPIRV_DIR}");
    let manifest = fs::read_to_string(dir.join(MANIFEST_FILE))
        .map_err(|e| format!("reading {manifest_path}: {e}; {rebuild}"))?;
    let mut problems = Vec::new();

    let current = source_hash(&root).map_err(|e| format!("hashing the shader sources: {e}"))?;
    let recorded = manifest_field(&manifest, "source_hash").unwrap_or_default();
    if recorded == current {
        println!("shader source hash {current} matches {manifest_path}");
    } else {
        problems.push(format!(
            "the shader sources changed since {SPIRV_DIR} was built (manifest hash \
             {recorded:?}, sources {current}): {rebuild}"
        ));
    }

    // The manifest must be exactly what the builder writes for this module.
    match fs::read(dir.join(MODULE_FILE))
        .map_err(|e| e.to_string())
        .and_then(|bytes| entry_points(&bytes))
    {
        Err(e) => problems.push(format!("{module_path}: {e}; {rebuild}")),
        Ok(entries) => {
            let expected = manifest_json(
                MODULE_FILE,
                &entries,
                &recorded,
                &manifest_field(&manifest, "toolchain").unwrap_or_default(),
                &manifest_field(&manifest, "spirv_builder").unwrap_or_default(),
            );
            if manifest != expected {
                problems.push(format!(
                    "{manifest_path} does not describe {module_path} (entry points {entries:?}): \
                     {rebuild}"
                ));
            }
        }
    }

    let Some(spirv_val) = find_in_path("spirv-val") else {
        problems.push(
            "spirv-val not found: run `cargo xtask setup` (Debian package spirv-tools)".to_string(),
        );
        return Err(problems.join("\n"));
    };
    let mut modules: Vec<PathBuf> = fs::read_dir(&dir)
        .map_err(|e| format!("reading {SPIRV_DIR}: {e}"))?
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension() == Some(OsStr::new("spv")))
        .collect();
    modules.sort();
    for module in &modules {
        let mut c = cmd(&spirv_val.to_string_lossy(), &["--target-env", "vulkan1.2"]);
        c.arg(module);
        if let Err(e) = run(c) {
            problems.push(e);
        }
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(problems.join("\n"))
    }
}

// ---------------------------------------------------------------------------------------
// demo

fn demo(args: &[String]) -> Result<(), String> {
    // The pictures need a Vulkan driver: install it as `setup` does, or say how, and let the
    // demo keep its CPU figures without it.
    if let Err(e) = install_vulkan_packages() {
        eprintln!("xtask demo: no pictures without a Vulkan driver: {e}");
    }
    let mut c = cmd(
        "cargo",
        &[
            "run",
            "--release",
            "-p",
            "caveclod-cli",
            "--bin",
            "caveclod",
            "--",
            "demo",
        ],
    );
    c.args(args);
    run(c)?;
    let out = args
        .iter()
        .position(|a| a == "--out")
        .and_then(|i| args.get(i + 1))
        .map_or_else(|| PathBuf::from("out"), PathBuf::from);
    update_readme_results(&out.join("results.md"))
}

const RESULTS_BEGIN: &str = "<!-- results:begin -->";
const RESULTS_END: &str = "<!-- results:end -->";

/// Puts the demo's results table into README.md between the results markers (through a
/// temporary file and a rename), so the README's table is always one the demo wrote.
fn update_readme_results(results: &Path) -> Result<(), String> {
    let table = fs::read_to_string(results).map_err(|e| format!("{}: {e}", results.display()))?;
    let readme = Path::new("README.md");
    let text = fs::read_to_string(readme).map_err(|e| format!("README.md: {e}"))?;
    let (Some(begin), Some(end)) = (text.find(RESULTS_BEGIN), text.find(RESULTS_END)) else {
        return Err(format!(
            "README.md: no {RESULTS_BEGIN} ... {RESULTS_END} block"
        ));
    };
    if end < begin {
        return Err(format!(
            "README.md: {RESULTS_END} comes before {RESULTS_BEGIN}"
        ));
    }
    let updated = format!(
        "{}{RESULTS_BEGIN}\n{}{}",
        &text[..begin],
        table.trim_end().to_string() + "\n",
        &text[end..]
    );
    let temp = readme.with_extension("md.tmp");
    fs::write(&temp, updated).map_err(|e| format!("{}: {e}", temp.display()))?;
    fs::rename(&temp, readme).map_err(|e| format!("README.md: {e}"))?;
    println!("README.md: results table from {}", results.display());
    Ok(())
}
