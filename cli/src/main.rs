//! `caveclod`: bake meshes into view-dependent hierarchies, inspect and export them.

mod args;
mod commands;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    end_quietly_on_closed_output();
    match commands::run(args::Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("caveclod: error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// A reader that closes the output early (`caveclod info FILE | head`) ends the process
/// quietly, as it ends other Unix tools, instead of a panic in the first print after it.
#[cfg(unix)]
fn end_quietly_on_closed_output() {
    // SAFETY: called first in `main`, before any thread is started, so no other thread reads
    // or changes signal dispositions meanwhile; `SIG_DFL` is a valid disposition for
    // `SIGPIPE`, and the Rust runtime's only use of it was setting it to be ignored.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[cfg(not(unix))]
fn end_quietly_on_closed_output() {}
