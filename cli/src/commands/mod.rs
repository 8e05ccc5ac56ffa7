//! One function per subcommand; [`run`] picks the one the command line names.

mod bake;
mod demo;
mod export;
mod flyover;
mod generate;
mod info;
mod progress;
mod refine;
mod render;

use std::path::Path;

use caveclod_cli::mapped::ClodBytes;
use caveclod_core::Hierarchy;
use indicatif::{ProgressBar, ProgressStyle};

use crate::args::{Cli, Command};

/// Runs the command the command line names.
pub fn run(cli: Cli) -> Result<(), String> {
    match cli.command {
        Command::Bake(a) => bake::bake(&a),
        Command::Demo(a) => demo::demo(a),
        Command::Flyover(a) => flyover::flyover(a),
        Command::Info(a) => info::info(&a),
        Command::Generate(a) => generate::generate(&a),
        Command::Export(a) => export::export(&a),
        Command::Render(a) => render::render(&a),
        Command::Refine(a) => refine::refine(&a),
    }
}

/// Maps a .clod file and hands its validated hierarchy, borrowing the mapped bytes, to `f`.
fn with_hierarchy<T>(
    path: &Path,
    f: impl FnOnce(&Hierarchy<'_>) -> Result<T, String>,
) -> Result<T, String> {
    // Page aligned: no record straddles two cache lines.
    let file = ClodBytes::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let h = file
        .hierarchy()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    f(&h)
}

/// A progress bar drawn with `template`.
fn progress_bar(template: &str) -> Result<ProgressBar, String> {
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template(template)
            .map_err(|e| e.to_string())?
            .progress_chars("=> "),
    );
    Ok(bar)
}
