//! The imported mesh: what every importer produces and the baker consumes.
//!
//! Attributes are indexed per corner, as OBJ stores them, so a seam (one position, two
//! normals or UVs) is represented exactly; formats with one index per vertex (glTF, PLY)
//! point every stream of a corner at the same source vertex (glTF indices differ between
//! streams by a per-stream offset when some primitives lack an attribute).

use rayon::prelude::*;

/// "No attribute" in a corner's attribute index.
pub const NO_ATTRIBUTE: u32 = u32::MAX;

pub use caveclod_core::format::materials::AlphaMode;

/// A surface: one material, one index list at run time.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Surface {
    /// Material name as the source names it (or a made-up one).
    pub name: String,
    /// Base colour (linear RGBA).
    pub base_color: [f32; 4],
    /// Base-colour texture, if any.
    pub texture: Option<Texture>,
    /// How the base colour's alpha is used.
    pub alpha: AlphaMode,
    /// Back faces are drawn.
    pub double_sided: bool,
}

/// A surface's base-colour texture.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Texture {
    /// An image file: a path relative to the source file's directory, `/` between
    /// components.
    File(String),
    /// An image embedded in the source (a GLB buffer view, a `data:` URI): its encoded bytes
    /// and MIME type.
    Embedded {
        /// E.g. `image/png`.
        mime: String,
        /// The encoded image.
        bytes: Vec<u8>,
    },
}

impl Surface {
    /// A white, untextured, opaque, single-sided surface named `name`: what a source without
    /// materials gets.
    pub fn plain(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            base_color: [1.0; 4],
            texture: None,
            alpha: AlphaMode::Opaque,
            double_sided: false,
        }
    }

    /// Whether the surface looks like [`Surface::plain`], whatever its name: nothing a
    /// renderer would draw differently from the default.
    pub fn is_plain(&self) -> bool {
        let Surface { name, .. } = self;
        *self == Self::plain(name.as_str())
    }

    /// The texture's file, when it is one.
    pub fn texture_file(&self) -> Option<&str> {
        match &self.texture {
            Some(Texture::File(f)) => Some(f),
            _ => None,
        }
    }
}

/// One triangle: per-corner indices into the attribute streams.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Triangle {
    /// Into [`Mesh::positions`].
    pub position: [u32; 3],
    /// Into [`Mesh::normals`], or [`NO_ATTRIBUTE`].
    pub normal: [u32; 3],
    /// Into [`Mesh::uvs`], or [`NO_ATTRIBUTE`].
    pub uv: [u32; 3],
    /// Into [`Mesh::colors`], or [`NO_ATTRIBUTE`].
    pub color: [u32; 3],
    /// Into [`Mesh::surfaces`].
    pub surface: u16,
}

/// A triangle mesh with per-corner attributes and surfaces.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Points (world space: importers apply node transforms).
    pub positions: Vec<[f32; 3]>,
    /// Normals.
    pub normals: Vec<[f32; 3]>,
    /// Texture coordinates, `(u, v)` with `v = 0` at the top row of the image (the glTF
    /// convention); importers of formats with `v` pointing up (OBJ, PLY) store `1 - v`.
    pub uvs: Vec<[f32; 2]>,
    /// Linear RGBA colours.
    pub colors: Vec<[f32; 4]>,
    /// Triangles, counter-clockwise seen from outside.
    pub triangles: Vec<Triangle>,
    /// Surfaces; every triangle's surface is below `surfaces.len()`.
    pub surfaces: Vec<Surface>,
}

impl Mesh {
    /// The largest magnitude of any coordinate, normal, texture coordinate or colour value:
    /// the bake squares and sums them in single precision (bounding spheres, lengths,
    /// interpolation), which must stay finite.
    pub const MAX_MAGNITUDE: f32 = 1e18;

    /// Checks what the bake needs beyond [`validate`](Self::validate): every value within
    /// [`Mesh::MAX_MAGNITUDE`]. Returns a description of the first value beyond it.
    pub fn check_magnitudes(&self) -> Result<(), String> {
        /// Values the bake squares, sums and interpolates in single precision (bounding
        /// spheres, lengths, quadrics) must stay far from `f32::MAX`.
        fn within<const N: usize>(name: &str, values: &[[f32; N]]) -> Result<(), String> {
            match values
                .iter()
                .position(|v| v.iter().any(|c| c.abs() > Mesh::MAX_MAGNITUDE))
            {
                None => Ok(()),
                Some(i) => Err(format!(
                    "{name}[{i}] is beyond ±{:e}: {:?}",
                    Mesh::MAX_MAGNITUDE,
                    values[i]
                )),
            }
        }
        within("positions", &self.positions)?;
        within("normals", &self.normals)?;
        within("uvs", &self.uvs)?;
        within("colors", &self.colors)
    }

    /// Checks the invariants every importer guarantees: every index in range (or
    /// [`NO_ATTRIBUTE`] where allowed), every surface id below `surfaces.len()`, every number
    /// finite. Returns a description of the first violation. Runs on all cores.
    pub fn validate(&self) -> Result<(), String> {
        fn finite<const N: usize>(name: &str, values: &[[f32; N]]) -> Result<(), String> {
            match values
                .par_iter()
                .position_first(|v| v.iter().any(|c| !c.is_finite()))
            {
                None => Ok(()),
                Some(i) => Err(format!("{name}[{i}] is not finite: {:?}", values[i])),
            }
        }
        finite("positions", &self.positions)?;
        finite("normals", &self.normals)?;
        finite("uvs", &self.uvs)?;
        finite("colors", &self.colors)?;
        let first = (0..self.triangles.len())
            .into_par_iter()
            .position_first(|t| self.triangle_problem(t).is_some());
        first
            .and_then(|t| self.triangle_problem(t))
            .map_or(Ok(()), Err)
    }

    /// What is wrong with triangle `t`'s indices, if anything ([`validate`](Self::validate)).
    fn triangle_problem(&self, t: usize) -> Option<String> {
        let streams: [(&str, usize); 3] = [
            ("normal", self.normals.len()),
            ("uv", self.uvs.len()),
            ("color", self.colors.len()),
        ];
        let tri = &self.triangles[t];
        if let Some(&p) = tri
            .position
            .iter()
            .find(|&&p| p as usize >= self.positions.len())
        {
            return Some(format!(
                "triangle {t}: position {p} out of range ({} positions)",
                self.positions.len()
            ));
        }
        for ((name, len), indices) in streams.iter().zip([tri.normal, tri.uv, tri.color]) {
            if let Some(&i) = indices
                .iter()
                .find(|&&i| i != NO_ATTRIBUTE && i as usize >= *len)
            {
                return Some(format!("triangle {t}: {name} {i} out of range ({len})"));
            }
        }
        if usize::from(tri.surface) >= self.surfaces.len() {
            return Some(format!(
                "triangle {t}: surface {} out of range ({} surfaces)",
                tri.surface,
                self.surfaces.len()
            ));
        }
        None
    }

    /// Triangles per surface, indexed like [`Mesh::surfaces`].
    pub fn triangles_per_surface(&self) -> Vec<usize> {
        let mut counts = vec![0; self.surfaces.len()];
        for tri in &self.triangles {
            if let Some(c) = counts.get_mut(usize::from(tri.surface)) {
                *c += 1;
            }
        }
        counts
    }
}
