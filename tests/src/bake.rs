//! Generated test meshes baked by `caveclod-bake`, the product's builder, in memory.
//!
//! The tests, examples and benchmarks of the runtime use exactly the hierarchies users get
//! from `caveclod bake`: no second, test-only builder whose behaviour could drift from it.

use caveclod_bake::baked::Baked;
use caveclod_bake::generate::{to_mesh, TestMesh};
use caveclod_bake::pipeline::bake_mesh;
use caveclod_core::Hierarchy;
use caveclod_io::AlignedBytes;

/// A baked test mesh; dereferences to the baker's arrays.
#[derive(Clone, Debug)]
pub struct BakedMesh(pub Baked);

impl std::ops::Deref for BakedMesh {
    type Target = Baked;
    fn deref(&self) -> &Baked {
        &self.0
    }
}

impl BakedMesh {
    /// The validated hierarchy.
    ///
    /// # Panics
    /// If the baker produced an invalid hierarchy (a baker bug, which the test reports).
    pub fn hierarchy(&self) -> Hierarchy<'_> {
        match self.0.hierarchy() {
            Ok(h) => h,
            Err(e) => panic!("the baker produced an invalid hierarchy: {e}"),
        }
    }

    /// The `.clod` file in aligned storage.
    ///
    /// # Panics
    /// If the baker produced an invalid hierarchy.
    pub fn to_bytes(&self) -> AlignedBytes {
        match self.0.to_bytes(&[]) {
            Ok(bytes) => AlignedBytes::from_slice(&bytes),
            Err(e) => panic!("the baker produced an invalid hierarchy: {e}"),
        }
    }
}

/// Bakes a test mesh with the default options, as `caveclod bake` would.
///
/// # Panics
/// If the bake fails (generated meshes are valid input, so that is a baker bug).
pub fn bake(t: &TestMesh) -> BakedMesh {
    match bake_mesh(&to_mesh(t), "test mesh", &mut |_| {}) {
        Ok((baked, _)) => BakedMesh(baked),
        Err(e) => panic!("baking a generated mesh failed: {e}"),
    }
}
