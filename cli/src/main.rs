//! `caveclod`: bake meshes into view-dependent hierarchies, inspect and export them.

mod args;
mod commands;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    match commands::run(args::Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("caveclod: error: {e}");
            ExitCode::FAILURE
        }
    }
}
