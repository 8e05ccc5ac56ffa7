//! The C interface's step of `cargo xtask test`, and `cargo xtask capi-header`.
//!
//! The step builds the static library (`caveclod-capi`) and the `caveclod` binary, bakes
//! Spot, compiles the C99 examples (`refine.c`, `arena.c`) and the C++17 test with the
//! system's `cc` and `c++` (`-Wall -Wextra -Werror`; the C++ test also under
//! `-fsanitize=address,undefined` where the compiler links it), and runs them:
//! - `refine.c` must print exactly what `caveclod refine --json` prints for each view;
//! - the C++ test checks every bad input's status, two cameras' indices and counts (against
//!   the CLI's numbers for its views), a budgeted camera, a morphing one, and two cuts of
//!   the octree of an out-of-core bake;
//! - `arena.c` must give the Rust twin's counts (`examples/fixed_arena.rs`), and report a
//!   full arena as its status (exit code 3) when given too small a one;
//! - `stream.c` must refine a camera over a paged Spot streaming through an eight-slot pool
//!   (installs, evictions, no fault, no read of an absent page), and report a damaged page
//!   once while the rest stream.

use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::process::{cmd, example_args, run, show, succeeds, workspace_root};

/// The mesh the C programs refine (baked on the fly).
const INPUT: &str = "data/spot/spot_triangulated.obj";

/// Views of Spot (about a unit across, at the origin) as `[eye, target]`: from the front,
/// from behind and above, and close up (partly outside the frustum).
const VIEWS: [[[f32; 3]; 2]; 3] = [
    [[0.0, 0.3, 2.5], [0.0, 0.0, 0.0]],
    [[-1.5, 1.2, -1.8], [0.0, 0.2, 0.0]],
    [[0.35, 0.25, 0.45], [0.0, 0.1, 0.0]],
];

/// Another hierarchy, for the C++ test's wrong-hierarchy statuses.
const OTHER: &str = "core/tests/data/terrain6.clod";

/// The polygon budget of the fixed-memory examples: below what the first view wants, so
/// the budget binds.
const BUDGET: &str = "1500";

/// Native libraries a Rust static library needs on this platform (what
/// `rustc --print native-static-libs` lists).
fn native_libs() -> &'static [&'static str] {
    if cfg!(target_os = "macos") {
        &["-lSystem", "-lc", "-lm"]
    } else {
        &[
            "-lgcc_s",
            "-lutil",
            "-lrt",
            "-lpthread",
            "-lm",
            "-ldl",
            "-lc",
        ]
    }
}

/// Cargo's target directory for this workspace.
fn target_dir() -> PathBuf {
    env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .map(|p| {
            if p.is_relative() {
                workspace_root().join(p)
            } else {
                p
            }
        })
        .unwrap_or_else(|| workspace_root().join("target"))
}

/// `cargo xtask capi-header`: writes `capi/include/caveclod.h` from the sources.
pub fn write_header() -> Result<(), String> {
    let mut c = cmd(
        "cargo",
        &["test", "-p", "caveclod-capi", "--test", "header", "--quiet"],
    );
    c.env("CAVECLOD_BLESS_HEADER", "1");
    run(c)?;
    println!("wrote capi/include/caveclod.h");
    Ok(())
}

/// Runs `c`, echoing it, and returns its standard output; `Err` on a non-zero exit.
fn output(mut c: Command) -> Result<String, String> {
    let shown = show(&c);
    println!("$ {shown}");
    let out = c
        .output()
        .map_err(|e| format!("could not start `{shown}`: {e}"))?;
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    if !out.status.success() {
        return Err(format!(
            "`{shown}` failed ({}):\n{stdout}{}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    Ok(stdout)
}

/// Compiles `sources` with `compiler` and `flags` against the header and the static
/// library into `out`.
fn compile(
    compiler: &str,
    flags: &[&str],
    source: &Path,
    library: &Path,
    out: &Path,
) -> Result<(), String> {
    let include = workspace_root().join("capi/include");
    let mut c = cmd(compiler, flags);
    c.arg("-I").arg(&include).arg(source).arg(library);
    c.args(native_libs()).arg("-o").arg(out);
    run(c)
}

/// `true` if `c++` builds and runs a program under the sanitizers here.
fn sanitizers_work(dir: &Path) -> bool {
    let src = dir.join("sanitizer_probe.cpp");
    let exe = dir.join("sanitizer_probe");
    std::fs::write(&src, "int main() { return 0; }\n").is_ok()
        && succeeds({
            let mut c = cmd("c++", &["-fsanitize=address,undefined"]);
            c.arg(&src).arg("-o").arg(&exe);
            c
        })
        && succeeds(Command::new(&exe))
}

/// The value of `"key": N` in a JSON line.
fn field(json: &str, key: &str) -> Option<u64> {
    let at = json.find(&format!("\"{key}\":"))? + key.len() + 3;
    let digits: String = json[at..]
        .trim_start()
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    digits.parse().ok()
}

fn coords(p: [f32; 3]) -> Vec<String> {
    p.iter().map(|x| x.to_string()).collect()
}

/// What the step builds and bakes: the library, the CLI, Spot's two files and the C and C++
/// programs.
struct Built {
    root: PathBuf,
    dir: PathBuf,
    library: PathBuf,
    cli: PathBuf,
    clod: PathBuf,
    octree_clod: PathBuf,
    paged_clod: PathBuf,
    refine_c: PathBuf,
    arena_c: PathBuf,
    stream_c: PathBuf,
    test_cpp: PathBuf,
}

/// The step of `cargo xtask test`.
pub fn check() -> Result<(), String> {
    let b = build_library_and_cli()?;
    bake_spot(&b)?;
    compile_programs(&b)?;
    compile_doc_snippets(&b)?;
    let counts = refine_c_against_the_cli(&b)?;
    run_cpp_test(&b, &counts)?;
    arena_c_against_its_twin(&b)?;
    stream_c_through_a_small_pool(&b)
}

/// Builds the static library and the `caveclod` binary (debug).
fn build_library_and_cli() -> Result<Built, String> {
    let root = workspace_root();
    let dir = env::temp_dir().join("caveclod-capi-check");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    run(cmd("cargo", &["build", "-p", "caveclod-capi"]))?;
    run(cmd(
        "cargo",
        &["build", "-p", "caveclod-cli", "--bin", "caveclod"],
    ))?;
    let debug = target_dir().join("debug");
    Ok(Built {
        library: debug.join("libcaveclod.a"),
        cli: debug.join("caveclod"),
        clod: dir.join("spot.clod"),
        octree_clod: dir.join("spot-ooc.clod"),
        paged_clod: dir.join("spot-paged.clod"),
        refine_c: dir.join("refine"),
        arena_c: dir.join("arena"),
        stream_c: dir.join("stream"),
        test_cpp: dir.join("capi_test"),
        root,
        dir,
    })
}

/// Bakes Spot in core, out of core (the octree's file) and paged.
fn bake_spot(b: &Built) -> Result<(), String> {
    let mut bake = Command::new(&b.cli);
    bake.arg("bake")
        .arg(b.root.join(INPUT))
        .arg("-o")
        .arg(&b.paged_clod)
        .args(["--page-size", "8K"]);
    run(bake)?;
    let mut bake = Command::new(&b.cli);
    bake.arg("bake")
        .arg(b.root.join(INPUT))
        .arg("-o")
        .arg(&b.clod);
    run(bake)?;
    let mut bake = Command::new(&b.cli);
    bake.arg("bake")
        .arg(b.root.join(INPUT))
        .arg("-o")
        .arg(&b.octree_clod)
        .arg("--out-of-core");
    run(bake)
}

/// The C99 flags of every C program and snippet.
const C99: [&str; 5] = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-O1"];

/// Compiles the C examples and the C++ test (under the sanitizers where they link).
fn compile_programs(b: &Built) -> Result<(), String> {
    let examples = b.root.join("capi/examples");
    compile(
        "cc",
        &C99,
        &examples.join("refine.c"),
        &b.library,
        &b.refine_c,
    )?;
    compile(
        "cc",
        &C99,
        &examples.join("arena.c"),
        &b.library,
        &b.arena_c,
    )?;
    compile(
        "cc",
        &C99,
        &examples.join("stream.c"),
        &b.library,
        &b.stream_c,
    )?;
    let mut cpp = vec!["-std=c++17", "-Wall", "-Wextra", "-Werror", "-O1", "-g"];
    if sanitizers_work(&b.dir) {
        cpp.extend(["-fsanitize=address,undefined", "-fno-sanitize-recover=all"]);
    } else {
        println!(
            "c++ cannot build with -fsanitize=address,undefined here: the C++ test runs without"
        );
    }
    let test = b.root.join("capi/tests/capi_test.cpp");
    compile("c++", &cpp, &test, &b.library, &b.test_cpp)
}

/// Compiles every C snippet of README.md and `docs/*.md` (a fenced block marked `c`, a
/// whole translation unit) against the header, as an object file: a snippet cannot drift
/// from the interface.
fn compile_doc_snippets(b: &Built) -> Result<(), String> {
    let mut pages = vec![b.root.join("README.md")];
    if let Ok(entries) = std::fs::read_dir(b.root.join("docs")) {
        let mut found: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "md"))
            .collect();
        found.sort();
        pages.extend(found);
    }
    let include = b.root.join("capi/include");
    let mut compiled = 0;
    for page in pages {
        let text =
            std::fs::read_to_string(&page).map_err(|e| format!("{}: {e}", page.display()))?;
        for (k, (line, snippet)) in c_snippets(&text).into_iter().enumerate() {
            let name = page
                .file_stem()
                .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
            let src = b.dir.join(format!("snippet-{name}-{k}.c"));
            std::fs::write(&src, snippet).map_err(|e| format!("{}: {e}", src.display()))?;
            let mut c = cmd("cc", &C99);
            c.arg("-c")
                .arg("-I")
                .arg(&include)
                .arg(&src)
                .arg("-o")
                .arg(src.with_extension("o"));
            run(c).map_err(|e| {
                format!(
                    "{}:{line}: the C snippet does not compile: {e}",
                    page.display()
                )
            })?;
            compiled += 1;
        }
    }
    println!("{compiled} C snippets of the docs compiled");
    Ok(())
}

/// The fenced blocks marked `c` in a Markdown text, with the line each starts on.
pub fn c_snippets(markdown: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut open: Option<(usize, String)> = None;
    for (i, line) in markdown.lines().enumerate() {
        let fence = line.trim_start().starts_with("```");
        match (&mut open, fence) {
            (None, true) if line.trim() == "```c" => open = Some((i + 1, String::new())),
            (Some(_), true) => out.extend(open.take()),
            (Some((_, text)), false) => {
                text.push_str(line);
                text.push('\n');
            }
            _ => {}
        }
    }
    out
}

/// The Rust API's counts of one view: eye, target, active polygons and indices.
type Counts = Vec<(Vec<String>, Vec<String>, u64, u64)>;

/// `refine.c` must print exactly what `caveclod refine --json` prints, view by view.
fn refine_c_against_the_cli(b: &Built) -> Result<Counts, String> {
    let mut rust_counts = Vec::new();
    for [eye, target] in VIEWS {
        let (e, t) = (coords(eye), coords(target));
        let mut c_run = Command::new(&b.refine_c);
        c_run.arg(&b.clod).args(&e).args(&t);
        let from_c = output(c_run)?;
        let mut rust_run = Command::new(&b.cli);
        rust_run
            .arg("refine")
            .arg(&b.clod)
            .arg(format!("--eye={}", e.join(",")))
            .arg(format!("--target={}", t.join(",")))
            .arg("--json");
        let from_rust = output(rust_run)?;
        print!("refine.c:        {from_c}caveclod refine: {from_rust}");
        if from_c != from_rust {
            return Err(format!(
                "refine.c and caveclod refine differ for eye {e:?} target {t:?}"
            ));
        }
        let polygons = field(&from_rust, "active_polygons").ok_or("no active_polygons")?;
        let indices = field(&from_rust, "indices").ok_or("no indices")?;
        rust_counts.push((e, t, polygons, indices));
    }
    Ok(rust_counts)
}

/// The C++ test, with the Rust API's counts of its two views.
fn run_cpp_test(b: &Built, counts: &Counts) -> Result<(), String> {
    let mut test = Command::new(&b.test_cpp);
    test.arg(&b.clod);
    for (e, t, polygons, indices) in counts.iter().take(2) {
        test.args(e)
            .args(t)
            .arg(polygons.to_string())
            .arg(indices.to_string());
    }
    test.arg(b.root.join(OTHER)).arg(&b.octree_clod);
    print!("{}", output(test)?);
    Ok(())
}

/// `arena.c` against its Rust twin, then with an arena too small for the file.
fn arena_c_against_its_twin(b: &Built) -> Result<(), String> {
    let (e, t) = (coords(VIEWS[0][0]), coords(VIEWS[0][1]));
    let mut c_run = Command::new(&b.arena_c);
    c_run.arg(&b.clod).args(&e).args(&t).arg(BUDGET);
    let from_c = output(c_run)?;
    let mut twin = cmd("cargo", &example_args("fixed_arena"));
    twin.arg(&b.clod).args(&e).args(&t).arg(BUDGET);
    let from_rust = output(twin)?;
    print!("arena.c:     {from_c}fixed_arena: {from_rust}");
    for key in ["active_polygons", "indices", "surfaces"] {
        if field(&from_c, key).is_none() || field(&from_c, key) != field(&from_rust, key) {
            return Err(format!("arena.c and fixed_arena differ in {key}"));
        }
    }
    if field(&from_c, "active_polygons").is_none_or(|p| p > BUDGET.parse::<u64>().unwrap_or(0)) {
        return Err("arena.c went over its polygon budget".into());
    }
    let mut small = Command::new(&b.arena_c);
    small.arg(&b.clod).args(&e).args(&t).arg(BUDGET).arg("4096");
    let shown = show(&small);
    let out = small
        .output()
        .map_err(|e| format!("could not start `{shown}`: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout);
    print!("arena.c, 4096-byte arena: {text}");
    if out.status.code() != Some(3) || field(&text, "status") != Some(15) {
        return Err(format!(
            "arena.c with a 4096-byte arena: expected CAVECLOD_STATUS_ARENA_FULL and exit code 3, got {}",
            out.status
        ));
    }
    Ok(())
}

/// `stream.c` refines a camera over the paged Spot streaming through a pool of a few slots:
/// pages are installed (their vertices copied to a device vertex pool) and evicted, none
/// fails, nothing reads an absent page, every index names a vertex copied; with the first
/// streamed page's bytes flipped, that page fails once and the pages outside its subtree
/// stream on.
fn stream_c_through_a_small_pool(b: &Built) -> Result<(), String> {
    let mut run_c = Command::new(&b.stream_c);
    run_c.arg(&b.paged_clod).args(["200", "8"]);
    let text = output(run_c)?;
    print!("stream.c:        {text}");
    let (installs, evictions) = (field(&text, "installs"), field(&text, "evictions"));
    if installs.is_none_or(|n| n == 0)
        || evictions.is_none_or(|n| n == 0)
        || field(&text, "faults") != Some(0)
        || field(&text, "absent_reads") != Some(0)
        || field(&text, "deferred").is_none_or(|n| n == 0)
        || field(&text, "vertex_installs") != installs
        || field(&text, "stale_indices") != Some(0)
    {
        return Err(
            "stream.c: expected installs (each copied to the device vertex pool), evictions, \
             deferred splits, no fault, no read of an absent page and no index naming a \
             vertex not copied"
                .into(),
        );
    }
    let mut bytes =
        std::fs::read(&b.paged_clod).map_err(|e| format!("{}: {e}", b.paged_clod.display()))?;
    // The first streamed page: it starts where the root ends (the header's `file_len`).
    let root_len = bytes
        .get(16..24)
        .and_then(|b| <[u8; 8]>::try_from(b).ok())
        .map_or(0, u64::from_le_bytes) as usize;
    let at = root_len + 100;
    if at >= bytes.len() {
        return Err("the paged Spot has no streamed page".into());
    }
    bytes[at] ^= 0x40;
    let damaged = b.dir.join("spot-paged-damaged.clod");
    std::fs::write(&damaged, &bytes).map_err(|e| format!("{}: {e}", damaged.display()))?;
    let mut run_c = Command::new(&b.stream_c);
    run_c.arg(&damaged).args(["200", "8"]);
    let text = output(run_c)?;
    print!("stream.c, a damaged page: {text}");
    if field(&text, "faults") != Some(1) || field(&text, "installs").is_none_or(|n| n == 0) {
        return Err("stream.c with a damaged page: expected one fault and installs".into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn c_snippets_are_the_blocks_marked_c() {
        let md = "text\n```c\nint a;\n```\n```rust\nfn f() {}\n```\n```c\nint b;\nint c;\n```\n";
        assert_eq!(
            c_snippets(md),
            vec![
                (2, "int a;\n".to_string()),
                (8, "int b;\nint c;\n".to_string())
            ]
        );
    }
}
