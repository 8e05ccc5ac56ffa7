//! Builds the caveclod shaders and commits-ready output:
//!
//! 0. runs the shader crate's tests on the CPU (its entry points called as plain functions;
//!    target dir `shaders/target/host`), and stops if one fails;
//! 1. compiles `shaders/caveclod-shaders` with rust-gpu (spirv-builder) for
//!    `spirv-unknown-vulkan1.2` into `shaders/target/spirv-builder`;
//! 2. copies the module to `vulkan/spirv/caveclod_shaders.spv` and writes
//!    `vulkan/spirv/manifest.json` (entry points and stages read back from the module, the
//!    source hash, the toolchain and the spirv-builder version), each through a temporary
//!    file and a rename;
//! 3. runs `spirv-val --target-env vulkan1.2` on the module when `spirv-val` is installed.
//!
//! Run from `shaders/`: `cargo run --release -p caveclod-shader-builder`. The hashing and
//! manifest rules are the file `xtask/src/shader_manifest.rs`, included here so
//! `cargo xtask check-shaders` computes exactly the same hash.

// The shared rules; `cargo xtask check-shaders` uses the parts the builder does not.
#[allow(dead_code)]
#[path = "../../../xtask/src/shader_manifest.rs"]
mod shader_manifest;

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::time::Instant;

use shader_manifest::{
    entry_points, manifest_json, source_hash, MANIFEST_FILE, MODULE_FILE, SHADER_CRATE_DIR,
    SPIRV_DIR,
};
use spirv_builder::{ModuleResult, SpirvBuilder};

/// The rust-gpu target; it declares the Vulkan memory model.
const TARGET: &str = "spirv-unknown-vulkan1.2";

fn main() -> ExitCode {
    match build() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("caveclod-shader-builder: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The repository root: two folders above this package.
fn repo_root() -> Result<PathBuf, String> {
    let here = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    here.canonicalize()
        .map_err(|e| format!("finding the repository root: {e}"))
}

fn build() -> Result<(), String> {
    let root = repo_root()?;
    // A crash of the rust-gpu backend would otherwise leave a `rustc-ice-*.txt` report in
    // the folder of the crate being compiled; the message on stderr is enough.
    std::env::set_var("RUSTC_ICE", "0");
    test_on_cpu(&root)?;
    let started = Instant::now();
    let result = SpirvBuilder::new(root.join(SHADER_CRATE_DIR), TARGET)
        .target_dir_path(root.join("shaders/target/spirv-builder"))
        .build()
        .map_err(|e| format!("building {SHADER_CRATE_DIR}: {e}"))?;
    let ModuleResult::SingleModule(module_path) = &result.module else {
        return Err("spirv-builder produced several modules; one was asked for".to_string());
    };
    println!(
        "compiled {SHADER_CRATE_DIR} in {:.1}s",
        started.elapsed().as_secs_f64()
    );

    let module = fs::read(module_path)
        .map_err(|e| format!("reading the built module {}: {e}", module_path.display()))?;
    let entries = entry_points(&module)?;
    let mut declared: Vec<&str> = entries.iter().map(|e| e.name.as_str()).collect();
    let mut reported: Vec<&str> = result.entry_points.iter().map(String::as_str).collect();
    declared.sort_unstable();
    reported.sort_unstable();
    if declared != reported {
        return Err(format!(
            "the module declares entry points {declared:?} but spirv-builder reported {reported:?}"
        ));
    }

    let hash = source_hash(&root).map_err(|e| format!("hashing the shader sources: {e}"))?;
    let toolchain = toolchain_channel(&root)?;
    let builder_version = locked_version(&root, "spirv-builder")?;
    let manifest = manifest_json(MODULE_FILE, &entries, &hash, &toolchain, &builder_version);

    let out_dir = root.join(SPIRV_DIR);
    fs::create_dir_all(&out_dir).map_err(|e| format!("creating {}: {e}", out_dir.display()))?;
    let module_out = out_dir.join(MODULE_FILE);
    write_atomically(&module_out, &module)?;
    write_atomically(&out_dir.join(MANIFEST_FILE), manifest.as_bytes())?;
    println!(
        "wrote {SPIRV_DIR}/{MODULE_FILE} ({} bytes, entry points {}) and {SPIRV_DIR}/{MANIFEST_FILE} (source hash {hash})",
        module.len(),
        entries
            .iter()
            .map(|e| format!("{} ({})", e.name, e.stage))
            .collect::<Vec<_>>()
            .join(", ")
    );

    validate(&module_out)
}

/// `cargo test` of the shader crate on the host.
fn test_on_cpu(root: &Path) -> Result<(), String> {
    let started = Instant::now();
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut c = Command::new(cargo);
    c.args(["test", "--quiet", "--lib", "--manifest-path"])
        .arg(root.join(SHADER_CRATE_DIR).join("Cargo.toml"))
        .arg("--target-dir")
        .arg(root.join("shaders/target/host"));
    let status = c
        .status()
        .map_err(|e| format!("could not start cargo test: {e}"))?;
    if !status.success() {
        return Err(format!(
            "the tests of {SHADER_CRATE_DIR} failed ({status}); nothing was written"
        ));
    }
    println!(
        "tested {SHADER_CRATE_DIR} on the CPU in {:.1}s",
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Writes `path` through a temporary file in the same folder and a rename.
fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), String> {
    let tmp = path.with_extension("tmp");
    fs::write(&tmp, bytes).map_err(|e| format!("writing {}: {e}", tmp.display()))?;
    fs::rename(&tmp, path).map_err(|e| {
        let _ = fs::remove_file(&tmp);
        format!("renaming {} to {}: {e}", tmp.display(), path.display())
    })
}

/// The `channel` of `shaders/rust-toolchain.toml`.
fn toolchain_channel(root: &Path) -> Result<String, String> {
    let path = root.join("shaders/rust-toolchain.toml");
    let text = fs::read_to_string(&path).map_err(|e| format!("reading {}: {e}", path.display()))?;
    text.lines()
        .filter_map(|l| l.trim().strip_prefix("channel"))
        .filter_map(|rest| rest.trim().strip_prefix('='))
        .map(|v| v.trim().trim_matches('"').to_string())
        .next()
        .ok_or_else(|| format!("{} has no `channel`", path.display()))
}

/// The version of package `name` in `shaders/Cargo.lock`.
fn locked_version(root: &Path, name: &str) -> Result<String, String> {
    let path = root.join("shaders/Cargo.lock");
    let text = fs::read_to_string(&path).map_err(|e| format!("reading {}: {e}", path.display()))?;
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        if line.trim() == format!("name = \"{name}\"") {
            if let Some(version) = lines
                .next()
                .and_then(|l| l.trim().strip_prefix("version = "))
            {
                return Ok(version.trim_matches('"').to_string());
            }
        }
    }
    Err(format!("{} does not list {name}", path.display()))
}

/// `spirv-val --target-env vulkan1.2 MODULE` if `spirv-val` is installed.
fn validate(module: &Path) -> Result<(), String> {
    let mut c = Command::new("spirv-val");
    c.args(["--target-env", "vulkan1.2"]).arg(module);
    match c.status() {
        Ok(s) if s.success() => {
            println!("spirv-val --target-env vulkan1.2: ok");
            Ok(())
        }
        Ok(s) => Err(format!(
            "spirv-val --target-env vulkan1.2 rejected {} ({s})",
            module.display()
        )),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            println!("spirv-val not installed: module not validated (Debian package spirv-tools)");
            Ok(())
        }
        Err(e) => Err(format!("could not start spirv-val: {e}")),
    }
}
