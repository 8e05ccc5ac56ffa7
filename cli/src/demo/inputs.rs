//! The demo's inputs: each baked once into the cache, loaded into aligned memory.

use std::path::{Path, PathBuf};
use std::time::Instant;

use caveclod_bake::import::ImportOptions;
use caveclod_bake::pipeline::build_file;
use caveclod_core::format::checksum64;
use caveclod_core::Hierarchy;
use caveclod_io::AlignedBytes;

/// A baked input, loaded.
pub struct Loaded {
    /// The input file.
    pub input: PathBuf,
    /// The cached `.clod`.
    pub clod: PathBuf,
    /// Whether it was baked now (false: read from the cache).
    pub baked_now: bool,
    /// Bake time if baked now.
    pub bake_seconds: f64,
    /// The file's bytes, cache-line aligned.
    bytes: AlignedBytes,
}

impl Loaded {
    /// The file's bytes.
    pub fn bytes(&self) -> &AlignedBytes {
        &self.bytes
    }

    /// The hierarchy (validated again on each call; cheap next to a flight).
    pub fn hierarchy(&self) -> Result<Hierarchy<'_>, String> {
        self.bytes
            .hierarchy()
            .map_err(|e| format!("{}: {e}", self.clod.display()))
    }
}

/// Bakes `input` into `cache` once: the cached file's name carries a checksum of the input,
/// the crate version and the format's major version, so a changed input, baker or format
/// bakes again.
pub fn bake_cached(input: &Path, cache: &Path, rebake: bool) -> Result<Loaded, String> {
    let bytes = std::fs::read(input).map_err(|e| format!("{}: {e}", input.display()))?;
    let version = format!(
        "{} format {}",
        env!("CARGO_PKG_VERSION"),
        caveclod_core::format::VERSION_MAJOR
    );
    let key = checksum64(&bytes) ^ checksum64(version.as_bytes());
    let stem = input
        .file_stem()
        .map_or("input".into(), |s| s.to_string_lossy().into_owned());
    std::fs::create_dir_all(cache).map_err(|e| format!("{}: {e}", cache.display()))?;
    let clod = cache.join(format!("{stem}-{key:016x}.clod"));
    let start = Instant::now();
    let mut baked_now = false;
    // A cached file that no longer loads (damaged, or left by another build) is baked again.
    let cached = AlignedBytes::read(&clod)
        .ok()
        .filter(|b| !rebake && b.hierarchy().is_ok());
    let bytes = match cached {
        Some(b) => b,
        None => {
            // Written one array at a time and validated before it is renamed into place.
            build_file(input, &ImportOptions::default(), &mut |_| {})
                .map_err(|e| e.to_string())?
                .write(&clod, &[])
                .map_err(|e| e.to_string())?;
            baked_now = true;
            AlignedBytes::read(&clod).map_err(|e| e.to_string())?
        }
    };
    Ok(Loaded {
        input: input.to_path_buf(),
        clod,
        baked_now,
        bake_seconds: start.elapsed().as_secs_f64(),
        bytes,
    })
}

/// A path as people should read it: relative to the working directory when it is inside it.
pub fn shown(path: &Path) -> String {
    let full = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
    let here = std::env::current_dir().and_then(|d| d.canonicalize());
    match here {
        Ok(here) => full
            .strip_prefix(&here)
            .map_or_else(|_| full.display().to_string(), |p| p.display().to_string()),
        Err(_) => full.display().to_string(),
    }
}
