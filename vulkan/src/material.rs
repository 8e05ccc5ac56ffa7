//! Surface materials on the GPU: per surface a descriptor set (base-colour texture and the
//! recorder's sampler) and the push values (base colour factor, alpha cutoff).
//!
//! Set 0 of the drawing pipelines: binding 0 a sampled image, binding 1 a sampler, both
//! read by the fragment stage (`vulkan/spirv/INTERFACE.md`). A surface without a texture
//! samples the recorder's 1 × 1 white texture, so the factor alone colours it.

use ash::vk;

use crate::buffer::Buffer;
use crate::device::Context;
use crate::error::{Error, Result, VkResultExt};
use crate::mesh::upload;
use crate::texture::{Texture, TextureDesc};

/// One surface's material, as the GPU draws it.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceMaterial<'a> {
    /// Base-colour texture (sampled at the vertex uv, multiplied with `factor`); `None`
    /// for the factor alone.
    pub texture: Option<&'a Texture>,
    /// Base colour factor, linear RGBA.
    pub factor: [f32; 4],
    /// Fragments whose alpha (texel × factor) is below this are discarded (glTF `MASK`);
    /// 0 keeps every fragment.
    pub alpha_cutoff: f32,
    /// Blend over what is drawn by alpha (glTF `BLEND`), after the camera's opaque
    /// surfaces, without writing depth; triangles are not sorted.
    pub blend: bool,
}

impl<'a> SurfaceMaterial<'a> {
    /// A plain colour (linear RGBA), untextured and opaque: with white, what the vertex
    /// colours say, lit.
    pub fn plain(factor: [f32; 4]) -> Self {
        Self {
            texture: None,
            factor,
            alpha_cutoff: 0.0,
            blend: false,
        }
    }

    /// `texture` as it is: white factor, no alpha cutoff, opaque.
    pub fn textured(texture: &'a Texture) -> Self {
        Self {
            texture: Some(texture),
            factor: [1.0; 4],
            alpha_cutoff: 0.0,
            blend: false,
        }
    }
}

/// The descriptor set layout, sampler and white texture every [`Recorder`](crate::Recorder)
/// shares among its pipelines and [`MaterialSet`]s, and the set palette draws bind.
pub(crate) struct Bindings {
    pub(crate) set_layout: vk::DescriptorSetLayout,
    pub(crate) sampler: vk::Sampler,
    white: Texture,
    /// One white vertex colour, bound with stride 0 for meshes without colours.
    pub(crate) white_colour: Buffer,
    pool: vk::DescriptorPool,
    /// The white texture's set, for palette colours.
    pub(crate) white_set: vk::DescriptorSet,
}

/// Creates the set layout of set 0.
fn set_layout(ctx: &Context) -> Result<vk::DescriptorSetLayout> {
    let bindings = [
        vk::DescriptorSetLayoutBinding::default()
            .binding(0)
            .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
            .descriptor_count(1)
            .stage_flags(vk::ShaderStageFlags::FRAGMENT),
        vk::DescriptorSetLayoutBinding::default()
            .binding(1)
            .descriptor_type(vk::DescriptorType::SAMPLER)
            .descriptor_count(1)
            .stage_flags(vk::ShaderStageFlags::FRAGMENT),
    ];
    let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
    // SAFETY: valid create info.
    unsafe { ctx.device.create_descriptor_set_layout(&info, None) }
        .vk("vkCreateDescriptorSetLayout")
}

/// Trilinear, repeating, every mip level.
fn sampler(ctx: &Context) -> Result<vk::Sampler> {
    let info = vk::SamplerCreateInfo::default()
        .mag_filter(vk::Filter::LINEAR)
        .min_filter(vk::Filter::LINEAR)
        .mipmap_mode(vk::SamplerMipmapMode::LINEAR)
        .address_mode_u(vk::SamplerAddressMode::REPEAT)
        .address_mode_v(vk::SamplerAddressMode::REPEAT)
        .address_mode_w(vk::SamplerAddressMode::REPEAT)
        .min_lod(0.0)
        .max_lod(vk::LOD_CLAMP_NONE);
    // SAFETY: valid create info.
    unsafe { ctx.device.create_sampler(&info, None) }.vk("vkCreateSampler")
}

/// A pool for `sets` sets of set 0.
fn pool(ctx: &Context, sets: u32) -> Result<vk::DescriptorPool> {
    let sizes = [
        vk::DescriptorPoolSize {
            ty: vk::DescriptorType::SAMPLED_IMAGE,
            descriptor_count: sets,
        },
        vk::DescriptorPoolSize {
            ty: vk::DescriptorType::SAMPLER,
            descriptor_count: sets,
        },
    ];
    let info = vk::DescriptorPoolCreateInfo::default()
        .max_sets(sets)
        .pool_sizes(&sizes);
    // SAFETY: valid create info.
    unsafe { ctx.device.create_descriptor_pool(&info, None) }.vk("vkCreateDescriptorPool")
}

/// Allocates one set per view from `pool` and writes each with its view and `sampler`.
fn write_sets(
    ctx: &Context,
    pool: vk::DescriptorPool,
    layout: vk::DescriptorSetLayout,
    sampler: vk::Sampler,
    views: &[vk::ImageView],
) -> Result<Vec<vk::DescriptorSet>> {
    if views.is_empty() {
        return Ok(Vec::new());
    }
    let layouts = vec![layout; views.len()];
    let alloc = vk::DescriptorSetAllocateInfo::default()
        .descriptor_pool(pool)
        .set_layouts(&layouts);
    // SAFETY: the pool was sized for these sets.
    let sets =
        unsafe { ctx.device.allocate_descriptor_sets(&alloc) }.vk("vkAllocateDescriptorSets")?;
    for (&set, &view) in sets.iter().zip(views) {
        let image = [vk::DescriptorImageInfo {
            sampler: vk::Sampler::null(),
            image_view: view,
            image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
        }];
        let samplers = [vk::DescriptorImageInfo {
            sampler,
            image_view: vk::ImageView::null(),
            image_layout: vk::ImageLayout::UNDEFINED,
        }];
        let writes = [
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                .image_info(&image),
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::SAMPLER)
                .image_info(&samplers),
        ];
        // SAFETY: the set is unused by pending work (just allocated); view and sampler are
        // alive.
        unsafe { ctx.device.update_descriptor_sets(&writes, &[]) };
    }
    Ok(sets)
}

impl Bindings {
    /// Creates the layout, the sampler, the white texture (one small upload, submitted and
    /// waited for) and its set.
    pub(crate) fn new(ctx: &Context) -> Result<Self> {
        let set_layout = set_layout(ctx)?;
        let sampler = match sampler(ctx) {
            Ok(s) => s,
            Err(e) => {
                // SAFETY: unused.
                unsafe { ctx.device.destroy_descriptor_set_layout(set_layout, None) };
                return Err(e);
            }
        };
        let partial = |white: Option<Texture>, pool: Option<vk::DescriptorPool>| {
            // SAFETY: nothing uses them yet.
            unsafe {
                if let Some(p) = pool {
                    ctx.device.destroy_descriptor_pool(p, None);
                }
                ctx.device.destroy_sampler(sampler, None);
                ctx.device.destroy_descriptor_set_layout(set_layout, None);
            }
            if let Some(w) = white {
                let _ = w.destroy(ctx);
            }
        };
        let desc = TextureDesc {
            width: 1,
            height: 1,
            srgb: false,
        };
        let white = match Texture::new(ctx, "white texture", desc, &[255; 4]) {
            Ok(t) => t,
            Err(e) => {
                partial(None, None);
                return Err(e);
            }
        };
        let pool = match pool(ctx, 1) {
            Ok(p) => p,
            Err(e) => {
                partial(Some(white), None);
                return Err(e);
            }
        };
        let white_colour = match upload(
            ctx,
            "white vertex colour",
            &[255; 4],
            vk::BufferUsageFlags::VERTEX_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER,
        ) {
            Ok(b) => b,
            Err(e) => {
                partial(Some(white), Some(pool));
                return Err(e);
            }
        };
        match write_sets(ctx, pool, set_layout, sampler, &[white.image.view]) {
            Ok(sets) if sets.len() == 1 => Ok(Self {
                set_layout,
                sampler,
                white,
                white_colour,
                pool,
                white_set: sets[0],
            }),
            Ok(_) => {
                let _ = white_colour.destroy(ctx);
                partial(Some(white), Some(pool));
                Err(Error::InvalidArgument("no descriptor set allocated".into()))
            }
            Err(e) => {
                let _ = white_colour.destroy(ctx);
                partial(Some(white), Some(pool));
                Err(e)
            }
        }
    }

    /// Destroys everything. The GPU must be done with it.
    pub(crate) fn destroy(self, ctx: &Context) -> Result<()> {
        // SAFETY: the caller guarantees no pending work uses them; the pool's sets go with it.
        unsafe {
            ctx.device.destroy_descriptor_pool(self.pool, None);
            ctx.device.destroy_sampler(self.sampler, None);
            ctx.device
                .destroy_descriptor_set_layout(self.set_layout, None);
        }
        let colour = self.white_colour.destroy(ctx);
        self.white.destroy(ctx).and(colour)
    }
}

/// Per surface a material as the GPU draws it: its descriptor set and push values, for
/// [`RecordCamera::materials`](crate::RecordCamera). Made for one [`Recorder`](crate::Recorder)
/// (its layout and sampler); the textures it names must outlive it.
#[derive(Debug)]
pub struct MaterialSet {
    pool: vk::DescriptorPool,
    sets: Vec<vk::DescriptorSet>,
    looks: Vec<([f32; 4], f32)>,
    blend: Vec<bool>,
}

impl MaterialSet {
    /// [`MaterialSet::new`](crate::MaterialSet::new) over the recorder's bindings `b`.
    pub(crate) fn with_bindings(
        ctx: &Context,
        b: &Bindings,
        surfaces: &[SurfaceMaterial<'_>],
    ) -> Result<Self> {
        let count = u32::try_from(surfaces.len().max(1))
            .map_err(|_| Error::InvalidArgument("too many surfaces for a material set".into()))?;
        let pool = pool(ctx, count)?;
        let views: Vec<vk::ImageView> = surfaces
            .iter()
            .map(|s| s.texture.map_or(b.white.image.view, |t| t.image.view))
            .collect();
        match write_sets(ctx, pool, b.set_layout, b.sampler, &views) {
            Ok(sets) => Ok(Self {
                pool,
                sets,
                looks: surfaces
                    .iter()
                    .map(|s| (s.factor, s.alpha_cutoff))
                    .collect(),
                blend: surfaces.iter().map(|s| s.blend).collect(),
            }),
            Err(e) => {
                // SAFETY: the pool's sets are unused.
                unsafe { ctx.device.destroy_descriptor_pool(pool, None) };
                Err(e)
            }
        }
    }

    /// Surfaces.
    pub fn len(&self) -> usize {
        self.sets.len()
    }

    /// `true` if it has no surface.
    pub fn is_empty(&self) -> bool {
        self.sets.is_empty()
    }

    /// Surface `s`'s set, factor and alpha cutoff.
    pub(crate) fn get(&self, s: usize) -> Option<(vk::DescriptorSet, [f32; 4], f32)> {
        let set = *self.sets.get(s)?;
        let (factor, cutoff) = *self.looks.get(s)?;
        Some((set, factor, cutoff))
    }

    /// Whether surface `s` blends.
    pub(crate) fn blends(&self, s: usize) -> Option<bool> {
        self.blend.get(s).copied()
    }

    /// Destroys the sets. The GPU must be done with every command buffer that bound them.
    pub fn destroy(self, ctx: &Context) {
        // SAFETY: the caller guarantees no pending work uses the sets.
        unsafe { ctx.device.destroy_descriptor_pool(self.pool, None) };
    }
}
