//! One function per subcommand; [`run`] picks the one the command line names.

mod bake;
mod demo;
mod export;
mod flyover;
mod generate;
mod info;
mod info_paged;
mod load;
mod page;
mod progress;
mod refine;
mod render;

use crate::args::{Cli, Command};

/// Runs the command the command line names.
pub fn run(cli: Cli) -> Result<(), String> {
    match cli.command {
        Command::Bake(a) => bake::bake(&a),
        Command::Demo(a) => demo::demo(a),
        Command::Flyover(a) => flyover::flyover(a),
        Command::Info(a) => info::info(&a),
        Command::Generate(a) => generate::generate(&a),
        Command::Page(a) => page::page(&a),
        Command::Export(a) => export::export(&a),
        Command::Render(a) => render::render(&a),
        Command::Refine(a) => refine::refine(&a),
    }
}
