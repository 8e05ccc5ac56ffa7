//! What an import takes besides the bytes ([`ImportOptions`], a [`Loader`] for the files the
//! input names) and what it reports besides the mesh ([`ImportReport`]).

/// Options that formats without units or scale need.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImportOptions {
    /// Metres per grid cell: required for `.npy` heightfields; for `.dem` it overrides the
    /// spacing the header gives (and is required when the header's ground units are
    /// arc-seconds or radians). Ignored by mesh formats.
    pub spacing: Option<f32>,
}

/// Reads a file that an input refers to (an OBJ's `mtllib`, a glTF buffer's URI) by the name
/// the input gives.
pub type Loader<'a> = dyn FnMut(&str) -> std::io::Result<Vec<u8>> + 'a;

/// What an import skipped or wants the user to know, beside the mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImportReport {
    /// Primitives that are not triangles and were skipped: glTF primitives in `POINTS` or
    /// `LINE*` modes, OBJ `p` and `l` statements, PLY faces with fewer than three vertices.
    pub skipped_primitives: usize,
    /// Human-readable notes (a missing MTL file, holes in a heightfield, ...), each a sentence.
    pub notes: Vec<String>,
    /// The grid, for heightfields (`.dem`, `.npy`).
    pub heightfield: Option<HeightfieldInfo>,
}

/// The grid a heightfield was read into.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeightfieldInfo {
    /// Posts along x (east).
    pub columns: usize,
    /// Posts along z (south).
    pub rows: usize,
    /// Posts with a height (the grid's other posts are missing: voids, irregular corners).
    pub posts: usize,
    /// Metres between neighbouring posts along x and z.
    pub spacing: [f32; 2],
    /// Lowest and highest height over all posts, in metres.
    pub height_range: [f32; 2],
}
