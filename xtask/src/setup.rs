//! `cargo xtask setup`: what the tests and the Vulkan side need, looked for, and installed
//! when running as root (lavapipe, the Vulkan loader, the validation layers, `spirv-val`,
//! Xvfb and the X client libraries, the no_std target, and the pinned nightly with miri).

use std::env;
use std::ffi::OsStr;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::process::{cmd, run, succeeds, NIGHTLY, NO_STD_TARGET};

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

pub(crate) fn find_in_path(program: &str) -> Option<PathBuf> {
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

pub(crate) fn setup(with_miri: bool) -> Result<(), String> {
    install_vulkan_packages()?;
    run(cmd("rustup", &["target", "add", NO_STD_TARGET]))?;
    if with_miri {
        install_miri()?;
    }
    Ok(())
}

/// Finds lavapipe, the loader, the validation layer and spirv-val; installs what is missing
/// from Debian's packages when run as root, otherwise says which command to run.
pub(crate) fn install_vulkan_packages() -> Result<(), String> {
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
pub(crate) fn install_miri() -> Result<(), String> {
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

pub(crate) fn miri_installed() -> bool {
    succeeds(cmd("cargo", &[&format!("+{NIGHTLY}"), "miri", "--version"]))
}
