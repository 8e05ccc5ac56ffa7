//! The welded store takes the tiled weld's pieces as they come.

use std::io;

use caveclod_core::format::PositionClass;

use super::sink::WeldSink;
use crate::weld::store::{StoreWriter, StoredTri};
use crate::weld::welded::Attributes;

impl WeldSink for StoreWriter {
    fn push_position(
        &mut self,
        xyz: [f32; 3],
        class: PositionClass,
        vertices: &[[u32; 2]],
    ) -> io::Result<()> {
        StoreWriter::push_position(self, xyz, class, vertices)
    }

    fn push_attributes(&mut self, attributes: &[Attributes]) -> io::Result<()> {
        StoreWriter::push_attributes(self, attributes)
    }

    fn push_triangles(&mut self, triangles: &[StoredTri]) -> io::Result<()> {
        StoreWriter::push_triangles(self, triangles)
    }
}
