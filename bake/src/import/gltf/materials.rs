//! Materials to surfaces: name, base colour factor, and the base colour texture's file.

use super::buffers::decode_uri;
use super::Importer;
use crate::import::{push_surface, ImportError};
use crate::mesh::Surface;

impl Importer<'_> {
    /// The surface of a material (`None`: the shared `default`), made on first use.
    pub(super) fn surface(&mut self, material: Option<usize>) -> Result<u16, ImportError> {
        if let Some(&id) = self.surfaces.get(&material) {
            return Ok(id);
        }
        let surface = match material.and_then(|m| self.root.materials.get(m).map(|j| (m, j))) {
            None => Surface {
                name: "default".to_owned(),
                base_color: [1.0; 4],
                texture: None,
            },
            Some((m, json)) => {
                let pbr = &json.pbr_metallic_roughness;
                let texture = match &pbr.base_color_texture {
                    None => None,
                    Some(info) => self.texture_uri(info.index.value(), m)?,
                };
                let base_color = pbr.base_color_factor.0;
                self.source.check_finite(
                    &base_color,
                    &["red", "green", "blue", "alpha"],
                    || format!("material {m} baseColorFactor"),
                )?;
                Surface {
                    name: json.name.clone().unwrap_or_else(|| format!("material {m}")),
                    base_color,
                    texture,
                }
            }
        };
        let id = push_surface(self.source, &mut self.mesh, surface)?;
        self.surfaces.insert(material, id);
        Ok(id)
    }

    /// The file name of a texture's image, if it is an external file.
    fn texture_uri(
        &mut self,
        texture: usize,
        material: usize,
    ) -> Result<Option<String>, ImportError> {
        let image = self
            .root
            .textures
            .get(texture)
            .and_then(|t| self.root.images.get(t.source.value()));
        let what = format!("material {material} base colour texture");
        match image.and_then(|i| i.uri.as_deref()) {
            Some(uri) if !uri.starts_with("data:") => {
                Ok(Some(decode_uri(self.source, &what, uri)?))
            }
            _ => {
                self.report.notes.push(format!(
                    "{}: {what} is embedded (buffer view or data URI) and not referenced by \
                     the surface",
                    self.source.name
                ));
                Ok(None)
            }
        }
    }
}
