//! Criterion benchmarks of caveclod live in `benches/`.
