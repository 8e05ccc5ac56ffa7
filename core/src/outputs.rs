//! The output-buffer check both emission paths (the hierarchy's cameras and the octree's
//! cuts) make before writing per-surface index lists: one place, so they refuse the same
//! buffers the same way; each maps the shortfall to its own error type.

use crate::ids::SurfaceId;

/// What is wrong with the buffers given for `surfaces` per-surface lists.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Shortfall {
    /// Fewer lists (or count slots) than surfaces.
    TooFewOutputs { needed: usize, given: usize },
    /// Surface `surface`'s list is shorter than its index count.
    TooSmall {
        surface: SurfaceId,
        needed: usize,
        given: usize,
    },
}

/// Checks `out` (one list per surface) and `written` (one count per surface) against
/// `needed(surface)` indices for each of `surfaces` (at most 65535, as validated for
/// hierarchies and octrees, so every surface has a [`SurfaceId`]).
pub(crate) fn check_lists(
    out: &[&mut [u32]],
    written: &[u32],
    surfaces: usize,
    needed: impl Fn(usize) -> usize,
) -> Result<(), Shortfall> {
    if out.len() < surfaces || written.len() < surfaces {
        return Err(Shortfall::TooFewOutputs {
            needed: surfaces,
            given: out.len().min(written.len()),
        });
    }
    for (s, list) in out.iter().enumerate().take(surfaces) {
        let n = needed(s);
        if list.len() < n {
            return Err(Shortfall::TooSmall {
                surface: SurfaceId(s as u16),
                needed: n,
                given: list.len(),
            });
        }
    }
    Ok(())
}
