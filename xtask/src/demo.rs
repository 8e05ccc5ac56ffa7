//! `cargo xtask demo`: the demo in release mode, then its results table into README.md.

use std::fs;
use std::path::{Path, PathBuf};

use crate::process::{cmd, run};
use crate::setup::install_vulkan_packages;

pub fn demo(args: &[String]) -> Result<(), String> {
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
