//! The OBJ reader, two passes over the file: the `v`, `vt` and `vn` records to temporary
//! files first, then the faces, their corners looked up through [`BlockCache`]s.

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};

use super::cache::BlockCache;
use super::sink::{SoupSink, StreamReport};
use crate::base::temp::{SpillWriter, TempSpace};
use crate::mesh::Surface;
use crate::ooc::error::OocError;
use crate::ooc::soup::{
    encode_normal, Corner, Cube, Keyer, SoupTriangle, HAS_COLOR, HAS_NORMAL, HAS_UV,
};

/// An OBJ file whose `v`, `vt` and `vn` records are in temporary files: the faces can be
/// read any number of times, each a pass over the file's lines.
pub(super) struct ObjInput<'a> {
    path: PathBuf,
    faces: Faces<'a>,
    cube: Cube,
    faces_hint: u64,
}

impl<'a> ObjInput<'a> {
    /// The first pass over the OBJ file at `path` (named `name` in errors): its records.
    pub(super) fn open(
        name: &'a str,
        path: &Path,
        temp: &TempSpace,
        cache_bytes: usize,
    ) -> Result<Self, OocError> {
        let open = || File::open(path).map_err(|source| OocError::io(name, "cannot read", source));
        let records = write_records(name, &open, temp)?;
        if records.np == 0 {
            return Err(OocError::Empty {
                file: name.to_string(),
            });
        }
        let tw = |e| OocError::temp("writing OBJ records", e);
        let paths = [
            records.pw.finish(),
            records.tw.finish(),
            records.nw.finish(),
        ];
        let [pp, tp, npth] = paths;
        let (pp, tp, npth) = (pp.map_err(tw)?, tp.map_err(tw)?, npth.map_err(tw)?);
        let rd = |p: &Path| File::open(p).map_err(|e| OocError::temp("reading OBJ records", e));
        let cube = Cube::around(records.lo, records.hi);
        let faces = Faces {
            name,
            pc: BlockCache::new(rd(&pp)?, records.np, cache_bytes / 2),
            tc: BlockCache::new(rd(&tp)?, records.nt, cache_bytes / 4),
            nc: BlockCache::new(rd(&npth)?, records.nn, cache_bytes / 4),
            keyer: cube.keyer(),
            color: if records.colors { HAS_COLOR } else { 0 },
            report: StreamReport {
                vertices: records.np,
                ..Default::default()
            },
            surface_ids: HashMap::new(),
            surface: None,
            seen: [0; 3],
            corners: Vec::new(),
            surfaces: Vec::new(),
        };
        Ok(Self {
            path: path.to_path_buf(),
            faces,
            cube,
            faces_hint: records.faces_hint,
        })
    }

    /// The second pass over the file (again on every call): materials and faces into `sink`.
    pub(super) fn faces(&mut self, sink: &mut dyn SoupSink) -> Result<StreamReport, OocError> {
        let f = &mut self.faces;
        f.report = StreamReport {
            vertices: f.report.vertices,
            ..Default::default()
        };
        f.surface_ids.clear();
        f.surfaces.clear();
        f.surface = None;
        f.seen = [0; 3];
        sink.start(&self.cube, self.faces_hint)?;
        let (name, path) = (f.name, &self.path);
        let open = || File::open(path).map_err(|source| OocError::io(name, "cannot read", source));
        read_lines(name, &open, &mut |n, s| f.line(n, s, sink))?;
        let mut report = f.report.clone();
        report.surfaces = f.surfaces.clone();
        Ok(report)
    }
}

/// An error on line `line` of the file `name`.
fn bad(name: &str, line: u64, message: String) -> OocError {
    OocError::Input {
        file: name.to_string(),
        at: format!("line {line}"),
        message,
    }
}

/// Calls `pass(line number, trimmed line)` on every line of the file, refusing control bytes
/// (binary data is not an OBJ file). A last line without a
/// line break that does not parse, or is a face with fewer than three corners, is reported
/// as the file cut off there.
fn read_lines(
    name: &str,
    open: &impl Fn() -> Result<File, OocError>,
    pass: &mut dyn FnMut(u64, &str) -> Result<(), OocError>,
) -> Result<(), OocError> {
    let mut r = BufReader::with_capacity(1 << 20, open()?);
    let mut bytes = Vec::new();
    let mut n = 0u64;
    let text = |b: u8| b >= 0x20 || matches!(b, b'\t' | b'\n' | 0x0b | 0x0c | b'\r');
    loop {
        bytes.clear();
        let k = r
            .read_until(b'\n', &mut bytes)
            .map_err(|e| OocError::io(name, "cannot read", e))?;
        if k == 0 {
            return Ok(());
        }
        n += 1;
        if let Some(&b) = bytes.iter().find(|&&b| !text(b)) {
            return Err(bad(
                name,
                n,
                format!("byte 0x{b:02x} is not text; expected a Wavefront OBJ text file"),
            ));
        }
        let s = String::from_utf8_lossy(&bytes);
        let line = s.trim();
        if s.ends_with('\n') {
            pass(n, line)?;
            continue;
        }
        let cut = |what: String| {
            bad(
                name,
                n,
                format!(
                    "the file ends in the middle of it ({what}); expected a complete last line"
                ),
            )
        };
        let mut words = line.split_ascii_whitespace();
        if matches!(words.next(), Some("f" | "fo")) && words.count() < 3 {
            return Err(cut("a face with fewer than 3 corners".to_owned()));
        }
        return pass(n, line).map_err(|e| match e {
            OocError::Input { message, .. } => cut(message),
            e => e,
        });
    }
}

/// The first `max` numbers of `rest`, at least `min`, all finite.
fn floats(name: &str, line: u64, rest: &str, min: usize, max: usize) -> Result<Vec<f32>, OocError> {
    let v: Vec<f32> = rest
        .split_ascii_whitespace()
        .take(max)
        .map(|t| t.parse::<f32>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(|| bad(name, line, format!("bad number in '{}'", rest.trim())))?;
    if v.len() < min {
        return Err(bad(
            name,
            line,
            format!("expected {min} numbers, got '{}'", rest.trim()),
        ));
    }
    Ok(v)
}

/// What the first pass wrote and found.
struct Records {
    /// Positions (with colours) as [`Corner`]s, UVs and encoded normals, one file each.
    pw: SpillWriter,
    tw: SpillWriter,
    nw: SpillWriter,
    /// How many of each.
    np: u64,
    nt: u64,
    nn: u64,
    /// The positions' bounding box.
    lo: [f32; 3],
    hi: [f32; 3],
    /// The number of `f` statements.
    faces_hint: u64,
    /// Whether a `v` record has a colour.
    colors: bool,
}

/// The first pass: the `v`, `vt` and `vn` records to their files.
fn write_records(
    name: &str,
    open: &impl Fn() -> Result<File, OocError>,
    temp: &TempSpace,
) -> Result<Records, OocError> {
    let tw = |e| OocError::temp("writing OBJ records", e);
    let mut rec = Records {
        pw: temp.create("obj-v", 1 << 20).map_err(tw)?,
        tw: temp.create("obj-vt", 1 << 18).map_err(tw)?,
        nw: temp.create("obj-vn", 1 << 18).map_err(tw)?,
        np: 0,
        nt: 0,
        nn: 0,
        lo: [f32::MAX; 3],
        hi: [f32::MIN; 3],
        faces_hint: 0,
        colors: false,
    };
    read_lines(name, open, &mut |n, s| {
        if let Some(rest) = s.strip_prefix("v ") {
            let v = floats(name, n, rest, 3, 6)?;
            let p = [v[0], v[1], v[2]];
            for k in 0..3 {
                rec.lo[k] = rec.lo[k].min(p[k]);
                rec.hi[k] = rec.hi[k].max(p[k]);
            }
            let c8 = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
            let color = if v.len() >= 6 {
                rec.colors = true;
                [c8(v[3]), c8(v[4]), c8(v[5]), 255]
            } else {
                [255; 4]
            };
            let c = Corner {
                position: p,
                color,
                ..Default::default()
            };
            rec.pw.write_all(bytemuck::bytes_of(&c)).map_err(tw)?;
            rec.np += 1;
        } else if let Some(rest) = s.strip_prefix("vt ") {
            let v = floats(name, n, rest, 1, 2)?;
            let uv = [v[0], 1.0 - v.get(1).copied().unwrap_or(0.0)];
            rec.tw.write_all(bytemuck::bytes_of(&uv)).map_err(tw)?;
            rec.nt += 1;
        } else if let Some(rest) = s.strip_prefix("vn ") {
            let v = floats(name, n, rest, 3, 3)?;
            rec.nw
                .write_all(bytemuck::bytes_of(&encode_normal([v[0], v[1], v[2]])))
                .map_err(tw)?;
            rec.nn += 1;
        } else if s.starts_with("f ") {
            rec.faces_hint += 1;
        }
        Ok(())
    })?;
    Ok(rec)
}

/// The second pass: materials and faces, records counted as they come (for relative
/// indices), corners read back through the caches.
struct Faces<'a> {
    name: &'a str,
    pc: BlockCache<Corner>,
    tc: BlockCache<[f32; 2]>,
    nc: BlockCache<[i16; 2]>,
    keyer: Keyer,
    /// `HAS_COLOR` when the positions have colours.
    color: u16,
    report: StreamReport,
    surface_ids: HashMap<String, u16>,
    /// The current surface, `None` before the first `usemtl` or face.
    surface: Option<u16>,
    /// Positions, UVs and normals so far.
    seen: [u64; 3],
    /// The current face's corners and what each carries.
    corners: Vec<(Corner, u16)>,
    surfaces: Vec<Surface>,
}

impl Faces<'_> {
    fn line(&mut self, n: u64, s: &str, sink: &mut dyn SoupSink) -> Result<(), OocError> {
        if s.starts_with("v ") {
            self.seen[0] += 1;
        } else if s.starts_with("vt ") {
            self.seen[1] += 1;
        } else if s.starts_with("vn ") {
            self.seen[2] += 1;
        } else if let Some(rest) = s.strip_prefix("usemtl") {
            self.use_material(rest)?;
        } else if let Some(rest) = s.strip_prefix("f ") {
            self.face(n, rest, sink)?;
        }
        Ok(())
    }

    /// `usemtl`: a surface per material name.
    fn use_material(&mut self, rest: &str) -> Result<(), OocError> {
        let m = rest.trim().to_string();
        let next = self.surfaces.len();
        let surfaces = &mut self.surfaces;
        let id = *self.surface_ids.entry(m.clone()).or_insert_with(|| {
            surfaces.push(Surface::plain(m));
            next as u16
        });
        if self.surfaces.len() > usize::from(u16::MAX) {
            return Err(OocError::Unsupported {
                file: self.name.to_string(),
                message: "more than 65,535 materials".into(),
            });
        }
        self.surface = Some(id);
        Ok(())
    }

    /// An `f` statement on line `n`: its corners, then a fan of triangles into `sink`.
    fn face(&mut self, n: u64, rest: &str, sink: &mut dyn SoupSink) -> Result<(), OocError> {
        self.corners.clear();
        for tok in rest.split_ascii_whitespace() {
            let c = self.corner(n, tok)?;
            self.corners.push(c);
        }
        if self.corners.len() < 3 {
            self.report.skipped_faces += 1;
            return Ok(());
        }
        let sid = self.current_surface();
        let corners = &self.corners;
        for k in 1..corners.len() - 1 {
            let tri = [corners[0], corners[k], corners[k + 1]];
            let flags = tri[0].1 & tri[1].1 & tri[2].1 | self.color;
            let t = SoupTriangle {
                key: self.keyer.key(&tri.map(|c| c.0.position)),
                surface: sid,
                flags,
                corners: tri.map(|c| c.0),
            };
            sink.push(&t)?;
            self.report.triangles += 1;
        }
        Ok(())
    }

    /// One corner `v`, `v/t`, `v//n` or `v/t/n` of a face on line `n`, read back from the
    /// records, and which of UV and normal it has.
    fn corner(&mut self, n: u64, tok: &str) -> Result<(Corner, u16), OocError> {
        let [seen_p, seen_t, seen_n] = self.seen;
        let mut parts = tok.split('/');
        let p = self
            .resolve(n, parts.next().unwrap_or(""), seen_p, "vertex")?
            .ok_or_else(|| bad(self.name, n, format!("corner '{tok}' has no vertex")))?;
        let t = self.resolve(n, parts.next().unwrap_or(""), seen_t, "texture coordinate")?;
        let nm = self.resolve(n, parts.next().unwrap_or(""), seen_n, "normal")?;
        let terr = |e| OocError::temp("reading OBJ records", e);
        let mut c = self.pc.get(p).map_err(terr)?;
        let mut f = 0;
        if let Some(t) = t {
            c.uv = self.tc.get(t).map_err(terr)?;
            f |= HAS_UV;
        }
        if let Some(nm) = nm {
            c.normal = self.nc.get(nm).map_err(terr)?;
            f |= HAS_NORMAL;
        }
        Ok((c, f))
    }

    /// The record an index `t` names (1-based, or negative: counted back from the last of
    /// the `seen` so far), `None` for an empty one.
    fn resolve(&self, n: u64, t: &str, seen: u64, what: &str) -> Result<Option<u64>, OocError> {
        if t.is_empty() {
            return Ok(None);
        }
        let i: i64 = t
            .parse()
            .map_err(|_| bad(self.name, n, format!("bad {what} index '{t}'")))?;
        let r = if i < 0 { seen as i64 + i } else { i - 1 };
        if i == 0 || r < 0 || r as u64 >= seen {
            return Err(bad(
                self.name,
                n,
                format!("{what} index {i} out of range ({seen} so far)"),
            ));
        }
        Ok(Some(r as u64))
    }

    /// The current surface, a default one for faces before any `usemtl`.
    fn current_surface(&mut self) -> u16 {
        match self.surface {
            Some(s) => s,
            None => {
                let surfaces = &mut self.surfaces;
                let id = *self.surface_ids.entry(String::new()).or_insert_with(|| {
                    surfaces.push(Surface::plain("default"));
                    (surfaces.len() - 1) as u16
                });
                self.surface = Some(id);
                id
            }
        }
    }
}
