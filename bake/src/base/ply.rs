//! What the two PLY readers (the in-core importer and the streaming reader) read alike: the
//! scalar types and how their bytes decode, and the vertex slots the properties fill.

/// Slots of a vertex, in the order of [`VERTEX_NAMES`].
pub const X: usize = 0;
pub const NX: usize = 3;
pub const U: usize = 6;
pub const R: usize = 8;
pub const A: usize = 11;
pub const SLOTS: usize = 12;

/// What each slot holds, as errors name it.
pub const VERTEX_NAMES: [&str; SLOTS] = [
    "coordinate x",
    "coordinate y",
    "coordinate z",
    "normal x",
    "normal y",
    "normal z",
    "texture coordinate u",
    "texture coordinate v",
    "red",
    "green",
    "blue",
    "alpha",
];

/// The slot the vertex property `name` fills, if any.
pub fn vertex_slot(name: &str) -> Option<usize> {
    Some(match name {
        "x" => X,
        "y" => X + 1,
        "z" => X + 2,
        "nx" => NX,
        "ny" => NX + 1,
        "nz" => NX + 2,
        "u" | "s" | "texture_u" | "texture_s" => U,
        "v" | "t" | "texture_v" | "texture_t" => U + 1,
        "red" | "diffuse_red" => R,
        "green" | "diffuse_green" => R + 1,
        "blue" | "diffuse_blue" => R + 2,
        "alpha" | "diffuse_alpha" => A,
        _ => return None,
    })
}

/// A PLY scalar type, which decodes its values from bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    /// The type a header names `s`, if any.
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    /// Bytes of one value.
    pub fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    /// Divisor that maps the type's range to 0..=1, for colours.
    pub fn color_scale(self) -> f64 {
        match self {
            Self::U16 => 65535.0,
            Self::F32 | Self::F64 => 1.0,
            _ => 255.0,
        }
    }

    /// Whether the type is an integer type.
    pub fn is_int(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }

    /// An integer type's value (a float type's, truncated).
    #[inline]
    pub fn decode_int(self, b: &[u8], big: bool) -> i64 {
        macro_rules! get {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                if big {
                    i64::from(<$t>::from_be_bytes(a))
                } else {
                    i64::from(<$t>::from_le_bytes(a))
                }
            }};
        }
        match self {
            Self::I8 => i64::from(b[0] as i8),
            Self::U8 => i64::from(b[0]),
            Self::I16 => get!(i16, 2),
            Self::U16 => get!(u16, 2),
            Self::I32 => get!(i32, 4),
            Self::U32 => get!(u32, 4),
            Self::F32 | Self::F64 => self.decode(b, big) as i64,
        }
    }

    /// The value, of any type, as an `f64`.
    #[inline]
    pub fn decode(self, b: &[u8], big: bool) -> f64 {
        macro_rules! get {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                if big {
                    <$t>::from_be_bytes(a) as f64
                } else {
                    <$t>::from_le_bytes(a) as f64
                }
            }};
        }
        match self {
            Self::I8 => f64::from(b[0] as i8),
            Self::U8 => f64::from(b[0]),
            Self::I16 => get!(i16, 2),
            Self::U16 => get!(u16, 2),
            Self::I32 => get!(i32, 4),
            Self::U32 => get!(u32, 4),
            Self::F32 => get!(f32, 4),
            Self::F64 => get!(f64, 8),
        }
    }
}
