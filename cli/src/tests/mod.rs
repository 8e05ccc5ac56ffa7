//! Tests of the application's modules that need generated meshes baked in memory (the
//! binary's integration tests in `cli/tests` run the built binary instead).

mod demo_render;
mod flyover;
mod popping;
