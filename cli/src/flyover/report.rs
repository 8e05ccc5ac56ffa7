//! The fly-over's report: one JSON object for scripts, a table for people.

use std::fmt::Write as _;
use std::time::Duration;

use serde_json::{json, Value};

use super::pilot::{HELD_WITHIN, SETTLING_FRAMES};
use super::{Flyover, Mode, Record, BUDGET_HEADROOM, FOV_Y_DEG, HEIGHT, SIZING_STRIDE, WIDTH};

fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1024.0 * 1024.0)
}

fn secs(d: Duration) -> f64 {
    d.as_secs_f64()
}

impl Flyover {
    /// The report as JSON, with the stable keys `cameras`, `frames`, `ops_per_camera_per_frame`
    /// (mean, max, first frame), `refine_ms_per_frame` (mean, p99), `active_polygons` (mean and
    /// max per camera), `static_bytes`, `camera_bytes`, `paper_camera_bytes` (for the camera
    /// actually flown: budgeted when sized, full otherwise), and more. Per camera of a
    /// per-camera flight on one thread: `max_jump_px` and `p99_jump_px` (popping, see
    /// `popping`), and with a polygon target `regulation` (the share of frames after the
    /// first 30 within 5% of the target, the share of them at the tolerance's floor and still
    /// short of it, the tolerance step's sign changes, the tolerance's mean, min and max).
    pub fn json(&self) -> Value {
        let s = &self.summary;
        let flown = if self.budget.is_some() {
            &self.memory_budgeted
        } else {
            &self.memory_full
        };
        let per_camera: Vec<Value> = self
            .names
            .iter()
            .zip(&self.flight.records)
            .enumerate()
            .map(|(c, (name, r))| {
                let pilot = self.pilots.get(c);
                let regulation = pilot.and_then(|p| {
                    let (mean, min, max) = p.tolerance_range();
                    Some(json!({
                        "target_polygons": p.regulator?.target(),
                        "held_share": p.held_share(r)?,
                        "out_of_reach_share": p.out_of_reach_share(r)?,
                        "sign_changes": p.sign_changes(),
                        "tolerance_mean_px": mean,
                        "tolerance_min_px": min,
                        "tolerance_max_px": max,
                    }))
                });
                json!({
                    "name": name,
                    "ops_mean": r.ops_mean(),
                    "ops_max": r.ops_max(),
                    "first_frame_ops": r.ops.first().copied().unwrap_or(0),
                    "refine_ms_mean": r.refine_ms_mean(),
                    "refine_ms_p99": r.refine_ms_p99(),
                    "refine_cpu_ms_p99": r.refine_cpu_ms_p99(),
                    "emit_ms_mean": r.emit_ms_mean(),
                    "index_edits": (!r.edits.is_empty()).then(|| json!({
                        "ms_mean": r.edits_ms_mean(),
                        "edits_mean": r.edits_mean(),
                        "bytes_per_changed_polygon": r.edit_bytes_per_change(),
                        "frames_rewriting_everything": r.edits_everything,
                    })),
                    "active_polygons_mean": r.active_mean(),
                    "active_polygons_max": r.active_max(),
                    "indices_total": r.indices_total(),
                    "morphs_started": r.morphs_started,
                    "morphs_dropped": r.morphs_dropped,
                    "max_morphing": pilot.map(|p| p.max_morphing),
                    "max_jump_px": pilot.map(|p| p.meter.max_px()),
                    "p99_jump_px": pilot.map(|p| p.meter.p99_px()),
                    "surface_max_jump_px": pilot.map(|p| p.meter.surface_max_px()),
                    "surface_p99_jump_px": pilot.map(|p| p.meter.surface_p99_px()),
                    "moved_vertices": pilot.map(|p| p.meter.jumps.len()),
                    "regulation": regulation,
                })
            })
            .collect();
        json!({
            "mode": self.options.mode.name(),
            "cameras": self.options.cameras,
            "frames": self.options.frames,
            "tolerance_px": self.options.tolerance,
            // The shared state emits each camera's turn into one list.
            "frames_in_flight": (self.options.mode != Mode::Shared)
                .then_some(self.options.frames_in_flight),
            "index_cache": self.options.index_cache,
            "hashed_pair_map": self.options.hashed_pair_map,
            "pinned": (self.options.mode == Mode::Threads).then_some(self.options.pin_threads),
            "geomorphs": self.morphing(),
            "max_morphs": self.morphing().then_some(self.max_morphs),
            "target_polygons": self.options.target_polygons,
            "ops_per_camera_per_frame": {
                "mean": s.ops_mean, "max": s.ops_max, "first_frame": s.first_frame_ops
            },
            "refine_ms_per_frame": { "mean": s.refine_ms_mean, "p99": s.refine_ms_p99 },
            "emit_ms_per_frame": s.emit_ms_mean,
            "active_polygons": { "mean": s.active_mean, "max": s.active_max },
            "capacity_refusals": s.refusals,
            "static_bytes": flown.static_bytes,
            "paper_static_bytes": flown.paper_static_bytes,
            "camera_bytes": flown.camera_bytes,
            "morph_bytes": self.flight.morph_bytes,
            "paper_camera_bytes": flown.paper_camera_bytes,
            "camera_ratio": flown.camera_ratio(),
            "camera_bytes_full": self.memory_full.camera_bytes,
            "camera_ratio_full": self.memory_full.camera_ratio(),
            "budget_polygons": self.budget_polygons,
            "budgeted_flown": self.budget.is_some(),
            "flight_s": secs(self.flight.wall),
            "sizing_s": self.sizing.as_ref().map(|f| secs(f.wall)),
            "per_camera": per_camera,
            "budget": self.budget_json(),
        })
    }

    /// How refinement and compaction were bounded, and how far the fronts lagged their views
    /// for it: per frame, the share of active nodes whose error projects over the tolerance
    /// (nodes a full pass would split; measured outside the timed work) and their excess in
    /// pixels per active node, over all cameras' frames after the first.
    fn budget_json(&self) -> Value {
        let o = &self.options;
        let lag = Lag::of(&self.flight.records);
        json!({
            "visit_fraction": o.visit_fraction,
            "compact_every": o.compact_every,
            "compact_step": o.compact_step,
            "lag_share": { "mean": lag.share_mean, "p99": lag.share_p99 },
            "lag_px_per_node_mean": lag.px_mean,
            "lag_worst_px": lag.worst_px,
            "per_camera_lag_share": self.flight.records.iter().map(Record::lag_share_mean)
                .collect::<Vec<_>>(),
        })
    }

    /// The budget line of the report for people.
    fn human_budget(&self, o: &mut String) {
        let lag = Lag::of(&self.flight.records);
        let compaction = match (self.options.compact_every, self.options.compact_step) {
            (0, _) => "never".to_string(),
            (every, 0) => format!("whole every {every} frames"),
            (every, step) => format!("a cycle every {every} frames, up to {step} work per frame"),
        };
        let _ = writeln!(
            o,
            "budget: refinement visits {:.0}% of the active list per frame; compaction {};              fronts over the tolerance: {:.2}% of active nodes mean, {:.2}% p99, {:.4} px              excess per active node, worst node {:.2} px",
            100.0 * self.options.visit_fraction,
            compaction,
            100.0 * lag.share_mean,
            100.0 * lag.share_p99,
            lag.px_mean,
            lag.worst_px
        );
    }

    /// The report for people: the set-up, the sizing flight, a table of the cameras and the
    /// memory against the paper's.
    pub fn human(&self) -> String {
        let mut o = String::new();
        self.human_setup(&mut o);
        self.human_cameras(&mut o);
        self.human_budget(&mut o);
        self.human_smoothness(&mut o);
        self.human_memory(&mut o);
        o
    }

    /// Whether the flight's cameras geomorph.
    pub fn morphing(&self) -> bool {
        self.options.geomorphs && self.options.mode != Mode::Shared
    }

    /// Per camera: popping, morphs and, with a polygon target, the regulation.
    fn human_smoothness(&self, o: &mut String) {
        if self.pilots.is_empty() {
            return;
        }
        let _ = writeln!(
            o,
            "popping (on-screen move per frame of each vertex refinement moves, in view and \
             facing the eye; surface: its part along the vertex normal; {}):",
            if self.morphing() {
                format!("geomorphs, up to {} per camera", self.max_morphs)
            } else {
                "no geomorphs".to_string()
            }
        );
        let _ = writeln!(
            o,
            "  {:<14} {:>10} {:>10} {:>10} {:>10} {:>9} {:>9} {:>8} {:>9}",
            "camera",
            "max-jump",
            "p99-jump",
            "max-surf",
            "p99-surf",
            "moved",
            "morphs",
            "dropped",
            "max-live"
        );
        for (name, (r, p)) in self
            .names
            .iter()
            .zip(self.flight.records.iter().zip(&self.pilots))
        {
            let _ = writeln!(
                o,
                "  {:<14} {:>7.3} px {:>7.3} px {:>7.3} px {:>7.3} px {:>9} {:>9} {:>8} {:>9}",
                name,
                p.meter.max_px(),
                p.meter.p99_px(),
                p.meter.surface_max_px(),
                p.meter.surface_p99_px(),
                p.meter.jumps.len(),
                r.morphs_started,
                r.morphs_dropped,
                p.max_morphing
            );
        }
        let Some(target) = self.options.target_polygons else {
            return;
        };
        let _ = writeln!(
            o,
            "regulation to {target} polygons (frames after the first {SETTLING_FRAMES} within \
             {:.0}%; out of reach: at the tolerance's floor and still short of the target; \
             sign changes of the tolerance's step):",
            HELD_WITHIN * 100.0
        );
        for (name, (r, p)) in self
            .names
            .iter()
            .zip(self.flight.records.iter().zip(&self.pilots))
        {
            let (mean, min, max) = p.tolerance_range();
            let _ = writeln!(
                o,
                "  {:<14} held {:>5.1}%  out of reach {:>5.1}%  sign changes {:>3}  tolerance \
                 {:.3} px mean ({:.3}..{:.3})",
                name,
                100.0 * p.held_share(r).unwrap_or(0.0),
                100.0 * p.out_of_reach_share(r).unwrap_or(0.0),
                p.sign_changes(),
                mean,
                min,
                max
            );
        }
    }

    /// How the cameras fly: their count, the tolerance, the mode and the sizing flight.
    fn human_setup(&self, o: &mut String) {
        let _ = writeln!(
            o,
            "{} camera(s), {} frames, tolerance {} px at {WIDTH}x{HEIGHT}, fov {FOV_Y_DEG} deg; \
             mode: {}",
            self.options.cameras,
            self.options.frames,
            self.options.tolerance,
            self.mode_description()
        );
        if let (Some(sz), Some(b)) = (&self.sizing, self.budget) {
            let _ = writeln!(
                o,
                "sizing flight (full-capacity cameras, refine only, every {SIZING_STRIDE}rd \
                 frame): {:.2} s -> budget {b} polygons (+{:.0}%)",
                secs(sz.wall),
                (BUDGET_HEADROOM - 1.0) * 100.0
            );
        }
    }

    /// The mode in words, with the emission and pair-map options that differ from the default.
    fn mode_description(&self) -> String {
        let mut mode = match self.options.mode {
            Mode::Shared => {
                "one shared state re-refined for each camera in turn (baseline)".to_string()
            }
            Mode::Threads => format!(
                "a state per camera, one thread per camera{}, {} frame(s) in flight",
                if self.options.pin_threads {
                    " (pinned, cores balanced)"
                } else {
                    ""
                },
                self.options.frames_in_flight
            ),
            Mode::PerCamera => format!(
                "a state per camera, one thread, {} frame(s) in flight",
                self.options.frames_in_flight
            ),
        };
        if !self.options.index_cache {
            mode += ", no index cache (every polygon looked up every frame)";
        }
        if self.options.hashed_pair_map {
            mode += ", hashed pair map";
        }
        mode
    }

    /// The flight's time and a row per camera (operations, times, fronts), then all cameras'.
    fn human_cameras(&self, o: &mut String) {
        let s = &self.summary;
        let _ = writeln!(
            o,
            "flight: {:.2} s for {} camera-frames (ops = splits + collapses; per-frame figures \
             leave out frame 0, which refines from the base mesh)",
            secs(self.flight.wall),
            self.options.cameras * self.options.frames
        );
        let _ = writeln!(
            o,
            "  {:<14} {:>9} {:>7} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>8}",
            "camera",
            "first-op",
            "ops/f",
            "max-ops/f",
            "refine",
            "p99",
            "emit",
            "active",
            "max-act",
            "refused"
        );
        for (name, r) in self.names.iter().zip(&self.flight.records) {
            let _ = writeln!(
                o,
                "  {:<14} {:>9} {:>7.1} {:>9} {:>6.3} ms {:>6.3} ms {:>6.3} ms {:>9.0} {:>9} {:>8}",
                name,
                r.ops.first().copied().unwrap_or(0),
                r.ops_mean(),
                r.ops_max(),
                r.refine_ms_mean(),
                r.refine_ms_p99(),
                r.emit_ms_mean(),
                r.active_mean(),
                r.active_max(),
                r.refusals,
            );
        }
        for (name, r) in self.names.iter().zip(&self.flight.records) {
            if r.edits.is_empty() {
                continue;
            }
            let _ = writeln!(
                o,
                "  {:<14} index edits: {:.3} ms mean against emission's {:.3} ms, {:.0} edits a \
                 frame, {:.1} bytes per changed polygon, {} frames rewrote every place",
                name,
                r.edits_ms_mean(),
                r.emit_ms_mean(),
                r.edits_mean(),
                r.edit_bytes_per_change(),
                r.edits_everything,
            );
        }
        let _ = writeln!(
            o,
            "  all cameras: {:.1} ops/frame/camera (max {}), refine {:.3} ms mean, {:.3} ms p99, \
             emit {:.3} ms mean, {:.0} active polygons mean, {} capacity refusals",
            s.ops_mean,
            s.ops_max,
            s.refine_ms_mean,
            s.refine_ms_p99,
            s.emit_ms_mean,
            s.active_mean,
            s.refusals
        );
    }

    /// Static and per-camera memory, ours against the paper's equation.
    fn human_memory(&self, o: &mut String) {
        let s = &self.summary;
        let (f, b) = (&self.memory_full, &self.memory_budgeted);
        let _ = writeln!(
            o,
            "memory (paper: b = 44n + 12p + 32d + 2se + 12n_a + 36p_a + c(4n + 4p + 16), with \
             n_a, p_a the largest front of one camera: {} nodes, {} polygons)",
            s.max_active_nodes, s.active_max
        );
        let _ = writeln!(
            o,
            "  static:               ours {:>10} B ({:6.2} MiB)  paper {:>10} B ({:6.2} MiB)  \
             ratio {:.2}  (vertex table {:.1}% filled)",
            f.static_bytes,
            mib(f.static_bytes),
            f.paper_static_bytes,
            mib(f.paper_static_bytes),
            f.static_bytes as f64 / f.paper_static_bytes.max(1) as f64,
            100.0 * self.vertex_table_fill.1 as f64 / self.vertex_table_fill.0.max(1) as f64
        );
        let _ = writeln!(
            o,
            "  per camera, full:     ours {:>10} B ({:6.2} MiB)  paper {:>10} B ({:6.2} MiB)  \
             ratio {:.2}",
            f.camera_bytes,
            mib(f.camera_bytes),
            f.paper_camera_bytes,
            mib(f.paper_camera_bytes),
            f.camera_ratio()
        );
        let _ = writeln!(
            o,
            "  per camera, budgeted: ours {:>10} B ({:6.2} MiB)  paper {:>10} B ({:6.2} MiB)  \
             ratio {:.2}  ({} polygons{})",
            b.camera_bytes,
            mib(b.camera_bytes),
            b.paper_camera_bytes,
            mib(b.paper_camera_bytes),
            b.camera_ratio(),
            self.budget_polygons,
            if self.budget.is_some() {
                ", flown"
            } else {
                ", computed, not flown"
            }
        );
    }
}

/// How far a flight's fronts lagged their views, over all cameras' frames after the first.
struct Lag {
    share_mean: f64,
    share_p99: f64,
    px_mean: f64,
    worst_px: f64,
}

impl Lag {
    fn of(records: &[Record]) -> Self {
        let mut shares: Vec<f64> = records
            .iter()
            .flat_map(|r| Record::steady(&r.lag_share).iter().map(|&x| f64::from(x)))
            .collect();
        shares.sort_by(f64::total_cmp);
        let p99 = shares
            .get(((shares.len() as f64 * 0.99).ceil() as usize).saturating_sub(1))
            .copied()
            .unwrap_or(0.0);
        let n = records.len().max(1) as f64;
        Self {
            share_mean: records.iter().map(Record::lag_share_mean).sum::<f64>() / n,
            share_p99: p99,
            px_mean: records.iter().map(Record::lag_px_mean).sum::<f64>() / n,
            worst_px: records
                .iter()
                .map(|r| f64::from(r.lag_worst_px))
                .fold(0.0, f64::max),
        }
    }
}
