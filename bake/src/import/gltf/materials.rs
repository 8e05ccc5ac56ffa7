//! Materials to surfaces: name, base colour factor, the base colour texture's image (a file
//! relative to the glTF file, or the bytes of a buffer view or `data:` URI with their MIME
//! type), alpha mode and cutoff, and double-sidedness.

use ::gltf::json;
use ::gltf::json::validation::Checked;

use super::buffers::{decode_base64, decode_uri};
use super::importer::Importer;
use crate::import::error::ImportError;
use crate::import::ids::push_surface;
use crate::mesh::{AlphaMode, Surface, Texture};

impl Importer<'_> {
    /// The surface of a material (`None`: the shared `default`), made on first use.
    pub(super) fn surface(&mut self, material: Option<usize>) -> Result<u16, ImportError> {
        if let Some(&id) = self.surfaces.get(&material) {
            return Ok(id);
        }
        let surface = match material.and_then(|m| self.root.materials.get(m).map(|j| (m, j))) {
            None => Surface::plain("default"),
            Some((m, json)) => self.material_surface(m, json)?,
        };
        let id = push_surface(self.source, &mut self.mesh, surface)?;
        self.surfaces.insert(material, id);
        Ok(id)
    }

    /// The surface of material `m`.
    fn material_surface(
        &mut self,
        m: usize,
        json: &json::Material,
    ) -> Result<Surface, ImportError> {
        let pbr = &json.pbr_metallic_roughness;
        let texture = match &pbr.base_color_texture {
            None => None,
            Some(info) => self.texture_image(info.index.value(), m)?,
        };
        let base_color = pbr.base_color_factor.0;
        self.source
            .check_finite(&base_color, &["red", "green", "blue", "alpha"], || {
                format!("material {m} baseColorFactor")
            })?;
        Ok(Surface {
            name: json.name.clone().unwrap_or_else(|| format!("material {m}")),
            base_color,
            texture,
            alpha: self.alpha_mode(m, json)?,
            double_sided: json.double_sided,
        })
    }

    /// The alpha mode, with its cutoff (0.5 when absent) for `MASK`.
    fn alpha_mode(&self, m: usize, json: &json::Material) -> Result<AlphaMode, ImportError> {
        Ok(match json.alpha_mode {
            Checked::Valid(json::material::AlphaMode::Mask) => {
                let cutoff = json.alpha_cutoff.unwrap_or_default().0;
                if !(cutoff.is_finite() && cutoff >= 0.0) {
                    return Err(self.source.malformed(
                        format!("material {m} alphaCutoff"),
                        format!("{cutoff} is not a finite number >= 0"),
                    ));
                }
                AlphaMode::Mask { cutoff }
            }
            Checked::Valid(json::material::AlphaMode::Blend) => AlphaMode::Blend,
            // The crate's validation has refused invalid modes.
            _ => AlphaMode::Opaque,
        })
    }

    /// The image of a texture: an external file, or embedded bytes (a buffer view or a
    /// `data:` URI) with their MIME type.
    fn texture_image(
        &mut self,
        texture: usize,
        material: usize,
    ) -> Result<Option<Texture>, ImportError> {
        let what = format!("material {material} base colour texture");
        let Some(image) = self
            .root
            .textures
            .get(texture)
            .and_then(|t| self.root.images.get(t.source.value()))
        else {
            return Ok(None);
        };
        let mime = image.mime_type.as_ref().map(|m| m.0.clone());
        if let Some(view) = image.buffer_view {
            let (bytes, _) = self.view_bytes(view.value(), &what)?;
            let mime = mime.ok_or_else(|| {
                self.source
                    .malformed(&what, "an image in a buffer view needs a mimeType")
            })?;
            return Ok(Some(Texture::Embedded {
                mime,
                bytes: bytes.to_vec(),
            }));
        }
        match image.uri.as_deref() {
            Some(uri) => match uri.strip_prefix("data:") {
                Some(rest) => self.data_uri_image(&what, rest, mime).map(Some),
                None => Ok(Some(Texture::File(decode_uri(self.source, &what, uri)?))),
            },
            None => Err(self
                .source
                .malformed(&what, "the image has neither a uri nor a bufferView")),
        }
    }

    /// The image of a `data:` URI (after `data:`): base64 bytes, the MIME type it names (or
    /// the image's `mimeType`).
    fn data_uri_image(
        &self,
        what: &str,
        rest: &str,
        mime: Option<String>,
    ) -> Result<Texture, ImportError> {
        let (header, payload) = rest.split_once(";base64,").ok_or_else(|| {
            self.source
                .unsupported(what, "data URI without base64 encoding")
        })?;
        let bytes = decode_base64(payload)
            .ok_or_else(|| self.source.malformed(what, "data URI is not valid base64"))?;
        let mime = Some(header.to_owned())
            .filter(|h| !h.is_empty())
            .or(mime)
            .ok_or_else(|| self.source.malformed(what, "data URI without a MIME type"))?;
        Ok(Texture::Embedded { mime, bytes })
    }
}
