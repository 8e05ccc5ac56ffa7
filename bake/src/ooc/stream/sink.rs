//! Where a streaming reader puts the soup ([`SoupSink`]), and what it reports besides
//! ([`StreamReport`]).

use crate::mesh::Surface;
use crate::ooc::error::OocError;
use crate::ooc::soup::{Cube, SoupTriangle};

/// Receives the soup as a reader produces it.
pub trait SoupSink {
    /// Called once, before the first triangle: the input's bounding cube and its triangle
    /// count as far as the header tells (0 when unknown).
    fn start(&mut self, cube: &Cube, triangles_hint: u64) -> Result<(), OocError>;
    /// Room for one more triangle, which the caller fills in completely (its key too):
    /// readers build triangles in place, with no copy of the record on the way.
    fn slot(&mut self) -> Result<&mut SoupTriangle, OocError>;
    /// Whether the sink reads only the triangles' positions and keys: readers may then leave
    /// the other attributes out (zero).
    fn positions_only(&self) -> bool {
        false
    }
    /// One triangle (its key already set).
    fn push(&mut self, t: &SoupTriangle) -> Result<(), OocError> {
        *self.slot()? = *t;
        Ok(())
    }
}

/// What a reader found besides the triangles.
#[derive(Clone, Debug, Default)]
pub struct StreamReport {
    /// Surfaces, indexed by [`SoupTriangle::surface`].
    pub surfaces: Vec<Surface>,
    /// Triangles produced.
    pub triangles: u64,
    /// Vertices read.
    pub vertices: u64,
    /// Faces with fewer than three corners, skipped.
    pub skipped_faces: u64,
}
