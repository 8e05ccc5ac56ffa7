//! `cargo xtask limits`: the limits that keep the code and the docs readable, checked on
//! every run of `cargo xtask test`:
//! - README.md under [`README_LINES`] lines, ARCHITECTURE.md under [`ARCHITECTURE_LINES`];
//! - every file under a member's `src/` under [`FILE_LINES`] lines;
//! - no function outside tests over [`FUNCTION_LINES`] lines (the members' libraries and
//!   binaries, their examples and benchmarks);
//! - no comment under a member's `src/` that carries a run's figure or a change's history
//!   ([`figure_or_history`]);
//! - no circle of files and no circle between the parts of a module in any crate
//!   ([`crate::graph`]).

use std::fs;
use std::path::{Path, PathBuf};

use crate::graph::{self, CrateGraph};

/// README.md must stay under this many lines.
pub const README_LINES: usize = 200;
/// ARCHITECTURE.md must stay under this many lines.
pub const ARCHITECTURE_LINES: usize = 150;
/// A file under a member's `src/` must stay under this many lines.
pub const FILE_LINES: usize = 800;
/// A function outside tests may have at most this many lines.
pub const FUNCTION_LINES: usize = 120;

/// Every limit, checked over the workspace at `root`: `Err` lists each breach.
pub fn check(root: &Path) -> Result<(), String> {
    let mut breaches = Vec::new();
    breaches.extend(doc_lines(root, "README.md", README_LINES));
    breaches.extend(doc_lines(root, "ARCHITECTURE.md", ARCHITECTURE_LINES));
    let members = graph::members(root)?;
    for file in source_files(root, &members) {
        let text =
            fs::read_to_string(root.join(&file)).map_err(|e| format!("{}: {e}", file.display()))?;
        let name = file.display().to_string();
        breaches.extend(file_lines(&name, &text));
        breaches.extend(comment_figures(&name, &text));
    }
    let crates = graph::workspace_crates(root)?;
    for g in &crates {
        breaches.extend(function_lines(g));
        breaches.extend(graph::problems(g));
    }
    if breaches.is_empty() {
        println!(
            "limits hold: {} crates, {} files in their module trees",
            crates.len(),
            crates.iter().map(|g| g.files.len()).sum::<usize>()
        );
        Ok(())
    } else {
        Err(format!(
            "{} limit(s) broken:\n{}",
            breaches.len(),
            breaches.join("\n")
        ))
    }
}

/// The `.rs` files under each member's `src/`, relative to `root`, sorted.
fn source_files(root: &Path, members: &[String]) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for m in members {
        walk(root, &Path::new(m).join("src"), &mut out);
    }
    out.sort();
    out
}

fn walk(root: &Path, dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(root.join(dir)) else {
        return;
    };
    for e in entries.flatten() {
        let rel = dir.join(e.file_name());
        if e.path().is_dir() {
            walk(root, &rel, out);
        } else if rel.extension().is_some_and(|x| x == "rs") {
            out.push(rel);
        }
    }
}

/// A breach if the document `name` at `root` has `limit` lines or more.
fn doc_lines(root: &Path, name: &str, limit: usize) -> Option<String> {
    let text = fs::read_to_string(root.join(name)).unwrap_or_default();
    lines_under(name, &text, limit)
}

/// A breach if `text` has `limit` lines or more.
pub fn lines_under(name: &str, text: &str, limit: usize) -> Option<String> {
    let n = text.lines().count();
    (n >= limit).then(|| format!("{name}: {n} lines; keep it under {limit}"))
}

fn file_lines(name: &str, text: &str) -> Option<String> {
    lines_under(name, text, FILE_LINES)
}

fn function_lines(g: &CrateGraph) -> Vec<String> {
    g.functions()
        .filter(|(_, f)| f.last + 1 - f.first > FUNCTION_LINES)
        .map(|(file, f)| {
            format!(
                "{}:{}: fn {} is {} lines; keep functions to {FUNCTION_LINES}",
                file.path.display(),
                f.first,
                f.name,
                f.last + 1 - f.first
            )
        })
        .collect()
}

/// A breach for every comment line of `text` that [`figure_or_history`] flags.
fn comment_figures(name: &str, text: &str) -> Vec<String> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.trim_start().starts_with("//") && figure_or_history(l))
        .map(|(i, l)| {
            format!(
                "{name}:{}: a comment carries a run's figure or a change's history (say the reason; \
                 figures go in the commit message): {}",
                i + 1,
                l.trim()
            )
        })
        .collect()
}

/// Whether a comment line names a run's figure or a change's history: a duration in
/// milliseconds or microseconds, a decimal ratio written with an `x`, the middle value of
/// several runs, or words that tell what the code did before. The patterns are those of the
/// issue that set this limit (a `grep -E` over the crates' `src/`), spelt out below.
pub fn figure_or_history(line: &str) -> bool {
    const WORDS: &[&str] = &[
        "the first version",
        "before this change",
        "Previously",
        "previously",
        "median",
    ];
    if WORDS.iter().any(|w| line.contains(w)) {
        return true;
    }
    let chars: Vec<char> = line.chars().collect();
    (0..chars.len()).any(|i| duration_at(&chars, i) || ratio_at(&chars, i))
}

fn is_word(c: Option<&char>) -> bool {
    c.is_some_and(|c| c.is_alphanumeric() || *c == '_')
}

/// `[0-9][0-9.,-]* ?(ms|µs)\b` starting at `i`.
fn duration_at(c: &[char], i: usize) -> bool {
    if !c[i].is_ascii_digit() {
        return false;
    }
    let mut j = i + 1;
    while j < c.len() && (c[j].is_ascii_digit() || matches!(c[j], '.' | ',' | '-')) {
        j += 1;
    }
    if c.get(j) == Some(&' ') {
        j += 1;
    }
    let unit = matches!((c.get(j), c.get(j + 1)), (Some('m' | 'µ'), Some('s')));
    unit && !is_word(c.get(j + 2))
}

/// `[0-9]\.[0-9]+x\b` starting at `i`.
fn ratio_at(c: &[char], i: usize) -> bool {
    if !c[i].is_ascii_digit() || c.get(i + 1) != Some(&'.') {
        return false;
    }
    let mut j = i + 2;
    let digits = j;
    while j < c.len() && c[j].is_ascii_digit() {
        j += 1;
    }
    j > digits && c.get(j) == Some(&'x') && !is_word(c.get(j + 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_200_line_readme_fails_and_a_199_line_one_passes() {
        let readme = |n: usize| "line\n".repeat(n);
        assert!(lines_under("README.md", &readme(200), README_LINES).is_some());
        assert!(lines_under("README.md", &readme(199), README_LINES).is_none());
        assert!(lines_under("ARCHITECTURE.md", &readme(150), ARCHITECTURE_LINES).is_some());
    }

    #[test]
    fn figures_and_history_in_comments_are_flagged() {
        for bad in [
            "// refinement takes 1.27 ms per frame",
            "/// 3ms at most",
            "// 12 µs a call",
            "// the ratio went to 1.6x",
            "// the median of five runs",
            "// Previously this copied the list",
            "// before this change it spiked",
            "// the first version scanned every node",
        ] {
            assert!(figure_or_history(bad), "{bad}");
        }
        for good in [
            "// milliseconds are the caller's clock",
            "// 4 msaa samples",
            "// 1.5x2 blocks",
            "// an index in ms_table",
            "// 2x the radius",
        ] {
            assert!(!figure_or_history(good), "{good}");
        }
    }

    #[test]
    fn long_functions_are_reported_with_their_place() {
        let dir = std::env::temp_dir().join(format!("xtask-limits-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(dir.join("src")).unwrap();
        let body = "    let _ = 1;\n".repeat(FUNCTION_LINES - 2);
        let src = format!(
            "pub fn short() {{\n{body}}}\npub fn long() {{\n{body}    let _ = 2;\n}}\n\
             #[cfg(test)]\nmod tests {{\n    fn long_test() {{\n{body}{body}    }}\n}}\n"
        );
        fs::write(dir.join("src/lib.rs"), src).unwrap();
        let g = CrateGraph::load(&dir, "t", Path::new("src/lib.rs")).unwrap();
        let found = function_lines(&g);
        assert_eq!(found.len(), 1, "{found:?}");
        assert!(found[0].starts_with(&format!(
            "src/lib.rs:{}: fn long is 121 lines",
            FUNCTION_LINES + 1
        )));
        let _ = fs::remove_dir_all(&dir);
    }
}
