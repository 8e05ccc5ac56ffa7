//! What the PLY reader reads with: the scalar types, the header's elements and properties,
//! the vertex slots, and reading one element item (ascii or binary) or a run of bytes.

use std::fs::File;
use std::io::{self, BufRead, BufReader, Read};

/// A vertex property read at a fixed offset: (offset, type, slot, colour scale).
pub(super) type Field = (usize, Scalar, usize, f64);

/// A PLY scalar type, which decodes its values from bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Scalar {
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
    pub(super) fn parse(s: &str) -> Option<Self> {
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
    pub(super) fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }
    /// Divisor that maps the type's range to 0..=1, for colours.
    pub(super) fn color_scale(self) -> f64 {
        match self {
            Self::U16 => 65535.0,
            Self::F32 | Self::F64 => 1.0,
            _ => 255.0,
        }
    }
    pub(crate) fn is_int(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }
    /// An integer type's value (a float type's, truncated).
    #[inline]
    pub(crate) fn decode_int(self, b: &[u8], big: bool) -> i64 {
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
    pub(crate) fn decode(self, b: &[u8], big: bool) -> f64 {
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

#[derive(Clone, Debug)]
pub(super) struct Property {
    pub(super) name: String,
    /// `Some(count type)` for lists.
    pub(super) list: Option<Scalar>,
    pub(super) ty: Scalar,
}

#[derive(Clone, Debug)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: u64,
    pub(super) properties: Vec<Property>,
}

#[derive(Clone, Copy, PartialEq)]
pub(super) enum Format {
    Ascii,
    Binary { big: bool },
}

/// Vertex slots: x y z nx ny nz u v r g b a.
pub(super) fn slot(name: &str) -> Option<usize> {
    Some(match name {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        "nx" => 3,
        "ny" => 4,
        "nz" => 5,
        "u" | "s" | "texture_u" | "texture_s" => 6,
        "v" | "t" | "texture_v" | "texture_t" => 7,
        "red" | "diffuse_red" => 8,
        "green" | "diffuse_green" => 9,
        "blue" | "diffuse_blue" => 10,
        "alpha" | "diffuse_alpha" => 11,
        _ => return None,
    })
}

/// Reads one element item's properties, calling `scalar(index, value)` for scalars and
/// `list(index, values)` for lists.
pub(super) struct ItemReader {
    pub(super) format: Format,
    pub(super) bytes: Vec<u8>,
    pub(super) line: String,
    pub(super) list: Vec<f64>,
}

impl ItemReader {
    pub(super) fn read(
        &mut self,
        r: &mut impl BufRead,
        el: &Element,
        out: &mut dyn FnMut(usize, f64, &[f64]),
    ) -> Result<(), String> {
        match self.format {
            Format::Binary { big } => {
                for (i, p) in el.properties.iter().enumerate() {
                    match p.list {
                        None => {
                            read_exact(r, &mut self.bytes, p.ty.size())?;
                            out(i, p.ty.decode(&self.bytes, big), &[]);
                        }
                        Some(ct) => {
                            read_exact(r, &mut self.bytes, ct.size())?;
                            let n = ct.decode(&self.bytes, big);
                            if !(0.0..=1e6).contains(&n) {
                                return Err(format!("list '{}' has {n} entries", p.name));
                            }
                            let n = n as usize;
                            read_exact(r, &mut self.bytes, n * p.ty.size())?;
                            self.list.clear();
                            for k in 0..n {
                                let s = p.ty.size();
                                self.list.push(p.ty.decode(&self.bytes[k * s..], big));
                            }
                            out(i, 0.0, &self.list);
                        }
                    }
                }
            }
            Format::Ascii => {
                self.line.clear();
                loop {
                    let n = r.read_line(&mut self.line).map_err(|e| e.to_string())?;
                    if n == 0 {
                        return Err("the file ends here".into());
                    }
                    if !self.line.trim().is_empty() {
                        break;
                    }
                    self.line.clear();
                }
                let mut tokens = self.line.split_ascii_whitespace();
                let mut next = |what: &str| -> Result<f64, String> {
                    let t = tokens
                        .next()
                        .ok_or_else(|| format!("missing value for '{what}'"))?;
                    t.parse::<f64>()
                        .map_err(|_| format!("'{t}' is not a number (property '{what}')"))
                };
                for (i, p) in el.properties.iter().enumerate() {
                    match p.list {
                        None => {
                            let v = next(&p.name)?;
                            out(i, v, &[]);
                        }
                        Some(_) => {
                            let n = next(&p.name)?;
                            if !(0.0..=1e6).contains(&n) {
                                return Err(format!("list '{}' has {n} entries", p.name));
                            }
                            self.list.clear();
                            for _ in 0..n as usize {
                                let v = next(&p.name)?;
                                self.list.push(v);
                            }
                            out(i, 0.0, &self.list);
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

pub(super) fn read_exact(r: &mut impl Read, buf: &mut Vec<u8>, n: usize) -> Result<(), String> {
    buf.resize(n, 0);
    r.read_exact(&mut buf[..n]).map_err(|e| {
        if e.kind() == io::ErrorKind::UnexpectedEof {
            "the file ends here (truncated?)".to_string()
        } else {
            e.to_string()
        }
    })
}

/// Calls `f` on the next `n` bytes of `r`: straight from its buffer when they are there (the
/// common case: no copy, no call through `Read`), through `scratch` when they straddle a
/// refill.
#[inline]
pub(super) fn with_bytes<T>(
    r: &mut BufReader<File>,
    scratch: &mut Vec<u8>,
    n: usize,
    f: impl FnOnce(&[u8]) -> T,
) -> Result<T, String> {
    let buf = r.buffer();
    if buf.len() >= n {
        let v = f(&buf[..n]);
        r.consume(n);
        return Ok(v);
    }
    read_exact(r, scratch, n)?;
    Ok(f(&scratch[..n]))
}
