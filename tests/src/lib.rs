//! Test support for caveclod: generated meshes and a small, test-only hierarchy builder.
//!
//! The builder here exists so that the core runtime can be tested, benchmarked and
//! demonstrated before (and independently of) `caveclod-bake`. It is deliberately simple:
//! shortest-edge half-edge collapses in passes of independent sets, a crude error bound, no
//! attribute-aware quadrics. It is not the product's builder and is not published.

pub mod builder;
pub mod check;
pub mod meshes;

pub use builder::{build, AlignedBytes, Built};
pub use meshes::{TestMesh, Tri};
