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
mod shader_manifest;

use std::env;
use std::ffi::OsStr;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::time::{Duration, Instant};

/// The nightly that miri runs on; pinned so a miri or nightly change cannot break CI.
const NIGHTLY: &str = "nightly-2026-08-15";
/// A target without `std`: building the core crate for it proves it is `no_std`.
const NO_STD_TARGET: &str = "thumbv7em-none-eabihf";
/// Debian packages that provide the Vulkan pieces `setup` checks for, and the X server
/// and client libraries the viewer's window check runs with.
const APT_PACKAGES: &[&str] = &[
    "mesa-vulkan-drivers",
    "libvulkan1",
    "vulkan-validationlayers",
    "spirv-tools",
    "xvfb",
    "xauth",
    "libx11-xcb1",
    "libxcursor1",
    "libxi6",
    "libxkbcommon-x11-0",
];
/// The mesh the viewer check opens (baked on the fly; its material names its texture) and
/// the image it writes.
const VIEWER_INPUT: &str = "data/spot/spot_triangulated.obj";
const VIEWER_SCREENSHOT: &str = "caveclod-viewer-check.png";

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
// setup

/// One thing `setup` looks for.
struct Requirement {
    what: &'static str,
    found: Option<PathBuf>,
}

fn requirements() -> Vec<Requirement> {
    vec![
        Requirement {
            what: "lavapipe ICD (/usr/share/vulkan/icd.d/lvp_icd*.json)",
            found: glob_in(Path::new("/usr/share/vulkan/icd.d"), "lvp_icd", ".json"),
        },
        Requirement {
            what: "Vulkan loader (libvulkan.so.1)",
            found: find_library("libvulkan.so.1"),
        },
        Requirement {
            what: "Khronos validation layer (VkLayer_khronos_validation.json)",
            found: Some(PathBuf::from(
                "/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json",
            ))
            .filter(|p| p.is_file()),
        },
        Requirement {
            what: "spirv-val",
            found: find_in_path("spirv-val"),
        },
        Requirement {
            what: "xvfb-run (a virtual X server for the viewer check)",
            found: find_in_path("xvfb-run"),
        },
        Requirement {
            what: "xauth",
            found: find_in_path("xauth"),
        },
    ]
    .into_iter()
    .chain(
        [
            "libX11-xcb.so.1",
            "libXcursor.so.1",
            "libXi.so.6",
            "libxkbcommon-x11.so.0",
        ]
        .map(|lib| Requirement {
            what: lib,
            found: find_library(lib),
        }),
    )
    .collect()
}

/// The first file in `dir` whose name starts with `prefix` and ends with `suffix`.
fn glob_in(dir: &Path, prefix: &str, suffix: &str) -> Option<PathBuf> {
    let mut hits: Vec<PathBuf> = fs::read_dir(dir)
        .ok()?
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(OsStr::to_str)
                .is_some_and(|n| n.starts_with(prefix) && n.ends_with(suffix))
        })
        .collect();
    hits.sort();
    hits.into_iter().next()
}

/// A shared library the dynamic loader can find: `ldconfig -p` first, then the usual
/// library directories.
fn find_library(name: &str) -> Option<PathBuf> {
    for ldconfig in ["ldconfig", "/sbin/ldconfig", "/usr/sbin/ldconfig"] {
        if let Ok(out) = Command::new(ldconfig).arg("-p").output() {
            let text = String::from_utf8_lossy(&out.stdout);
            for line in text.lines() {
                let line = line.trim();
                if line.starts_with(&format!("{name} ")) {
                    if let Some((_, path)) = line.rsplit_once(" => ") {
                        return Some(PathBuf::from(path));
                    }
                }
            }
            break;
        }
    }
    let dirs = [
        "/usr/lib/x86_64-linux-gnu",
        "/usr/lib/aarch64-linux-gnu",
        "/usr/lib64",
        "/usr/lib",
        "/lib/x86_64-linux-gnu",
        "/lib64",
        "/lib",
        "/usr/local/lib",
    ];
    dirs.iter()
        .map(|d| Path::new(d).join(name))
        .find(|p| p.exists())
}

fn find_in_path(program: &str) -> Option<PathBuf> {
    env::split_paths(&env::var_os("PATH")?)
        .map(|d| d.join(program))
        .find(|p| p.is_file())
}

/// `true` when running as root (uid 0), read from `/proc/self/status`, else from `id -u`.
fn is_root() -> bool {
    if let Ok(status) = fs::read_to_string("/proc/self/status") {
        if let Some(line) = status.lines().find(|l| l.starts_with("Uid:")) {
            return line.split_whitespace().nth(2) == Some("0");
        }
    }
    Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
}

fn setup(with_miri: bool) -> Result<(), String> {
    install_vulkan_packages()?;
    run(cmd("rustup", &["target", "add", NO_STD_TARGET]))?;
    if with_miri {
        install_miri()?;
    }
    Ok(())
}

/// Finds lavapipe, the loader, the validation layer and spirv-val; installs what is missing
/// from Debian's packages when run as root, otherwise says which command to run.
fn install_vulkan_packages() -> Result<(), String> {
    let missing: Vec<&'static str> = requirements()
        .into_iter()
        .filter_map(|r| match r.found {
            Some(p) => {
                println!("found   {}: {}", r.what, p.display());
                None
            }
            None => {
                println!("missing {}", r.what);
                Some(r.what)
            }
        })
        .collect();
    if !missing.is_empty() {
        let packages = APT_PACKAGES.join(" ");
        if find_in_path("apt-get").is_none() && !Path::new("/usr/bin/apt-get").is_file() {
            return Err(format!(
                "missing: {}; this is not a Debian-like system (no apt-get): install the \
                 equivalents of the Debian packages {packages}",
                missing.join(", ")
            ));
        }
        if !is_root() {
            return Err(format!(
                "missing: {}; as root, run:\n    sudo apt-get update && sudo apt-get install -y {packages}",
                missing.join(", ")
            ));
        }
        run(cmd("apt-get", &["update"]))?;
        let mut install = cmd("apt-get", &["install", "-y"]);
        install
            .args(APT_PACKAGES)
            .env("DEBIAN_FRONTEND", "noninteractive");
        run(install)?;
        let still: Vec<_> = requirements()
            .into_iter()
            .filter(|r| r.found.is_none())
            .map(|r| r.what)
            .collect();
        if !still.is_empty() {
            return Err(format!(
                "still missing after apt-get install: {}",
                still.join(", ")
            ));
        }
    }
    Ok(())
}

/// Installs the pinned nightly with miri and rust-src (a no-op when present), then builds
/// miri's sysroot so the first `cargo miri test` does not.
fn install_miri() -> Result<(), String> {
    run(cmd(
        "rustup",
        &[
            "toolchain",
            "install",
            NIGHTLY,
            "--profile",
            "minimal",
            "--component",
            "miri,rust-src",
        ],
    ))?;
    run(cmd("cargo", &[&format!("+{NIGHTLY}"), "miri", "setup"]))
}

fn miri_installed() -> bool {
    succeeds(cmd("cargo", &[&format!("+{NIGHTLY}"), "miri", "--version"]))
}

// ---------------------------------------------------------------------------------------
// test

/// Features for the miri run. libm (through glam) computes `sqrtf` with inline `sqrtss` on
/// x86, which miri cannot interpret; its `force-soft-floats` feature selects the portable
/// implementation. Only the miri build uses it.
const MIRI_FEATURES: &str = "libm/force-soft-floats";

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
            "C interface: refine.c and arena.c (C99), the C++17 test (sanitizers), against the Rust API"
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
            format!("cargo +{NIGHTLY} miri test -p caveclod-core"),
            Box::new(|| {
                if !miri_installed() {
                    install_miri()?;
                }
                let nightly = format!("+{NIGHTLY}");
                run(cmd(
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
                ))
            }),
        ),
    ]
}

/// Runs every step (a failure does not stop the others), timing each; `Err` if any failed.
fn test() -> Result<(), String> {
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

// ---------------------------------------------------------------------------------------
// viewer

/// Runs the interactive viewer in a virtual X server on lavapipe: 4 cameras, 300 animated
/// frames, validation on, and a resize storm (the window resizes itself every 12 frames,
/// back to its size before the end). The viewer itself writes the last frame, checks that
/// every camera's viewport is at least 10% non-background outside its panel and that every
/// size asked for got a swapchain, and exits non-zero on a validation message (this tool
/// stays std-only, so it cannot decode the PNG).
fn viewer_check() -> Result<(), String> {
    let shot = env::temp_dir().join(VIEWER_SCREENSHOT);
    let shot = shot.to_string_lossy();
    run(cmd(
        "xvfb-run",
        &[
            "-a",
            "-s",
            "-screen 0 1280x720x24",
            "cargo",
            "run",
            "--quiet",
            "-p",
            "caveclod-examples",
            "--example",
            "viewer",
            "--",
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
        ],
    ))?;
    println!("viewer screenshot: {shot}");
    Ok(())
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
