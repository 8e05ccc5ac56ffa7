//! `caveclod generate`: a procedural terrain as binary PLY, streamed to disk.

use caveclod_bake::generate::{terrain_with, TerrainStyle};

use crate::outputs;

use super::progress::progress_bar;
use crate::args::GenerateArgs;

/// Writes the terrain with a progress bar and prints its size.
pub fn generate(a: &GenerateArgs) -> Result<(), String> {
    outputs::check_file_output(&a.output, &["ply"], "binary PLY", &[])?;
    let bar = progress_bar("{spinner} writing [{bar:30}] {percent}% ({elapsed})")?;
    let style = TerrainStyle {
        roughness: a.roughness,
        seed: a.seed,
    };
    let grid = terrain_with(&a.output, a.triangles, style, &mut |done, total| {
        bar.set_length(total);
        bar.set_position(done);
    });
    bar.finish_and_clear();
    let grid = grid.map_err(|e| e.to_string())?;
    println!(
        "generated {}: terrain {}x{} quads, {} vertices, {} triangles, roughness {} (seed {})",
        a.output.display(),
        grid.columns,
        grid.rows,
        grid.vertices(),
        grid.triangles(),
        a.roughness,
        a.seed
    );
    Ok(())
}
