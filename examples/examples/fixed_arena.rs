//! A runtime in fixed memory, as a console runs one: the Rust twin of the C example
//! `capi/examples/arena.c`, over caveclod-core directly.
//!
//! `cargo run -p caveclod-examples --example fixed_arena -- FILE.clod EX EY EZ TX TY TZ
//! [POLYGON_BUDGET [ARENA_BYTES]]`
//!
//! One arena is reserved at start (64 MiB, or its first ARENA_BYTES); every byte the runtime
//! touches is carved from it: the file's bytes, one camera with a hard polygon budget
//! (default 20000) and its index lists, each sized from the file's counts and the budget.
//! Refinement and emission allocate nothing. Prints the JSON line `arena.c` prints; a full
//! arena is reported (exit code 3), never a crash.

use std::io::Read;
use std::process::ExitCode;

use caveclod_core::glam::Vec3;
use caveclod_core::{CameraConfig, CameraState, Hierarchy, LookAt, RefineParams};

const ARENA_CAPACITY: usize = 64 << 20;
const MAX_PASSES: u32 = 1000;

/// A bump arena of 32-bit words; a request that does not fit is `None`.
struct Arena<'a> {
    rest: &'a mut [u32],
    used_bytes: usize,
    size_bytes: usize,
}

impl<'a> Arena<'a> {
    fn new(words: &'a mut [u32]) -> Self {
        let size_bytes = 4 * words.len();
        Self {
            rest: words,
            used_bytes: 0,
            size_bytes,
        }
    }

    /// `bytes` bytes (rounded up to words) starting on a multiple of `align` bytes.
    fn take(&mut self, bytes: usize, align: usize) -> Option<&'a mut [u32]> {
        let at = self.rest.as_ptr() as usize;
        let pad = (at.next_multiple_of(align) - at) / 4;
        let words = bytes.div_ceil(4);
        if pad + words > self.rest.len() {
            return None;
        }
        let rest = std::mem::take(&mut self.rest);
        let (taken, rest) = rest[pad..].split_at_mut(words);
        self.rest = rest;
        self.used_bytes += 4 * (pad + words);
        Some(taken)
    }

    fn full(&self, what: &str) -> ExitCode {
        println!(
            "{{\"error\": \"{what}\", \"message\": \"the arena is full\", \"arena_used\": {}, \
             \"arena_size\": {}}}",
            self.used_bytes, self.size_bytes
        );
        ExitCode::from(3)
    }
}

fn point(args: &[String]) -> Result<Vec3, String> {
    let v: Vec<f32> = args
        .iter()
        .map(|a| a.parse::<f32>().map_err(|e| format!("`{a}`: {e}")))
        .collect::<Result<_, _>>()?;
    Ok(Vec3::new(v[0], v[1], v[2]))
}

fn main() -> ExitCode {
    match run() {
        Ok(code) => code,
        Err(e) => {
            eprintln!("fixed_arena: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<ExitCode, String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 7 || args.len() > 9 {
        return Err(
            "usage: fixed_arena FILE.clod EX EY EZ TX TY TZ [POLYGON_BUDGET [ARENA_BYTES]]".into(),
        );
    }
    let budget: u32 = args
        .get(7)
        .map_or(Ok(20_000), |b| b.parse())
        .map_err(|e| format!("{e}"))?;
    let arena_bytes: usize = args
        .get(8)
        .map_or(Ok(ARENA_CAPACITY), |b| b.parse())
        .map_err(|e| format!("{e}"))?
        .min(ARENA_CAPACITY);
    let (eye, target) = (point(&args[1..4])?, point(&args[4..7])?);

    // The one reservation, made at start.
    let mut reserved = vec![0u32; arena_bytes / 4];
    let mut arena = Arena::new(&mut reserved);

    // The file, into the arena (64-byte aligned: no record straddles cache lines).
    let mut file = std::fs::File::open(&args[0]).map_err(|e| format!("{}: {e}", args[0]))?;
    let len = file.metadata().map_err(|e| e.to_string())?.len() as usize;
    let Some(words) = arena.take(len, 64) else {
        return Ok(arena.full("file"));
    };
    let bytes = &mut bytemuck::cast_slice_mut::<u32, u8>(words)[..len];
    file.read_exact(bytes)
        .map_err(|e| format!("{}: {e}", args[0]))?;
    let h = Hierarchy::from_bytes(bytes).map_err(|e| format!("{}: {e}", args[0]))?;

    // One camera of at most `budget` polygons, and index lists for that many.
    let config = CameraConfig::with_polygon_budget(&h, budget);
    let camera_bytes = 4 * CameraState::words_needed_for(&h, &config);
    let Some(camera_words) = arena.take(camera_bytes, 8) else {
        return Ok(arena.full("camera"));
    };
    let index_room = 3 * budget.max(h.base_polygon_count() as u32) as usize;
    let Some(indices) = arena.take(4 * index_room, 4) else {
        return Ok(arena.full("indices"));
    };
    let Some(offsets) = arena.take(4 * (h.surface_count() + 1), 4) else {
        return Ok(arena.full("indices"));
    };
    let mut cam = CameraState::with_config(&h, camera_words, &config).map_err(|e| e.to_string())?;

    let look = LookAt {
        eye,
        target,
        up: Vec3::Y,
        fov_y: core::f32::consts::FRAC_PI_3,
        near: 0.1,
        far: 1e5,
    };
    let view = look.view(1280, 720);
    let params = RefineParams::default();
    for _ in 0..MAX_PASSES {
        let stats = cam.refine(&h, &view, &params).map_err(|e| e.to_string())?;
        if stats.operations() == 0 {
            break;
        }
    }
    let total = cam
        .emit_indices_packed(&h, indices, offsets)
        .map_err(|e| e.to_string())?;
    println!(
        "{{\"active_polygons\": {}, \"indices\": {total}, \"surfaces\": {}, \"budget\": {budget}, \
         \"arena_used\": {}}}",
        cam.active_polygon_count(),
        h.surface_count(),
        arena.used_bytes
    );
    Ok(ExitCode::SUCCESS)
}
