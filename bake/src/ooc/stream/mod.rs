//! Streaming readers: PLY (ascii and binary, either endianness) and OBJ to a triangle soup,
//! never holding the whole file.
//!
//! Indexed formats name vertices by number, so a triangle can only be written once its
//! corners are known. [`open`] reads the vertices first (taking the bounding box on the way,
//! which the spatial keys need): binary PLY vertices of a fixed stride stay where they are in
//! the input, others are copied into fixed-size records in a temporary file. [`Input::faces`]
//! then reads the faces, as many times as asked, and looks their corners up through a
//! [`BlockCache`]: a direct-mapped cache of blocks of vertices (decoded as a block comes in)
//! whose size the memory budget sets. Real meshes (scanner output, exported models, the
//! generator's terrain) name nearby vertices in nearby faces, so the cache hits almost always;
//! a file whose faces jump around still works, only slower. This is cheaper than
//! dereferencing by external sorts (Lindstrom's OoCS) while bounded the same way. A sink that
//! needs only positions ([`SoupSink::positions_only`]) gets binary PLY corners without their
//! other attributes decoded.
//!
//! PLY: element `vertex` with `x y z`, optional `nx ny nz`, `red green blue [alpha]` (integer
//! colours divided by their maximum and taken as sRGB, as the in-core importer does), `u v`
//! (or `s t`, `texture_u texture_v`, `texture_s texture_t`); element `face` with a
//! `vertex_indices` (or `vertex_index`) list, polygons triangulated as fans; other elements and
//! properties are read past. The vertex element must come before the face element. A
//! `comment TextureFile NAME` line names the surface's texture.
//!
//! OBJ: two passes over the file: `v` (with optional `r g b`), `vt`, `vn` records first, then
//! `f` statements (any of `v`, `v/t`, `v//n`, `v/t/n`, negative indices), with `usemtl`
//! starting a surface per material name (the MTL file is not read). `v` flips to `1 - v` in
//! both formats.
//!
//! Errors name the file and the element (`face 123`, `line 45`, `vertex 17`); a file that ends
//! early says where.

mod cache;
mod obj;
mod ply;
pub(crate) mod ply_format;
mod sink;

use std::fs::File;
use std::path::Path;

pub use cache::{BlockCache, RecordSource};
pub use ply::{read_indexed, IndexedHeader, IndexedSink};
pub use sink::{SoupSink, StreamReport};

use crate::base::temp::TempSpace;
use crate::ooc::error::OocError;

/// An input whose vertices have been read into temporary records: its faces can be streamed
/// any number of times ([`Input::faces`]), each pass reading only the faces again (the
/// clustering's second pass needs the resolution the first pass's keys give).
pub struct Input<'a> {
    name: &'a str,
    kind: Kind<'a>,
}

enum Kind<'a> {
    Ply(ply::PlyInput<'a>),
    Obj(obj::ObjInput<'a>),
}

/// Opens `path` (chosen by extension: `.ply`, `.obj`; named `name` in errors) and reads its
/// vertices, using at most about `cache_bytes` for the vertex look-up afterwards.
pub fn open<'a>(
    path: &Path,
    name: &'a str,
    temp: &TempSpace,
    cache_bytes: usize,
) -> Result<Input<'a>, OocError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let file = || File::open(path).map_err(|source| OocError::io(name, "cannot read", source));
    let kind = match ext.as_str() {
        "ply" => Kind::Ply(ply::PlyInput::open(name, file()?, temp, cache_bytes)?),
        "obj" => Kind::Obj(obj::ObjInput::open(name, path, temp, cache_bytes)?),
        _ => {
            return Err(OocError::Unsupported {
                file: name.to_string(),
                message: format!(
                    "out-of-core baking reads .ply and .obj files, not '.{ext}' (bake it in core)"
                ),
            })
        }
    };
    Ok(Input { name, kind })
}

impl Input<'_> {
    /// The input's name in errors.
    pub fn name(&self) -> &str {
        self.name
    }

    /// Streams every face into `sink` (starting it with the bounding cube and the triangle
    /// count the header or first pass gave).
    pub fn faces(&mut self, sink: &mut dyn SoupSink) -> Result<StreamReport, OocError> {
        match &mut self.kind {
            Kind::Ply(p) => p.faces(sink),
            Kind::Obj(o) => o.faces(sink),
        }
    }
}

/// Streams `path` (chosen by extension: `.ply`, `.obj`) into `sink`, using at most about
/// `cache_bytes` for the vertex look-up.
pub fn stream_file(
    path: &Path,
    temp: &TempSpace,
    cache_bytes: usize,
    sink: &mut dyn SoupSink,
) -> Result<StreamReport, OocError> {
    let name = path.display().to_string();
    open(path, &name, temp, cache_bytes)?.faces(sink)
}
