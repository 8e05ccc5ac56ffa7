//! The runtime's soak, as long as asked: four cameras over the St. Helens terrain (whole by
//! default) or a baked `.clod` file, with everything drawn at random from the seed (see
//! `caveclod_tests::soak`), the full invariants every `--check-every` frames, and the frame
//! loop's allocations counted.
//!
//! `cargo run --release -p caveclod-tests --example soak -- --frames 100000 --seed 1`
//!
//! Options: `--frames N` (100,000), `--seed S` (1), `--check-every N` (1,000), `--crop F`
//! (share of the terrain's extent kept round its centre, 1), `--clod FILE` (a baked file
//! instead of the terrain), `--quiet` (no progress lines). Exits non-zero on a violated
//! invariant or an allocation.

#[path = "../../core/tests/counting/mod.rs"]
mod counting;

use std::process::ExitCode;
use std::time::Instant;

use caveclod_tests::soak::terrain::{bake_terrain, load_clod, st_helens};
use caveclod_tests::soak::{run, SoakConfig, SoakReport};

struct Options {
    config: SoakConfig,
    crop: f32,
    clod: Option<std::path::PathBuf>,
    quiet: bool,
}

fn parse() -> Result<Options, String> {
    let mut o = Options {
        config: SoakConfig {
            frames: 100_000,
            seed: 1,
            check_every: 1000,
        },
        crop: 1.0,
        clod: None,
        quiet: false,
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or(format!("{a} needs a value"));
        let number = |v: String| {
            v.replace('_', "")
                .parse::<u64>()
                .map_err(|e| format!("{a}: {e}"))
        };
        match a.as_str() {
            "--frames" => o.config.frames = number(value()?)?,
            "--seed" => o.config.seed = number(value()?)?,
            "--check-every" => o.config.check_every = number(value()?)?,
            "--crop" => o.crop = value()?.parse().map_err(|e| format!("--crop: {e}"))?,
            "--clod" => o.clod = Some(value()?.into()),
            "--quiet" => o.quiet = true,
            _ => return Err(format!("unknown argument {a}")),
        }
    }
    Ok(o)
}

fn print_report(r: &SoakReport, seconds: f64) {
    println!("frames              {}", r.frames);
    println!("refinements         {}", r.refinements);
    println!(
        "operations          {} (splits {}, of them forced {}; collapses {}; API splits {}, \
         collapses {}, refusals {}; morphs started {})",
        r.operations(),
        r.splits,
        r.forced_splits,
        r.collapses,
        r.api_splits,
        r.api_collapses,
        r.api_refusals,
        r.morphs_started
    );
    println!(
        "morphs              started {}, finished {}, aborted {}, dropped {}",
        r.morphs_started, r.morphs_finished, r.morphs_aborted, r.morphs_dropped
    );
    println!(
        "refusals            capacity {}, stack overflows {}",
        r.capacity_refusals, r.stack_overflows
    );
    println!("nodes visited       {}", r.nodes_visited);
    println!(
        "events              teleports {}, resets {}, cameras remade {}, whole compactions {}, \
         compaction steps {} ({} cycles), morph finishes {}",
        r.teleports,
        r.resets,
        r.reconfigurations,
        r.compactions,
        r.compaction_steps,
        r.compaction_cycles,
        r.morph_finishes
    );
    println!("indices emitted     {}", r.indices_emitted);
    println!("most active polys   {}", r.max_active_polygons);
    println!(
        "invariant checks    {} (nodes {}, polygons {}, links {}, indices {}, morph slots {})",
        r.invariant_checks,
        r.checked.nodes,
        r.checked.polygons,
        r.checked.links,
        r.checked.indices,
        r.checked.morph_slots
    );
    println!("allocations         {}", r.allocations);
    println!("fingerprint         {:016x}", r.fingerprint);
    println!("wall time           {seconds:.1} s");
}

fn main() -> ExitCode {
    let o = match parse() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("soak: {e}");
            return ExitCode::FAILURE;
        }
    };
    let setup = Instant::now();
    let bytes = match &o.clod {
        Some(path) => load_clod(path),
        None => bake_terrain(&st_helens(), o.crop),
    };
    let bytes = match bytes {
        Ok(b) => b,
        Err(e) => {
            eprintln!("soak: {e}");
            return ExitCode::FAILURE;
        }
    };
    let h = match bytes.hierarchy() {
        Ok(h) => h,
        Err(e) => {
            eprintln!("soak: {e}");
            return ExitCode::FAILURE;
        }
    };
    println!(
        "hierarchy           {} nodes, {} polygons ({} base), ready in {:.1} s; seed {}",
        h.node_count(),
        h.polygon_count(),
        h.base_polygon_count(),
        setup.elapsed().as_secs_f64(),
        o.config.seed
    );
    let start = Instant::now();
    let quiet = o.quiet;
    let result = run(&h, &o.config, &counting::allocations, &mut |r| {
        if !quiet {
            println!(
                "frame {:>8}: {} checks, {} operations, {} allocations, {:.0} s",
                r.frames,
                r.invariant_checks,
                r.operations(),
                r.allocations,
                start.elapsed().as_secs_f64()
            );
        }
    });
    match result {
        Ok(r) => {
            print_report(&r, start.elapsed().as_secs_f64());
            if r.allocations == 0 {
                ExitCode::SUCCESS
            } else {
                eprintln!("soak: the frame loop allocated {} times", r.allocations);
                ExitCode::FAILURE
            }
        }
        Err(e) => {
            eprintln!("{e}");
            ExitCode::FAILURE
        }
    }
}
