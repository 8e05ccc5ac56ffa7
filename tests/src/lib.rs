//! Test support for caveclod: generated meshes, baked in memory by `caveclod-bake`, and
//! checks of a camera's front against a from-scratch derivation, and the runtime's soak
//! ([`soak`]).

pub mod aligned;
pub mod bake;
pub mod check;
pub mod generate;
pub mod meshes;
pub mod parts;
pub mod rng;
pub mod shared_data;
pub mod soak;

pub use bake::{bake, to_mesh, AlignedBytes, BakedMesh};
pub use meshes::{TestMesh, Tri};
