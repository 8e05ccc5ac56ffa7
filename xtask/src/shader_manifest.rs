//! The rules of the committed shader module and its manifest, shared by the shader builder
//! (`shaders/builder`, which includes this file with `#[path]`, since it lives in a workspace
//! of its own) and by `cargo xtask check-shaders`, so both compute the source hash the same
//! way. Only std.
//!
//! **Source hash.** FNV-1a, 64 bits (offset basis `0xcbf29ce484222325`, prime
//! `0x100000001b3`), over the files that decide the shaders' code: every file under
//! [`SHADER_CRATE_DIR`] (its sources, manifest and lock file; a `target` folder there is
//! skipped) and [`SHARED_SOURCES`] (the math in caveclod-core). The files are taken in
//! order of their paths relative to the repository root, written with `/`; each
//! contributes its path, a zero byte, its length as a little-endian `u64` and its bytes,
//! with every `\r\n` read as `\n` so a checkout's line endings do not matter. The hash is
//! written as 16 lowercase hex digits. FNV-1a is not cryptographic: it detects forgotten
//! rebuilds, not tampering.
//!
//! **Manifest.** `vulkan/spirv/manifest.json`, written by [`manifest_json`]: the module's
//! file name, its entry points with their stages (read from the module's `OpEntryPoint`s),
//! the source hash, the toolchain and the spirv-builder version.

use std::fs;
use std::io;
use std::path::Path;

/// The folder of the committed SPIR-V, relative to the repository root.
pub const SPIRV_DIR: &str = "vulkan/spirv";
/// The module's file name in [`SPIRV_DIR`].
pub const MODULE_FILE: &str = "caveclod_shaders.spv";
/// The manifest's file name in [`SPIRV_DIR`].
pub const MANIFEST_FILE: &str = "manifest.json";
/// The shader crate, relative to the repository root; all its files are hashed.
pub const SHADER_CRATE_DIR: &str = "shaders/caveclod-shaders";
/// Files outside the shader crate whose code it compiles.
pub const SHARED_SOURCES: &[&str] = &["core/src/gpu.rs"];
/// The command that rebuilds the module and the manifest, from the repository root.
pub const REBUILD_COMMAND: &str = "cd shaders && cargo run --release -p caveclod-shader-builder";

/// The hashed files, relative to `root` with `/` separators, in hashing order.
pub fn hashed_files(root: &Path) -> io::Result<Vec<String>> {
    let mut files = Vec::new();
    collect_files(root, SHADER_CRATE_DIR, &mut files)?;
    for shared in SHARED_SOURCES {
        if !root.join(shared).is_file() {
            return Err(io::Error::new(
                io::ErrorKind::NotFound,
                format!("shared shader source {shared} not found"),
            ));
        }
        files.push((*shared).to_string());
    }
    files.sort();
    Ok(files)
}

/// Every file under `root/dir`, skipping folders named `target`.
fn collect_files(root: &Path, dir: &str, out: &mut Vec<String>) -> io::Result<()> {
    let entries = fs::read_dir(root.join(dir))
        .map_err(|e| io::Error::new(e.kind(), format!("reading folder {dir}: {e}")))?;
    for entry in entries {
        let entry = entry?;
        let name = entry.file_name();
        let Some(name) = name.to_str() else {
            return Err(io::Error::new(
                io::ErrorKind::InvalidData,
                format!("a file name in {dir} is not UTF-8"),
            ));
        };
        let path = format!("{dir}/{name}");
        let kind = entry.file_type()?;
        if kind.is_dir() {
            if name != "target" {
                collect_files(root, &path, out)?;
            }
        } else {
            out.push(path);
        }
    }
    Ok(())
}

/// FNV-1a 64 state.
struct Fnv1a64(u64);

impl Fnv1a64 {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

/// `bytes` with every `\r\n` replaced by `\n`.
fn normalise_line_endings(bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(bytes.len());
    for (i, &b) in bytes.iter().enumerate() {
        if b == b'\r' && bytes.get(i + 1) == Some(&b'\n') {
            continue;
        }
        out.push(b);
    }
    out
}

/// The source hash of the shaders under `root` (see the module docs), as 16 hex digits.
pub fn source_hash(root: &Path) -> io::Result<String> {
    let mut h = Fnv1a64::new();
    for file in hashed_files(root)? {
        let bytes = fs::read(root.join(&file))
            .map_err(|e| io::Error::new(e.kind(), format!("reading {file}: {e}")))?;
        let bytes = normalise_line_endings(&bytes);
        h.write(file.as_bytes());
        h.write(&[0]);
        h.write(&(bytes.len() as u64).to_le_bytes());
        h.write(&bytes);
    }
    Ok(format!("{:016x}", h.0))
}

/// An entry point of a SPIR-V module.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EntryPoint {
    /// The entry point's name.
    pub name: String,
    /// Its stage: `vertex`, `fragment`, `compute`, ...
    pub stage: &'static str,
}

/// The entry points declared by a SPIR-V module (little-endian words), in module order.
pub fn entry_points(spirv: &[u8]) -> Result<Vec<EntryPoint>, String> {
    if !spirv.len().is_multiple_of(4) || spirv.len() < 20 {
        return Err(format!(
            "not a SPIR-V module: {} bytes is not a header plus whole words",
            spirv.len()
        ));
    }
    let words: Vec<u32> = spirv
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    if words[0] != 0x0723_0203 {
        return Err(format!(
            "not a little-endian SPIR-V module: magic {:#010x}",
            words[0]
        ));
    }
    const OP_ENTRY_POINT: u32 = 15;
    let mut found = Vec::new();
    let mut at = 5;
    while at < words.len() {
        let count = (words[at] >> 16) as usize;
        let opcode = words[at] & 0xffff;
        if count == 0 || at + count > words.len() {
            return Err(format!("malformed instruction at word {at}"));
        }
        if opcode == OP_ENTRY_POINT {
            if count < 4 {
                return Err(format!("OpEntryPoint at word {at} is too short"));
            }
            let stage = match words[at + 1] {
                0 => "vertex",
                1 => "tessellation_control",
                2 => "tessellation_evaluation",
                3 => "geometry",
                4 => "fragment",
                5 => "compute",
                other => return Err(format!("entry point with execution model {other}")),
            };
            let bytes: Vec<u8> = words[at + 3..at + count]
                .iter()
                .flat_map(|w| w.to_le_bytes())
                .collect();
            let end = bytes.iter().position(|&b| b == 0).ok_or_else(|| {
                format!("OpEntryPoint at word {at}: name without terminating zero")
            })?;
            let name = String::from_utf8(bytes[..end].to_vec())
                .map_err(|_| format!("OpEntryPoint at word {at}: name is not UTF-8"))?;
            found.push(EntryPoint { name, stage });
        }
        at += count;
    }
    Ok(found)
}

/// The manifest's text.
pub fn manifest_json(
    module: &str,
    entry_points: &[EntryPoint],
    source_hash: &str,
    toolchain: &str,
    spirv_builder: &str,
) -> String {
    let mut s = String::from("{\n");
    s.push_str(&format!("  \"module\": \"{module}\",\n"));
    s.push_str("  \"entry_points\": [\n");
    for (i, e) in entry_points.iter().enumerate() {
        let comma = if i + 1 < entry_points.len() { "," } else { "" };
        s.push_str(&format!("    {}{comma}\n", entry_point_json(e)));
    }
    s.push_str("  ],\n");
    s.push_str(&format!("  \"source_hash\": \"{source_hash}\",\n"));
    s.push_str(&format!("  \"toolchain\": \"{toolchain}\",\n"));
    s.push_str(&format!("  \"spirv_builder\": \"{spirv_builder}\"\n"));
    s.push_str("}\n");
    s
}

/// One entry point as the manifest writes it.
pub fn entry_point_json(e: &EntryPoint) -> String {
    format!("{{\"name\": \"{}\", \"stage\": \"{}\"}}", e.name, e.stage)
}

/// The value of the string field `key` of a manifest written by [`manifest_json`].
pub fn manifest_field(manifest: &str, key: &str) -> Option<String> {
    let pattern = format!("\"{key}\": \"");
    let start = manifest.find(&pattern)? + pattern.len();
    let len = manifest[start..].find('"')?;
    Some(manifest[start..start + len].to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a64_known_values() {
        let hash = |bytes: &[u8]| {
            let mut h = Fnv1a64::new();
            h.write(bytes);
            h.0
        };
        assert_eq!(hash(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(hash(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(hash(b"foobar"), 0x8594_4171_f739_67e8);
    }

    #[test]
    fn line_endings_do_not_change_the_bytes_hashed() {
        assert_eq!(normalise_line_endings(b"a\r\nb\rc\n\r\n"), b"a\nb\rc\n\n");
    }

    /// A module with a header and the given instructions.
    fn module(instructions: &[Vec<u32>]) -> Vec<u8> {
        let mut words = vec![0x0723_0203, 0x0001_0500, 0, 100, 0];
        for i in instructions {
            words.extend_from_slice(i);
        }
        words.iter().flat_map(|w| w.to_le_bytes()).collect()
    }

    /// `OpEntryPoint model %id "name"`.
    fn entry(model: u32, name: &str) -> Vec<u32> {
        let mut bytes = name.as_bytes().to_vec();
        bytes.push(0);
        while !bytes.len().is_multiple_of(4) {
            bytes.push(0);
        }
        let mut words = vec![0, model, 7];
        words.extend(
            bytes
                .chunks_exact(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])),
        );
        words[0] = ((words.len() as u32) << 16) | 15;
        words
    }

    #[test]
    fn entry_points_are_read_with_their_stages() {
        let capability = vec![(2 << 16) | 17, 1];
        let m = module(&[
            capability,
            entry(0, "draw_vs"),
            entry(4, "draw_fs"),
            entry(5, "geomorph_cs"),
        ]);
        let found = entry_points(&m).unwrap();
        let got: Vec<(&str, &str)> = found.iter().map(|e| (e.name.as_str(), e.stage)).collect();
        assert_eq!(
            got,
            [
                ("draw_vs", "vertex"),
                ("draw_fs", "fragment"),
                ("geomorph_cs", "compute")
            ]
        );
    }

    #[test]
    fn malformed_modules_are_errors() {
        assert!(entry_points(&[0; 19]).is_err());
        let mut bad_magic = module(&[]);
        bad_magic[0] = 0;
        assert!(entry_points(&bad_magic).is_err());
        // An instruction claiming more words than the module has.
        assert!(entry_points(&module(&[vec![(9 << 16) | 15, 0]])).is_err());
        // A zero word count would loop forever.
        assert!(entry_points(&module(&[vec![0]])).is_err());
    }

    #[test]
    fn manifest_fields_read_back() {
        let entries = [EntryPoint {
            name: "geomorph_cs".to_string(),
            stage: "compute",
        }];
        let json = manifest_json(
            MODULE_FILE,
            &entries,
            "0123456789abcdef",
            "nightly-x",
            "0.11.0",
        );
        assert_eq!(
            manifest_field(&json, "source_hash").as_deref(),
            Some("0123456789abcdef")
        );
        assert_eq!(
            manifest_field(&json, "module").as_deref(),
            Some(MODULE_FILE)
        );
        assert_eq!(
            manifest_field(&json, "spirv_builder").as_deref(),
            Some("0.11.0")
        );
        assert!(json.contains("{\"name\": \"geomorph_cs\", \"stage\": \"compute\"}"));
    }

    #[test]
    fn hash_covers_the_shader_crate_and_core_gpu() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let files = hashed_files(&root).unwrap();
        assert!(files.contains(&"core/src/gpu.rs".to_string()));
        assert!(files.contains(&"shaders/caveclod-shaders/src/lib.rs".to_string()));
        assert!(files.windows(2).all(|w| w[0] < w[1]));
        assert!(files.iter().all(|f| !f.contains("/target/")));
    }
}
