//! The PLY header, read up to `end_header`, and the layout the reader takes from it: which
//! elements hold the vertices and faces, the vertex slot of each property, what the
//! triangles carry.

use std::fs::File;
use std::io::{BufRead, BufReader};

use crate::base::ply::{vertex_slot, Scalar};
use crate::ooc::error::OocError;
use crate::ooc::soup::{HAS_COLOR, HAS_NORMAL, HAS_UV};
use crate::ooc::stream::ply_format::{Element, Format, Property};

/// The header: the format, the elements and a texture named in a comment.
pub(super) struct Header {
    pub(super) format: Format,
    pub(super) elements: Vec<Element>,
    pub(super) texture: Option<String>,
}

impl Header {
    /// Reads the header, up to and with its `end_header` line.
    pub(super) fn read(r: &mut BufReader<File>, name: &str) -> Result<Self, OocError> {
        let bad = |at: &str, message: String| OocError::input(name, at, message);
        let mut line = Vec::new();
        let mut lines = 0;
        let mut format = None;
        let mut elements: Vec<Element> = Vec::new();
        let mut texture = None;
        loop {
            line.clear();
            let n = r
                .read_until(b'\n', &mut line)
                .map_err(|e| OocError::io(name, "cannot read", e))?;
            lines += 1;
            if n == 0 {
                return Err(bad("header", "the file ends before 'end_header'".into()));
            }
            let text = String::from_utf8_lossy(&line);
            let words: Vec<&str> = text.split_ascii_whitespace().collect();
            let at = || format!("header line {lines}");
            match words.as_slice() {
                ["ply"] if lines == 1 => {}
                _ if lines == 1 => {
                    return Err(bad(
                        "header",
                        "not a PLY file (no 'ply' magic line); expected the first line 'ply'"
                            .into(),
                    ))
                }
                ["format", f, _] => {
                    format = Some(match *f {
                        "ascii" => Format::Ascii,
                        "binary_little_endian" => Format::Binary { big: false },
                        "binary_big_endian" => Format::Binary { big: true },
                        _ => return Err(bad(&at(), format!("unknown format '{f}'"))),
                    })
                }
                ["comment", "TextureFile", t, ..] => texture = Some(t.to_string()),
                ["comment", ..] | ["obj_info", ..] | [] => {}
                ["element", n, c] => elements.push(Element {
                    name: n.to_string(),
                    count: c
                        .parse()
                        .map_err(|_| bad(&at(), format!("bad element count '{c}'")))?,
                    properties: Vec::new(),
                }),
                ["property", "list", ct, ty, n] => {
                    let el = elements
                        .last_mut()
                        .ok_or_else(|| bad(&at(), "property before any element".into()))?;
                    let (Some(ct), Some(ty)) = (Scalar::parse(ct), Scalar::parse(ty)) else {
                        return Err(bad(&at(), format!("unknown type in '{}'", text.trim())));
                    };
                    el.properties.push(Property {
                        name: n.to_string(),
                        list: Some(ct),
                        ty,
                    });
                }
                ["property", ty, n] => {
                    let el = elements
                        .last_mut()
                        .ok_or_else(|| bad(&at(), "property before any element".into()))?;
                    let ty = Scalar::parse(ty)
                        .ok_or_else(|| bad(&at(), format!("unknown type '{ty}'")))?;
                    el.properties.push(Property {
                        name: n.to_string(),
                        list: None,
                        ty,
                    });
                }
                ["end_header"] => break,
                _ => return Err(bad(&at(), format!("cannot read '{}'", text.trim()))),
            }
        }
        let format = format.ok_or_else(|| bad("header", "no 'format' line".into()))?;
        Ok(Self {
            format,
            elements,
            texture,
        })
    }
}

/// Where the header puts what the reader needs.
pub(super) struct Layout {
    /// The vertex element.
    pub(super) vi: usize,
    /// The face element (after the vertex element).
    pub(super) fi: usize,
    /// The vertex slot of each vertex property (`None` for lists and unknown names).
    pub(super) vslots: Vec<Option<usize>>,
    /// What the triangles carry: `HAS_NORMAL`, `HAS_UV`, `HAS_COLOR`.
    pub(super) flags: u16,
    /// What each vertex property's colour values are divided by.
    pub(super) color_scale: Vec<f64>,
    /// The face property with the vertex indices.
    pub(super) face_list: usize,
}

impl Layout {
    pub(super) fn of(header: &Header, name: &str) -> Result<Self, OocError> {
        let bad = |at: &str, message: String| OocError::input(name, at, message);
        let elements = &header.elements;
        let vi = elements
            .iter()
            .position(|e| e.name == "vertex")
            .ok_or_else(|| bad("header", "no vertex element".into()))?;
        let fi = elements
            .iter()
            .position(|e| e.name == "face")
            .ok_or_else(|| bad("header", "no face element".into()))?;
        if fi < vi {
            return Err(OocError::Unsupported {
                file: name.to_string(),
                message: "faces before vertices cannot be streamed".into(),
            });
        }
        let vslots: Vec<Option<usize>> = elements[vi]
            .properties
            .iter()
            .map(|p| {
                if p.list.is_some() {
                    None
                } else {
                    vertex_slot(&p.name)
                }
            })
            .collect();
        let has = |s: usize| vslots.contains(&Some(s));
        if !(has(0) && has(1) && has(2)) {
            return Err(bad("header", "the vertex element lacks x, y or z".into()));
        }
        let mut flags = 0;
        if has(3) && has(4) && has(5) {
            flags |= HAS_NORMAL;
        }
        if has(6) && has(7) {
            flags |= HAS_UV;
        }
        if has(8) && has(9) && has(10) {
            flags |= HAS_COLOR;
        }
        let color_scale: Vec<f64> = elements[vi]
            .properties
            .iter()
            .map(|p| p.ty.color_scale())
            .collect();
        let face_list = elements[fi]
            .properties
            .iter()
            .position(|p| {
                p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index")
            })
            .ok_or_else(|| {
                bad(
                    "header",
                    "the face element has no vertex_indices list".into(),
                )
            })?;
        Ok(Self {
            vi,
            fi,
            vslots,
            flags,
            color_scale,
            face_list,
        })
    }
}
