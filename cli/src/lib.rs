//! # caveclod-cli
//!
//! The application around the caveclod libraries: the `caveclod` binary's commands, the demo
//! ([`demo`]), the CAVECLOD fly-over experiment ([`flyover`]), headless snapshots
//! ([`snapshot`]), the `info` report ([`info`]) and the huge-page buffers ([`aligned`]), the memory-mapped `.clod`
//! reader ([`mapped`]) and the checks every command makes on its outputs before any work ([`outputs`]).

pub mod aligned;
pub mod demo;
pub mod flyover;
pub mod info;
pub mod mapped;
pub mod materials;
pub mod outputs;
pub mod snapshot;
