//! `caveclod export`: one level of a .clod file as Wavefront OBJ.

use caveclod_bake::baked::write_atomically;
use caveclod_bake::export::{self, Level};

use super::with_hierarchy;
use crate::args::{ExportArgs, LevelArg};

/// Writes the chosen level as OBJ, replacing the output only once complete.
pub fn export(a: &ExportArgs) -> Result<(), String> {
    with_hierarchy(&a.file, |h| {
        let level = match a.level {
            LevelArg::Full => Level::Full,
            LevelArg::Base => Level::Base,
        };
        let text = export::obj(h, level);
        write_atomically(&a.output, text.as_bytes()).map_err(|e| e.to_string())
    })
}
