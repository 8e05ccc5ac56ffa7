//! Output safety: before any work, every command that writes checks that its output is not
//! one of its inputs, carries the extension of the format it writes, and lies in a directory
//! that exists and can be written. The files themselves are then written through a temporary
//! file and a rename, so a reader never sees a partial file and a failed run leaves the old
//! one in place.
//!
//! Messages follow the importers' style, `<file>: <element>: <what>; expected …`:
//! `same.clod: output: is the input same.clod; expected a different file`.

use std::path::{Path, PathBuf};

/// Checks a file output before any work: `extensions` (lower case, without the dot) names
/// the format written (`format` in words, for the message); none of `inputs` may be the same
/// file (same path, a link to it, or a hard link: same device and inode); the directory must
/// exist and be writable; the path must not name a directory.
pub fn check_file_output(
    output: &Path,
    extensions: &[&str],
    format: &str,
    inputs: &[&Path],
) -> Result<(), String> {
    refuse_inputs(output, inputs)?;
    let shown = output.display();
    let extension = output
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if !extension
        .as_deref()
        .is_some_and(|e| extensions.contains(&e))
    {
        let found = match &extension {
            Some(e) => format!("extension .{e} does not name {format}"),
            None => format!("no extension (the output is {format})"),
        };
        let expected: Vec<String> = extensions.iter().map(|e| format!(".{e}")).collect();
        return Err(format!(
            "{shown}: output: {found}; expected a name ending in {}",
            expected.join(" or ")
        ));
    }
    if output.is_dir() {
        return Err(format!(
            "{shown}: output: is a directory; expected a file name"
        ));
    }
    check_writable_dir(parent_dir(output), output)
}

/// Checks an output directory before any work: created if missing (as the commands that take
/// one promise), then probed for writing; none of the `files` it will hold may be one of
/// `inputs`.
pub fn prepare_output_dir(dir: &Path, files: &[&str], inputs: &[&Path]) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| {
        format!(
            "{}: output directory: cannot be created ({e}); expected a directory that can be \
             made",
            dir.display()
        )
    })?;
    if !dir.is_dir() {
        return Err(format!(
            "{}: output directory: is a file; expected a directory",
            dir.display()
        ));
    }
    for name in files {
        refuse_inputs(&dir.join(name), inputs)?;
    }
    check_writable_dir(dir, dir)
}

/// Fails when `output` is the same file as one of `inputs`.
fn refuse_inputs(output: &Path, inputs: &[&Path]) -> Result<(), String> {
    match inputs.iter().find(|i| same_file(i, output)) {
        Some(input) => Err(format!(
            "{}: output: is the input {}{}; expected a different file (the input is never \
             overwritten)",
            output.display(),
            input.display(),
            if output == *input {
                ""
            } else {
                " (the same file under another name)"
            }
        )),
        None => Ok(()),
    }
}

/// Whether `a` and `b` are one existing file: the same device and inode where the system
/// says (catching hard links and symbolic links), else the same canonical path.
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return ma.dev() == mb.dev() && ma.ino() == mb.ino();
        }
        false
    }
    #[cfg(not(unix))]
    {
        match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        }
    }
}

/// The directory a file path lies in (`.` for a bare name).
fn parent_dir(path: &Path) -> &Path {
    path.parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// The directory exists and a file can be created in it (a probe file, removed at once).
fn check_writable_dir(dir: &Path, output: &Path) -> Result<(), String> {
    let shown = output.display();
    if !dir.is_dir() {
        return Err(format!(
            "{shown}: output: directory {} does not exist; expected an existing directory",
            dir.display()
        ));
    }
    let probe: PathBuf = dir.join(format!(".caveclod-probe.{}", std::process::id()));
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(format!(
            "{shown}: output: directory {} cannot be written ({e}); expected a writable \
             directory",
            dir.display()
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hard_links_and_symbolic_links_are_the_same_file() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.clod");
        std::fs::write(&a, b"x").unwrap();
        let hard = dir.path().join("hard.clod");
        std::fs::hard_link(&a, &hard).unwrap();
        assert!(same_file(&a, &hard));
        #[cfg(unix)]
        {
            let soft = dir.path().join("soft.clod");
            std::os::unix::fs::symlink(&a, &soft).unwrap();
            assert!(same_file(&a, &soft));
        }
        let other = dir.path().join("other.clod");
        std::fs::write(&other, b"x").unwrap();
        assert!(!same_file(&a, &other));
        assert!(!same_file(&a, &dir.path().join("missing.clod")));
    }

    #[test]
    fn output_checks_name_the_file_and_what_was_expected() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("in.clod");
        std::fs::write(&input, b"x").unwrap();
        let e = check_file_output(&input, &["clod"], "a .clod hierarchy", &[&input]).unwrap_err();
        assert!(e.contains("is the input") && e.contains("in.clod"), "{e}");
        let ply = dir.path().join("x.ply");
        let e = check_file_output(&ply, &["clod"], "a .clod hierarchy", &[]).unwrap_err();
        assert!(e.contains("x.ply: output: extension .ply"), "{e}");
        assert!(e.contains("expected a name ending in .clod"), "{e}");
        let missing = dir.path().join("nowhere").join("x.clod");
        let e = check_file_output(&missing, &["clod"], "a .clod hierarchy", &[]).unwrap_err();
        assert!(e.contains("does not exist"), "{e}");
        let fine = dir.path().join("X.CLOD");
        check_file_output(&fine, &["clod"], "a .clod hierarchy", &[&input]).unwrap();
        // The probe leaves nothing behind.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
