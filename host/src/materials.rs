//! A hierarchy's materials on the GPU: each base-colour texture decoded (the `image` crate)
//! and uploaded once, however many surfaces name it, and one [`MaterialSet`] for a
//! recorder. Surfaces without a material draw with their palette colour.

use std::collections::HashMap;
use std::path::Path;

use caveclod_core::format::materials::{AlphaMode, TextureRef};
use caveclod_core::Hierarchy;
use caveclod_vulkan::{
    Context, Error, MaterialSet, Recorder, Result, SurfaceMaterial, Texture, TextureDesc,
};

use crate::palette::palette;

/// The textures and the material set of one hierarchy, for one recorder.
pub struct GpuMaterials {
    textures: Vec<Texture>,
    /// The set to draw with ([`RecordCamera::materials`](caveclod_vulkan::RecordCamera)).
    pub set: MaterialSet,
}

/// Decodes an image file's bytes to RGBA8; `what` names it in errors.
fn decode(bytes: &[u8], what: &str) -> Result<(TextureDesc, Vec<u8>)> {
    let image = image::load_from_memory(bytes)
        .map_err(|e| Error::InvalidArgument(format!("{what}: {e}")))?
        .to_rgba8();
    let desc = TextureDesc {
        width: image.width(),
        height: image.height(),
        srgb: true,
    };
    Ok((desc, image.into_raw()))
}

impl GpuMaterials {
    /// The materials of `h` (texture paths relative to `dir`, the `.clod` file's
    /// directory) for `recorder`; `None` if the file has none. A texture that cannot be
    /// read or decoded is an error naming the material and the file.
    pub fn load(
        ctx: &Context,
        recorder: &Recorder,
        h: &Hierarchy<'_>,
        dir: &Path,
    ) -> Result<Option<Self>> {
        Self::load_with(ctx, recorder, h, dir, true)
    }

    /// [`load`](Self::load), drawing `BLEND` materials opaque unless `blend`: for images
    /// that must not depend on triangle order (blended triangles are not sorted).
    pub fn load_with(
        ctx: &Context,
        recorder: &Recorder,
        h: &Hierarchy<'_>,
        dir: &Path,
        blend: bool,
    ) -> Result<Option<Self>> {
        let Some(materials) = h.materials() else {
            return Ok(None);
        };
        let mut textures: Vec<Texture> = Vec::new();
        let mut by_source: HashMap<Vec<u8>, usize> = HashMap::new();
        let mut chosen: Vec<Option<usize>> = Vec::with_capacity(h.surface_count());
        let result = (|| -> Result<()> {
            for s in 0..h.surface_count() {
                let Some(texture) = materials.get(s).and_then(|m| m.texture) else {
                    chosen.push(None);
                    continue;
                };
                let name = materials.get(s).map_or("", |m| m.name);
                let key = match texture {
                    TextureRef::Path(p) => p.as_bytes().to_vec(),
                    TextureRef::Embedded { bytes, .. } => bytes.to_vec(),
                };
                if let Some(&i) = by_source.get(&key) {
                    chosen.push(Some(i));
                    continue;
                }
                let (desc, pixels) = match texture {
                    TextureRef::Path(p) => {
                        let path = dir.join(p);
                        let what = format!("material {s} ({name}): {}", path.display());
                        let bytes = std::fs::read(&path)
                            .map_err(|e| Error::InvalidArgument(format!("{what}: {e}")))?;
                        decode(&bytes, &what)?
                    }
                    TextureRef::Embedded { mime, bytes } => {
                        decode(bytes, &format!("material {s} ({name}): embedded {mime}"))?
                    }
                };
                textures.push(Texture::new(ctx, name, desc, &pixels)?);
                by_source.insert(key, textures.len() - 1);
                chosen.push(Some(textures.len() - 1));
            }
            Ok(())
        })();
        if let Err(e) = result {
            for t in textures {
                let _ = t.destroy(ctx);
            }
            return Err(e);
        }
        let surfaces: Vec<SurfaceMaterial<'_>> = (0..h.surface_count())
            .map(|s| match materials.get(s) {
                Some(m) => SurfaceMaterial {
                    texture: chosen[s].map(|i| &textures[i]),
                    factor: m.base_colour,
                    alpha_cutoff: match m.alpha {
                        AlphaMode::Mask { cutoff } => cutoff,
                        AlphaMode::Opaque | AlphaMode::Blend => 0.0,
                    },
                    blend: blend && m.alpha == AlphaMode::Blend,
                },
                None => SurfaceMaterial {
                    texture: None,
                    factor: palette(s),
                    alpha_cutoff: 0.0,
                    blend: false,
                },
            })
            .collect();
        match MaterialSet::new(ctx, recorder, &surfaces) {
            Ok(set) => Ok(Some(Self { textures, set })),
            Err(e) => {
                for t in textures {
                    let _ = t.destroy(ctx);
                }
                Err(e)
            }
        }
    }

    /// Textures uploaded (one per distinct source).
    pub fn texture_count(&self) -> usize {
        self.textures.len()
    }

    /// Destroys the set and the textures. The GPU must be done with them.
    pub fn destroy(self, ctx: &Context) -> Result<()> {
        self.set.destroy(ctx);
        let mut first = Ok(());
        for t in self.textures {
            if let Err(e) = t.destroy(ctx) {
                if first.is_ok() {
                    first = Err(e);
                }
            }
        }
        first
    }
}
