//! The pieces a pass runs in, and the small checks every pass shares.

use core::ops::Range;

use crate::format::{FormatError, HierarchyParts, Tag, VertexKey};
use crate::ids::PositionId;

/// How the validation runs each pass over its records: split into consecutive ranges that
/// may be checked at once, on other threads (the core has none of its own; a caller with a
/// thread pool implements this over it). Validation is the same whatever the split.
pub trait Pieces: Sync {
    /// `map` of consecutive ranges that cover `0..n` in order (at least one range, which may
    /// be empty), folded from the first to the last by `join`.
    fn fold<T: Send>(
        &self,
        n: usize,
        map: &(dyn Fn(Range<usize>) -> T + Sync),
        join: &dyn Fn(T, T) -> T,
    ) -> T;
}

/// Every pass in one piece, on the caller's thread.
#[derive(Clone, Copy, Debug, Default)]
pub struct OnePiece;

impl Pieces for OnePiece {
    fn fold<T: Send>(
        &self,
        n: usize,
        map: &(dyn Fn(Range<usize>) -> T + Sync),
        _join: &dyn Fn(T, T) -> T,
    ) -> T {
        map(0..n)
    }
}

/// `pass` over the records `0..n`, in pieces; the first error in record order.
pub(super) fn in_pieces(
    pieces: &impl Pieces,
    n: usize,
    pass: &(dyn Fn(Range<usize>) -> Result<(), FormatError> + Sync),
) -> Result<(), FormatError> {
    pieces.fold(n, pass, &|a, b| a.and(b))
}

/// The error of a record's field breaking a rule.
pub(crate) fn invalid(
    tag: Tag,
    record: usize,
    field: &'static str,
    problem: &'static str,
    value: u64,
) -> FormatError {
    FormatError::Invalid {
        tag,
        record: record as u64,
        field,
        problem,
        value,
    }
}

/// Whether every value is finite.
pub(super) fn finite(v: &[f32]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// The sorted vertex-table entries of a position (offsets already validated).
pub(super) fn keys<'a>(parts: &HierarchyParts<'a>, p: PositionId) -> &'a [VertexKey] {
    let o = parts.vertex_table_offsets;
    &parts.vertex_table[o[p.index()] as usize..o[p.index() + 1] as usize]
}

/// A count that must equal what the other sections imply.
pub(super) fn count(tag: Tag, expected: usize, found: usize) -> Result<(), FormatError> {
    if expected != found {
        return Err(FormatError::Count {
            tag,
            expected: expected as u64,
            found: found as u64,
        });
    }
    Ok(())
}
