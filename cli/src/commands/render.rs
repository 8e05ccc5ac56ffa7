//! `caveclod render`: one frame of orbiting cameras, read back and written as PNG.

use caveclod_cli::snapshot::{
    render_octree_snapshot, render_snapshot, Layout, Snapshot, SnapshotDesc,
};
use caveclod_core::{Hierarchy, Octree};
use caveclod_vulkan::{Context, HeadlessDesc};

use super::with_hierarchy;
use crate::args::RenderArgs;

/// Renders the file headless, writes the PNG files and prints what each camera drew; the
/// validation layer's messages, if any, make it fail.
pub fn render(a: &RenderArgs) -> Result<(), String> {
    with_hierarchy(&a.file, |h| {
        let octree = if a.octree { Some(octree_of(h)?) } else { None };
        check_size(a)?;
        let (snapshot, messages) = render_frame(h, octree.as_ref(), a)?;
        let written = write_images(&snapshot, a)?;
        print_stats(&snapshot, &written);
        if !messages.is_empty() {
            return Err(format!(
                "{} validation message(s):\n{}",
                messages.len(),
                messages.join("\n")
            ));
        }
        Ok(())
    })
}

/// The out-of-core bake's multiresolution octree stored in the file.
fn octree_of<'a>(h: &Hierarchy<'a>) -> Result<Octree<'a>, String> {
    match Octree::from_hierarchy(h) {
        Ok(Some(o)) => Ok(o),
        Ok(None) => {
            Err("--octree: the file has no octree (bake it with --out-of-core)".to_string())
        }
        Err(e) => Err(format!("--octree: {e}")),
    }
}

/// Rejects camera counts and image sizes the snapshot cannot draw.
fn check_size(a: &RenderArgs) -> Result<(), String> {
    if !(1..=4).contains(&a.cameras) {
        return Err(format!("--cameras {}: 1 to 4 supported", a.cameras));
    }
    if a.width < 2 || a.height < 2 {
        return Err(format!(
            "--width {} --height {}: at least 2",
            a.width, a.height
        ));
    }
    Ok(())
}

/// Draws the frame on a headless device; returns it with the validation layer's messages.
fn render_frame(
    h: &Hierarchy<'_>,
    octree: Option<&Octree<'_>>,
    a: &RenderArgs,
) -> Result<(Snapshot, Vec<String>), String> {
    let ctx = Context::headless(&HeadlessDesc {
        validation: a.validate,
        prefer_lavapipe: !a.gpu,
    })
    .map_err(|e| format!("no Vulkan device for rendering: {e}"))?;
    let desc = SnapshotDesc {
        cameras: a.cameras,
        tolerance_px: a.tolerance,
        width: a.width,
        height: a.height,
        layout: if a.separate {
            Layout::Separate
        } else {
            Layout::SplitScreen
        },
        materials_dir: Some(a.file.parent().map_or_else(
            || std::path::PathBuf::from("."),
            std::path::Path::to_path_buf,
        )),
    };
    let snapshot = match octree {
        Some(o) => render_octree_snapshot(&ctx, o, &desc),
        None => render_snapshot(&ctx, h, &desc),
    };
    let messages = ctx.take_validation_messages();
    ctx.destroy().map_err(|e| e.to_string())?;
    let snapshot = snapshot.map_err(|e| e.to_string())?;
    Ok((snapshot, messages))
}

/// Writes one PNG per camera, or the split-screen image; returns the paths written.
fn write_images(snapshot: &Snapshot, a: &RenderArgs) -> Result<Vec<String>, String> {
    std::fs::create_dir_all(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let mut written = Vec::new();
    for (i, image) in snapshot.images.iter().enumerate() {
        let name = if a.separate {
            format!("camera{i}.png")
        } else {
            format!("split{}.png", a.cameras)
        };
        let path = a.out.join(name);
        caveclod_cli::snapshot::write_png(image, &path).map_err(|e| e.to_string())?;
        written.push(path.display().to_string());
    }
    Ok(written)
}

/// Each camera's active polygons and index bytes, then the frame's totals.
fn print_stats(snapshot: &Snapshot, written: &[String]) {
    for (i, (polys, bytes)) in snapshot
        .active_polygons
        .iter()
        .zip(&snapshot.stats.camera_index_bytes)
        .enumerate()
    {
        println!("camera {i}: {polys} active polygons, {bytes} index bytes");
    }
    println!(
        "{} draws, {} index bytes in the frame; wrote {}",
        snapshot.stats.draws,
        snapshot.stats.index_bytes,
        written.join(", ")
    );
}
