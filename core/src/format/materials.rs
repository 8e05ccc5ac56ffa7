//! How surfaces look: materials, one per surface, and colours, one per vertex.
//!
//! Three optional sections (tags in [`material_tags`]), each found by tag, so a reader that
//! does not know them skips them:
//!
//! | tag    | record | per |
//! |--------|--------|-----|
//! | `MATL` | [`MaterialRecord`] (64 bytes) | surface, in surface order |
//! | `MBLB` | `u8` | byte of the blob the records point into: names, texture paths, MIME types and embedded images |
//! | `VCOL` | `[u8; 4]` | vertex, parallel to `VERT` |
//!
//! `MATL` and `MBLB` come together. A record names its strings and images by a [`BlobRef`]
//! (offset and length into `MBLB`); [`Hierarchy::from_bytes`](crate::Hierarchy::from_bytes)
//! checks every reference once: in range, names, paths and MIME types UTF-8, paths relative.
//! [`Hierarchy::materials`](crate::Hierarchy::materials) then hands out borrowed
//! [`Material`]s without copying.
//!
//! **Texture paths** use `/` between components and are resolved against the directory of the
//! `.clod` file. They are never absolute (no leading `/`, no drive or URI scheme such as `C:`
//! or `file:`) and contain no `\` or NUL. They may climb out of that directory with `..`
//! components: a file baked into another directory than its source refers to the source's
//! textures where they lie. An engine that loads files it does not trust and must keep reads
//! inside an asset directory checks [`path_climbs_out`] before opening one.
//!
//! **Vertex colours** are RGBA8: red, green and blue sRGB-encoded, alpha linear (the layout of
//! an `R8G8B8A8_SRGB` texel), so 8-bit source colours round-trip exactly and dark tones keep
//! their precision; [`vertex_colour_linear`] decodes one.

use bytemuck::{Pod, Zeroable};

use super::ExtraSection;

/// Section tags of materials and vertex colours.
pub mod material_tags {
    use crate::format::Tag;
    /// [`MaterialRecord`](super::MaterialRecord) per surface.
    pub const MATERIALS: Tag = Tag(*b"MATL");
    /// The bytes the material records point into.
    pub const BLOB: Tag = Tag(*b"MBLB");
    /// `[u8; 4]` per vertex: sRGB red, green, blue and linear alpha.
    pub const VERTEX_COLOURS: Tag = Tag(*b"VCOL");
}

/// A byte range of the `MBLB` section.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct BlobRef {
    /// First byte.
    pub offset: u32,
    /// Bytes.
    pub len: u32,
}

impl BlobRef {
    /// No bytes (an absent string or image).
    pub const EMPTY: Self = Self { offset: 0, len: 0 };

    /// The range `offset..offset + len`.
    pub const fn new(offset: u32, len: u32) -> Self {
        Self { offset, len }
    }

    /// The bytes of `blob` it names; `None` when they lie outside it.
    pub fn get(self, blob: &[u8]) -> Option<&[u8]> {
        let start = self.offset as usize;
        blob.get(start..start.checked_add(self.len as usize)?)
    }
}

/// What [`MaterialRecord::texture`] names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum TextureKind {
    /// No base-colour texture.
    None = 0,
    /// A UTF-8 path, relative to the `.clod` file's directory.
    Path = 1,
    /// The image file's bytes (PNG, JPEG, ...), with a MIME type in [`MaterialRecord::mime`].
    Embedded = 2,
}

impl TextureKind {
    /// Decodes the stored `u32`; `None` for an unknown value.
    pub const fn from_u32(value: u32) -> Option<Self> {
        match value {
            0 => Some(Self::None),
            1 => Some(Self::Path),
            2 => Some(Self::Embedded),
            _ => None,
        }
    }
}

/// How a surface's alpha (base colour alpha times texture alpha) is used, as in glTF.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AlphaMode {
    /// Alpha is ignored: the surface is fully opaque.
    #[default]
    Opaque,
    /// Fragments with alpha below `cutoff` are discarded, the others are opaque.
    Mask {
        /// Finite and `>= 0` (glTF's default is 0.5).
        cutoff: f32,
    },
    /// Alpha blends the surface over what lies behind it.
    Blend,
}

impl AlphaMode {
    /// The stored `alpha_mode` value.
    pub const fn code(self) -> u32 {
        match self {
            Self::Opaque => 0,
            Self::Mask { .. } => 1,
            Self::Blend => 2,
        }
    }

    /// The stored `alpha_cutoff`: the cutoff for [`Mask`](Self::Mask), else 0.
    pub const fn cutoff(self) -> f32 {
        match self {
            Self::Mask { cutoff } => cutoff,
            _ => 0.0,
        }
    }

    /// glTF's word: `OPAQUE`, `MASK` or `BLEND`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Opaque => "OPAQUE",
            Self::Mask { .. } => "MASK",
            Self::Blend => "BLEND",
        }
    }
}

/// [`MaterialRecord::flags`]: back faces are drawn (and lit with the normal reversed).
pub const DOUBLE_SIDED: u32 = 1;

/// One surface's material, exactly as it lies in the `MATL` section (64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MaterialRecord {
    /// The name, UTF-8 (may be empty).
    pub name: BlobRef,
    /// Base colour factor, linear RGBA; finite.
    pub base_colour: [f32; 4],
    /// A [`TextureKind`] as `u32`.
    pub texture_kind: u32,
    /// The texture's path (UTF-8, non-empty) or image bytes (non-empty); empty for
    /// [`TextureKind::None`].
    pub texture: BlobRef,
    /// The embedded image's MIME type (UTF-8, non-empty, e.g. `image/png`); empty otherwise.
    pub mime: BlobRef,
    /// [`AlphaMode::code`].
    pub alpha_mode: u32,
    /// [`AlphaMode::cutoff`]: finite and `>= 0` for mask, exactly 0 otherwise.
    pub alpha_cutoff: f32,
    /// [`DOUBLE_SIDED`] or 0.
    pub flags: u32,
    /// Zero.
    pub reserved: [u32; 2],
}

const _: () = assert!(core::mem::size_of::<MaterialRecord>() == 64);

/// A texture as a material names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureRef<'a> {
    /// A path relative to the `.clod` file's directory, `/` between components (see the
    /// [module docs](self) for what it may contain).
    Path(&'a str),
    /// An image file's bytes, embedded in the `.clod` file.
    Embedded {
        /// Its MIME type, e.g. `image/png`.
        mime: &'a str,
        /// The encoded image (not decoded here).
        bytes: &'a [u8],
    },
}

/// One surface's material, borrowed from the file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material<'a> {
    /// As the source named it (may be empty).
    pub name: &'a str,
    /// Linear RGBA factor, multiplied with the texture (and vertex colours, where present).
    pub base_colour: [f32; 4],
    /// The base-colour texture.
    pub texture: Option<TextureRef<'a>>,
    /// How alpha is used.
    pub alpha: AlphaMode,
    /// Back faces are drawn.
    pub double_sided: bool,
}

/// The materials of a hierarchy: one per surface, validated when the file was loaded.
#[derive(Clone, Copy, Debug)]
pub struct Materials<'a> {
    records: &'a [MaterialRecord],
    blob: &'a [u8],
}

impl<'a> Materials<'a> {
    /// A view over records and blob that [`validate`](crate::format::validate) accepted.
    pub(crate) fn new(records: &'a [MaterialRecord], blob: &'a [u8]) -> Self {
        Self { records, blob }
    }

    /// Number of materials: the hierarchy's surface count.
    pub fn len(&self) -> usize {
        self.records.len()
    }

    /// No materials (a hierarchy with no surfaces).
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// The material of surface `surface`; `None` past the last surface.
    pub fn get(&self, surface: usize) -> Option<Material<'a>> {
        let r = self.records.get(surface)?;
        // Validated at load: every reference is in range and its strings are UTF-8, so the
        // `?`s below never return for a loaded hierarchy.
        let text = |b: BlobRef| core::str::from_utf8(b.get(self.blob)?).ok();
        let texture = match TextureKind::from_u32(r.texture_kind)? {
            TextureKind::None => None,
            TextureKind::Path => Some(TextureRef::Path(text(r.texture)?)),
            TextureKind::Embedded => Some(TextureRef::Embedded {
                mime: text(r.mime)?,
                bytes: r.texture.get(self.blob)?,
            }),
        };
        let alpha = match r.alpha_mode {
            0 => AlphaMode::Opaque,
            1 => AlphaMode::Mask {
                cutoff: r.alpha_cutoff,
            },
            2 => AlphaMode::Blend,
            _ => return None,
        };
        Some(Material {
            name: text(r.name)?,
            base_colour: r.base_colour,
            texture,
            alpha,
            double_sided: r.flags & DOUBLE_SIDED != 0,
        })
    }

    /// Every surface's material, in surface order.
    pub fn iter(&self) -> impl Iterator<Item = Material<'a>> + '_ {
        (0..self.len()).filter_map(move |s| self.get(s))
    }

    /// The records and the blob, as stored.
    pub fn parts(&self) -> MaterialParts<'a> {
        MaterialParts {
            records: self.records,
            blob: self.blob,
        }
    }
}

/// Material records and their blob, borrowed: what a builder writes (as two extra sections)
/// and what [`Materials`] views.
#[derive(Clone, Copy, Debug, Default)]
pub struct MaterialParts<'a> {
    /// One per surface.
    pub records: &'a [MaterialRecord],
    /// The bytes the records point into.
    pub blob: &'a [u8],
}

impl<'a> MaterialParts<'a> {
    /// The `MATL` and `MBLB` sections, to pass to [`write_into`](crate::format::write_into),
    /// which validates them as a reader would.
    pub fn sections(&self) -> [ExtraSection<'a>; 2] {
        [
            ExtraSection {
                tag: material_tags::MATERIALS,
                record_size: core::mem::size_of::<MaterialRecord>() as u32,
                bytes: bytemuck::cast_slice(self.records),
            },
            ExtraSection {
                tag: material_tags::BLOB,
                record_size: 1,
                bytes: self.blob,
            },
        ]
    }
}

/// The `VCOL` section of `colours`, one per vertex of the vertex buffer.
pub fn vertex_colour_section(colours: &[[u8; 4]]) -> ExtraSection<'_> {
    ExtraSection {
        tag: material_tags::VERTEX_COLOURS,
        record_size: 4,
        bytes: bytemuck::cast_slice(colours),
    }
}

/// A stored vertex colour as linear RGBA in `0..=1`.
pub fn vertex_colour_linear(c: [u8; 4]) -> [f32; 4] {
    let decode = |v: u8| {
        let s = v as f32 / 255.0;
        if s <= 0.04045 {
            s / 12.92
        } else {
            libm::powf((s + 0.055) / 1.055, 2.4)
        }
    };
    [
        decode(c[0]),
        decode(c[1]),
        decode(c[2]),
        c[3] as f32 / 255.0,
    ]
}

/// Whether a texture path reaches above the directory it is resolved against: some `..`
/// component is not matched by a component before it (`a/../b` stays, `a/../../b` climbs).
pub fn path_climbs_out(path: &str) -> bool {
    let mut depth = 0usize;
    for component in path.split('/') {
        match component {
            "" | "." => {}
            ".." => match depth.checked_sub(1) {
                Some(d) => depth = d,
                None => return true,
            },
            _ => depth += 1,
        }
    }
    false
}

/// Why the format refuses a texture path, or `None` for an acceptable one (see the
/// [module docs](self)): a writer checks the paths it makes with it.
pub fn path_problem(path: &str) -> Option<&'static str> {
    if path.is_empty() {
        return Some("empty path");
    }
    if path.starts_with('/') {
        return Some("absolute path (paths are relative to the .clod file)");
    }
    if path.contains('\\') {
        return Some("backslash in the path (components are separated by '/')");
    }
    if path.contains('\0') {
        return Some("NUL byte in the path");
    }
    let first = path.split('/').next().unwrap_or("");
    if first.contains(':') {
        return Some("drive or URI scheme (paths are relative to the .clod file)");
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_that_climb_out_are_told_apart() {
        assert!(!path_climbs_out("tex/a.png"));
        assert!(!path_climbs_out("a/../b.png"));
        assert!(!path_climbs_out("./a.png"));
        assert!(path_climbs_out("../a.png"));
        assert!(path_climbs_out("a/../../b.png"));
    }

    #[test]
    fn path_rules() {
        assert_eq!(path_problem("a/b.png"), None);
        assert_eq!(path_problem("../up/b.png"), None);
        for bad in [
            "",
            "/etc/x.png",
            "a\\b.png",
            "C:/x.png",
            "file:x.png",
            "a\0b",
        ] {
            assert!(path_problem(bad).is_some(), "{bad:?}");
        }
    }

    #[test]
    fn vertex_colours_decode_from_srgb() {
        assert_eq!(vertex_colour_linear([0, 255, 0, 255]), [0.0, 1.0, 0.0, 1.0]);
        let mid = vertex_colour_linear([188, 0, 0, 128])[0];
        assert!((mid - 0.503).abs() < 1e-3, "{mid}");
    }

    #[test]
    fn blob_refs_stay_in_range() {
        let blob = [1u8, 2, 3];
        assert_eq!(BlobRef::new(1, 2).get(&blob), Some(&blob[1..3]));
        assert_eq!(BlobRef::new(2, 2).get(&blob), None);
        assert_eq!(BlobRef::new(u32::MAX, u32::MAX).get(&blob), None);
        assert_eq!(BlobRef::EMPTY.get(&[]), Some(&[][..]));
    }
}
