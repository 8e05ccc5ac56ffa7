//! The output-buffer check both emission paths (the hierarchy's cameras and the octree's
//! cuts) make before writing per-surface index lists: one place, so they refuse the same
//! buffers the same way; each maps the shortfall to its own error type.

use crate::ids::SurfaceId;

/// The message of an output list that is too small, shared by both paths' errors: surface
/// `surface`'s list, or the packed list when `None`.
pub(crate) fn write_too_small(
    f: &mut core::fmt::Formatter<'_>,
    surface: Option<SurfaceId>,
    needed: usize,
    given: usize,
) -> core::fmt::Result {
    match surface {
        Some(s) => write!(
            f,
            "index list of surface {}: room for {given}, {needed} needed",
            s.0
        ),
        None => write!(f, "packed index list: room for {given}, {needed} needed"),
    }
}

/// `From<Shortfall>` for an emission error with `TooFewOutputs { needed, given }` and
/// `OutputTooSmall { surface, needed, given }` variants.
macro_rules! from_shortfall {
    ($error:ty) => {
        impl From<$crate::outputs::Shortfall> for $error {
            fn from(e: $crate::outputs::Shortfall) -> Self {
                match e {
                    $crate::outputs::Shortfall::TooFewOutputs { needed, given } => {
                        Self::TooFewOutputs { needed, given }
                    }
                    $crate::outputs::Shortfall::TooSmall {
                        surface,
                        needed,
                        given,
                    } => Self::OutputTooSmall {
                        surface,
                        needed,
                        given,
                    },
                }
            }
        }
    };
}
pub(crate) use from_shortfall;

/// What is wrong with the buffers given for `surfaces` per-surface lists.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Shortfall {
    /// Fewer lists (or count slots) than surfaces.
    TooFewOutputs { needed: usize, given: usize },
    /// Surface `surface`'s list (the packed list when `None`) is shorter than its index
    /// count.
    TooSmall {
        surface: Option<SurfaceId>,
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
                surface: Some(SurfaceId(s as u16)),
                needed: n,
                given: list.len(),
            });
        }
    }
    Ok(())
}

/// Checks a packed list of `out_len` indices and `offsets` (surfaces + 1 entries) against
/// `needed(surface)` indices for each of `surfaces`, then sets `offsets[0]` to 0 and
/// `offsets[s + 1]` to where surface `s` starts: its cursor while the lists are written,
/// its end once they are. Returns the total.
pub(crate) fn start_packed(
    out_len: usize,
    offsets: &mut [u32],
    surfaces: usize,
    needed: impl Fn(usize) -> usize,
) -> Result<usize, Shortfall> {
    if offsets.len() < surfaces + 1 {
        return Err(Shortfall::TooFewOutputs {
            needed: surfaces + 1,
            given: offsets.len(),
        });
    }
    let total = (0..surfaces).map(&needed).sum();
    if out_len < total {
        return Err(Shortfall::TooSmall {
            surface: None,
            needed: total,
            given: out_len,
        });
    }
    offsets[0] = 0;
    let mut start = 0u32;
    for s in 0..surfaces {
        offsets[s + 1] = start;
        start += needed(s) as u32;
    }
    Ok(total)
}
