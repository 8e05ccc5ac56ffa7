//! numpy `.npy` heightfields.
//!
//! Supported: format versions 1.0, 2.0 and 3.0; two-dimensional arrays in C order
//! (`fortran_order: False`), shape `(rows, columns)`; dtypes `i1 u1 i2 u2 i4 u4 f4 f8` in
//! either byte order (`<`, `>`, `|`, `=`). Heights are metres; [`ImportOptions::spacing`]
//! (metres between neighbouring cells, required) scales x and z. Row 0 is the northern edge,
//! columns run west to east (an image's orientation); see the heightfield module for the axes.
//!
//! Missing data: NaN cells, and the most negative value of `i2`/`i4` grids (`-32768`, the
//! SRTM void), become holes. Rejected with an error: Fortran order, other ranks, structured
//! or other dtypes, ±inf heights, a data section of the wrong length.

use super::error::{ImportError, Source};
use super::heightfield::{heightfield_to_mesh, Heightfield};
use super::options::{ImportOptions, ImportReport, Loader};
use crate::mesh::Mesh;

pub(crate) fn import_npy(
    source: &Source,
    bytes: &[u8],
    _load: &mut Loader<'_>,
    options: &ImportOptions,
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    let spacing = options.spacing.ok_or_else(|| ImportError::MissingOption {
        file: source.name.clone(),
        message: "a .npy grid has no scale: give the spacing (metres per grid cell, \
                  `--spacing M`)"
            .to_owned(),
    })?;
    let grid = parse_npy(source, bytes, spacing)?;
    heightfield_to_mesh(source, &grid, "terrain", report)
}

/// Element types the importer reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Kind {
    fn size(self) -> usize {
        match self {
            Kind::I8 | Kind::U8 => 1,
            Kind::I16 | Kind::U16 => 2,
            Kind::I32 | Kind::U32 | Kind::F32 => 4,
            Kind::F64 => 8,
        }
    }
}

/// The dictionary of an npy header.
struct Header {
    descr: String,
    fortran_order: bool,
    shape: Vec<u64>,
}

/// The header read and checked, then the data section, which must be exactly the shape's.
fn parse_npy(source: &Source, bytes: &[u8], spacing: f32) -> Result<Heightfield, ImportError> {
    let (text, end) = header_text(source, bytes)?;
    let header = parse_header(&text).map_err(|m| source.malformed("header", m))?;
    let (little, kind) = parse_descr(&header.descr).ok_or_else(|| {
        source.unsupported(
            "header",
            format!(
                "dtype '{}' (read: i1 u1 i2 u2 i4 u4 f4 f8, either byte order)",
                header.descr
            ),
        )
    })?;
    if header.fortran_order {
        return Err(source.unsupported(
            "header",
            "fortran_order: True (save the array in C order, e.g. np.ascontiguousarray)",
        ));
    }
    let (rows, cols) = grid_shape(source, &header, kind, &bytes[end..])?;
    let heights: Vec<f32> = bytes[end..]
        .chunks_exact(kind.size())
        .map(|b| decode(kind, little, b))
        .collect();
    Ok(Heightfield {
        width: cols,
        depth: rows,
        spacing: [spacing, spacing],
        heights,
    })
}

/// The header dictionary's text (latin-1 before version 3, UTF-8 from it) and where the data
/// starts.
fn header_text(source: &Source, bytes: &[u8]) -> Result<(String, usize), ImportError> {
    const MAGIC: &[u8] = b"\x93NUMPY";
    if bytes.len() < MAGIC.len() + 2 || &bytes[..MAGIC.len()] != MAGIC {
        return Err(source.malformed("header", "not an .npy file (no \\x93NUMPY magic)"));
    }
    let major = bytes[6];
    let (len_size, utf8) = match major {
        1 => (2, false),
        2 => (4, false),
        3 => (4, true),
        v => {
            return Err(source.unsupported(
                "header",
                format!("format version {v}.{} (1.0 to 3.0 are read)", bytes[7]),
            ))
        }
    };
    let start = 8 + len_size;
    let header_len = match bytes.get(8..start) {
        Some(b) if len_size == 2 => usize::from(u16::from_le_bytes([b[0], b[1]])),
        Some(b) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
        None => return Err(source.truncated("the header length is cut off")),
    };
    let end = start
        .checked_add(header_len)
        .filter(|&e| e <= bytes.len())
        .ok_or_else(|| {
            source.truncated(format!(
                "the header claims {header_len} bytes, the file has {}",
                bytes.len().saturating_sub(start)
            ))
        })?;
    let text: String = if utf8 {
        std::str::from_utf8(&bytes[start..end])
            .map_err(|_| source.malformed("header", "not UTF-8"))?
            .to_owned()
    } else {
        // Versions 1 and 2 are latin-1.
        bytes[start..end].iter().map(|&b| char::from(b)).collect()
    };
    Ok((text, end))
}

/// `(rows, columns)` of a 2-D shape whose elements exactly fill `data`.
fn grid_shape(
    source: &Source,
    header: &Header,
    kind: Kind,
    data: &[u8],
) -> Result<(usize, usize), ImportError> {
    let &[rows, cols] = header.shape.as_slice() else {
        return Err(source.unsupported(
            "header",
            format!(
                "shape {:?}: a heightfield is a 2-D array (rows, columns)",
                header.shape
            ),
        ));
    };
    let too_big = || source.unsupported("header", format!("shape ({rows}, {cols}) is too large"));
    let rows = usize::try_from(rows).map_err(|_| too_big())?;
    let cols = usize::try_from(cols).map_err(|_| too_big())?;
    let count = rows.checked_mul(cols).ok_or_else(too_big)?;
    let expected = count.checked_mul(kind.size()).ok_or_else(too_big)?;
    if data.len() < expected {
        return Err(source.truncated(format!(
            "shape ({rows}, {cols}) of {} needs {expected} data bytes, the file has {}",
            header.descr,
            data.len()
        )));
    }
    if data.len() > expected {
        return Err(source.malformed(
            "data",
            format!(
                "{} bytes after the header, {expected} expected for shape ({rows}, {cols}) of {}",
                data.len(),
                header.descr
            ),
        ));
    }
    Ok((rows, cols))
}

/// One element as a height in metres; NaN for a missing cell.
fn decode(kind: Kind, little: bool, b: &[u8]) -> f32 {
    let mut raw = [0u8; 8];
    raw[..b.len()].copy_from_slice(b);
    if !little {
        raw[..b.len()].reverse();
    }
    match kind {
        Kind::I8 => f32::from(raw[0] as i8),
        Kind::U8 => f32::from(raw[0]),
        Kind::I16 => match i16::from_le_bytes([raw[0], raw[1]]) {
            i16::MIN => f32::NAN,
            v => f32::from(v),
        },
        Kind::U16 => f32::from(u16::from_le_bytes([raw[0], raw[1]])),
        Kind::I32 => match i32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]) {
            i32::MIN => f32::NAN,
            v => v as f32,
        },
        Kind::U32 => u32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]) as f32,
        Kind::F32 => f32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]),
        Kind::F64 => f64::from_le_bytes(raw) as f32,
    }
}

/// `'<f4'` to (little-endian, kind).
fn parse_descr(descr: &str) -> Option<(bool, Kind)> {
    let mut chars = descr.chars();
    let order = chars.next()?;
    let rest = chars.as_str();
    let kind = match rest {
        "i1" => Kind::I8,
        "u1" => Kind::U8,
        "i2" => Kind::I16,
        "u2" => Kind::U16,
        "i4" => Kind::I32,
        "u4" => Kind::U32,
        "f4" => Kind::F32,
        "f8" => Kind::F64,
        _ => return None,
    };
    let little = match order {
        '<' => true,
        '>' => false,
        '|' if kind.size() == 1 => true,
        '=' => cfg!(target_endian = "little"),
        _ => return None,
    };
    Some((little, kind))
}

/// Parses the header, a Python dict literal such as
/// `{'descr': '<f4', 'fortran_order': False, 'shape': (3, 4), }`.
fn parse_header(text: &str) -> Result<Header, String> {
    let mut p = Literal {
        s: text.as_bytes(),
        i: 0,
    };
    let mut descr = None;
    let mut fortran_order = None;
    let mut shape = None;
    p.expect(b'{')?;
    loop {
        p.skip_ws();
        if p.eat(b'}') {
            break;
        }
        let key = p.string()?;
        p.expect(b':')?;
        match key.as_str() {
            "descr" => {
                p.skip_ws();
                if p.peek() != Some(b'\'') && p.peek() != Some(b'"') {
                    return Err(
                        "'descr' is not a simple dtype string (structured arrays are \
                                not heightfields)"
                            .to_owned(),
                    );
                }
                descr = Some(p.string()?);
            }
            "fortran_order" => fortran_order = Some(p.boolean()?),
            "shape" => shape = Some(p.tuple()?),
            other => return Err(format!("unexpected key '{other}'")),
        }
        p.skip_ws();
        if !p.eat(b',') {
            p.expect(b'}')?;
            break;
        }
    }
    Ok(Header {
        descr: descr.ok_or("no 'descr'")?,
        fortran_order: fortran_order.ok_or("no 'fortran_order'")?,
        shape: shape.ok_or("no 'shape'")?,
    })
}

/// A cursor over a Python literal.
struct Literal<'a> {
    s: &'a [u8],
    i: usize,
}

impl Literal<'_> {
    fn peek(&self) -> Option<u8> {
        self.s.get(self.i).copied()
    }

    fn skip_ws(&mut self) {
        while self.peek().is_some_and(|c| c.is_ascii_whitespace()) {
            self.i += 1;
        }
    }

    fn eat(&mut self, c: u8) -> bool {
        self.skip_ws();
        if self.peek() == Some(c) {
            self.i += 1;
            true
        } else {
            false
        }
    }

    fn expect(&mut self, c: u8) -> Result<(), String> {
        if self.eat(c) {
            Ok(())
        } else {
            Err(format!(
                "expected '{}' at byte {} of the header dictionary",
                char::from(c),
                self.i
            ))
        }
    }

    fn string(&mut self) -> Result<String, String> {
        self.skip_ws();
        let quote = match self.peek() {
            Some(q @ (b'\'' | b'"')) => q,
            _ => return Err(format!("expected a string at byte {}", self.i)),
        };
        self.i += 1;
        let start = self.i;
        while let Some(c) = self.peek() {
            if c == quote {
                let s = String::from_utf8_lossy(&self.s[start..self.i]).into_owned();
                self.i += 1;
                return Ok(s);
            }
            self.i += 1;
        }
        Err("unterminated string".to_owned())
    }

    fn boolean(&mut self) -> Result<bool, String> {
        self.skip_ws();
        let rest = &self.s[self.i..];
        if rest.starts_with(b"True") {
            self.i += 4;
            Ok(true)
        } else if rest.starts_with(b"False") {
            self.i += 5;
            Ok(false)
        } else {
            Err(format!("expected True or False at byte {}", self.i))
        }
    }

    fn tuple(&mut self) -> Result<Vec<u64>, String> {
        self.expect(b'(')?;
        let mut values = Vec::new();
        loop {
            if self.eat(b')') {
                return Ok(values);
            }
            self.skip_ws();
            let start = self.i;
            while self.peek().is_some_and(|c| c.is_ascii_digit()) {
                self.i += 1;
            }
            // Python 2 headers may write long integers as `3L`.
            let digits = std::str::from_utf8(&self.s[start..self.i]).unwrap_or("");
            let value = digits
                .parse::<u64>()
                .map_err(|_| format!("expected a dimension at byte {start}"))?;
            values.push(value);
            self.eat(b'L');
            if !self.eat(b',') {
                self.expect(b')')?;
                return Ok(values);
            }
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// An npy file (version 1.0) with the given dtype, shape and raw data.
    pub(crate) fn npy_bytes(descr: &str, fortran: bool, shape: &str, data: &[u8]) -> Vec<u8> {
        let mut dict = format!(
            "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
            if fortran { "True" } else { "False" }
        );
        while (10 + dict.len() + 1) % 64 != 0 {
            dict.push(' ');
        }
        dict.push('\n');
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
        out.extend_from_slice(dict.as_bytes());
        out.extend_from_slice(data);
        out
    }

    fn src() -> Source {
        Source {
            name: "h.npy".to_owned(),
        }
    }

    #[test]
    fn parses_header_dictionaries() {
        let h =
            parse_header("{'descr': '<i2', 'fortran_order': False, 'shape': (3, 4), }").unwrap();
        assert_eq!(h.descr, "<i2");
        assert!(!h.fortran_order);
        assert_eq!(h.shape, vec![3, 4]);
        let h =
            parse_header("{\"shape\": (7,), \"fortran_order\": True, \"descr\": \">f8\"}").unwrap();
        assert_eq!(h.shape, vec![7]);
        assert!(h.fortran_order);
        assert_eq!(h.descr, ">f8");
        assert_eq!(
            parse_header("{'shape': (2L, 3L), 'fortran_order': False, 'descr': '<f4'}")
                .unwrap()
                .shape,
            vec![2, 3]
        );
        assert!(
            parse_header("{'descr': [('a', '<f4')], 'fortran_order': False, 'shape': (2,)}")
                .is_err()
        );
        assert!(parse_header("{'descr': '<f4', 'shape': (2, 3)").is_err());
        assert!(parse_header("").is_err());
    }

    #[test]
    fn decodes_every_dtype_and_byte_order() {
        let v: i16 = -1234;
        for (descr, bytes) in [
            ("<i2", v.to_le_bytes().to_vec()),
            (">i2", v.to_be_bytes().to_vec()),
            ("<f4", (-1234.0f32).to_le_bytes().to_vec()),
            (">f4", (-1234.0f32).to_be_bytes().to_vec()),
            ("<f8", (-1234.0f64).to_le_bytes().to_vec()),
            (">i4", (-1234i32).to_be_bytes().to_vec()),
        ] {
            let file = npy_bytes(descr, false, "(1, 1)", &bytes);
            let g = parse_npy(&src(), &file, 1.0).unwrap();
            assert_eq!(g.heights, vec![-1234.0], "{descr}");
        }
        let g = parse_npy(&src(), &npy_bytes("|u1", false, "(1, 2)", &[7, 250]), 1.0).unwrap();
        assert_eq!(g.heights, vec![7.0, 250.0]);
        let file = npy_bytes("<i2", false, "(1, 1)", &i16::MIN.to_le_bytes());
        assert!(parse_npy(&src(), &file, 1.0).unwrap().heights[0].is_nan());
    }

    #[test]
    fn rejects_bad_files() {
        let err = |bytes: &[u8]| parse_npy(&src(), bytes, 1.0).err().unwrap().to_string();
        assert!(err(b"not numpy").contains("no \\x93NUMPY magic"));
        assert!(err(&npy_bytes("<f4", true, "(1, 1)", &[0; 4])).contains("fortran_order"));
        assert!(err(&npy_bytes("<f4", false, "(2, 2, 2)", &[0; 32])).contains("2-D"));
        assert!(err(&npy_bytes("<c8", false, "(1, 1)", &[0; 8])).contains("dtype '<c8'"));
        assert!(err(&npy_bytes("<f4", false, "(2, 2)", &[0; 15])).contains("truncated"));
        assert!(err(&npy_bytes("<f4", false, "(2, 2)", &[0; 17])).contains("17 bytes"));
        let huge = npy_bytes("<f8", false, "(4294967296, 4294967296)", &[]);
        assert!(err(&huge).contains("too large") || err(&huge).contains("truncated"));
        let mut cut = npy_bytes("<f4", false, "(1, 1)", &[0; 4]);
        cut.truncate(30);
        assert!(err(&cut).contains("truncated"), "{}", err(&cut));
        let mut v9 = npy_bytes("<f4", false, "(1, 1)", &[0; 4]);
        v9[6] = 9;
        assert!(err(&v9).contains("format version 9.0"));
    }
}
