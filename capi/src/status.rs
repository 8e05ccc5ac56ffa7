//! Status codes: what every entry point returns, one static message each, and the mapping
//! from the core crate's typed errors.

use caveclod_core::{
    CameraError, CutError, EmitError, FormatError, OctreeFormatError, OpError, ViewError,
};
use core::ffi::c_char;

/// What a call did. `CAVECLOD_STATUS_OK` is zero; every other value names one reason a call
/// did nothing (or, for emission, left its outputs unusable), and
/// `caveclod_status_message` gives a sentence for it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CaveclodStatus {
    /// Success.
    Ok = 0,
    /// A pointer argument that must not be null was null.
    NullPointer = 1,
    /// A pointer is not aligned as the function documents: file bytes to
    /// `CAVECLOD_BYTES_ALIGN`, camera and cut memory to `CAVECLOD_MEMORY_ALIGN`, structs to
    /// their type's alignment.
    Misaligned = 2,
    /// The file is shorter than its header or its recorded length says: truncated. (Longer
    /// than its recorded length is `CAVECLOD_STATUS_TRAILING_BYTES`.)
    Truncated = 3,
    /// The bytes are not a `.clod` file this library reads (magic or major version).
    NotAClodFile = 4,
    /// The file's checksum does not match its bytes: corrupt.
    Corrupt = 5,
    /// The file breaks a rule of the format or of the hierarchy (a bad index, count or
    /// section).
    InvalidFile = 6,
    /// A handle was not made by its `_open` or `_init` function (or that call failed).
    InvalidHandle = 7,
    /// The camera (or cut) was made for another hierarchy (or octree).
    WrongHierarchy = 8,
    /// The memory given for a camera or a cut is smaller than its `_memory_size`.
    MemoryTooSmall = 9,
    /// The camera configuration asks for more splits than the hierarchy has, or more
    /// morphs than 32-bit indices can name.
    InvalidConfig = 10,
    /// An output buffer (index list, offsets, per-surface counts) is too small.
    OutputTooSmall = 11,
    /// An argument is out of range: a surface index, a non-finite or degenerate view,
    /// refinement parameters the core refuses (a tolerance that is not a finite number above
    /// 0, a negative or NaN time, speed or bound, a guard band outside [0, π/2)).
    InvalidArgument = 12,
    /// The hierarchy's connectivity contradicts the camera's state (data corrupt in a way
    /// validation cannot see); reset the camera. Emitted indices are unusable.
    Inconsistent = 13,
    /// The file has no octree sections (bake it out of core for one).
    NoOctree = 14,
    /// An arena has no room left for the bytes asked.
    ArenaFull = 15,
    /// A bug in this library: a panic was caught at the boundary. Nothing unwound into
    /// the caller; the handles the call was given must not be used again.
    Internal = 16,
    /// The bytes run on past the length the file's header records: extra bytes after the
    /// file's end (pass the file's own length, not a larger buffer's).
    TrailingBytes = 17,
    /// The file is paged (its pages stream into a pool): this call reads whole files only.
    Paged = 18,
    /// A streamed page failed its checks (or could not be read): it stays absent, it is
    /// reported once, and the frame goes on at the coarser level.
    BadPage = 19,
    /// A streamed page's parent is still loading: the slot keeps its bytes; install it
    /// again once the parent is installed (install a frame's pages parents first).
    PageWaits = 20,
    /// A streamed page's parent failed while it loaded: its slot is free again, the page
    /// absent; nothing is wrong with its bytes, so nothing is reported.
    PageAbandoned = 21,
}

impl CaveclodStatus {
    /// The static, NUL-terminated message of this status.
    pub fn message(self) -> &'static core::ffi::CStr {
        match self {
            Self::Ok => c"success",
            Self::NullPointer => c"a required pointer argument is null",
            Self::Misaligned => c"a pointer is not aligned as documented",
            Self::Truncated => c"the file is truncated",
            Self::NotAClodFile => c"not a .clod file of a version this library reads",
            Self::Corrupt => c"the file's checksum does not match: corrupt",
            Self::InvalidFile => c"the file breaks a rule of the .clod format",
            Self::InvalidHandle => c"the handle was not initialised by its _open or _init call",
            Self::WrongHierarchy => c"the camera or cut belongs to another hierarchy or octree",
            Self::MemoryTooSmall => c"the memory given is smaller than _memory_size says",
            Self::InvalidConfig => c"the camera configuration exceeds what the hierarchy allows",
            Self::OutputTooSmall => c"an output buffer is too small",
            Self::InvalidArgument => c"an argument is out of range",
            Self::Inconsistent => c"the hierarchy contradicts the camera's state: reset the camera",
            Self::NoOctree => c"the file has no octree",
            Self::ArenaFull => c"the arena is full",
            Self::Internal => c"internal error (a bug): a panic was caught at the C boundary",
            Self::TrailingBytes => c"the file has bytes after the end its header records",
            Self::Paged => c"the file is paged: its pages stream, and this call reads whole files",
            Self::BadPage => c"a page failed its checks: it stays absent and the frame goes on",
            Self::PageWaits => c"a parent page is still loading: install this page after it",
            Self::PageAbandoned => c"a parent page failed: this page was not installed",
        }
    }

    /// The status of a file `Hierarchy::from_bytes` refused.
    pub fn from_format(e: FormatError) -> Self {
        match e {
            FormatError::Truncated { .. } | FormatError::LengthMismatch { .. } => Self::Truncated,
            FormatError::TrailingBytes { .. } => Self::TrailingBytes,
            FormatError::BadMagic | FormatError::UnsupportedVersion { .. } => Self::NotAClodFile,
            FormatError::ChecksumMismatch { .. } => Self::Corrupt,
            FormatError::Misaligned { .. } => Self::Misaligned,
            FormatError::Paged => Self::Paged,
            _ => Self::InvalidFile,
        }
    }
}

impl From<CameraError> for CaveclodStatus {
    fn from(e: CameraError) -> Self {
        match e {
            CameraError::Capacity { .. } => Self::MemoryTooSmall,
            CameraError::TooManyPairs { .. }
            | CameraError::TooManyMorphs { .. }
            | CameraError::IndexEdits { .. } => Self::InvalidConfig,
        }
    }
}

impl From<OpError> for CaveclodStatus {
    fn from(e: OpError) -> Self {
        match e {
            OpError::WrongHierarchy => Self::WrongHierarchy,
            OpError::InvalidParams(_) => Self::InvalidArgument,
            _ => Self::Inconsistent,
        }
    }
}

impl From<EmitError> for CaveclodStatus {
    fn from(e: EmitError) -> Self {
        match e {
            EmitError::WrongHierarchy => Self::WrongHierarchy,
            EmitError::NoIndexEdits => Self::InvalidArgument,
            EmitError::TooFewOutputs { .. } | EmitError::OutputTooSmall { .. } => {
                Self::OutputTooSmall
            }
            EmitError::MissingVertex { .. }
            | EmitError::CountMismatch { .. }
            | EmitError::NoDeviceVertex { .. } => Self::Inconsistent,
        }
    }
}

impl From<CutError> for CaveclodStatus {
    fn from(e: CutError) -> Self {
        match e {
            CutError::Capacity { .. } => Self::MemoryTooSmall,
            CutError::WrongOctree => Self::WrongHierarchy,
            CutError::TooFewOutputs { .. } | CutError::OutputTooSmall { .. } => {
                Self::OutputTooSmall
            }
            CutError::InvalidParams(_) => Self::InvalidArgument,
        }
    }
}

impl From<ViewError> for CaveclodStatus {
    fn from(_: ViewError) -> Self {
        Self::InvalidArgument
    }
}

impl From<OctreeFormatError> for CaveclodStatus {
    fn from(_: OctreeFormatError) -> Self {
        Self::InvalidFile
    }
}

/// The static message of `status`: a NUL-terminated string that lives as long as the
/// program. A value that is no status gets the message of `CAVECLOD_STATUS_INVALID_ARGUMENT`.
///
/// Thread-safe: any thread, any time.
#[no_mangle]
pub extern "C" fn caveclod_status_message(status: i32) -> *const c_char {
    const ALL: [CaveclodStatus; 22] = [
        CaveclodStatus::Ok,
        CaveclodStatus::NullPointer,
        CaveclodStatus::Misaligned,
        CaveclodStatus::Truncated,
        CaveclodStatus::NotAClodFile,
        CaveclodStatus::Corrupt,
        CaveclodStatus::InvalidFile,
        CaveclodStatus::InvalidHandle,
        CaveclodStatus::WrongHierarchy,
        CaveclodStatus::MemoryTooSmall,
        CaveclodStatus::InvalidConfig,
        CaveclodStatus::OutputTooSmall,
        CaveclodStatus::InvalidArgument,
        CaveclodStatus::Inconsistent,
        CaveclodStatus::NoOctree,
        CaveclodStatus::ArenaFull,
        CaveclodStatus::Internal,
        CaveclodStatus::TrailingBytes,
        CaveclodStatus::Paged,
        CaveclodStatus::BadPage,
        CaveclodStatus::PageWaits,
        CaveclodStatus::PageAbandoned,
    ];
    let status = ALL
        .iter()
        .copied()
        .find(|s| *s as i32 == status)
        .unwrap_or(CaveclodStatus::InvalidArgument);
    status.message().as_ptr()
}
