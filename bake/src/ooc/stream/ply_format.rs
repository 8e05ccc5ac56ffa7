//! What the streaming PLY reader reads with: the header's elements and properties, and
//! reading one element item (ascii or binary) or a run of bytes. The scalar types and the
//! vertex slots are the in-core importer's too ([`crate::base::ply`]).

use std::fs::File;
use std::io::{self, BufRead, BufReader, Read};

use crate::base::ply::Scalar;

/// A vertex property read at a fixed offset: (offset, type, slot, colour scale).
pub(super) type Field = (usize, Scalar, usize, f64);

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
