//! `caveclod`: bake meshes into view-dependent hierarchies, inspect and export them.
//!
//! The application around the caveclod libraries: the commands ([`commands`], their
//! arguments in [`args`]), the demo ([`demo`]), the CAVECLOD fly-over experiment
//! ([`flyover`]), headless snapshots ([`snapshot`]), the `info` report ([`info`]) and the
//! checks every command makes on its outputs before any work ([`outputs`]). Loading `.clod`
//! files is caveclod-io's, generated meshes are caveclod-bake's, and the Vulkan host's
//! pieces (materials, palette, PNG files) are caveclod-host's.

mod args;
mod commands;
mod demo;
mod flyover;
mod info;
mod outputs;
mod snapshot;
#[cfg(test)]
mod tests;

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
