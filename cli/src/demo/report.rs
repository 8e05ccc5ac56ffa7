//! The demo's written results: the per-frame CSV, the results table and `report.md`.

use std::fmt::Write as _;
use std::path::Path;

use caveclod_bake::baked::write_atomically;

use super::flights::{emit_ms_all_cameras, refine_ms_all_cameras};
use super::flights::{Flights, Ratios, DISPLAY_FPS, SEGMENT, THREADS_ROUNDS};
use super::inputs::{shown, Loaded};

/// Writes the per-frame CSV.
pub(super) fn write_csv(path: &Path, f: &Flights) -> Result<(), String> {
    let mut s = String::from(
        "mode,cameras,camera,route,frame,operations,refine_us,emit_us,active_polygons\n",
    );
    let all = [&f.per_camera, &f.shared, &f.threads]
        .into_iter()
        .chain(f.fewer.iter())
        .chain(f.alone.iter())
        .chain([&f.uncached, &f.lean]);
    for fl in all {
        let mut mode = fl.options.mode.name().to_string();
        if !fl.options.index_cache {
            mode += "-no-index-cache";
        }
        if fl.options.hashed_pair_map {
            mode += "-hashed-pair-map";
        }
        for (c, (name, r)) in fl.names.iter().zip(&fl.flight.records).enumerate() {
            for i in 0..r.ops.len() {
                let _ = writeln!(
                    s,
                    "{mode},{},{c},{name},{i},{},{:.1},{:.1},{}",
                    fl.options.cameras,
                    r.ops[i],
                    r.refine_ns[i] as f64 / 1e3,
                    r.emit_ns[i] as f64 / 1e3,
                    r.active_polygons[i]
                );
            }
        }
    }
    write_atomically(path, s.as_bytes()).map_err(|e| e.to_string())
}

fn verdict(ok: bool) -> &'static str {
    if ok {
        "met"
    } else {
        "not met"
    }
}

/// The table of the measures against their targets: the head of `report.md`, and
/// `results.md`, which `cargo xtask demo` puts into the README.
pub fn results_table(f: &Flights, r: &Ratios) -> String {
    let mut s = String::new();
    let pc = &f.per_camera;
    let _ = writeln!(s, "| measure | value | target | |\n|---|---|---|---|");
    let _ = writeln!(
        s,
        "| refinement operations per camera per frame, shared state / per-camera state | {:.1}x ({:.1} vs {:.1}) | >= 7x | {} |",
        r.ops,
        f.shared.summary.ops_mean,
        pc.summary.ops_mean,
        verdict(r.ops >= 7.0)
    );
    let _ = writeln!(
        s,
        "| refinement time per frame (median per camera, summed), shared / per-camera | {:.1}x ({:.3} ms vs {:.3} ms) | >= 3x | {} |",
        r.refine_time,
        refine_ms_all_cameras(&f.shared),
        refine_ms_all_cameras(pc),
        verdict(r.refine_time >= 3.0)
    );
    let _ = writeln!(
        s,
        "| refinement time (medians), 4 cameras together / the mean of each camera alone (flown interleaved) | {:.2}x | <= 4.4x | {} |",
        r.four_over_one,
        verdict(r.four_over_one <= 4.4)
    );
    let _ = writeln!(
        s,
        "| flight time, one thread / a thread per camera (median of {THREADS_ROUNDS} rounds, the two flown in turn) | {:.2}x | >= 1.6x on 2 cores | {} |",
        r.threads_speedup,
        verdict(r.threads_speedup >= 1.6)
    );
    let _ = writeln!(
        s,
        "| per-camera memory / the paper's c(4n + 4p + 16) + 12n_a + 36p_a (the state; its geomorph memory, which the paper's cameras lack, beside) | {:.2} ({} B vs {} B; morphs {} B) | <= 0.5 (goal 0.25) | {} |",
        r.memory,
        pc.memory_budgeted.camera_bytes,
        pc.memory_budgeted.paper_camera_bytes,
        pc.flight.morph_bytes,
        verdict(r.memory <= 0.5)
    );
    s.push_str(&super::smooth::rows(f));
    s
}

/// The markdown report: the inputs, the results table, how the flights were measured, the
/// index cache's cost, each flight's own report and the list of figures.
pub(super) fn report(
    terrain: &Loaded,
    model: &Loaded,
    f: &Flights,
    r: &Ratios,
    streaming: &str,
    seconds: f64,
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# caveclod demo report\n");
    inputs(&mut s, terrain, model, f, seconds);
    s.push_str(&results_table(f, r));
    s.push_str(streaming);
    how_measured(&mut s, f);
    huge_pages(&mut s, terrain);
    paper_unit(&mut s, f);
    index_cache(&mut s, f);
    super::smooth::section(&mut s, f);
    flight_reports(&mut s, f);
    figures_list(&mut s);
    s
}

/// The inputs (baked now or from the cache), the flights' length and the whole run's time.
fn inputs(s: &mut String, terrain: &Loaded, model: &Loaded, f: &Flights, seconds: f64) {
    let pc = &f.per_camera;
    let _ = writeln!(
        s,
        "Terrain: `{}` ({}); model: `{}` ({}). {} frames per flight, 4 cameras, {} px \
         tolerance at 1280x720. Whole demo: {seconds:.1} s.\n",
        shown(&terrain.input),
        if terrain.baked_now {
            format!("baked in {:.2} s", terrain.bake_seconds)
        } else {
            "from the bake cache".into()
        },
        shown(&model.input),
        if model.baked_now {
            format!("baked in {:.2} s", model.bake_seconds)
        } else {
            "from the bake cache".into()
        },
        pc.options.frames,
        pc.options.tolerance
    );
}

/// How the flights were flown so that the ratios compare like with like.
fn how_measured(s: &mut String, f: &Flights) {
    let pc = &f.per_camera;
    let _ = writeln!(
        s,
        "\nTimes are wall-clock on this machine, shared with whatever else runs; ratios come \
         from flights in the same run. The per-camera flights (4 cameras, 2 and 3 cameras, \
         each camera alone, 4 cameras without the index cache, 4 lean ones) are flown \
         interleaved, {SEGMENT} frames of each in turn, each with its own states, so the \
         flights compared ran under the same load; 4 cameras on one thread and on a thread \
         each fly whole flights in turn, {THREADS_ROUNDS} times (the threads' speed-up is a \
         ratio of wall times, and a segment's end would make the threads wait for the slowest \
         every {SEGMENT} frames; the rounds' ratios, in order: {}); the shared state flies on \
         its own. Each camera emits into {} index \
         lists in turn ({} frames in flight), so a camera's thread may start its next frame \
         while another camera finishes this one, up to {} frame(s) ahead of the slowest.\n",
        f.threads_rounds
            .iter()
            .map(|r| format!("{r:.2}x"))
            .collect::<Vec<_>>()
            .join(", "),
        pc.options.frames_in_flight,
        pc.options.frames_in_flight,
        pc.options.frames_in_flight.saturating_sub(1)
    );
}

/// How much of the terrain's hierarchy the system backs with huge pages.
fn huge_pages(s: &mut String, terrain: &Loaded) {
    let _ = writeln!(
        s,
        "The terrain's hierarchy ({} bytes) lies in memory of which the system backs {} with \
         huge pages, as are the flights' camera states where it grants them (transparent huge \
         pages, asked for with `madvise`; see `caveclod_io::aligned`).\n",
        terrain.bytes().len(),
        terrain.bytes().huge_page_bytes().map_or(
            "an unknown amount (not Linux)".to_string(),
            |b| format!("{:.1} MiB", b as f64 / (1u64 << 20) as f64)
        )
    );
}

/// Operations per camera per second, the CAVECLOD paper's unit.
fn paper_unit(s: &mut String, f: &Flights) {
    let pc = &f.per_camera;
    let _ = writeln!(
        s,
        "In the paper's unit, at {DISPLAY_FPS:.0} frames per second: {:.0} refinement operations \
         per camera per second with a state per camera, {:.0} with one shared state (the paper, \
         Grand Canyon at a 7% tolerance: under about 2,000 against 14,868 on average). Each \
         turn of the shared state rebuilds much of the camera's front, so its count follows \
         the front's size (the tolerance and the terrain); the ratio of the two counts is what \
         compares with the paper's.\n",
        pc.summary.ops_mean * DISPLAY_FPS,
        f.shared.summary.ops_mean * DISPLAY_FPS,
    );
}

/// The index cache's table: refinement, emission and memory with and without it, and with
/// hashed pair maps.
fn index_cache(s: &mut String, f: &Flights) {
    let pc = &f.per_camera;
    let (u, l) = (&f.uncached, &f.lean);
    let (r0, e0, r1, e1, r2, e2) = (
        refine_ms_all_cameras(pc),
        emit_ms_all_cameras(pc),
        refine_ms_all_cameras(u),
        emit_ms_all_cameras(u),
        refine_ms_all_cameras(l),
        emit_ms_all_cameras(l),
    );
    let _ = writeln!(
        s,
        "## The index cache, and cameras lean in memory\n\nThe flights above keep the index \
         cache (the library's default, `CameraConfig::index_cache`; the shared state too, \
         whose emission is not compared): the operations keep each active polygon's indices, \
         and emission copies them. The paper's cameras looked every active polygon up through \
         the hierarchy every frame instead; four cameras doing that, a state each, flew \
         interleaved with the flights above, and four more that also keep their map from \
         split to pair hashed (`CameraConfig::hashed_pair_map`), as lean in memory as the \
         library allows (per frame, medians per camera, summed over the cameras; ratios \
         against the first column):\n\n\
         | | index cache | looked up every frame | looked up, hashed pair map |\n\
         |---|---|---|---|\n\
         | refinement | {r0:.3} ms | {r1:.3} ms ({:.2}x) | {r2:.3} ms ({:.2}x) |\n\
         | emission | {e0:.3} ms | {e1:.3} ms ({:.2}x) | {e2:.3} ms ({:.2}x) |\n\
         | both | {:.3} ms | {:.3} ms ({:.2}x) | {:.3} ms ({:.2}x) |\n\
         | per-camera memory / the paper's | {:.2} ({} B) | {:.2} ({} B) | {:.2} ({} B) |\n",
        r1 / r0.max(1e-9),
        r2 / r0.max(1e-9),
        e1 / e0.max(1e-9),
        e2 / e0.max(1e-9),
        r0 + e0,
        r1 + e1,
        (r1 + e1) / (r0 + e0).max(1e-9),
        r2 + e2,
        (r2 + e2) / (r0 + e0).max(1e-9),
        pc.memory_budgeted.camera_ratio(),
        pc.memory_budgeted.camera_bytes,
        u.memory_budgeted.camera_ratio(),
        u.memory_budgeted.camera_bytes,
        l.memory_budgeted.camera_ratio(),
        l.memory_budgeted.camera_bytes,
    );
}

/// Each measured flight's own report: a state per camera, one shared state, a thread each.
fn flight_reports(s: &mut String, f: &Flights) {
    let pc = &f.per_camera;
    let _ = writeln!(
        s,
        "## Per-camera state, 4 cameras\n\n```text\n{}```\n",
        pc.human()
    );
    let _ = writeln!(
        s,
        "## One shared state, 4 cameras (the paper's baseline)\n\n```text\n{}```\n",
        f.shared.human()
    );
    let _ = writeln!(
        s,
        "## A thread per camera, 4 cameras\n\n```text\n{}```\n",
        f.threads.human()
    );
}

/// The files the demo writes besides the report.
fn figures_list(s: &mut String) {
    let _ = writeln!(
        s,
        "## Figures\n\n- `fig-operations.svg`: refinement operations per camera per frame, and per second at {DISPLAY_FPS:.0} frames per second on the right axis\n\
         - `fig-active-polygons.svg`: active polygons per camera\n\
         - `fig-memory.svg`: memory against the number of cameras\n\
         - `fig-scaling.svg`: refinement time against the number of cameras\n\
         - `flyover.csv`: every camera's every frame in every run"
    );
}
