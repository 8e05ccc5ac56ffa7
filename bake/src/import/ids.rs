//! The id ranges an imported mesh stays within: a surface id per triangle (`u16`), a `u32`
//! index per element, short of [`NO_ATTRIBUTE`].

use super::error::{ImportError, Source};
use crate::mesh::{Mesh, Surface, NO_ATTRIBUTE};

/// Adds a surface, failing when a triangle could no longer name it (`u16` ids).
pub(crate) fn push_surface(
    source: &Source,
    mesh: &mut Mesh,
    surface: Surface,
) -> Result<u16, ImportError> {
    let id = u16::try_from(mesh.surfaces.len()).map_err(|_| {
        source.unsupported(
            format!("material '{}'", surface.name),
            "more than 65,536 materials",
        )
    })?;
    mesh.surfaces.push(surface);
    Ok(id)
}

/// `u32` index for the next element of a stream of length `len`.
pub(crate) fn next_index(source: &Source, len: usize, what: &str) -> Result<u32, ImportError> {
    u32::try_from(len)
        .ok()
        .filter(|&i| i != NO_ATTRIBUTE)
        .ok_or_else(|| source.unsupported("mesh", format!("more than 2^32 - 1 {what}")))
}
