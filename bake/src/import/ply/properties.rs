//! The parser's element records: vertices (named slots), faces and strips (index lists and
//! per-corner UVs), and elements read past.

use ply_rs_bw::ply::{PropertyAccess, PropertyAccessResult, ScalarType};

use crate::base::ply::{vertex_slot, A, R, SLOTS};

/// One vertex as the parser fills it.
#[derive(Clone, Copy)]
pub(super) struct Vertex {
    pub(super) values: [f32; SLOTS],
}

impl Vertex {
    /// A vertex with no value set yet (opaque).
    pub(super) fn unset() -> Self {
        let mut values = [0.0; SLOTS];
        values[A] = 1.0;
        Vertex { values }
    }

    /// Stores `value` in `slot`; colours are normalised by `color_scale` (1/255 for bytes,
    /// ...).
    pub(super) fn put(&mut self, slot: usize, value: f64, color_scale: f64) {
        self.values[slot] = if slot >= R {
            (value * color_scale) as f32
        } else {
            value as f32
        };
    }

    /// Stores `value` in the slot `name` names, if any.
    fn set(&mut self, name: &str, value: f64, color_scale: f64) -> PropertyAccessResult {
        match vertex_slot(name) {
            Some(slot) => {
                self.put(slot, value, color_scale);
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::Ignored,
        }
    }
}

/// The scale of integer colours (bytes and other integer types but `ushort`).
pub(super) const BYTE_COLOR: f64 = 1.0 / 255.0;
/// The scale of `ushort` colours.
pub(super) const USHORT_COLOR: f64 = 1.0 / 65535.0;

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Vertex::unset()
    }
    fn set_char(&mut self, name: &str, value: i8) -> PropertyAccessResult {
        self.set(name, f64::from(value), BYTE_COLOR)
    }
    fn set_uchar(&mut self, name: &str, value: u8) -> PropertyAccessResult {
        self.set(name, f64::from(value), BYTE_COLOR)
    }
    fn set_short(&mut self, name: &str, value: i16) -> PropertyAccessResult {
        self.set(name, f64::from(value), BYTE_COLOR)
    }
    fn set_ushort(&mut self, name: &str, value: u16) -> PropertyAccessResult {
        self.set(name, f64::from(value), USHORT_COLOR)
    }
    fn set_int(&mut self, name: &str, value: i32) -> PropertyAccessResult {
        self.set(name, f64::from(value), BYTE_COLOR)
    }
    fn set_uint(&mut self, name: &str, value: u32) -> PropertyAccessResult {
        self.set(name, f64::from(value), BYTE_COLOR)
    }
    fn set_float(&mut self, name: &str, value: f32) -> PropertyAccessResult {
        self.set(name, f64::from(value), 1.0)
    }
    fn set_double(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        self.set(name, value, 1.0)
    }
}

/// One `face` or `tristrips` element: its index list and optional per-corner UVs.
#[derive(Default)]
pub(super) struct Face {
    pub(super) indices: Vec<i64>,
    pub(super) texcoord: Vec<f32>,
}

pub(super) fn is_index_list(name: &str) -> bool {
    name == "vertex_indices" || name == "vertex_index"
}

impl Face {
    fn set_indices<T: Into<i64>>(&mut self, name: &str, values: Vec<T>) -> PropertyAccessResult {
        if is_index_list(name) {
            self.indices = values.into_iter().map(Into::into).collect();
            PropertyAccessResult::Set
        } else {
            PropertyAccessResult::Ignored
        }
    }
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Face::default()
    }
    fn set_list_char(&mut self, name: &str, value: Vec<i8>) -> PropertyAccessResult {
        self.set_indices(name, value)
    }
    fn set_list_uchar(&mut self, name: &str, value: Vec<u8>) -> PropertyAccessResult {
        self.set_indices(name, value)
    }
    fn set_list_short(&mut self, name: &str, value: Vec<i16>) -> PropertyAccessResult {
        self.set_indices(name, value)
    }
    fn set_list_ushort(&mut self, name: &str, value: Vec<u16>) -> PropertyAccessResult {
        self.set_indices(name, value)
    }
    fn set_list_int(&mut self, name: &str, value: Vec<i32>) -> PropertyAccessResult {
        self.set_indices(name, value)
    }
    fn set_list_uint(&mut self, name: &str, value: Vec<u32>) -> PropertyAccessResult {
        self.set_indices(name, value)
    }
    fn set_list_float(&mut self, name: &str, value: Vec<f32>) -> PropertyAccessResult {
        if name == "texcoord" {
            self.texcoord = value;
            PropertyAccessResult::Set
        } else if is_index_list(name) {
            PropertyAccessResult::UnsupportedType
        } else {
            PropertyAccessResult::Ignored
        }
    }
    fn set_list_double(&mut self, name: &str, value: Vec<f64>) -> PropertyAccessResult {
        if name == "texcoord" {
            self.texcoord = value.into_iter().map(|v| v as f32).collect();
            PropertyAccessResult::Set
        } else if is_index_list(name) {
            PropertyAccessResult::UnsupportedType
        } else {
            PropertyAccessResult::Ignored
        }
    }
}

/// An element the importer does not use: read past.
pub(super) struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
}

/// The value [`Vertex`] stores for the 8-bit colour channel `k`.
pub(super) fn byte_colour(k: usize) -> f32 {
    (k as f64 * BYTE_COLOR) as f32
}

/// The elements the importer uses.
pub(super) struct Elements {
    pub(super) vertices: Vec<Vertex>,
    pub(super) faces: Vec<Face>,
    pub(super) strips: Vec<Face>,
}

/// Bytes of one value of the parser's scalar type `t`.
pub(super) fn scalar_size(t: &ScalarType) -> usize {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}
