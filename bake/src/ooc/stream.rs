//! Streaming readers: PLY (ascii and binary, either endianness) and OBJ to a triangle soup,
//! never holding the whole file.
//!
//! Indexed formats name vertices by number, so a triangle can only be written once its
//! corners are known. The readers first copy the vertex data into fixed-size records in a
//! temporary file (and take the bounding box on the way, which the spatial keys need), then
//! read the faces and look their corners up through a [`BlockCache`]: a direct-mapped cache
//! of blocks of that file whose size the memory budget sets. Real meshes (scanner output,
//! exported models, the generator's terrain) name nearby vertices in nearby faces, so the
//! cache hits almost always; a file whose faces jump around still works, only slower. This
//! is cheaper than dereferencing by external sorts (Lindstrom's OoCS) while bounded the same
//! way.
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

use std::collections::HashMap;
use std::fs::File;
use std::io::{self, BufRead, BufReader, Read, Write};
use std::os::unix::fs::FileExt;
use std::path::Path;

use bytemuck::Pod;

use super::soup::{encode_normal, Corner, Cube, SoupTriangle, HAS_COLOR, HAS_NORMAL, HAS_UV};
use super::temp::TempSpace;
use super::OocError;
use crate::mesh::Surface;

/// Receives the soup as a reader produces it.
pub trait SoupSink {
    /// Called once, before the first triangle: the input's bounding cube and its triangle
    /// count as far as the header tells (0 when unknown).
    fn start(&mut self, cube: &Cube, triangles_hint: u64) -> Result<(), OocError>;
    /// Room for one more triangle, which the caller fills in completely (its key too):
    /// readers build triangles in place, with no copy of the record on the way.
    fn slot(&mut self) -> Result<&mut SoupTriangle, OocError>;
    /// One triangle (its key already set).
    fn push(&mut self, t: &SoupTriangle) -> Result<(), OocError> {
        *self.slot()? = *t;
        Ok(())
    }
}

/// What a reader found besides the triangles.
#[derive(Clone, Debug, Default)]
pub struct StreamReport {
    /// Surfaces, indexed by [`SoupTriangle::surface`].
    pub surfaces: Vec<Surface>,
    /// Triangles produced.
    pub triangles: u64,
    /// Vertices read.
    pub vertices: u64,
    /// Faces with fewer than three corners, skipped.
    pub skipped_faces: u64,
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
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let open = || File::open(path).map_err(|source| OocError::io(&name, "cannot read", source));
    match ext.as_str() {
        "ply" => ply(&name, open()?, temp, cache_bytes, sink),
        "obj" => obj(&name, open, temp, cache_bytes, sink),
        _ => Err(OocError::Unsupported {
            file: name,
            message: format!(
                "out-of-core baking reads .ply and .obj files, not '.{ext}' (bake it in core)"
            ),
        }),
    }
}

/// Records per block of a [`BlockCache`].
const BLOCK_LEN: u64 = 1024;

/// A direct-mapped cache of fixed-size records in a file: blocks of [`BLOCK_LEN`] records in a
/// power-of-two number of slots (so a look-up is shifts and masks, no division).
pub struct BlockCache<T: Pod> {
    file: File,
    count: u64,
    mask: u64,
    tags: Vec<u64>,
    data: Vec<T>,
}

impl<T: Pod> BlockCache<T> {
    /// A cache of at most about `bytes` (at least two blocks) over `count` records in `file`.
    pub fn new(file: File, count: u64, bytes: usize) -> Self {
        let size = std::mem::size_of::<T>().max(1);
        let fit = (bytes / (size * BLOCK_LEN as usize)).max(2);
        let blocks = count.div_ceil(BLOCK_LEN).max(1) as usize;
        // The largest power of two that fits the budget, no larger than needed.
        let slots =
            (1usize << (usize::BITS - 1 - fit.leading_zeros())).min(blocks.next_power_of_two());
        Self {
            file,
            count,
            mask: slots as u64 - 1,
            tags: vec![u64::MAX; slots],
            data: vec![T::zeroed(); slots * BLOCK_LEN as usize],
        }
    }

    /// Record `i` (below the count).
    #[inline]
    pub fn get(&mut self, i: u64) -> io::Result<T> {
        self.get_ref(i).copied()
    }

    /// Record `i` (below the count), by reference: a record copied straight to where it goes
    /// is not moved through a `Result` on the stack.
    #[inline]
    pub fn get_ref(&mut self, i: u64) -> io::Result<&T> {
        let block = i / BLOCK_LEN;
        let slot = (block & self.mask) as usize;
        let bl = BLOCK_LEN as usize;
        if self.tags[slot] != block {
            self.load(block, slot)?;
        }
        Ok(&self.data[slot * bl + (i % BLOCK_LEN) as usize])
    }

    #[cold]
    fn load(&mut self, block: u64, slot: usize) -> io::Result<()> {
        let bl = BLOCK_LEN as usize;
        let start = block * BLOCK_LEN;
        let n = (self.count - start).min(BLOCK_LEN) as usize;
        let dst = &mut self.data[slot * bl..slot * bl + n];
        let size = std::mem::size_of::<T>() as u64;
        self.file
            .read_exact_at(bytemuck::cast_slice_mut(dst), start * size)?;
        self.tags[slot] = block;
        Ok(())
    }
}

// ---------------------------------------------------------------- PLY

/// A vertex property read at a fixed offset: (offset, type, slot, colour scale).
type Field = (usize, Scalar, usize, f64);

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
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
    fn parse(s: &str) -> Option<Self> {
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
    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }
    /// Divisor that maps the type's range to 0..=1, for colours.
    fn color_scale(self) -> f64 {
        match self {
            Self::U16 => 65535.0,
            Self::F32 | Self::F64 => 1.0,
            _ => 255.0,
        }
    }
    fn is_int(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }
    /// An integer type's value (a float type's, truncated).
    #[inline]
    fn decode_int(self, b: &[u8], big: bool) -> i64 {
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
    #[inline]
    fn decode(self, b: &[u8], big: bool) -> f64 {
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
struct Property {
    name: String,
    /// `Some(count type)` for lists.
    list: Option<Scalar>,
    ty: Scalar,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
}

#[derive(Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    Binary { big: bool },
}

/// Vertex slots: x y z nx ny nz u v r g b a.
fn slot(name: &str) -> Option<usize> {
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
struct ItemReader {
    format: Format,
    bytes: Vec<u8>,
    line: String,
    list: Vec<f64>,
}

impl ItemReader {
    fn read(
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

fn read_exact(r: &mut impl Read, buf: &mut Vec<u8>, n: usize) -> Result<(), String> {
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
fn with_bytes<T>(
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

fn ply(
    name: &str,
    file: File,
    temp: &TempSpace,
    cache_bytes: usize,
    sink: &mut dyn SoupSink,
) -> Result<StreamReport, OocError> {
    let bad = |at: &str, message: String| OocError::Input {
        file: name.to_string(),
        at: at.to_string(),
        message,
    };
    let mut r = BufReader::with_capacity(1 << 20, file);
    // Header.
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
            _ if lines == 1 => return Err(bad("header", "not a PLY file (no 'ply' line)".into())),
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
                let ty =
                    Scalar::parse(ty).ok_or_else(|| bad(&at(), format!("unknown type '{ty}'")))?;
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
                slot(&p.name)
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
        .position(|p| p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index"))
        .ok_or_else(|| {
            bad(
                "header",
                "the face element has no vertex_indices list".into(),
            )
        })?;

    let mut items = ItemReader {
        format,
        bytes: Vec::new(),
        line: String::new(),
        list: Vec::new(),
    };
    let skip = |r: &mut BufReader<File>, items: &mut ItemReader, el: &Element| {
        for i in 0..el.count {
            items
                .read(r, el, &mut |_, _, _| {})
                .map_err(|m| bad(&format!("{} {i}", el.name), m))?;
        }
        Ok::<(), OocError>(())
    };
    for el in &elements[..vi] {
        skip(&mut r, &mut items, el)?;
    }
    // Vertices to fixed records.
    let vcount = elements[vi].count;
    let mut vfile = temp
        .create("vertices", 1 << 16)
        .map_err(|e| OocError::temp("creating the vertex file", e))?;
    let verr = |e| OocError::temp("writing the vertex file", e);
    // Records go to the file a block at a time (one write call, one quota check).
    let mut block: Vec<Corner> = Vec::with_capacity(1 << 14);
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    let mut v = [0f64; 12];
    // Binary vertices without lists have a fixed stride: one read, decodes at offsets.
    let fixed: Option<(usize, Vec<Field>)> = match format {
        Format::Binary { .. } if elements[vi].properties.iter().all(|p| p.list.is_none()) => {
            let mut offset = 0;
            let mut fields = Vec::new();
            for (k, p) in elements[vi].properties.iter().enumerate() {
                if let Some(s) = vslots[k] {
                    fields.push((offset, p.ty, s, color_scale[k]));
                }
                offset += p.ty.size();
            }
            Some((offset, fields))
        }
        _ => None,
    };
    let big = format == Format::Binary { big: true };
    let mut record = Vec::new();
    for i in 0..vcount {
        v = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
        match &fixed {
            Some((stride, fields)) => {
                with_bytes(&mut r, &mut record, *stride, |b| {
                    for &(offset, ty, s, scale) in fields {
                        let x = ty.decode(&b[offset..], big);
                        v[s] = if s >= 8 { x / scale } else { x };
                    }
                })
                .map_err(|m| bad(&format!("vertex {i}"), m))?;
            }
            None => items
                .read(&mut r, &elements[vi], &mut |p, x, _| {
                    if let Some(s) = vslots[p] {
                        v[s] = if s >= 8 { x / color_scale[p] } else { x };
                    }
                })
                .map_err(|m| bad(&format!("vertex {i}"), m))?,
        }
        if v.iter().any(|x| !x.is_finite()) {
            return Err(bad(&format!("vertex {i}"), "a number is not finite".into()));
        }
        let p = [v[0] as f32, v[1] as f32, v[2] as f32];
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
        let c8 = |x: f64| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
        block.push(Corner {
            position: p,
            uv: [v[6] as f32, 1.0 - v[7] as f32],
            normal: encode_normal([v[3] as f32, v[4] as f32, v[5] as f32]),
            color: [c8(v[8]), c8(v[9]), c8(v[10]), c8(v[11])],
        });
        if block.len() == block.capacity() {
            vfile
                .write_all(bytemuck::cast_slice(&block))
                .map_err(verr)?;
            block.clear();
        }
    }
    let _ = v;
    vfile
        .write_all(bytemuck::cast_slice(&block))
        .map_err(verr)?;
    drop(block);
    let vpath = vfile.finish().map_err(verr)?;
    if vcount == 0 {
        return Err(OocError::Empty {
            file: name.to_string(),
        });
    }
    let cube = Cube::around(lo, hi);
    let keyer = cube.keyer();
    sink.start(&cube, elements[fi].count)?;
    let vf = File::open(&vpath).map_err(|e| OocError::temp("reading the vertex file", e))?;
    let mut cache = BlockCache::<Corner>::new(vf, vcount, cache_bytes);
    for el in &elements[vi + 1..fi] {
        skip(&mut r, &mut items, el)?;
    }
    let mut report = StreamReport {
        surfaces: vec![Surface {
            name: "default".into(),
            base_color: [1.0; 4],
            texture,
        }],
        vertices: vcount,
        ..Default::default()
    };
    // Binary faces whose only property is an integer index list (the usual layout): counts
    // and indices decoded as integers straight from the read buffer.
    let int_list = match (format, elements[fi].properties.as_slice()) {
        (
            Format::Binary { big },
            [Property {
                list: Some(ct), ty, ..
            }],
        ) if ct.is_int() && ty.is_int() => Some((big, *ct, *ty)),
        _ => None,
    };
    let mut raw: Vec<i64> = Vec::new();
    let mut idx: Vec<u64> = Vec::new();
    for f in 0..elements[fi].count {
        let at = || format!("face {f}");
        raw.clear();
        match int_list {
            Some((big, ct, ty)) => {
                let n = with_bytes(&mut r, &mut record, ct.size(), |b| ct.decode_int(b, big))
                    .map_err(|m| bad(&at(), m))?;
                if !(0..=1_000_000).contains(&n) {
                    let list = &elements[fi].properties[0].name;
                    return Err(bad(&at(), format!("list '{list}' has {n} entries")));
                }
                let s = ty.size();
                with_bytes(&mut r, &mut record, n as usize * s, |b| {
                    raw.extend(b.chunks_exact(s).map(|c| ty.decode_int(c, big)));
                })
                .map_err(|m| bad(&at(), m))?;
            }
            None => {
                let mut fraction = None;
                items
                    .read(&mut r, &elements[fi], &mut |p, _, list| {
                        if p == face_list {
                            for &i in list {
                                if i.fract() != 0.0 || !i.is_finite() {
                                    fraction = Some(i);
                                }
                                raw.push(i as i64);
                            }
                        }
                    })
                    .map_err(|m| bad(&at(), m))?;
                if let (Some(i), 3..) = (fraction, raw.len()) {
                    return Err(bad(
                        &at(),
                        format!("vertex index {i} out of range ({vcount} vertices)"),
                    ));
                }
            }
        }
        if raw.len() < 3 {
            report.skipped_faces += 1;
            continue;
        }
        idx.clear();
        for &i in &raw {
            if i < 0 || i as u64 >= vcount {
                return Err(bad(
                    &at(),
                    format!("vertex index {i} out of range ({vcount} vertices)"),
                ));
            }
            idx.push(i as u64);
        }
        let terr = |e| OocError::temp("reading the vertex file", e);
        for k in 1..idx.len() - 1 {
            let t = sink.slot()?;
            t.surface = 0;
            t.flags = flags;
            t.corners[0] = *cache.get_ref(idx[0]).map_err(terr)?;
            t.corners[1] = *cache.get_ref(idx[k]).map_err(terr)?;
            t.corners[2] = *cache.get_ref(idx[k + 1]).map_err(terr)?;
            t.key = keyer.key(&t.corners.map(|c| c.position));
            report.triangles += 1;
        }
    }
    drop(cache);
    let _ = std::fs::remove_file(&vpath);
    Ok(report)
}

// ---------------------------------------------------------------- OBJ

fn obj(
    name: &str,
    open: impl Fn() -> Result<File, OocError>,
    temp: &TempSpace,
    cache_bytes: usize,
    sink: &mut dyn SoupSink,
) -> Result<StreamReport, OocError> {
    let bad = |line: u64, message: String| OocError::Input {
        file: name.to_string(),
        at: format!("line {line}"),
        message,
    };
    let tw = |e| OocError::temp("writing OBJ records", e);
    let mut pw = temp.create("obj-v", 1 << 20).map_err(tw)?;
    let mut tw_ = temp.create("obj-vt", 1 << 18).map_err(tw)?;
    let mut nw = temp.create("obj-vn", 1 << 18).map_err(tw)?;
    let (mut np, mut nt, mut nn) = (0u64, 0u64, 0u64);
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    let mut faces_hint = 0u64;
    let mut colors = false;
    let floats = |line: u64, rest: &str, min: usize, max: usize| -> Result<Vec<f32>, OocError> {
        let v: Vec<f32> = rest
            .split_ascii_whitespace()
            .take(max)
            .map(|t| t.parse::<f32>().ok().filter(|x| x.is_finite()))
            .collect::<Option<_>>()
            .ok_or_else(|| bad(line, format!("bad number in '{}'", rest.trim())))?;
        if v.len() < min {
            return Err(bad(
                line,
                format!("expected {min} numbers, got '{}'", rest.trim()),
            ));
        }
        Ok(v)
    };
    let read_lines = |pass: &mut dyn FnMut(u64, &str) -> Result<(), OocError>| {
        let mut r = BufReader::with_capacity(1 << 20, open()?);
        let mut s = String::new();
        let mut n = 0u64;
        loop {
            s.clear();
            let k = r
                .read_line(&mut s)
                .map_err(|e| OocError::io(name, "cannot read", e))?;
            if k == 0 {
                return Ok::<(), OocError>(());
            }
            n += 1;
            pass(n, s.trim())?;
        }
    };
    read_lines(&mut |n, s| {
        if let Some(rest) = s.strip_prefix("v ") {
            let v = floats(n, rest, 3, 6)?;
            let p = [v[0], v[1], v[2]];
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
            let c8 = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
            let color = if v.len() >= 6 {
                colors = true;
                [c8(v[3]), c8(v[4]), c8(v[5]), 255]
            } else {
                [255; 4]
            };
            let c = Corner {
                position: p,
                color,
                ..Default::default()
            };
            pw.write_all(bytemuck::bytes_of(&c)).map_err(tw)?;
            np += 1;
        } else if let Some(rest) = s.strip_prefix("vt ") {
            let v = floats(n, rest, 1, 2)?;
            let uv = [v[0], 1.0 - v.get(1).copied().unwrap_or(0.0)];
            tw_.write_all(bytemuck::bytes_of(&uv)).map_err(tw)?;
            nt += 1;
        } else if let Some(rest) = s.strip_prefix("vn ") {
            let v = floats(n, rest, 3, 3)?;
            nw.write_all(bytemuck::bytes_of(&encode_normal([v[0], v[1], v[2]])))
                .map_err(tw)?;
            nn += 1;
        } else if s.starts_with("f ") {
            faces_hint += 1;
        }
        Ok(())
    })?;
    if np == 0 {
        return Err(OocError::Empty {
            file: name.to_string(),
        });
    }
    let paths = [pw.finish(), tw_.finish(), nw.finish()];
    let [pp, tp, npth] = paths;
    let (pp, tp, npth) = (pp.map_err(tw)?, tp.map_err(tw)?, npth.map_err(tw)?);
    let rd = |p: &Path| File::open(p).map_err(|e| OocError::temp("reading OBJ records", e));
    let mut pc = BlockCache::<Corner>::new(rd(&pp)?, np, cache_bytes / 2);
    let mut tc = BlockCache::<[f32; 2]>::new(rd(&tp)?, nt, cache_bytes / 4);
    let mut nc = BlockCache::<[i16; 2]>::new(rd(&npth)?, nn, cache_bytes / 4);
    let cube = Cube::around(lo, hi);
    let keyer = cube.keyer();
    sink.start(&cube, faces_hint)?;
    let mut report = StreamReport {
        vertices: np,
        ..Default::default()
    };
    let mut surface_ids: HashMap<String, u16> = HashMap::new();
    let mut surface = None::<u16>;
    let (mut seen_p, mut seen_t, mut seen_n) = (0u64, 0u64, 0u64);
    let mut corners: Vec<(Corner, u16)> = Vec::new();
    let mut surfaces: Vec<Surface> = Vec::new();
    read_lines(&mut |n, s| {
        let resolve = |t: &str, seen: u64, what: &str| -> Result<Option<u64>, OocError> {
            if t.is_empty() {
                return Ok(None);
            }
            let i: i64 = t
                .parse()
                .map_err(|_| bad(n, format!("bad {what} index '{t}'")))?;
            let r = if i < 0 { seen as i64 + i } else { i - 1 };
            if i == 0 || r < 0 || r as u64 >= seen {
                return Err(bad(
                    n,
                    format!("{what} index {i} out of range ({seen} so far)"),
                ));
            }
            Ok(Some(r as u64))
        };
        if s.starts_with("v ") {
            seen_p += 1;
        } else if s.starts_with("vt ") {
            seen_t += 1;
        } else if s.starts_with("vn ") {
            seen_n += 1;
        } else if let Some(rest) = s.strip_prefix("usemtl") {
            let m = rest.trim().to_string();
            let next = surfaces.len();
            let id = *surface_ids.entry(m.clone()).or_insert_with(|| {
                surfaces.push(Surface {
                    name: m,
                    base_color: [1.0; 4],
                    texture: None,
                });
                next as u16
            });
            if surfaces.len() > usize::from(u16::MAX) {
                return Err(OocError::Unsupported {
                    file: name.to_string(),
                    message: "more than 65,535 materials".into(),
                });
            }
            surface = Some(id);
        } else if let Some(rest) = s.strip_prefix("f ") {
            corners.clear();
            for tok in rest.split_ascii_whitespace() {
                let mut parts = tok.split('/');
                let p = resolve(parts.next().unwrap_or(""), seen_p, "vertex")?
                    .ok_or_else(|| bad(n, format!("corner '{tok}' has no vertex")))?;
                let t = resolve(parts.next().unwrap_or(""), seen_t, "texture coordinate")?;
                let nm = resolve(parts.next().unwrap_or(""), seen_n, "normal")?;
                let terr = |e| OocError::temp("reading OBJ records", e);
                let mut c = pc.get(p).map_err(terr)?;
                let mut f = 0;
                if let Some(t) = t {
                    c.uv = tc.get(t).map_err(terr)?;
                    f |= HAS_UV;
                }
                if let Some(nm) = nm {
                    c.normal = nc.get(nm).map_err(terr)?;
                    f |= HAS_NORMAL;
                }
                corners.push((c, f));
            }
            if corners.len() < 3 {
                report.skipped_faces += 1;
                return Ok(());
            }
            let sid = match surface {
                Some(s) => s,
                None => {
                    let id = *surface_ids.entry(String::new()).or_insert_with(|| {
                        surfaces.push(Surface {
                            name: "default".into(),
                            base_color: [1.0; 4],
                            texture: None,
                        });
                        (surfaces.len() - 1) as u16
                    });
                    surface = Some(id);
                    id
                }
            };
            let color = if colors { HAS_COLOR } else { 0 };
            for k in 1..corners.len() - 1 {
                let tri = [corners[0], corners[k], corners[k + 1]];
                let flags = tri[0].1 & tri[1].1 & tri[2].1 | color;
                let t = SoupTriangle {
                    key: keyer.key(&tri.map(|c| c.0.position)),
                    surface: sid,
                    flags,
                    corners: tri.map(|c| c.0),
                };
                sink.push(&t)?;
                report.triangles += 1;
            }
        }
        Ok(())
    })?;
    report.surfaces = surfaces;
    Ok(report)
}
