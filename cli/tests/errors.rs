//! Bad input and unsafe outputs: each case exits non-zero with a message naming the file and
//! the element at fault (or is refused before any work), and no input file is ever changed.

mod common;

use std::path::{Path, PathBuf};

use common::{caveclod, json, s, TERRAIN6};
use serde_json::Value;

/// Runs the command, which must fail; returns its stderr after checking that every one of
/// `inputs` still holds the bytes it had before.
fn fails(args: &[&str], inputs: &[&Path]) -> String {
    let before: Vec<Vec<u8>> = inputs.iter().map(|p| std::fs::read(p).unwrap()).collect();
    let out = caveclod(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "{args:?} succeeded: {stderr}");
    for (p, b) in inputs.iter().zip(before) {
        assert_eq!(std::fs::read(p).unwrap(), b, "{} changed", p.display());
    }
    stderr
}

/// Asserts that `text` contains every one of `parts`.
fn says(text: &str, parts: &[&str]) {
    for p in parts {
        assert!(text.contains(p), "'{p}' missing from: {text}");
    }
}

/// An `n` × `n` grid of quads as OBJ text (positions only), a complete last line.
fn grid_obj(n: usize) -> String {
    let mut t = String::new();
    for z in 0..=n {
        for x in 0..=n {
            t.push_str(&format!("v {x} {} {z}\n", (x * z % 3) as f32 * 0.1));
        }
    }
    let id = |x: usize, z: usize| z * (n + 1) + x + 1;
    for z in 0..n {
        for x in 0..n {
            let (a, b, c, d) = (id(x, z), id(x, z + 1), id(x + 1, z + 1), id(x + 1, z));
            t.push_str(&format!("f {a} {b} {c} {d}\n"));
        }
    }
    t
}

/// A file of `len` pseudo-random bytes (a fixed LCG, the same every run).
fn random_bytes(len: usize) -> Vec<u8> {
    let mut x: u64 = 0x2545_f491_4f6c_dd1d;
    (0..len)
        .map(|_| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 56) as u8
        })
        .collect()
}

struct Dir {
    dir: tempfile::TempDir,
}

impl Dir {
    fn new() -> Self {
        Dir {
            dir: tempfile::tempdir().unwrap(),
        }
    }
    fn file(&self, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
        let p = self.dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }
    fn clod(&self, name: &str) -> PathBuf {
        let bytes = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join(TERRAIN6)).unwrap();
        self.file(name, bytes)
    }
    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }
}

#[test]
fn export_refuses_to_write_over_its_input() {
    let d = Dir::new();
    let clod = d.clod("same.clod");
    let e = fails(&["export", s(&clod), "-o", s(&clod)], &[&clod]);
    says(&e, &["same.clod: output:"]);
    // Under an .obj name that is a hard link to the input: the same file all the same.
    let link = d.path("link.obj");
    std::fs::hard_link(&clod, &link).unwrap();
    let e = fails(&["export", s(&clod), "-o", s(&link)], &[&clod]);
    says(
        &e,
        &[
            "link.obj: output: is the input",
            "same file under another name",
        ],
    );
}

#[test]
fn export_refuses_an_extension_other_than_obj() {
    let d = Dir::new();
    let clod = d.clod("in.clod");
    let out = d.path("out.ply");
    let e = fails(&["export", s(&clod), "-o", s(&out)], &[&clod]);
    says(
        &e,
        &[
            "out.ply: output: extension .ply",
            "expected a name ending in .obj",
        ],
    );
    assert!(!out.exists());
}

#[test]
fn bake_refuses_an_output_not_named_clod() {
    let d = Dir::new();
    let obj = d.file("grid.obj", grid_obj(4));
    let out = d.path("x.ply");
    let e = fails(&["bake", s(&obj), "-o", s(&out)], &[&obj]);
    says(
        &e,
        &[
            "x.ply: output: extension .ply",
            "expected a name ending in .clod",
        ],
    );
    assert!(!out.exists());
    let e = fails(&["bake", s(&obj), "-o", s(&obj)], &[&obj]);
    says(&e, &["grid.obj: output:"]);
}

#[test]
fn bake_refuses_a_hard_link_to_its_input() {
    let d = Dir::new();
    let obj = d.file("grid.obj", grid_obj(4));
    let link = d.path("grid.clod");
    std::fs::hard_link(&obj, &link).unwrap();
    let e = fails(&["bake", s(&obj), "-o", s(&link)], &[&obj]);
    says(&e, &["grid.clod: output: is the input", "grid.obj"]);
}

#[test]
fn bake_checks_the_output_directory_before_reading_the_input() {
    let d = Dir::new();
    // The input is bad too: the output is checked first, so its error is the one reported.
    let obj = d.file("bad.obj", random_bytes(4096));
    let out = d.path("missing").join("x.clod");
    let e = fails(&["bake", s(&obj), "-o", s(&out)], &[&obj]);
    says(&e, &["x.clod: output: directory", "missing does not exist"]);
    assert!(!e.contains("bad.obj"), "{e}");
}

#[test]
fn an_obj_cut_mid_line_is_an_error_naming_the_line() {
    let d = Dir::new();
    let text = grid_obj(4);
    // Cut inside the last face: `f a b` of `f a b c d`, no line break after it.
    let last = text.trim_end().rfind('\n').unwrap() + 1;
    let cut_at = last + text[last..].match_indices(' ').nth(2).unwrap().0;
    let obj = d.file("cut.obj", &text[..cut_at]);
    let lines = text[..cut_at].lines().count();
    let out = d.path("cut.clod");
    let e = fails(&["bake", s(&obj), "-o", s(&out)], &[&obj]);
    says(
        &e,
        &[
            "cut.obj: truncated:",
            &format!("line {lines}: the file ends in the middle of it"),
            "fewer than 3 corners",
        ],
    );
    // Cut inside a vertex line: `v 1 0` of `v 1 0 0`.
    let obj = d.file("cutv.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\nv 1 0");
    let e = fails(&["bake", s(&obj), "-o", s(&out)], &[&obj]);
    says(
        &e,
        &[
            "cutv.obj: truncated: line 5:",
            "v needs 3, 4, 6 or 7 numbers",
        ],
    );
    assert!(!out.exists());
}

#[test]
fn skipped_faces_are_counted_in_the_repairs_and_printed() {
    let d = Dir::new();
    let mut text = grid_obj(4);
    text.push_str("f 1 2\nl 1 2 3\n");
    let obj = d.file("skips.obj", &text);
    let out = d.path("skips.clod");
    let r = json(&caveclod(&["bake", s(&obj), "-o", s(&out), "--json"]));
    assert_eq!(r["repairs"]["skipped_primitives"], 2, "{r}");
    let notes = r["notes"].as_array().unwrap();
    assert!(
        notes.iter().any(|n| n
            .as_str()
            .unwrap()
            .contains("2 point, line and degenerate face statements skipped")),
        "{r}"
    );
    // The human report prints them too, and `info` reads them back from the file.
    let info = caveclod(&["info", s(&out)]);
    let text = String::from_utf8_lossy(&info.stdout);
    says(
        &text,
        &["skipped_primitives 2", "degenerate face statements skipped"],
    );
}

#[test]
fn random_bytes_named_obj_are_not_text() {
    let d = Dir::new();
    let obj = d.file("noise.obj", random_bytes(4096));
    let e = fails(&["bake", s(&obj), "-o", s(&d.path("n.clod"))], &[&obj]);
    says(
        &e,
        &[
            "noise.obj: line ",
            "is not text; expected a Wavefront OBJ text file",
        ],
    );
}

#[test]
fn an_ascii_ply_with_nan_names_the_vertex_like_the_binary_reader() {
    let d = Dir::new();
    let ply = |x: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
             end_header\n0 0 0\n1 0 0\n{x} 0 1\n3 0 1 2\n"
        )
    };
    let nan = d.file("nan.ply", ply("nan"));
    let e = fails(&["bake", s(&nan), "-o", s(&d.path("n.clod"))], &[&nan]);
    says(&e, &["nan.ply: vertex 2: coordinate x is NaN"]);
    let word = d.file("word.ply", ply("zero"));
    let e = fails(&["bake", s(&word), "-o", s(&d.path("n.clod"))], &[&word]);
    says(
        &e,
        &["word.ply: vertex 2 (line 12): property 'x': 'zero'; expected a float"],
    );
    // Cut after the second vertex.
    let text = ply("0");
    let cut = d.file("cut.ply", &text[..text.find("0 0 1").unwrap()]);
    let e = fails(&["bake", s(&cut), "-o", s(&d.path("n.clod"))], &[&cut]);
    says(
        &e,
        &["cut.ply: truncated: vertex 2: the file ends after 2 of the 3 'vertex' lines"],
    );
}

#[test]
fn random_bytes_named_glb_or_gltf_name_the_header() {
    let d = Dir::new();
    let glb = d.file("noise.glb", random_bytes(4096));
    let e = fails(&["bake", s(&glb), "-o", s(&d.path("n.clod"))], &[&glb]);
    says(
        &e,
        &[
            "noise.glb: header: not a binary glTF file",
            "expected the magic 'glTF'",
        ],
    );
    let gltf = d.file("noise.gltf", random_bytes(4096));
    let e = fails(&["bake", s(&gltf), "-o", s(&d.path("n.clod"))], &[&gltf]);
    says(
        &e,
        &[
            "noise.gltf: header: not a glTF JSON file",
            "expected a JSON object",
        ],
    );
    let ply = d.file("noise.ply", random_bytes(4096));
    let e = fails(&["bake", s(&ply), "-o", s(&d.path("n.clod"))], &[&ply]);
    says(
        &e,
        &[
            "noise.ply: header: not a PLY file",
            "expected the first line 'ply'",
        ],
    );
}

#[test]
fn info_json_reports_a_bad_file_on_stdout() {
    let d = Dir::new();
    let bad = d.file("bad.clod", random_bytes(1000));
    let out = caveclod(&["info", "--json", s(&bad)]);
    assert!(!out.status.success());
    let r: Value = serde_json::from_slice(&out.stdout).expect("one JSON object on stdout");
    assert_eq!(r["valid"], false);
    assert!(r["error"].as_str().unwrap().contains("bad.clod"), "{r}");
    let good = d.clod("good.clod");
    let r = json(&caveclod(&["info", "--json", s(&good)]));
    assert_eq!(r["valid"], true);
}

#[test]
fn generate_and_render_check_their_outputs_first() {
    let d = Dir::new();
    let out = d.path("terrain.obj");
    let e = fails(&["generate", "--triangles", "100", "-o", s(&out)], &[]);
    says(
        &e,
        &[
            "terrain.obj: output: extension .obj",
            "expected a name ending in .ply",
        ],
    );
    assert!(!out.exists());
    let ply = d.path("terrain.ply");
    let e = fails(
        &[
            "generate",
            "--triangles",
            "100",
            "--roughness=-1",
            "-o",
            s(&ply),
        ],
        &[],
    );
    says(&e, &["`-1`: expected a finite number of zero or more"]);
    assert!(!ply.exists());
    // The split-screen image would be written over the file rendered: refused before any
    // device is asked for.
    let clod = d.clod("split1.png");
    let e = fails(&["render", s(&clod), "--out", s(d.dir.path())], &[&clod]);
    says(&e, &["split1.png: output: is the input"]);
}

#[test]
fn the_out_of_core_readers_name_the_same_elements() {
    let d = Dir::new();
    let out = d.path("o.clod");
    let ooc = |input: &Path| {
        fails(
            &["bake", "--out-of-core", s(input), "-o", s(&out)],
            &[input],
        )
    };
    let cut = d.file("cut.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\nf 1 2");
    says(
        &ooc(&cut),
        &["cut.obj: line 5: the file ends in the middle of it (a face with fewer than 3 corners)"],
    );
    let noise = d.file("noise.obj", random_bytes(4096));
    says(
        &ooc(&noise),
        &["noise.obj: line ", "is not text; expected a Wavefront OBJ"],
    );
    let nan = d.file(
        "nan.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
         end_header\n0 0 0\n1 0 0\nnan 0 1\n3 0 1 2\n",
    );
    says(&ooc(&nan), &["nan.ply: vertex 2: coordinate x is NaN"]);
    let noise = d.file("noise.ply", random_bytes(4096));
    says(
        &ooc(&noise),
        &[
            "noise.ply: header: not a PLY file",
            "expected the first line 'ply'",
        ],
    );
    assert!(!out.exists());
    // A two-corner face inside the file is skipped and counted.
    let mut text = grid_obj(6);
    text.push_str("f 1 2\n");
    let obj = d.file("skips.obj", &text);
    let r = json(&caveclod(&[
        "bake",
        "--out-of-core",
        s(&obj),
        "-o",
        s(&out),
        "--json",
    ]));
    assert_eq!(r["repairs"]["skipped_primitives"], 1, "{r}");
}
