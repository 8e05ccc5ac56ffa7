//! Binary element data read straight into the mesh: each value decoded once, where the
//! header puts it, with no record per element nor list per face (the parser's way, which
//! takes most of a large file's import).
//!
//! It takes the layouts real files use: a `vertex` and a `face` element, other elements read
//! past, every list with a non-negative integer count; on faces, one integer
//! `vertex_indices` list and no per-corner `texcoord`. Everything else (triangle strips,
//! per-corner UVs, a payload shorter than its lists need) goes to the parser's reader: a
//! walk over the payload first proves that every element ends within the file, so any
//! error this reader reports is one the parser's path reports too (a value, an index), in
//! the same order: the same mesh and the same errors either way.

use ply_rs_bw::ply::{ElementDef, Encoding, Header, PropertyType, ScalarType};
use rayon::prelude::*;

use super::corners::Corners;
use super::properties::scalar_size;
use super::properties::{is_index_list, Vertex};
use crate::base::ply::{vertex_slot, Scalar};
use crate::import::error::ImportError;
use crate::import::options::ImportReport;
use crate::mesh::Mesh;

/// Where each element's data starts, from a walk that checked every element ends within
/// the payload.
pub(super) struct Payload<'a> {
    bytes: &'a [u8],
    big: bool,
    vertices: Option<(&'a ElementDef, usize)>,
    faces: Option<(&'a ElementDef, usize)>,
    /// Triangles the faces' fans make.
    triangles: usize,
    /// The count and index types of the faces' index list, when it is their only property
    /// and every face has three corners: faces of one stride.
    triangle_list: Option<(&'a ScalarType, &'a ScalarType)>,
}

impl<'a> Payload<'a> {
    /// The element data `bytes` (what follows the header) in a layout this reader takes, or
    /// `None` (the parser's reader then reads it).
    pub(super) fn find(header: &'a Header, bytes: &'a [u8]) -> Option<Self> {
        let big = match header.encoding {
            Encoding::Ascii => return None,
            Encoding::BinaryBigEndian => true,
            Encoding::BinaryLittleEndian => false,
        };
        let mut payload = Payload {
            bytes,
            big,
            vertices: None,
            faces: None,
            triangles: 0,
            triangle_list: None,
        };
        let mut at = 0usize;
        for def in header.elements.values() {
            let start = at;
            let index_list = def.properties.keys().position(|k| is_index_list(k));
            let is_face = match def.name.as_str() {
                "vertex" if stride(def).is_some() => {
                    payload.vertices = Some((def, start));
                    false
                }
                "vertex" => return None,
                "face" if face_layout_taken(def) => {
                    payload.faces = Some((def, start));
                    true
                }
                "face" | "tristrips" => return None,
                _ => false,
            };
            if let Some(stride) = stride(def) {
                at = at.checked_add(def.count.checked_mul(stride)?)?;
                if at > bytes.len() {
                    return None;
                }
                continue;
            }
            let (mut triangles, mut all_triangles) = (0usize, true);
            let mut instance = |corners: usize| {
                triangles += corners.saturating_sub(2);
                all_triangles &= corners == 3;
            };
            at = match only_list(def) {
                Some(list) => {
                    let counted = index_list == Some(0);
                    payload
                        .walk_lists(def.count, list, at, |n| instance(n * usize::from(counted)))?
                }
                None => {
                    for _ in 0..def.count {
                        let mut corners = 0usize;
                        at = payload.walk_instance(def, at, |p, _, _| {
                            corners += usize::from(Some(p) == index_list);
                        })?;
                        instance(corners);
                    }
                    at
                }
            };
            if is_face {
                payload.triangles += triangles;
                if all_triangles {
                    payload.triangle_list = only_list(def);
                }
            }
        }
        Some(payload)
    }

    /// [`walk_instance`](Self::walk_instance) of `count` instances of an element whose only
    /// property is a list of `(count type, item type)`, from `at`, handing each list's length
    /// to `length`; the offset after them, or `None` when the payload ends first or a count
    /// is negative.
    fn walk_lists(
        &self,
        count: usize,
        (count_type, item): (&ScalarType, &ScalarType),
        mut at: usize,
        mut length: impl FnMut(usize),
    ) -> Option<usize> {
        let (count_size, item_size) = (scalar_size(count_type), scalar_size(item));
        for _ in 0..count {
            let end = at.checked_add(count_size)?;
            let n = integer(self.bytes.get(at..end)?, count_type, self.big)?;
            let items = usize::try_from(n).ok()?;
            at = end.checked_add(items.checked_mul(item_size)?)?;
            if at > self.bytes.len() {
                return None;
            }
            length(items);
        }
        Some(at)
    }

    /// Reads the vertices, then the faces, into `mesh` (as the parser's path pushes its
    /// records); faces under three corners are skipped and counted.
    pub(super) fn read(
        &self,
        corners: &mut Corners<'_>,
        mesh: &mut Mesh,
        report: &mut ImportReport,
    ) -> Result<(), ImportError> {
        if let Some((def, start)) = self.vertices {
            self.read_vertices(corners, mesh, def, start)?;
        }
        if let Some((def, start)) = self.faces {
            mesh.triangles.reserve(self.triangles);
            if let Some(list) = self.triangle_list {
                return self.read_triangles(corners, mesh, report, list, (def.count, start));
            }
            let index_list = def.properties.keys().position(|k| is_index_list(k));
            let mut indices: Vec<i64> = Vec::new();
            let mut at = start;
            for f in 0..def.count {
                indices.clear();
                at = self
                    .walk_instance(def, at, |p, t, b| {
                        if Some(p) == index_list {
                            indices.push(integer(b, t, self.big).unwrap_or(0));
                        }
                    })
                    // The walk in `find` covered every instance.
                    .unwrap_or(self.bytes.len());
                corners.push_face(mesh, f, &indices, &[], report)?;
            }
        }
        Ok(())
    }

    /// The vertices, records of a fixed stride from `start`.
    fn read_vertices(
        &self,
        corners: &Corners<'_>,
        mesh: &mut Mesh,
        def: &ElementDef,
        start: usize,
    ) -> Result<(), ImportError> {
        let stride = stride(def).unwrap_or(0);
        // `(offset in the record, type, slot)` of every property with a slot.
        let mut fields = Vec::new();
        let mut offset = 0usize;
        for (name, property) in &def.properties {
            if let PropertyType::Scalar(t) = &property.data_type {
                if let Some(slot) = vertex_slot(name) {
                    fields.push((offset, t.clone(), slot));
                }
                offset += scalar_size(t);
            }
        }
        let fields: Vec<(usize, Scalar, usize, f64)> = fields
            .into_iter()
            .map(|(offset, t, slot)| (offset, scalar(&t), slot, colour_scale(&t)))
            .collect();
        let records = &self.bytes[start..start + def.count * stride];
        let vertex = |i: usize| {
            let record = &records[i * stride..(i + 1) * stride];
            let mut v = Vertex::unset();
            for &(offset, s, slot, scale) in &fields {
                v.put(slot, s.decode(&record[offset..], self.big), scale);
            }
            v
        };
        corners.push_vertices(mesh, def.count, vertex)
    }

    /// Faces whose only property is the index list, each of three corners (what
    /// [`find`](Self::find) saw): records of one stride from `start`, read on all cores. On
    /// an index out of range, the error of the first face with one, as reading the faces in
    /// order gives.
    fn read_triangles(
        &self,
        corners: &mut Corners<'_>,
        mesh: &mut Mesh,
        report: &mut ImportReport,
        (count, index): (&ScalarType, &ScalarType),
        (faces, start): (usize, usize),
    ) -> Result<(), ImportError> {
        let (count_size, index_size) = (scalar_size(count), scalar_size(index));
        let stride = count_size + 3 * index_size;
        let index = scalar(index);
        let corners_of = |f: usize| {
            let at = start + f * stride + count_size;
            [0, 1, 2].map(|k| index.decode_int(&self.bytes[at + k * index_size..], self.big))
        };
        let bad = (0..faces)
            .into_par_iter()
            .position_first(|f| !corners_of(f).iter().all(|&i| corners.in_range(i)));
        if let Some(f) = bad {
            return corners.push_face(mesh, f, &corners_of(f), &[], report);
        }
        let corners = &*corners;
        mesh.triangles.par_extend(
            (0..faces)
                .into_par_iter()
                .map(|f| corners.triangle(corners_of(f).map(|i| i as u32), None)),
        );
        Ok(())
    }

    /// Walks one instance of `def` from `at`, handing each scalar (a property's, or a list
    /// item's; not list counts) to `value` with its property's index; the offset after it,
    /// or `None` when the payload ends first or a list count is negative.
    fn walk_instance(
        &self,
        def: &ElementDef,
        mut at: usize,
        mut value: impl FnMut(usize, &ScalarType, &[u8]),
    ) -> Option<usize> {
        for (p, property) in def.properties.values().enumerate() {
            match &property.data_type {
                PropertyType::Scalar(t) => {
                    let end = at.checked_add(scalar_size(t))?;
                    value(p, t, self.bytes.get(at..end)?);
                    at = end;
                }
                PropertyType::List(count_type, t) => {
                    let end = at.checked_add(scalar_size(count_type))?;
                    let n = integer(self.bytes.get(at..end)?, count_type, self.big)?;
                    at = end;
                    let size = scalar_size(t);
                    let items = usize::try_from(n).ok()?;
                    let end = at.checked_add(items.checked_mul(size)?)?;
                    let list = self.bytes.get(at..end)?;
                    for item in list.chunks_exact(size) {
                        value(p, t, item);
                    }
                    at = end;
                }
            }
        }
        Some(at)
    }
}

/// The bytes of each instance of `def` when every property is a scalar.
fn stride(def: &ElementDef) -> Option<usize> {
    def.properties
        .values()
        .map(|p| match &p.data_type {
            PropertyType::Scalar(t) => Some(scalar_size(t)),
            PropertyType::List(..) => None,
        })
        .sum()
}

/// The count and item types of `def`'s list when it is `def`'s only property.
fn only_list(def: &ElementDef) -> Option<(&ScalarType, &ScalarType)> {
    let mut properties = def.properties.values();
    match (properties.next().map(|p| &p.data_type), properties.next()) {
        (Some(PropertyType::List(count, item)), None) => Some((count, item)),
        _ => None,
    }
}

/// Whether this reader takes a `face` element's properties: exactly one index list, of an
/// integer type, and no per-corner `texcoord`.
fn face_layout_taken(def: &ElementDef) -> bool {
    let mut index_lists = 0;
    for (name, property) in &def.properties {
        match &property.data_type {
            PropertyType::List(_, t) if is_index_list(name) => {
                if is_float(t) {
                    return false;
                }
                index_lists += 1;
            }
            PropertyType::List(..) if name == "texcoord" => return false,
            _ => {}
        }
    }
    index_lists == 1
}

fn is_float(t: &ScalarType) -> bool {
    matches!(t, ScalarType::Float | ScalarType::Double)
}

/// The streamed reader's decoder for a scalar of type `t`, whose values are those the
/// parser reads.
fn scalar(t: &ScalarType) -> Scalar {
    match t {
        ScalarType::Char => Scalar::I8,
        ScalarType::UChar => Scalar::U8,
        ScalarType::Short => Scalar::I16,
        ScalarType::UShort => Scalar::U16,
        ScalarType::Int => Scalar::I32,
        ScalarType::UInt => Scalar::U32,
        ScalarType::Float => Scalar::F32,
        ScalarType::Double => Scalar::F64,
    }
}

/// An integer of type `t` from its bytes `b`; `None` for a floating type.
#[inline]
fn integer(b: &[u8], t: &ScalarType, big: bool) -> Option<i64> {
    let s = scalar(t);
    s.is_int().then(|| s.decode_int(b, big))
}

/// What a colour of type `t` is divided by its maximum with (the parser's setters'
/// scales, [`Vertex`]'s `PropertyAccess`).
fn colour_scale(t: &ScalarType) -> f64 {
    match t {
        ScalarType::UShort => super::properties::USHORT_COLOR,
        ScalarType::Float | ScalarType::Double => 1.0,
        _ => super::properties::BYTE_COLOR,
    }
}
