//! What the reader targets share: an input split into the file and the one file it may name
//! (an MTL library, a glTF buffer), and the checks every import result must pass.

use caveclod_bake::import::{import_bytes, ImportError, ImportOptions, ImportReport};
use caveclod_bake::mesh::Mesh;

/// Separates the main file from the side file (served for any name the main file asks for).
pub const SIDE: &[u8] = b"\n#%side\n";

/// `data` split at the first [`SIDE`] marker: the main file and the side file, if any.
pub fn split(data: &[u8]) -> (&[u8], Option<&[u8]>) {
    match data.windows(SIDE.len()).position(|w| w == SIDE) {
        Some(at) => (&data[..at], Some(&data[at + SIDE.len()..])),
        None => (data, None),
    }
}

/// Imports `data` as the file `name` (its extension picks the importer), the side file served
/// for any name it refers to; the mesh must validate and be non-empty.
pub fn import(
    name: &str,
    data: &[u8],
    options: &ImportOptions,
) -> Result<(Mesh, ImportReport), ImportError> {
    let (main, side) = split(data);
    let mut load = |_: &str| match side {
        Some(bytes) => Ok(bytes.to_vec()),
        None => Err(std::io::Error::from(std::io::ErrorKind::NotFound)),
    };
    let result = import_bytes(name, main, &mut load, options);
    if let Ok((mesh, _)) = &result {
        if let Err(e) = mesh.validate() {
            panic!("an imported mesh does not validate: {e}");
        }
        assert!(!mesh.triangles.is_empty(), "an empty mesh imported");
    }
    if let Err(ImportError::Internal { message, .. }) = &result {
        panic!("internal error: {message}");
    }
    result
}
