//! The PLY reader: the header, the vertices to fixed records in a temporary file, then the
//! faces, their corners looked up through a [`BlockCache`].

use std::fs::File;
use std::io::{BufRead, BufReader, Seek, SeekFrom, Write};
use std::os::unix::fs::FileExt;
use std::path::PathBuf;

use super::cache::{BlockCache, RecordSource};
use super::ply_format::{with_bytes, Field, Format, ItemReader, Property};
use super::sink::{SoupSink, StreamReport};
use crate::base::ply::{Scalar, VERTEX_NAMES};
use crate::base::temp::{SpillWriter, TempSpace};
use crate::mesh::{Surface, Texture};
use crate::ooc::error::OocError;
use crate::ooc::soup::{encode_normal, Corner, Cube};

mod header;

use header::{Header, Layout};

/// A PLY file whose vertices are in a temporary file: the faces can be read any number of
/// times, from their offset in the file.
pub(super) struct PlyInput<'a> {
    reader: Reader<'a>,
    cache: BlockCache<Corner, VertexSource>,
    cube: Cube,
    /// Byte offset of the first item after the vertex element's (where the faces' reading
    /// starts).
    after_vertices: u64,
    surfaces: Vec<Surface>,
    vertices: u64,
}

impl<'a> PlyInput<'a> {
    /// Reads the header and the vertices of the PLY file `file` (named `name` in errors).
    pub(super) fn open(
        name: &'a str,
        file: File,
        temp: &TempSpace,
        cache_bytes: usize,
    ) -> Result<Self, OocError> {
        let direct = file
            .try_clone()
            .map_err(|e| OocError::io(name, "cannot read", e))?;
        let mut reader = Reader::new(name, file)?;
        let vi = reader.layout.vi;
        reader.skip(0..vi)?;
        let vertices = reader.header.elements[vi].count;
        let pos = |r: &mut Reader| {
            r.r.stream_position()
                .map_err(|e| OocError::io(name, "cannot read", e))
        };
        let vertices_at = pos(&mut reader)?;
        let (stored, cube) = reader.write_vertices(temp)?;
        if vertices == 0 {
            return Err(OocError::Empty {
                file: name.to_string(),
            });
        }
        let after_vertices = pos(&mut reader)?;
        let source = match stored {
            Stored::File(vpath) => {
                let vf =
                    File::open(&vpath).map_err(|e| OocError::temp("reading the vertex file", e))?;
                // The open file keeps the records readable; the name can go now.
                let _ = std::fs::remove_file(&vpath);
                VertexSource::Records(vf)
            }
            Stored::Input(stride, fields) => VertexSource::Input(FixedVertices {
                file: direct,
                start: vertices_at,
                stride,
                position_fields: fields.iter().filter(|f| f.2 < 3).copied().collect(),
                fields,
                big: reader.header.format == Format::Binary { big: true },
                positions_only: false,
                bytes: Vec::new(),
            }),
        };
        let surfaces = vec![Surface {
            texture: reader.header.texture.take().map(Texture::File),
            ..Surface::plain("default")
        }];
        Ok(Self {
            reader,
            cache: BlockCache::new(source, vertices, cache_bytes),
            cube,
            after_vertices,
            surfaces,
            vertices,
        })
    }

    /// Streams the faces into `sink`.
    pub(super) fn faces(&mut self, sink: &mut dyn SoupSink) -> Result<StreamReport, OocError> {
        let r = &mut self.reader;
        r.r.seek(SeekFrom::Start(self.after_vertices))
            .map_err(|e| OocError::io(r.name, "cannot read", e))?;
        let (vi, fi) = (r.layout.vi, r.layout.fi);
        sink.start(&self.cube, r.header.elements[fi].count)?;
        let positions_only = sink.positions_only();
        if let VertexSource::Input(v) = self.cache.source_mut() {
            if v.positions_only != positions_only {
                v.positions_only = positions_only;
                self.cache.clear();
            }
        }
        r.skip(vi + 1..fi)?;
        let mut report = StreamReport {
            surfaces: self.surfaces.clone(),
            vertices: self.vertices,
            ..Default::default()
        };
        r.read_faces(&self.cube, &mut self.cache, sink, &mut report)?;
        Ok(report)
    }
}

/// The reader past the header.
struct Reader<'a> {
    name: &'a str,
    r: BufReader<File>,
    items: ItemReader,
    /// Scratch space for byte runs that straddle a refill of `r`.
    record: Vec<u8>,
    header: Header,
    layout: Layout,
}

impl<'a> Reader<'a> {
    /// Reads the header of the PLY file `file` (named `name` in errors) and stands at its
    /// first item.
    fn new(name: &'a str, file: File) -> Result<Self, OocError> {
        let mut r = BufReader::with_capacity(1 << 20, file);
        let header = Header::read(&mut r, name)?;
        let layout = Layout::of(&header, name)?;
        Ok(Reader {
            name,
            r,
            items: ItemReader {
                format: header.format,
                bytes: Vec::new(),
                line: String::new(),
                list: Vec::new(),
            },
            record: Vec::new(),
            header,
            layout,
        })
    }

    fn bad(&self, at: &str, message: String) -> OocError {
        OocError::input(self.name, at, message)
    }

    /// Reads past the items of the elements `range`.
    fn skip(&mut self, range: std::ops::Range<usize>) -> Result<(), OocError> {
        for el in &self.header.elements[range] {
            for i in 0..el.count {
                self.items
                    .read(&mut self.r, el, &mut |_, _, _| {})
                    .map_err(|m| OocError::input(self.name, &format!("{} {i}", el.name), m))?;
            }
        }
        Ok(())
    }

    /// Binary vertices without lists have a fixed stride: one read, decodes at offsets.
    fn fixed_vertex(&self) -> Option<(usize, Vec<Field>)> {
        let vertex = &self.header.elements[self.layout.vi];
        match self.header.format {
            Format::Binary { .. } if vertex.properties.iter().all(|p| p.list.is_none()) => {
                let mut offset = 0;
                let mut fields = Vec::new();
                for (k, p) in vertex.properties.iter().enumerate() {
                    if let Some(s) = self.layout.vslots[k] {
                        fields.push((offset, p.ty, s, self.layout.color_scale[k]));
                    }
                    offset += p.ty.size();
                }
                Some((offset, fields))
            }
            _ => None,
        }
    }

    /// The vertices checked and bounded; those without a fixed stride copied to fixed
    /// records in a temporary file (those with one are read from the input itself, decoded
    /// as they come into the cache: nothing to write). Returns where they are and their
    /// bounding cube.
    fn write_vertices(&mut self, temp: &TempSpace) -> Result<(Stored, Cube), OocError> {
        /// Where the vertices go.
        enum Dest {
            /// Nowhere: they stay in the input, at this stride, these fields decoded.
            Input(usize, Vec<Field>),
            /// To records in this file, through this block.
            File(SpillWriter, Vec<Corner>),
        }
        let vi = self.layout.vi;
        let vcount = self.header.elements[vi].count;
        let verr = |e| OocError::temp("writing the vertex file", e);
        let mut dest = match self.fixed_vertex() {
            Some((stride, fields)) => Dest::Input(stride, fields),
            // Records go to the file a block at a time (one write call, one quota check).
            None => Dest::File(
                temp.create("vertices", 1 << 16)
                    .map_err(|e| OocError::temp("creating the vertex file", e))?,
                Vec::with_capacity(1 << 14),
            ),
        };
        let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
        let big = self.header.format == Format::Binary { big: true };
        let Layout {
            vslots,
            color_scale,
            ..
        } = &self.layout;
        for i in 0..vcount {
            let mut v = NO_SLOTS;
            match &dest {
                Dest::Input(stride, fields) => {
                    with_bytes(&mut self.r, &mut self.record, *stride, |b| {
                        decode_fixed(b, fields, big, &mut v);
                    })
                    .map_err(|m| OocError::input(self.name, &format!("vertex {i}"), m))?;
                }
                Dest::File(..) => self
                    .items
                    .read(&mut self.r, &self.header.elements[vi], &mut |p, x, _| {
                        if let Some(s) = vslots[p] {
                            v[s] = if s >= 8 {
                                x * (1.0 / color_scale[p])
                            } else {
                                x
                            };
                        }
                    })
                    .map_err(|m| OocError::input(self.name, &format!("vertex {i}"), m))?,
            }
            if let Some(k) = v.iter().position(|x| !x.is_finite()) {
                return Err(self.bad(
                    &format!("vertex {i}"),
                    format!("{} is {}", VERTEX_NAMES[k], v[k]),
                ));
            }
            let p = [v[0] as f32, v[1] as f32, v[2] as f32];
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
            if let Dest::File(vfile, block) = &mut dest {
                block.push(corner(p, &v));
                if block.len() == block.capacity() {
                    vfile.write_all(bytemuck::cast_slice(block)).map_err(verr)?;
                    block.clear();
                }
            }
        }
        let stored = match dest {
            Dest::Input(stride, fields) => Stored::Input(stride, fields),
            Dest::File(mut vfile, block) => {
                vfile
                    .write_all(bytemuck::cast_slice(&block))
                    .map_err(verr)?;
                Stored::File(vfile.finish().map_err(verr)?)
            }
        };
        Ok((stored, Cube::around(lo, hi)))
    }

    /// The faces, each a fan of triangles whose corners come from `cache`, into `sink`.
    fn read_faces(
        &mut self,
        cube: &Cube,
        cache: &mut BlockCache<Corner, VertexSource>,
        sink: &mut dyn SoupSink,
        report: &mut StreamReport,
    ) -> Result<(), OocError> {
        let keyer = cube.keyer();
        let fi = self.layout.fi;
        let vcount = report.vertices;
        let int_list = self.int_list();
        let mut raw: Vec<i64> = Vec::new();
        for f in 0..self.header.elements[fi].count {
            let at = || format!("face {f}");
            self.face_indices(f, int_list, &mut raw)?;
            if raw.len() < 3 {
                report.skipped_faces += 1;
                continue;
            }
            if let Some(&i) = raw.iter().find(|&&i| i < 0 || i as u64 >= vcount) {
                return Err(self.bad(
                    &at(),
                    format!("vertex index {i} out of range ({vcount} vertices)"),
                ));
            }
            // Every index is in range: the casts are exact.
            let idx = |k: usize| raw[k] as u64;
            let terr = |e| OocError::temp("reading the vertex file", e);
            for k in 1..raw.len() - 1 {
                let t = sink.slot()?;
                t.surface = 0;
                t.flags = self.layout.flags;
                t.corners[0] = *cache.get_ref(idx(0)).map_err(terr)?;
                t.corners[1] = *cache.get_ref(idx(k)).map_err(terr)?;
                t.corners[2] = *cache.get_ref(idx(k + 1)).map_err(terr)?;
                t.key = keyer.key(&t.corners.map(|c| c.position));
                report.triangles += 1;
            }
        }
        Ok(())
    }

    /// Binary faces whose only property is an integer index list (the usual layout): their
    /// counts and indices are decoded as integers straight from the read buffer.
    fn int_list(&self) -> Option<(bool, Scalar, Scalar)> {
        match (
            self.header.format,
            self.header.elements[self.layout.fi].properties.as_slice(),
        ) {
            (
                Format::Binary { big },
                [Property {
                    list: Some(ct), ty, ..
                }],
            ) if ct.is_int() && ty.is_int() => Some((big, *ct, *ty)),
            _ => None,
        }
    }

    /// The vertex indices of a binary face whose count and indices are all in the read
    /// buffer into `raw`, consumed in one step (the common case: one buffer look-up a face);
    /// false, with nothing read, when they are not there or the count is out of range (the
    /// general path then reads them, or names the error).
    #[inline]
    fn face_from_buffer(&mut self, big: bool, ct: Scalar, ty: Scalar, raw: &mut Vec<i64>) -> bool {
        let (cs, s) = (ct.size(), ty.size());
        let buf = self.r.buffer();
        let Some(head) = buf.get(..cs) else {
            return false;
        };
        let n = ct.decode_int(head, big);
        if !(0..=1_000_000).contains(&n) {
            return false;
        }
        let end = cs + n as usize * s;
        let Some(list) = buf.get(cs..end) else {
            return false;
        };
        match (ty, big) {
            (Scalar::I32, false) => raw.extend(
                list.chunks_exact(4)
                    .map(|c| i64::from(i32::from_le_bytes([c[0], c[1], c[2], c[3]]))),
            ),
            (Scalar::U32, false) => raw.extend(
                list.chunks_exact(4)
                    .map(|c| i64::from(u32::from_le_bytes([c[0], c[1], c[2], c[3]]))),
            ),
            _ => raw.extend(list.chunks_exact(s).map(|c| ty.decode_int(c, big))),
        }
        self.r.consume(end);
        true
    }

    /// The vertex indices of face `f` into `raw`, as they are in the file.
    fn face_indices(
        &mut self,
        f: u64,
        int_list: Option<(bool, Scalar, Scalar)>,
        raw: &mut Vec<i64>,
    ) -> Result<(), OocError> {
        let name = self.name;
        let at = || format!("face {f}");
        let fi = self.layout.fi;
        raw.clear();
        match int_list {
            Some((big, ct, ty)) if self.face_from_buffer(big, ct, ty, raw) => {}
            Some((big, ct, ty)) => {
                let n = with_bytes(&mut self.r, &mut self.record, ct.size(), |b| {
                    ct.decode_int(b, big)
                })
                .map_err(|m| OocError::input(name, &at(), m))?;
                if !(0..=1_000_000).contains(&n) {
                    let list = &self.header.elements[fi].properties[0].name;
                    return Err(OocError::input(
                        name,
                        &at(),
                        format!("list '{list}' has {n} entries"),
                    ));
                }
                let s = ty.size();
                with_bytes(&mut self.r, &mut self.record, n as usize * s, |b| {
                    raw.extend(b.chunks_exact(s).map(|c| ty.decode_int(c, big)));
                })
                .map_err(|m| OocError::input(name, &at(), m))?;
            }
            None => {
                let mut fraction = None;
                let face_list = self.layout.face_list;
                self.items
                    .read(&mut self.r, &self.header.elements[fi], &mut |p, _, list| {
                        if p == face_list {
                            for &i in list {
                                if i.fract() != 0.0 || !i.is_finite() {
                                    fraction = Some(i);
                                }
                                raw.push(i as i64);
                            }
                        }
                    })
                    .map_err(|m| OocError::input(name, &at(), m))?;
                if let (Some(i), 3..) = (fraction, raw.len()) {
                    let vcount = self.header.elements[self.layout.vi].count;
                    return Err(OocError::input(
                        name,
                        &at(),
                        format!("vertex index {i} out of range ({vcount} vertices)"),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// What [`read_indexed`] found in the header.
#[derive(Clone, Debug)]
pub struct IndexedHeader {
    /// Vertices.
    pub vertices: u64,
    /// Faces (polygons, before triangulation).
    pub faces: u64,
    /// What the vertices carry: `HAS_NORMAL`, `HAS_UV`, `HAS_COLOR`.
    pub flags: u16,
    /// The texture a `comment TextureFile` line names.
    pub texture: Option<String>,
    /// What the file has that the in-core importer reads and this reader does not (a
    /// `tristrips` element, a per-corner `texcoord` list), if anything.
    pub unread: Option<String>,
}

/// Receives a PLY file as [`read_indexed`] reads it.
pub trait IndexedSink {
    /// The header, first.
    fn header(&mut self, header: &IndexedHeader) -> Result<(), OocError>;
    /// Vertex `i`'s slots: x y z nx ny nz u v r g b a, colours in 0..=1 as stored, `v` not
    /// flipped; all finite.
    fn vertex(&mut self, i: u64, slots: &[f64; 12]) -> Result<(), OocError>;
    /// Face `f`'s vertex indices (three or more, each in range), after every vertex.
    fn face(&mut self, f: u64, corners: &[u64]) -> Result<(), OocError>;
}

/// Reads the PLY file `file` (named `name` in errors) once, in file order, into `sink`:
/// the header, every vertex's slots, every face's vertex indices (faces of fewer than three
/// corners skipped and counted). For a reader that keeps the attributes at full precision,
/// where the soup quantises them. Returns the faces skipped.
pub fn read_indexed(name: &str, file: File, sink: &mut dyn IndexedSink) -> Result<u64, OocError> {
    let mut reader = Reader::new(name, file)?;
    let (vi, fi) = (reader.layout.vi, reader.layout.fi);
    let vcount = reader.header.elements[vi].count;
    sink.header(&IndexedHeader {
        vertices: vcount,
        faces: reader.header.elements[fi].count,
        flags: reader.layout.flags,
        texture: reader.header.texture.clone(),
        unread: unread(&reader.header, fi),
    })?;
    reader.skip(0..vi)?;
    let fixed = reader.fixed_vertex();
    let big = reader.header.format == Format::Binary { big: true };
    for i in 0..vcount {
        let mut v = NO_SLOTS;
        let at = || format!("vertex {i}");
        match &fixed {
            Some((stride, fields)) => {
                with_bytes(&mut reader.r, &mut reader.record, *stride, |b| {
                    decode_fixed(b, fields, big, &mut v);
                })
                .map_err(|m| OocError::input(name, &at(), m))?;
            }
            None => {
                let Layout {
                    vslots,
                    color_scale,
                    ..
                } = &reader.layout;
                reader
                    .items
                    .read(
                        &mut reader.r,
                        &reader.header.elements[vi],
                        &mut |p, x, _| {
                            if let Some(s) = vslots[p] {
                                v[s] = if s >= 8 {
                                    x * (1.0 / color_scale[p])
                                } else {
                                    x
                                };
                            }
                        },
                    )
                    .map_err(|m| OocError::input(name, &at(), m))?;
            }
        }
        if let Some(k) = v.iter().position(|x| !x.is_finite()) {
            return Err(OocError::input(
                name,
                &at(),
                format!("{} is {}", VERTEX_NAMES[k], v[k]),
            ));
        }
        sink.vertex(i, &v)?;
    }
    if vcount == 0 {
        return Err(OocError::Empty {
            file: name.to_string(),
        });
    }
    reader.skip(vi + 1..fi)?;
    let int_list = reader.int_list();
    let mut raw: Vec<i64> = Vec::new();
    let mut indices: Vec<u64> = Vec::new();
    let mut skipped = 0;
    for f in 0..reader.header.elements[fi].count {
        reader.face_indices(f, int_list, &mut raw)?;
        if raw.len() < 3 {
            skipped += 1;
            continue;
        }
        if let Some(&i) = raw.iter().find(|&&i| i < 0 || i as u64 >= vcount) {
            return Err(reader.bad(
                &format!("face {f}"),
                format!("vertex index {i} out of range ({vcount} vertices)"),
            ));
        }
        indices.clear();
        indices.extend(raw.iter().map(|&i| i as u64));
        sink.face(f, &indices)?;
    }
    Ok(skipped)
}

/// What of the file the in-core importer reads and [`read_indexed`] does not.
fn unread(header: &Header, fi: usize) -> Option<String> {
    if header.elements.iter().any(|e| e.name == "tristrips") {
        return Some("a 'tristrips' element".into());
    }
    let corner_uvs = header.elements[fi]
        .properties
        .iter()
        .any(|p| p.list.is_some() && p.name == "texcoord");
    corner_uvs.then(|| "a per-corner 'texcoord' list".into())
}

/// The vertex slots before a vertex is read: what a property the file lacks reads as.
const NO_SLOTS: [f64; 12] = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];

/// The slots of a vertex of fixed stride from its bytes `b`.
#[inline]
fn decode_fixed(b: &[u8], fields: &[Field], big: bool, v: &mut [f64; 12]) {
    for &(offset, ty, s, scale) in fields {
        let x = ty.decode(&b[offset..], big);
        v[s] = if s >= 8 { x * (1.0 / scale) } else { x };
    }
}

/// Where the vertices are after the vertex pass.
enum Stored {
    /// Fixed records in a temporary file.
    File(PathBuf),
    /// In the input, at a stride, these fields decoded.
    Input(usize, Vec<Field>),
}

/// Where the PLY reader's vertex cache reads from.
pub(super) enum VertexSource {
    /// Records written from vertices without a fixed stride (ascii, lists).
    Records(File),
    /// The input's own binary vertices.
    Input(FixedVertices),
}

/// The binary vertices of a PLY file, decoded a block at a time.
pub(super) struct FixedVertices {
    file: File,
    /// Byte offset of the first vertex.
    start: u64,
    stride: usize,
    fields: Vec<Field>,
    /// The position fields alone.
    position_fields: Vec<Field>,
    big: bool,
    /// Whether to decode the positions alone (the rest left zero).
    positions_only: bool,
    /// The block's bytes.
    bytes: Vec<u8>,
}

impl RecordSource<Corner> for VertexSource {
    fn read(&mut self, first: u64, dst: &mut [Corner]) -> std::io::Result<()> {
        let f = match self {
            VertexSource::Records(file) => return file.read(first, dst),
            VertexSource::Input(f) => f,
        };
        f.bytes.resize(dst.len() * f.stride, 0);
        f.file
            .read_exact_at(&mut f.bytes, f.start + first * f.stride as u64)?;
        for (c, b) in dst.iter_mut().zip(f.bytes.chunks_exact(f.stride)) {
            let mut v = NO_SLOTS;
            if f.positions_only {
                decode_fixed(b, &f.position_fields, f.big, &mut v);
                *c = Corner {
                    position: [v[0] as f32, v[1] as f32, v[2] as f32],
                    ..Corner::default()
                };
            } else {
                decode_fixed(b, &f.fields, f.big, &mut v);
                *c = corner([v[0] as f32, v[1] as f32, v[2] as f32], &v);
            }
        }
        Ok(())
    }
}

/// The record of a vertex from its slots `v` (x y z nx ny nz u v r g b a), `p` its
/// position; `v` flips to `1 - v`.
fn corner(p: [f32; 3], v: &[f64; 12]) -> Corner {
    let c8 = |x: f64| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    Corner {
        position: p,
        uv: [v[6] as f32, 1.0 - v[7] as f32],
        normal: encode_normal([v[3] as f32, v[4] as f32, v[5] as f32]),
        color: [c8(v[8]), c8(v[9]), c8(v[10]), c8(v[11])],
    }
}
