//! What a bake tells its caller as it goes: the stage it is in, handed to the progress
//! callback every bake entry point takes (`&mut dyn FnMut(Stage)`).

/// Stages of a bake, for progress reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Reading the input.
    Import,
    /// Welding and grouping.
    Weld,
    /// Collapsing: `(done, at most)`.
    Collapse(u64, u64),
    /// Assembling the arrays.
    Assemble,
}
