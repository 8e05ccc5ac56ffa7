//! `cargo xtask check-shaders`: the committed SPIR-V against the shader sources and
//! `spirv-val` (see the crate docs).

use std::ffi::OsStr;
use std::fs;
use std::path::PathBuf;

use crate::process::{cmd, run, workspace_root};
use crate::setup::find_in_path;
use crate::shader_manifest;

/// Checks the committed shader module against the sources and `spirv-val` (see the module
/// docs); every problem found is reported, not just the first.
pub fn check_shaders() -> Result<(), String> {
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
