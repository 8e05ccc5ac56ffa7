//! The streamed flight's baseline: the same views flown over the whole-file form of the same
//! terrain, each frame at the tolerance the streamed flight refined with (its pressure
//! replayed), with cameras of the same budget and morph memory. Refinement times then
//! compare streaming with its absence at the same quality, in the same run.

use std::path::{Path, PathBuf};
use std::time::Instant;

use caveclod_core::format::paged::PagedRoot;
use caveclod_core::{CameraConfig, CameraState, RefineParams, View};
use caveclod_io::ClodFile;

/// What the baseline flight measured.
#[derive(Clone, Debug)]
pub struct Baseline {
    /// The whole file flown.
    pub file: PathBuf,
    /// Refinement time per camera-frame, in nanoseconds.
    pub refine_ns: Vec<u64>,
    /// Active polygons per camera and frame, on average.
    pub active_polygons_mean: f64,
}

/// The cameras' set-up, shared with the streamed flight.
pub struct BaselineFlight<'a> {
    /// The streamed file's root, to check the whole file is the same terrain.
    pub root: &'a PagedRoot<'a>,
    /// Each camera's views, one per frame.
    pub views: &'a [Vec<View>],
    /// The flight's parameters before pressure.
    pub params: &'a RefineParams,
    /// The scale pressure put on the tolerance, per frame.
    pub scales: &'a [f32],
    /// Each camera's polygon budget and morph memory.
    pub camera_polygons: u32,
    pub morphs: u32,
}

impl BaselineFlight<'_> {
    /// Flies the views over the whole file at `path`.
    pub fn fly(&self, path: &Path) -> Result<Baseline, String> {
        let file = ClodFile::open(path).map_err(|e| e.to_string())?;
        let h = file.hierarchy().map_err(|e| e.to_string())?;
        let (a, b) = (h.meta(), self.root.meta());
        if (a.bounds_min, a.bounds_max) != (b.bounds_min, b.bounds_max) {
            return Err(format!(
                "--baseline {}: not the paged file's terrain (its bounds differ)",
                path.display()
            ));
        }
        let config =
            CameraConfig::with_polygon_budget(&h, self.camera_polygons).with_morphs(self.morphs);
        let words = CameraState::words_needed_for(&h, &config);
        let mut memories: Vec<Vec<u32>> = self.views.iter().map(|_| vec![0u32; words]).collect();
        let mut cameras = memories
            .iter_mut()
            .map(|m| CameraState::with_config(&h, m, &config).map_err(|e| e.to_string()))
            .collect::<Result<Vec<_>, _>>()?;
        let mut refine_ns = Vec::with_capacity(self.scales.len() * cameras.len());
        let mut polygons = 0u64;
        for (f, scale) in self.scales.iter().enumerate() {
            let params = RefineParams {
                tolerance_px: self.params.tolerance_px * scale,
                ..*self.params
            };
            for (cam, views) in cameras.iter_mut().zip(self.views) {
                let t = Instant::now();
                let st = cam
                    .refine(&h, &views[f], &params)
                    .map_err(|e| format!("baseline frame {f}: {e}"))?;
                refine_ns.push(t.elapsed().as_nanos() as u64);
                polygons += u64::from(st.active_polygons);
            }
        }
        Ok(Baseline {
            file: path.to_path_buf(),
            active_polygons_mean: polygons as f64 / refine_ns.len().max(1) as f64,
            refine_ns,
        })
    }
}
