//! The `.clod` file's appearance sections from the imported surfaces and the welded
//! vertices: one material per surface and one colour per vertex
//! ([`caveclod_core::format::materials`] defines them).
//!
//! - **Which meshes get materials.** A mesh whose surfaces are all plain (white,
//!   untextured, opaque, single-sided: [`Surface::is_plain`]) gets no material sections, so
//!   generated meshes, heightfields, PLY scans and OBJ files without an MTL bake to the same
//!   bytes as before; their surface names are not kept. Otherwise every surface gets its
//!   material: material `i` is surface `i`, since welding and the hierarchy keep the
//!   importers' surface ids.
//! - **Texture files** are stored relative to the `.clod` file's own directory, where
//!   engines resolve them. The importers give them relative to the source file;
//!   [`TexturePaths::rewrite`] turns that into the path from the output's directory to the
//!   same file, climbing with `..` where the output lies elsewhere. Nothing is copied, so
//!   the textures stay where the source had them.
//! - **Embedded images** (GLB buffer views, `data:` URIs) are stored in the file, bytes and
//!   MIME type, undecoded.
//! - **Vertex colours**: welding keeps one colour per vertex and collapses are half-edge
//!   collapses, which create no vertex, so every level draws the full-resolution colours of
//!   the vertices it keeps (colour differences are part of each collapse's cost,
//!   [`crate::quadric`]). They are stored as RGBA8 with sRGB-encoded colour and linear alpha.

use std::path::{Component, Path, PathBuf};

use caveclod_core::format::materials::{
    path_problem, BlobRef, MaterialParts, MaterialRecord, TextureKind, DOUBLE_SIDED,
};

pub use crate::base::colour::encode_colour;
use crate::mesh::{Surface, Texture};

/// Whether any surface carries a material worth storing (see the module docs).
pub fn has_materials(surfaces: &[Surface]) -> bool {
    surfaces.iter().any(|s| !s.is_plain())
}

/// Why a surface's texture cannot be stored.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
#[error("surface {surface} ('{name}'): texture '{texture}': {problem}")]
pub struct TextureError {
    /// The surface.
    pub surface: usize,
    /// Its name.
    pub name: String,
    /// The texture as the surface names it.
    pub texture: String,
    /// Why.
    pub problem: String,
}

/// The `MATL` records and `MBLB` blob of a list of surfaces.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MaterialSections {
    records: Vec<MaterialRecord>,
    blob: Vec<u8>,
}

impl MaterialSections {
    /// One record per surface; each texture file's path passed through `path` (from the
    /// directory the surfaces' paths are relative to, to the `.clod` file's) and checked
    /// against the format's rules.
    pub fn new(
        surfaces: &[Surface],
        path: &dyn Fn(&str) -> Result<String, String>,
    ) -> Result<Self, TextureError> {
        let mut out = Self::default();
        for (i, s) in surfaces.iter().enumerate() {
            let error = |texture: &str, problem: String| TextureError {
                surface: i,
                name: s.name.clone(),
                texture: texture.to_owned(),
                problem,
            };
            let name = out.put(s.name.as_bytes(), &|p| error("", p))?;
            let (kind, texture, mime) = match &s.texture {
                None => (TextureKind::None, BlobRef::EMPTY, BlobRef::EMPTY),
                Some(Texture::File(file)) => {
                    let stored = path(file).map_err(|p| error(file, p))?;
                    if let Some(problem) = path_problem(&stored) {
                        return Err(error(file, format!("stored as '{stored}': {problem}")));
                    }
                    let r = out.put(stored.as_bytes(), &|p| error(file, p))?;
                    (TextureKind::Path, r, BlobRef::EMPTY)
                }
                Some(Texture::Embedded { mime, bytes }) => {
                    let what = format!("embedded {mime} image");
                    if bytes.is_empty() || mime.is_empty() {
                        return Err(error(&what, "no bytes or no MIME type".to_owned()));
                    }
                    let b = out.put(bytes, &|p| error(&what, p))?;
                    let m = out.put(mime.as_bytes(), &|p| error(&what, p))?;
                    (TextureKind::Embedded, b, m)
                }
            };
            out.records.push(MaterialRecord {
                name,
                base_colour: s.base_color,
                texture_kind: kind as u32,
                texture,
                mime,
                alpha_mode: s.alpha.code(),
                alpha_cutoff: s.alpha.cutoff(),
                flags: if s.double_sided { DOUBLE_SIDED } else { 0 },
                reserved: [0; 2],
            });
        }
        Ok(out)
    }

    /// Appends `bytes` to the blob; an error past the 4 GiB a [`BlobRef`] can address.
    fn put(
        &mut self,
        bytes: &[u8],
        error: &dyn Fn(String) -> TextureError,
    ) -> Result<BlobRef, TextureError> {
        let too_big = || error("the material blob would exceed 4 GiB".to_owned());
        let offset = u32::try_from(self.blob.len()).map_err(|_| too_big())?;
        let len = u32::try_from(bytes.len()).map_err(|_| too_big())?;
        offset.checked_add(len).ok_or_else(too_big)?;
        self.blob.extend_from_slice(bytes);
        Ok(BlobRef::new(offset, len))
    }

    /// The records and blob, for [`MaterialParts::sections`].
    pub fn parts(&self) -> MaterialParts<'_> {
        MaterialParts {
            records: &self.records,
            blob: &self.blob,
        }
    }
}

/// Rewrites texture paths relative to one directory (`from`) into paths relative to another
/// (`to`) that name the same files: from a source file's directory to the `.clod` file's, or
/// from the `.clod` file's to an exported OBJ's.
#[derive(Clone, Debug)]
pub struct TexturePaths {
    from: PathBuf,
    to: PathBuf,
}

impl TexturePaths {
    /// Both directories made absolute (symbolic links resolved where they exist; an empty
    /// path is the current directory).
    pub fn new(from: &Path, to: &Path) -> Self {
        Self {
            from: absolute_dir(from),
            to: absolute_dir(to),
        }
    }

    /// The path from `to` to the file `path` names from `from`, with `/` between components
    /// and `..` where it climbs; an error when no relative path exists (another drive) or a
    /// component is not UTF-8.
    pub fn rewrite(&self, path: &str) -> Result<String, String> {
        let target = normalise(&self.from.join(path));
        let (t, d): (Vec<Component<'_>>, Vec<Component<'_>>) = (
            target.components().collect(),
            self.to.components().collect(),
        );
        let prefix = |c: &[Component<'_>]| {
            c.iter()
                .take_while(|c| matches!(c, Component::Prefix(_) | Component::RootDir))
                .count()
        };
        if t[..prefix(&t)] != d[..prefix(&d)] {
            return Err(format!(
                "'{}' has no path relative to '{}'",
                target.display(),
                self.to.display()
            ));
        }
        let common = t.iter().zip(&d).take_while(|(a, b)| a == b).count();
        let mut parts: Vec<&str> = vec![".."; d.len() - common];
        for c in &t[common..] {
            parts.push(
                c.as_os_str()
                    .to_str()
                    .ok_or_else(|| format!("'{}' is not a UTF-8 path", target.display()))?,
            );
        }
        Ok(parts.join("/"))
    }
}

/// `dir` as an absolute path: canonical when it exists, else joined to the current directory
/// and normalised.
fn absolute_dir(dir: &Path) -> PathBuf {
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    std::fs::canonicalize(dir).unwrap_or_else(|_| {
        normalise(
            &std::env::current_dir()
                .unwrap_or_else(|_| PathBuf::from("/"))
                .join(dir),
        )
    })
}

/// `p` with `.` components dropped and each `..` taking the component before it.
fn normalise(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                if !out.pop() {
                    out.push(c);
                }
            }
            other => out.push(other),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::AlphaMode;

    #[test]
    fn paths_are_rewritten_between_directories() {
        let t = TexturePaths {
            from: PathBuf::from("/data/models/helmet"),
            to: PathBuf::from("/data/out"),
        };
        assert_eq!(
            t.rewrite("tex/a b.png").unwrap(),
            "../models/helmet/tex/a b.png"
        );
        assert_eq!(
            t.rewrite("../shared/c.png").unwrap(),
            "../models/shared/c.png"
        );
        let same = TexturePaths {
            from: PathBuf::from("/data/out"),
            to: PathBuf::from("/data/out"),
        };
        assert_eq!(same.rewrite("./t.png").unwrap(), "t.png");
        let inside = TexturePaths {
            from: PathBuf::from("/data"),
            to: PathBuf::from("/data/out"),
        };
        assert_eq!(inside.rewrite("out/t.png").unwrap(), "t.png");
    }

    #[test]
    fn plain_surfaces_carry_no_material() {
        let plain = [Surface::plain("s0"), Surface::plain("default")];
        assert!(!has_materials(&plain));
        let mask = Surface {
            alpha: AlphaMode::Mask { cutoff: 0.5 },
            ..Surface::plain("leaves")
        };
        assert!(has_materials(&[Surface::plain("a"), mask]));
        let textured = Surface {
            texture: Some(Texture::File("t.png".into())),
            ..Surface::plain("a")
        };
        assert!(has_materials(&[textured]));
    }

    #[test]
    fn sections_hold_every_surface() {
        let surfaces = [
            Surface {
                texture: Some(Texture::File("t.png".into())),
                double_sided: true,
                ..Surface::plain("wood")
            },
            Surface {
                texture: Some(Texture::Embedded {
                    mime: "image/png".into(),
                    bytes: vec![1, 2, 3],
                }),
                alpha: AlphaMode::Blend,
                ..Surface::plain("glass")
            },
        ];
        let s = MaterialSections::new(&surfaces, &|p| Ok(format!("tex/{p}"))).unwrap();
        let parts = s.parts();
        assert_eq!(parts.records.len(), 2);
        let text = |r: BlobRef| std::str::from_utf8(r.get(parts.blob).unwrap()).unwrap();
        assert_eq!(text(parts.records[0].name), "wood");
        assert_eq!(text(parts.records[0].texture), "tex/t.png");
        assert_eq!(parts.records[0].flags, DOUBLE_SIDED);
        assert_eq!(
            parts.records[1].texture.get(parts.blob),
            Some(&[1u8, 2, 3][..])
        );
        assert_eq!(text(parts.records[1].mime), "image/png");
        assert_eq!(parts.records[1].alpha_mode, AlphaMode::Blend.code());
        // A path the format refuses is an error naming the surface.
        let e = MaterialSections::new(&surfaces, &|_| Ok("/abs/t.png".into())).unwrap_err();
        assert_eq!((e.surface, e.name.as_str()), (0, "wood"));
    }

    #[test]
    fn colours_are_stored_as_srgb8() {
        assert_eq!(encode_colour([0.0, 1.0, 0.5, 0.5]), [0, 255, 188, 128]);
    }
}
