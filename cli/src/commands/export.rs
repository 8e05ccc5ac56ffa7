//! `caveclod export`: one level of a .clod file as Wavefront OBJ, with its materials as an
//! MTL file beside it and its embedded textures as image files beside that.

use caveclod_bake::export::{obj_export, Level};

use crate::outputs;

use super::load::with_hierarchy;
use crate::args::{ExportArgs, LevelArg};

/// Writes the chosen level as OBJ (and its MTL and images), each file replaced only once
/// complete and none over an input.
pub fn export(a: &ExportArgs) -> Result<(), String> {
    outputs::check_file_output(&a.output, &["obj"], "Wavefront OBJ", &[&a.file])?;
    with_hierarchy(&a.file, |h| {
        let level = match a.level {
            LevelArg::Full => Level::Full,
            LevelArg::Base => Level::Base,
        };
        let files = obj_export(h, level, &a.file, &a.output).map_err(|e| e.to_string())?;
        files.write().map_err(|e| e.to_string())
    })
}
