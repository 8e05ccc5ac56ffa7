//! `caveclod refine`: one camera refined to rest over a file, its indices emitted, the
//! counts printed. The same views and output as the C example `capi/examples/refine.c`, so
//! `cargo xtask test` can compare the C interface with the Rust one.

use caveclod_core::glam::Vec3;
use caveclod_core::{CameraState, LookAt, RefineParams};

use super::load::with_hierarchy;
use crate::args::RefineArgs;

/// The viewport of the comparison, in pixels.
const WIDTH: u32 = 1280;
const HEIGHT: u32 = 720;
/// At most this many passes; refinement settles in a few.
const MAX_PASSES: u32 = 1000;

/// Refines a full camera until a pass changes nothing, emits its indices and prints
/// `active_polygons`, `indices` and `surfaces`.
pub fn refine(a: &RefineArgs) -> Result<(), String> {
    with_hierarchy(&a.file, |h| {
        let mut memory = vec![0u32; CameraState::words_needed(h)];
        let mut cam = CameraState::new(h, &mut memory).map_err(|e| e.to_string())?;
        let look = LookAt {
            eye: Vec3::from_array(a.eye),
            target: Vec3::from_array(a.target),
            up: Vec3::Y,
            fov_y: core::f32::consts::FRAC_PI_3,
            near: 0.1,
            far: 1e5,
        };
        let view = look.view(WIDTH, HEIGHT);
        let params = RefineParams::default();
        let mut passes = 0;
        loop {
            let stats = cam.refine(h, &view, &params).map_err(|e| e.to_string())?;
            passes += 1;
            if stats.operations() == 0 || passes == MAX_PASSES {
                break;
            }
        }
        let mut indices = vec![0u32; cam.total_index_count()];
        let mut offsets = vec![0u32; h.surface_count() + 1];
        let n = cam
            .emit_indices_packed(h, &mut indices, &mut offsets)
            .map_err(|e| e.to_string())?;
        let (polygons, surfaces) = (cam.active_polygon_count(), h.surface_count());
        if a.json {
            println!(
                "{{\"active_polygons\": {polygons}, \"indices\": {n}, \"surfaces\": {surfaces}}}"
            );
        } else {
            println!(
                "{}: {polygons} active polygons, {n} indices over {surfaces} surfaces after \
                 {passes} passes",
                a.file.display()
            );
        }
        Ok(())
    })
}
