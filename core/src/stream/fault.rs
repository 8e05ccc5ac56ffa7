//! What goes wrong while streaming: a page whose bytes fail (reported once, never a panic),
//! and calls that do not fit the pool's state.

use crate::format::FormatError;
use crate::ids::PageKey;

/// Why a page could not be installed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaultKind {
    /// The host could not read it.
    Io,
    /// Its bytes do not match the page table's checksum.
    Checksum {
        /// The checksum the page table records.
        stored: u64,
        /// The checksum of the bytes.
        computed: u64,
    },
    /// Its contents break the format.
    Content(FormatError),
}

/// A page that failed: it stays absent, and the frames go on at the coarser level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PageFault {
    /// The page.
    pub key: PageKey,
    /// What failed.
    pub kind: FaultKind,
}

impl core::fmt::Display for PageFault {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let PageKey { file, page } = self.key;
        write!(f, "file {file}: page {page}: ")?;
        match &self.kind {
            FaultKind::Io => write!(f, "could not be read"),
            FaultKind::Checksum { stored, computed } => write!(
                f,
                "checksum {computed:#018x} of its bytes, the page table says {stored:#018x}"
            ),
            FaultKind::Content(e) => write!(f, "{e}"),
        }
    }
}

impl core::error::Error for PageFault {}

/// A call that does not fit the pool's state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StreamError {
    /// The pool serves no such page.
    UnknownPage(PageKey),
    /// The page is not resident.
    NotResident(PageKey),
    /// The page has no use to release.
    NotInUse(PageKey),
    /// No page is loading into this slot.
    NotLoading {
        /// The slot.
        slot: u32,
    },
    /// The pool has no such slot (lists made for another pool).
    NoSuchSlot {
        /// The slot.
        slot: u32,
    },
}

impl core::fmt::Display for StreamError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::UnknownPage(k) => write!(f, "file {}: page {}: not in the pool", k.file, k.page),
            Self::NotResident(k) => write!(f, "file {}: page {}: not resident", k.file, k.page),
            Self::NotInUse(k) => write!(
                f,
                "file {}: page {}: released more than used",
                k.file, k.page
            ),
            Self::NotLoading { slot } => write!(f, "slot {slot}: no page is loading into it"),
            Self::NoSuchSlot { slot } => write!(f, "slot {slot}: the pool has no such slot"),
        }
    }
}

impl core::error::Error for StreamError {}

/// Why [`Residency::complete`](super::Residency::complete) installed nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InstallError {
    /// The page's bytes failed: it is reported here, once, and stays absent.
    Fault(PageFault),
    /// A parent of the page is still loading: the slot keeps its bytes; complete it again
    /// once the parent is installed.
    Wait,
    /// A parent of the page failed while it loaded: its slot is free again and the page
    /// absent (nothing is wrong with its bytes, so nothing is reported).
    Abandoned(PageKey),
    /// The call does not fit the pool's state.
    Misuse(StreamError),
}

impl core::fmt::Display for InstallError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Fault(e) => e.fmt(f),
            Self::Wait => write!(f, "a parent page is still loading"),
            Self::Abandoned(k) => write!(
                f,
                "file {}: page {}: a parent failed, so it is not installed",
                k.file, k.page
            ),
            Self::Misuse(e) => e.fmt(f),
        }
    }
}

impl core::error::Error for InstallError {}
