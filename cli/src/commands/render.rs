//! `caveclod render`: one frame of orbiting cameras, read back and written as PNG.

use caveclod_core::format::materials::TextureRef;
use caveclod_core::{Hierarchy, Octree};
use caveclod_host::write_png;
use caveclod_vulkan::{Context, HeadlessDesc};

use super::load::with_hierarchy;
use crate::args::RenderArgs;
use crate::outputs;
use crate::snapshot::{render_octree_snapshot, render_snapshot, Layout, Snapshot, SnapshotDesc};

/// Renders the file headless, writes the PNG files and prints what each camera drew; the
/// validation layer's messages, if any, make it fail.
pub fn render(a: &RenderArgs) -> Result<(), String> {
    with_hierarchy(&a.file, |h| {
        let octree = if a.octree { Some(octree_of(h)?) } else { None };
        check_size(a)?;
        check_out(h, a)?;
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

/// The PNG files' names, one per camera or the split-screen image.
fn image_names(a: &RenderArgs) -> Vec<String> {
    if a.separate {
        (0..a.cameras).map(|i| format!("camera{i}.png")).collect()
    } else {
        vec![format!("split{}.png", a.cameras)]
    }
}

/// The output directory made and probed before rendering; no image may replace the file or a
/// texture it names.
fn check_out(h: &Hierarchy<'_>, a: &RenderArgs) -> Result<(), String> {
    let dir = a.file.parent().unwrap_or(std::path::Path::new(""));
    let textures: Vec<std::path::PathBuf> = h
        .materials()
        .map(|ms| {
            ms.iter()
                .filter_map(|m| match m.texture {
                    Some(TextureRef::Path(p)) => Some(dir.join(p)),
                    _ => None,
                })
                .collect()
        })
        .unwrap_or_default();
    let mut inputs: Vec<&std::path::Path> = vec![&a.file];
    inputs.extend(textures.iter().map(std::path::PathBuf::as_path));
    let names = image_names(a);
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    outputs::prepare_output_dir(&a.out, &names, &inputs)
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
        synchronization_validation: false,
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
    let mut written = Vec::new();
    for (image, name) in snapshot.images.iter().zip(image_names(a)) {
        let path = a.out.join(name);
        write_png(image, &path).map_err(|e| e.to_string())?;
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
