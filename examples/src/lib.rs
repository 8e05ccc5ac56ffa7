//! Runnable examples of caveclod live in `examples/`.
