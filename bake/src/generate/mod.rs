//! Procedural meshes, in one place for the `caveclod generate` command, the tests, the
//! benchmarks and the examples: inputs of any size without downloads.
//!
//! - [`meshes`]: small meshes in memory ([`TestMesh`]: a terrain with two surfaces and a
//!   texture seam, the same with holes, a bumpy sphere), each made an imported
//!   [`Mesh`](crate::mesh::Mesh) by [`to_mesh`].
//! - The streamed terrain ([`terrain_with`], [`write_terrain_with`]): a heightfield of tens of
//!   millions of triangles written to binary PLY one grid row at a time, smooth ([`terrain`])
//!   or with fractal detail ([`TerrainStyle`], [`noise`]) that keeps a camera busy at a
//!   pixel's tolerance.
//! - [`rng`]: the deterministic random numbers both draw from (and the tests use).

pub mod meshes;
pub mod noise;
pub mod rng;
pub mod terrain_ply;

pub use meshes::{to_mesh, TestMesh, Tri};
pub use rng::SplitMix64;
pub use terrain_ply::{
    terrain, terrain_with, write_terrain, write_terrain_with, GenerateError, TerrainGrid,
    TerrainStyle, TERRAIN_SIZE,
};
