//! How a pool names a page: its file and its index there.

/// A page of one of a pool's files: the file's index (from
/// [`Residency::add_file`](super::Residency::add_file)) and the page's index in its table.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PageKey {
    /// The file.
    pub file: u32,
    /// The page.
    pub page: u32,
}
