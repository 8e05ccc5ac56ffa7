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
//!   Xvfb (a resize storm, its screenshot's coverage and no validation message; then over a
//!   paged terrain streaming through a small vertex pool), clippy on the core crate without its
//!   `prefetch` feature (where it forbids `unsafe`), the core crate's tests under miri (two
//!   groups side by side: miri interprets on one core), and
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
//! - `miri`: the miri step of `test` alone (see [`miri`]).
//!
//! Only std: the tool must build before anything else is installed.

mod capi;
mod demo;
mod graph;
mod limits;
mod miri;
mod process;
mod setup;
mod shader_manifest;
mod shaders;
mod test;

use std::env;
use std::process::ExitCode;

use demo::demo;
use process::workspace_root;
use setup::setup;
use shaders::check_shaders;
use test::test;

const USAGE: &str = "\
usage: cargo xtask <command>

commands:
  setup [--with-miri]   check/install lavapipe, the Vulkan loader, validation layers,
                        spirv-val, Xvfb and the thumbv7em-none-eabihf target; --with-miri also
                        installs the pinned nightly with miri
  test                  setup, then shader check, fmt, clippy, tests, the reader sweep
                        (release), the C interface (C examples, C++ test), no_std build,
                        the viewer under Xvfb (a mesh; a paged terrain), clippy without
                        prefetch, miri
  check-shaders         the committed SPIR-V matches the shader sources and passes spirv-val
  capi-header           write capi/include/caveclod.h from the caveclod-capi sources
  capi-check            test's C interface step alone
  miri                  test's miri step alone
  limits                README < 200 lines, ARCHITECTURE < 150, src files < 800, functions
                        <= 120 lines, no figures or history in src comments, no import
                        circle in any crate (test runs it)
  graph                 each crate's modules in layers, bottom first, and any circle
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
        "miri" => parse_flags(rest, &[]).and_then(|_| miri::step()),
        "limits" => parse_flags(rest, &[]).and_then(|_| limits::check(&workspace_root())),
        "graph" => parse_flags(rest, &[]).and_then(|_| print_graph()),
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

/// Prints every crate's module layers and circles (`cargo xtask graph`).
fn print_graph() -> Result<(), String> {
    let crates = graph::workspace_crates(&workspace_root())?;
    let mut problems = 0;
    for g in &crates {
        print!("{}", graph::report::describe(g));
        problems += graph::problems(g).len();
    }
    if problems == 0 {
        Ok(())
    } else {
        Err(format!("{problems} circle(s)"))
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
