//! The optional appearance sections: materials with their blob, and vertex colours.
//!
//! Checked after the hierarchy (they only need its surface and vertex counts): `MATL` and
//! `MBLB` present together, one material per surface and one colour per vertex, then each
//! material record in order: its name, colour, texture, alpha mode, flags and reserved words.

use crate::format::materials::{
    material_tags as tags, path_problem, BlobRef, MaterialRecord, Materials, TextureKind,
    DOUBLE_SIDED,
};
use crate::format::{FormatError, Tag};

/// The appearance sections of a file or of a writer's extra sections, found and cast but not
/// yet validated.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct AppearanceSections<'a> {
    pub materials: Option<&'a [MaterialRecord]>,
    pub blob: Option<&'a [u8]>,
    pub vertex_colours: Option<&'a [[u8; 4]]>,
}

/// What [`appearance`] accepted.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Appearance<'a> {
    pub materials: Option<Materials<'a>>,
    pub vertex_colours: Option<&'a [[u8; 4]]>,
}

/// Validates the appearance sections of a hierarchy of `surface_count` surfaces and
/// `vertex_count` vertices.
pub(crate) fn appearance<'a>(
    s: &AppearanceSections<'a>,
    surface_count: usize,
    vertex_count: usize,
) -> Result<Appearance<'a>, FormatError> {
    let materials = match (s.materials, s.blob) {
        (None, None) => None,
        (Some(_), None) => return Err(FormatError::MissingSection { tag: tags::BLOB }),
        (None, Some(_)) => {
            return Err(FormatError::MissingSection {
                tag: tags::MATERIALS,
            })
        }
        (Some(records), Some(blob)) => {
            count(tags::MATERIALS, surface_count, records.len())?;
            for (i, r) in records.iter().enumerate() {
                record(r, i, blob)?;
            }
            Some(Materials::new(records, blob))
        }
    };
    if let Some(colours) = s.vertex_colours {
        count(tags::VERTEX_COLOURS, vertex_count, colours.len())?;
    }
    Ok(Appearance {
        materials,
        vertex_colours: s.vertex_colours,
    })
}

fn count(tag: Tag, expected: usize, found: usize) -> Result<(), FormatError> {
    if expected != found {
        return Err(FormatError::Count {
            tag,
            expected: expected as u64,
            found: found as u64,
        });
    }
    Ok(())
}

fn invalid(i: usize, field: &'static str, problem: &'static str, value: u64) -> FormatError {
    FormatError::Invalid {
        tag: tags::MATERIALS,
        record: i as u64,
        field,
        problem,
        value,
    }
}

/// The bytes `r` names in `blob`, or the error naming record `i`'s `field`.
fn bytes<'a>(
    blob: &'a [u8],
    r: BlobRef,
    i: usize,
    field: &'static str,
) -> Result<&'a [u8], FormatError> {
    r.get(blob).ok_or(FormatError::BlobRange {
        tag: tags::MATERIALS,
        record: i as u64,
        field,
        offset: r.offset,
        len: r.len,
        blob_len: blob.len() as u64,
    })
}

/// The UTF-8 string `r` names in `blob`.
fn text<'a>(
    blob: &'a [u8],
    r: BlobRef,
    i: usize,
    field: &'static str,
) -> Result<&'a str, FormatError> {
    core::str::from_utf8(bytes(blob, r, i, field)?).map_err(|_| FormatError::NotUtf8 {
        tag: tags::MATERIALS,
        record: i as u64,
        field,
    })
}

/// Material record `i`: name, colour, texture, alpha, flags, reserved words.
fn record(r: &MaterialRecord, i: usize, blob: &[u8]) -> Result<(), FormatError> {
    text(blob, r.name, i, "name")?;
    if let Some(x) = r.base_colour.iter().find(|x| !x.is_finite()) {
        return Err(invalid(
            i,
            "base_colour",
            "not a finite number",
            x.to_bits().into(),
        ));
    }
    texture(r, i, blob)?;
    alpha(r, i)?;
    if r.flags & !DOUBLE_SIDED != 0 {
        return Err(invalid(
            i,
            "flags",
            "unknown flag bits (only DOUBLE_SIDED is defined)",
            r.flags.into(),
        ));
    }
    if let Some(&w) = r.reserved.iter().find(|&&w| w != 0) {
        return Err(invalid(i, "reserved", "not zero", w.into()));
    }
    Ok(())
}

/// The texture: nothing for none; a relative path; or non-empty bytes with a MIME type.
fn texture(r: &MaterialRecord, i: usize, blob: &[u8]) -> Result<(), FormatError> {
    let empty = |field: &'static str, b: BlobRef| {
        if b == BlobRef::EMPTY {
            Ok(())
        } else {
            Err(invalid(
                i,
                field,
                "not empty, but this texture kind has none",
                b.len.into(),
            ))
        }
    };
    let non_empty = |field: &'static str, b: BlobRef| {
        if b.len == 0 {
            Err(invalid(i, field, "empty", 0))
        } else {
            Ok(())
        }
    };
    match TextureKind::from_u32(r.texture_kind) {
        None => Err(invalid(
            i,
            "texture_kind",
            "not NONE (0), PATH (1) or EMBEDDED (2)",
            r.texture_kind.into(),
        )),
        Some(TextureKind::None) => {
            empty("texture", r.texture)?;
            empty("mime", r.mime)
        }
        Some(TextureKind::Path) => {
            let path = text(blob, r.texture, i, "texture")?;
            if let Some(problem) = path_problem(path) {
                return Err(FormatError::BadPath {
                    tag: tags::MATERIALS,
                    record: i as u64,
                    problem,
                });
            }
            empty("mime", r.mime)
        }
        Some(TextureKind::Embedded) => {
            bytes(blob, r.texture, i, "texture")?;
            non_empty("texture", r.texture)?;
            text(blob, r.mime, i, "mime")?;
            non_empty("mime", r.mime)
        }
    }
}

/// A known alpha mode; for mask a finite, non-negative cutoff, else a zero one.
fn alpha(r: &MaterialRecord, i: usize) -> Result<(), FormatError> {
    let cutoff = r.alpha_cutoff;
    match r.alpha_mode {
        1 if !(cutoff.is_finite() && cutoff >= 0.0) => Err(invalid(
            i,
            "alpha_cutoff",
            "not a finite number >= 0",
            cutoff.to_bits().into(),
        )),
        0 | 2 if cutoff.to_bits() != 0 => Err(invalid(
            i,
            "alpha_cutoff",
            "not zero, but the alpha mode is not MASK",
            cutoff.to_bits().into(),
        )),
        0..=2 => Ok(()),
        m => Err(invalid(
            i,
            "alpha_mode",
            "not OPAQUE (0), MASK (1) or BLEND (2)",
            m.into(),
        )),
    }
}
