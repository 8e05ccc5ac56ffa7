//! Test support for caveclod: generated meshes (caveclod-bake's [`generate`] module, under the
//! names the tests use) baked in memory by `caveclod-bake`, checks of a camera's front against
//! a from-scratch derivation, and the runtime's soak ([`soak`]).

pub mod bake;
pub mod check;
pub mod paged;
pub mod parts;
pub mod shared_data;
pub mod soak;

pub use bake::{bake, BakedMesh};
pub use caveclod_bake::generate;
pub use caveclod_bake::generate::{meshes, rng, to_mesh, TestMesh, Tri};
pub use caveclod_io::AlignedBytes;
