//! Hostile versions of the real inputs in `../shared/data` (relative to the repository root)
//! through the in-memory bake: every truncation point on a grid and seeded byte flips of
//! FlightHelmet (its glTF JSON and its buffer), spot (OBJ), lucy (binary PLY) and St. Helens
//! (USGS DEM), each imported with `import_bytes`, as `pipeline::bake_bytes` does.
//!
//! Every case must give a typed error or a mesh that validates, never a panic nor
//! [`ImportError::Internal`] (the import's panic guard). A mesh that differs from the
//! unmodified file's is then baked around its first change: the window of triangles there
//! (the input's other triangles baked by `real_data`) goes through the welder, surface groups
//! and hierarchy builder, is written as `.clod` bytes and must load with
//! `Hierarchy::from_bytes`, unless the bake refuses it with a typed error.
//!
//! Parsing megabytes thousands of times needs an optimised build: the sweep is ignored in
//! debug builds and runs in `cargo test --release -p caveclod-bake --test reader_sweep`
//! (a step of `cargo xtask test`). Inputs absent from `../shared/data` are skipped with a note.

use std::collections::HashMap;
use std::hash::Hash;
use std::path::Path;
use std::time::Instant;

use caveclod_bake::import::{import_bytes, ImportError, ImportOptions};
use caveclod_bake::mesh::{Mesh, Triangle, NO_ATTRIBUTE};
use caveclod_bake::pipeline::{bake_mesh, BakeError};
use caveclod_tests::rng::SplitMix64 as Rng;
use caveclod_tests::shared_data;
use caveclod_tests::AlignedBytes;

/// Truncation points per input, evenly spaced over its length (with the empty file).
const TRUNCATIONS: usize = 48;
/// Seeded byte flips per input.
const FLIPS: usize = 700;
/// Triangles baked around a mesh's first change.
const WINDOW: usize = 192;

/// A real input: the file mutated, and the file the import starts from (the same file, or
/// the glTF whose buffer is mutated).
struct Input {
    /// The file the importer is given, under `../shared/data`.
    main: &'static str,
    /// The file that is truncated and flipped (`main` or a file it names).
    mutated: &'static str,
}

const INPUTS: [Input; 5] = [
    Input {
        main: "FlightHelmet/FlightHelmet.gltf",
        mutated: "FlightHelmet/FlightHelmet.gltf",
    },
    Input {
        main: "FlightHelmet/FlightHelmet.gltf",
        mutated: "FlightHelmet/FlightHelmet.bin",
    },
    Input {
        main: "spot/spot_triangulated.obj",
        mutated: "spot/spot_triangulated.obj",
    },
    Input {
        main: "scans/lucy.ply",
        mutated: "scans/lucy.ply",
    },
    Input {
        main: "terrain/SainteHelens.dem",
        mutated: "terrain/SainteHelens.dem",
    },
];

/// An input's files in memory: the main file and every file next to it that it may name.
struct Files {
    name: String,
    main: Vec<u8>,
    /// Files beside the main one, by name.
    side: HashMap<String, Vec<u8>>,
    /// The name of the mutated file among `side`, or `None` when the main file is mutated.
    mutated_side: Option<String>,
}

impl Files {
    fn read(input: &Input) -> Option<Files> {
        let dir = shared_data::dir();
        let main_path = dir.join(input.main);
        let mutated_path = dir.join(input.mutated);
        if !main_path.exists() || !mutated_path.exists() {
            eprintln!(
                "note: {} not found under ../shared/data; skipping",
                input.mutated
            );
            return None;
        }
        let main = std::fs::read(&main_path).expect("reading the input");
        // The buffers and material libraries beside the input (not its textures).
        let mut side = HashMap::new();
        let beside = main_path.parent().expect("a file in a directory");
        for entry in std::fs::read_dir(beside).expect("listing the input's directory") {
            let path = entry.expect("listing the input's directory").path();
            if matches!(
                path.extension().and_then(|e| e.to_str()),
                Some("bin" | "mtl")
            ) {
                let bytes = std::fs::read(&path).expect("reading the input");
                side.insert(file_name(&path.to_string_lossy()), bytes);
            }
        }
        let mutated_side = (input.mutated != input.main).then(|| file_name(input.mutated));
        Some(Files {
            name: file_name(input.main),
            main,
            side,
            mutated_side,
        })
    }

    fn mutated(&self) -> &[u8] {
        match &self.mutated_side {
            Some(name) => &self.side[name],
            None => &self.main,
        }
    }

    /// Imports with `mutated` standing for the mutated file; side files the input names that
    /// are not in memory (textures) are not found.
    fn import(&self, mutated: &[u8]) -> Result<Mesh, ImportError> {
        let main = match self.mutated_side {
            Some(_) => &self.main[..],
            None => mutated,
        };
        let mut load = |name: &str| match (&self.mutated_side, self.side.get(name)) {
            (Some(m), Some(_)) if m == name => Ok(mutated.to_vec()),
            (_, Some(bytes)) => Ok(bytes.clone()),
            _ => Err(std::io::Error::from(std::io::ErrorKind::NotFound)),
        };
        let result = import_bytes(&self.name, main, &mut load, &ImportOptions::default());
        result.map(|(mesh, _)| mesh)
    }
}

fn file_name(relative: &str) -> String {
    Path::new(relative)
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The first triangle at which `mesh` differs from `base` (its indices, the attribute values
/// they name, or its existence), or `None` when the two are the same mesh; a change in the
/// surfaces counts as a change at triangle 0.
fn first_change(base: &Mesh, mesh: &Mesh) -> Option<usize> {
    if base.surfaces != mesh.surfaces {
        return Some(0);
    }
    let same = |a: &Triangle, b: &Triangle| {
        a == b
            && (0..3).all(|k| {
                same_value(&base.positions, &mesh.positions, a.position[k])
                    && same_value(&base.normals, &mesh.normals, a.normal[k])
                    && same_value(&base.uvs, &mesh.uvs, a.uv[k])
                    && same_value(&base.colors, &mesh.colors, a.color[k])
            })
    };
    let common = base.triangles.len().min(mesh.triangles.len());
    (0..common)
        .find(|&i| !same(&base.triangles[i], &mesh.triangles[i]))
        .or((base.triangles.len() != mesh.triangles.len()).then_some(common))
}

/// Whether attribute `index` has the same bits in both streams.
fn same_value<const N: usize>(a: &[[f32; N]], b: &[[f32; N]], index: u32) -> bool {
    if index == NO_ATTRIBUTE {
        return true;
    }
    let bits = |s: &[[f32; N]]| s.get(index as usize).map(|v| v.map(f32::to_bits));
    bits(a) == bits(b)
}

/// The triangles `range` of `mesh` as a mesh of their own, each attribute stream compacted
/// to the values they name.
fn window(mesh: &Mesh, range: std::ops::Range<usize>) -> Mesh {
    fn remap<T: Copy, K: Hash + Eq + Copy>(
        map: &mut HashMap<K, u32>,
        out: &mut Vec<T>,
        key: K,
        value: T,
    ) -> u32 {
        *map.entry(key).or_insert_with(|| {
            out.push(value);
            (out.len() - 1) as u32
        })
    }
    let mut w = Mesh {
        surfaces: mesh.surfaces.clone(),
        ..Mesh::default()
    };
    let (mut p, mut n, mut t, mut c) = (
        HashMap::new(),
        HashMap::new(),
        HashMap::new(),
        HashMap::new(),
    );
    for tri in &mesh.triangles[range] {
        let mut out = *tri;
        for k in 0..3 {
            let i = tri.position[k];
            out.position[k] = remap(&mut p, &mut w.positions, i, mesh.positions[i as usize]);
            if tri.normal[k] != NO_ATTRIBUTE {
                let i = tri.normal[k];
                out.normal[k] = remap(&mut n, &mut w.normals, i, mesh.normals[i as usize]);
            }
            if tri.uv[k] != NO_ATTRIBUTE {
                let i = tri.uv[k];
                out.uv[k] = remap(&mut t, &mut w.uvs, i, mesh.uvs[i as usize]);
            }
            if tri.color[k] != NO_ATTRIBUTE {
                let i = tri.color[k];
                out.color[k] = remap(&mut c, &mut w.colors, i, mesh.colors[i as usize]);
            }
        }
        w.triangles.push(out);
    }
    w
}

/// What the cases of one input came to.
#[derive(Debug, Default)]
struct Tally {
    errors: usize,
    unchanged: usize,
    baked: usize,
    refused: usize,
}

/// One mutated version of the input: a typed error, the same mesh, or a changed mesh whose
/// window around the change bakes into a hierarchy that loads (or is refused by a typed error).
fn check_case(files: &Files, base: &Mesh, bytes: &[u8], case: &str, tally: &mut Tally) {
    let mesh = match files.import(bytes) {
        Err(ImportError::Internal { message, .. }) => {
            panic!("{case}: the import failed internally: {message}")
        }
        Err(_) => {
            tally.errors += 1;
            return;
        }
        Ok(mesh) => mesh,
    };
    if let Err(e) = mesh.validate() {
        panic!("{case}: the imported mesh does not validate: {e}");
    }
    let Some(at) = first_change(base, &mesh) else {
        tally.unchanged += 1;
        return;
    };
    let start = at.saturating_sub(WINDOW / 2).min(mesh.triangles.len());
    let end = (start + WINDOW).min(mesh.triangles.len());
    let part = window(&mesh, start..end);
    match bake_mesh(&part, &files.name, &mut |_| {}) {
        Err(BakeError::Invalid(e)) => panic!("{case}: the baked hierarchy does not validate: {e}"),
        Err(_) => tally.refused += 1,
        Ok((baked, _)) => {
            let bytes = baked
                .to_bytes(&[])
                .unwrap_or_else(|e| panic!("{case}: writing the hierarchy: {e}"));
            if let Err(e) = AlignedBytes::from_slice(&bytes).hierarchy() {
                panic!("{case}: the baked file does not load: {e:?}");
            }
            tally.baked += 1;
        }
    }
}

/// Truncations on a grid, then seeded flips (a random bit, or a random byte value).
fn sweep(input: &Input, seed: u64) {
    let Some(files) = Files::read(input) else {
        return;
    };
    let start = Instant::now();
    let base = files
        .import(files.mutated())
        .expect("the unmodified input imports");
    let original = files.mutated().to_vec();
    let mut tally = Tally::default();
    for k in 0..TRUNCATIONS {
        let len = original.len() * k / TRUNCATIONS;
        let case = format!("{} truncated to {len} bytes", input.mutated);
        check_case(&files, &base, &original[..len], &case, &mut tally);
    }
    let mut rng = Rng::new(seed);
    let mut bytes = original.clone();
    for _ in 0..FLIPS {
        let at = rng.below(bytes.len());
        let value = if rng.below(2) == 0 {
            bytes[at] ^ (1 << rng.below(8))
        } else {
            rng.next_u64() as u8
        };
        let case = format!(
            "{} with byte {at} set from {:#04x} to {value:#04x}",
            input.mutated, bytes[at]
        );
        bytes[at] = value;
        check_case(&files, &base, &bytes, &case, &mut tally);
        bytes[at] = original[at];
    }
    eprintln!(
        "{}: {} cases in {:.1} s: {tally:?}",
        input.mutated,
        TRUNCATIONS + FLIPS,
        start.elapsed().as_secs_f64()
    );
}

#[test]
#[cfg_attr(debug_assertions, ignore = "slow in debug builds: run with --release")]
fn flight_helmet_json() {
    sweep(&INPUTS[0], 1);
}

#[test]
#[cfg_attr(debug_assertions, ignore = "slow in debug builds: run with --release")]
fn flight_helmet_buffer() {
    sweep(&INPUTS[1], 2);
}

#[test]
#[cfg_attr(debug_assertions, ignore = "slow in debug builds: run with --release")]
fn spot_obj() {
    sweep(&INPUTS[2], 3);
}

#[test]
#[cfg_attr(debug_assertions, ignore = "slow in debug builds: run with --release")]
fn lucy_ply() {
    sweep(&INPUTS[3], 4);
}

#[test]
#[cfg_attr(debug_assertions, ignore = "slow in debug builds: run with --release")]
fn st_helens_dem() {
    sweep(&INPUTS[4], 5);
}
