//! `caveclod demo`: the whole demo, then its ratios against the targets.

use crate::demo::{self, DemoOptions};

use crate::args::DemoArgs;

/// Runs the demo with progress on stderr, then prints the ratios and the files written.
pub fn demo(a: DemoArgs) -> Result<(), String> {
    let mut options = DemoOptions {
        out: a.out,
        frames: a.frames,
        rebake: a.rebake,
        no_render: a.no_render,
        ..DemoOptions::default()
    };
    if let Some(d) = a.data {
        options.data = d;
    }
    let outcome = demo::run(&options, &mut |line| eprintln!("{line}"))?;
    let r = outcome.ratios;
    println!(
        "operations per camera, shared / per-camera state: {:.1}x (target >= 7)\n\
         refinement time, shared / per-camera: {:.1}x (target >= 3)\n\
         refinement time, 4 cameras together / one alone (mean): {:.2}x (target <= 4.4)\n\
         a thread per camera, speed-up: {:.2}x (target >= 1.6 on 2 cores)\n\
         per-camera memory / the paper's: {:.2} (target <= 0.5)",
        r.ops, r.refine_time, r.four_over_one, r.threads_speedup, r.memory
    );
    for f in &outcome.files {
        println!("wrote {}", f.display());
    }
    println!("report: {}", outcome.report.display());
    Ok(())
}
