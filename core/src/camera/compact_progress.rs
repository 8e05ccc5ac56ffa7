//! How far an incremental compaction has come ([`Progress`]), kept in the camera's state
//! between calls of `CameraState::compact_step` (see `compact_step`), and the gaps of its
//! Shell sorts.

/// Ciura's gaps, extended by a factor of 2.25: past the largest a list would need more
/// records than a camera can address.
pub(crate) const GAPS: [u32; 24] = [
    1,
    4,
    10,
    23,
    57,
    132,
    301,
    701,
    1750,
    3937,
    8858,
    19930,
    44842,
    100_894,
    227_011,
    510_774,
    1_149_241,
    2_585_792,
    5_818_032,
    13_090_572,
    29_453_787,
    66_271_020,
    149_109_795,
    335_497_038,
];

/// The phases of a compaction: none under way, squeezing out free records, sorting the
/// records, sorting the pairs.
pub(crate) const IDLE: u32 = 0;
pub(crate) const SQUEEZE: u32 = 1;
pub(crate) const RECORDS: u32 = 2;
pub(crate) const PAIRS: u32 = 3;

/// How far an incremental compaction has come: its phase, and in a sort the gap's index, the
/// element being inserted and where it stands now.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Progress {
    pub phase: u32,
    pub gap: u32,
    pub i: u32,
    pub j: u32,
}

impl Progress {
    /// No compaction under way.
    pub(crate) const IDLE: Self = Self {
        phase: IDLE,
        gap: 0,
        i: 0,
        j: 0,
    };

    /// The first insertion of a sort of `n` elements in `phase`, with the largest gap below
    /// `n`.
    pub(crate) fn sort(phase: u32, n: u32) -> Self {
        let gap = GAPS.iter().rposition(|&g| g < n.max(2)).unwrap_or(0);
        let first = GAPS.get(gap).copied().unwrap_or(1);
        Self {
            phase,
            gap: gap as u32,
            i: first,
            j: first,
        }
    }
}
