//! The report of a streamed flight: a summary for people, and every frame in JSON.

use serde_json::{json, Value};

use super::fly::percentile;
use super::streamed::{StreamedFlight, StreamedFrame};

/// One per-frame count of the summary table.
type Column = fn(&StreamedFrame) -> u64;

/// Frames before the settled part of a flight (the first second fills the pool).
pub const SETTLE_FRAMES: usize = 60;
/// A settled frame keeps its deferred splits within this share of the fronts' nodes...
pub const DEFERRED_SHARE: f64 = 0.01;
/// ...and no page waited for longer than this many frames.
pub const OLDEST_WANT_FRAMES: u32 = 30;

impl StreamedFlight {
    /// Of the frames after [`SETTLE_FRAMES`], the share whose deferred splits are at most
    /// [`DEFERRED_SHARE`] of the fronts and whose oldest want is at most
    /// [`OLDEST_WANT_FRAMES`] frames old.
    pub fn settled_share(&self) -> f64 {
        let settled = self.frames.get(SETTLE_FRAMES..).unwrap_or(&[]);
        if settled.is_empty() {
            return 1.0;
        }
        let good = settled
            .iter()
            .filter(|f| {
                f64::from(f.deferred) <= DEFERRED_SHARE * f64::from(f.active_nodes.max(1))
                    && f.oldest_want <= OLDEST_WANT_FRAMES
            })
            .count();
        good as f64 / settled.len() as f64
    }

    /// Refinement p99 streamed over the baseline's (with a baseline), over the whole flight
    /// and after [`SETTLE_FRAMES`] (while the first pages arrive, a front's growth spreads
    /// over many frames, where over the whole file it is one frame's work).
    pub fn p99_ratio(&self) -> Option<(f64, f64)> {
        let b = self.baseline.as_ref()?;
        let ratio = |streamed: &[u64], whole: &[u64]| {
            percentile(streamed, 0.99) as f64 / percentile(whole, 0.99).max(1) as f64
        };
        Some((
            ratio(&self.refine_ns, &b.refine_ns),
            ratio(
                self.settled_ns(&self.refine_ns),
                self.settled_ns(&b.refine_ns),
            ),
        ))
    }

    /// The camera-frames of `ns` (frame-major) after [`SETTLE_FRAMES`].
    fn settled_ns<'n>(&self, ns: &'n [u64]) -> &'n [u64] {
        let per_frame = ns.len() / self.frames.len().max(1);
        ns.get(SETTLE_FRAMES * per_frame..).unwrap_or(&[])
    }

    fn column<T: Copy>(&self, f: impl Fn(&StreamedFrame) -> T) -> Vec<T> {
        self.frames.iter().map(f).collect()
    }

    /// Mean, p99 and largest of a per-frame count.
    fn spread(&self, f: impl Fn(&StreamedFrame) -> u64) -> (f64, u64, u64) {
        let v = self.column(f);
        let mean = v.iter().sum::<u64>() as f64 / v.len().max(1) as f64;
        (
            mean,
            percentile(&v, 0.99),
            v.iter().copied().max().unwrap_or(0),
        )
    }

    /// The report as one JSON object, with every frame.
    pub fn json(&self) -> Value {
        let frames: Vec<Value> = self
            .frames
            .iter()
            .map(|f| {
                json!({
                    "requested": f.requested, "installs": f.installs,
                    "evictions": f.evictions, "bytes_read": f.bytes_read,
                    "faults": f.faults, "resident": f.resident, "deferred": f.deferred,
                    "active_nodes": f.active_nodes, "active_polygons": f.active_polygons,
                    "oldest_want_frames": f.oldest_want, "lag_px": f.lag_px,
                    "worst_lag_px": f.worst_lag_px, "pressure": f.pressure,
                    "operations": f.operations, "refine_max_ms": f.refine_max_ms,
                })
            })
            .collect();
        json!({
            "files": self.files.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            "routes": self.names,
            "pages": self.pages.0, "root_pages": self.pages.1,
            "pool_bytes": self.pool.0, "pool_slots": self.pool.1,
            "bookkeeping_bytes": self.bookkeeping_bytes, "camera_bytes": self.camera_bytes,
            "root_bytes": self.root_bytes, "peak_rss_bytes": self.peak_rss,
            "open_to_first_frame_ms": self.open_to_first_frame.as_secs_f64() * 1e3,
            "refine_mean_ms": mean_ms(&self.refine_ns),
            "refine_p99_ms": percentile(&self.refine_ns, 0.99) as f64 / 1e6,
            "settled_refine_p99_ms": percentile(self.settled_ns(&self.refine_ns), 0.99) as f64 / 1e6,
            "settled_share": self.settled_share(),
            "pressure_mean": self.frames.iter().map(|f| f64::from(f.pressure)).sum::<f64>()
                / self.frames.len().max(1) as f64,
            "absent_reads": self.reads.absent_reads,
            "untracked_uses": self.reads.untracked_uses,
            "wants_dropped": self.reads.wants_dropped,
            "faults": self.faults,
            "baseline": self.baseline.as_ref().map(|b| json!({
                "file": b.file.display().to_string(),
                "refine_mean_ms": mean_ms(&b.refine_ns),
                "refine_p99_ms": percentile(&b.refine_ns, 0.99) as f64 / 1e6,
                "active_polygons_mean": b.active_polygons_mean,
                "settled_refine_p99_ms": percentile(self.settled_ns(&b.refine_ns), 0.99) as f64 / 1e6,
                "p99_ratio": self.p99_ratio().map(|r| r.0),
                "settled_p99_ratio": self.p99_ratio().map(|r| r.1),
            })),
            "frames": frames,
        })
    }

    /// The report for people.
    pub fn human(&self) -> String {
        let mut o = String::new();
        let mib = |b: f64| b / f64::from(1u32 << 20);
        o += &format!(
            "streamed flight: {} file(s), {} pages ({} in roots), {} camera(s) x {} frames\n",
            self.files.len(),
            self.pages.0,
            self.pages.1,
            self.names.len(),
            self.frames.len()
        );
        o += &format!(
            "pool: {:.1} MiB in {} slots; open to the first refined frame: {:.1} ms\n",
            mib(self.pool.0 as f64),
            self.pool.1,
            self.open_to_first_frame.as_secs_f64() * 1e3
        );
        o += "per frame                  mean      p99      max\n";
        let rows: [(&str, Column); 7] = [
            ("requested pages", |f| u64::from(f.requested)),
            ("installs", |f| u64::from(f.installs)),
            ("evictions", |f| u64::from(f.evictions)),
            ("KiB read", |f| f.bytes_read / 1024),
            ("deferred splits", |f| u64::from(f.deferred)),
            ("oldest want (frames)", |f| u64::from(f.oldest_want)),
            ("active polygons", |f| u64::from(f.active_polygons)),
        ];
        for (name, f) in rows {
            let (mean, p99, max) = self.spread(f);
            o += &format!("  {name:<22} {mean:>8.1} {p99:>8} {max:>8}\n");
        }
        let pressure = self.column(|f| f.pressure);
        o += &format!(
            "tolerance scale under pool pressure: {:.2} mean, {:.2} max\n",
            pressure.iter().sum::<f32>() / pressure.len().max(1) as f32,
            pressure.iter().copied().fold(1.0, f32::max)
        );
        let lag = self.column(|f| f.lag_px);
        let worst = self.column(|f| f.worst_lag_px);
        o += &format!(
            "lag: {:.1} px of excess summed over the fronts per frame on average, worst node {:.2} px\n",
            lag.iter().sum::<f32>() / lag.len().max(1) as f32,
            worst.iter().copied().fold(0.0, f32::max)
        );
        o += &format!(
            "settled frames (after {SETTLE_FRAMES}) with deferred <= {:.0}% of the front and no want over {OLDEST_WANT_FRAMES} frames: {:.1}%\n",
            DEFERRED_SHARE * 100.0,
            self.settled_share() * 100.0
        );
        o += &format!(
            "refinement per camera-frame: {:.3} ms mean, {:.3} ms p99\n",
            mean_ms(&self.refine_ns),
            percentile(&self.refine_ns, 0.99) as f64 / 1e6
        );
        if let (Some(b), Some((all, settled))) = (&self.baseline, self.p99_ratio()) {
            o += &format!(
                "refinement over the whole file {} (the same views and tolerances): {:.3} ms mean, {:.3} ms p99, {:.0} polygons per camera; streamed p99 / whole-file p99: {all:.2} (after frame {SETTLE_FRAMES}: {settled:.2})\n",
                b.file.display(),
                mean_ms(&b.refine_ns),
                percentile(&b.refine_ns, 0.99) as f64 / 1e6,
                b.active_polygons_mean,
            );
        }
        o += &format!(
            "memory: pool {:.1} MiB, bookkeeping {:.2} MiB, cameras {:.1} MiB, roots {:.2} MiB; peak RSS {}\n",
            mib(self.pool.0 as f64),
            mib(self.bookkeeping_bytes as f64),
            mib(self.camera_bytes as f64),
            mib(self.root_bytes as f64),
            self.peak_rss
                .map_or("unknown".into(), |b| format!("{:.1} MiB", mib(b as f64)))
        );
        o += &format!(
            "reads of absent pages: {}; bad pages: {}\n",
            self.reads.absent_reads,
            self.faults.len()
        );
        for f in self.faults.iter().take(10) {
            o += &format!("  {f}\n");
        }
        o
    }
}

fn mean_ms(v: &[u64]) -> f64 {
    v.iter().sum::<u64>() as f64 / v.len().max(1) as f64 / 1e6
}
