//! Geomorphs on the GPU: `geomorph_cs` writes `morph_vertex(a[i], b[i], t)` of two vertex
//! buffers into a third, the same function ([`caveclod_core::gpu::morph_vertex`]) the CPU
//! runs, so results can be compared directly.

use ash::vk;
use caveclod_core::format::Vertex;
use caveclod_core::gpu::MorphPush;

use crate::buffer::{Buffer, BufferDesc};
use crate::device::Context;
use crate::error::{Error, Result, VkResultExt};
use crate::mesh::upload;
use crate::pipeline::{ComputePipeline, GEOMORPH_LOCAL_SIZE};

/// The geomorph compute pipeline with a descriptor pool for its dispatches.
#[derive(Debug)]
pub struct Geomorph {
    pipeline: ComputePipeline,
    pool: vk::DescriptorPool,
}

impl Geomorph {
    /// Creates the pipeline and a descriptor pool.
    pub fn new(ctx: &Context) -> Result<Self> {
        let pipeline = ComputePipeline::geomorph(ctx)?;
        let sizes = [vk::DescriptorPoolSize {
            ty: vk::DescriptorType::STORAGE_BUFFER,
            descriptor_count: 3,
        }];
        let info = vk::DescriptorPoolCreateInfo::default()
            .flags(vk::DescriptorPoolCreateFlags::FREE_DESCRIPTOR_SET)
            .max_sets(1)
            .pool_sizes(&sizes);
        // SAFETY: valid create info.
        match unsafe { ctx.device.create_descriptor_pool(&info, None) }.vk("vkCreateDescriptorPool")
        {
            Ok(pool) => Ok(Self { pipeline, pool }),
            Err(e) => {
                pipeline.destroy(ctx);
                Err(e)
            }
        }
    }

    /// Records a dispatch of `push.count` morphs from the storage buffers `a` and `b` into
    /// `out`, using descriptor `set` (from this pool, written by the caller).
    fn record(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        set: vk::DescriptorSet,
        push: MorphPush,
    ) {
        let d = &ctx.device;
        // SAFETY: `cmd` is recording; set and pipeline are alive and compatible.
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline.raw);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                self.pipeline.layout,
                0,
                &[set],
                &[],
            );
            d.cmd_push_constants(
                cmd,
                self.pipeline.layout,
                vk::ShaderStageFlags::COMPUTE,
                0,
                bytemuck::bytes_of(&push),
            );
            d.cmd_dispatch(cmd, push.count.div_ceil(GEOMORPH_LOCAL_SIZE), 1, 1);
        }
    }

    /// Morphs `a[i]` towards `b[i]` by `t` on the GPU and reads the result back.
    pub fn morph(&self, ctx: &Context, a: &[Vertex], b: &[Vertex], t: f32) -> Result<Vec<Vertex>> {
        if a.len() != b.len() || a.is_empty() {
            return Err(Error::InvalidArgument(format!(
                "geomorph of {} and {} vertices (need equal, non-zero counts)",
                a.len(),
                b.len()
            )));
        }
        let count = u32::try_from(a.len())
            .map_err(|_| Error::InvalidArgument("too many vertices for one dispatch".into()))?;
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let buf_a = upload(ctx, "geomorph a", bytemuck::cast_slice(a), usage)?;
        let buf_b = match upload(ctx, "geomorph b", bytemuck::cast_slice(b), usage) {
            Ok(x) => x,
            Err(e) => {
                buf_a.destroy(ctx)?;
                return Err(e);
            }
        };
        let size = std::mem::size_of_val(a) as u64;
        let out = Buffer::new(ctx, "geomorph out", BufferDesc::gpu_to_cpu(size, usage));
        let result = out.and_then(|out| {
            let r = self.dispatch(ctx, &buf_a, &buf_b, &out, t, count);
            let read = r.and_then(|()| {
                let bytes = out.mapped().ok_or_else(|| {
                    Error::InvalidArgument("geomorph output is not host-visible".into())
                })?;
                Ok(bytes[..size as usize]
                    .chunks_exact(std::mem::size_of::<Vertex>())
                    .map(bytemuck::pod_read_unaligned::<Vertex>)
                    .collect())
            });
            out.destroy(ctx)?;
            read
        });
        buf_a.destroy(ctx)?;
        buf_b.destroy(ctx)?;
        result
    }

    fn dispatch(
        &self,
        ctx: &Context,
        a: &Buffer,
        b: &Buffer,
        out: &Buffer,
        t: f32,
        count: u32,
    ) -> Result<()> {
        let d = &ctx.device;
        let layouts = [self.pipeline.set_layout];
        let alloc = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.pool)
            .set_layouts(&layouts);
        // SAFETY: the pool has room for one set of this layout.
        let set = unsafe { d.allocate_descriptor_sets(&alloc) }
            .vk("vkAllocateDescriptorSets")?
            .first()
            .copied()
            .ok_or_else(|| Error::InvalidArgument("no descriptor set allocated".into()))?;
        let infos = [a, b, out].map(|buf| {
            [vk::DescriptorBufferInfo {
                buffer: buf.raw,
                offset: 0,
                range: vk::WHOLE_SIZE,
            }]
        });
        let writes: Vec<_> = infos
            .iter()
            .enumerate()
            .map(|(i, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(i as u32)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(info)
            })
            .collect();
        // SAFETY: the set and buffers are alive; no pending work uses the set.
        unsafe { d.update_descriptor_sets(&writes, &[]) };
        let push = MorphPush {
            t,
            count,
            src_offset: 0,
            dst_offset: 0,
        };
        let r = ctx.submit_and_wait(|cmd| {
            self.record(ctx, cmd, set, push);
            let barrier = [vk::BufferMemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
                .src_access_mask(vk::AccessFlags2::SHADER_STORAGE_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::HOST)
                .dst_access_mask(vk::AccessFlags2::HOST_READ)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .buffer(out.raw)
                .offset(0)
                .size(vk::WHOLE_SIZE)];
            let dep = vk::DependencyInfo::default().buffer_memory_barriers(&barrier);
            // SAFETY: `cmd` is recording.
            unsafe { d.cmd_pipeline_barrier2(cmd, &dep) };
        });
        // SAFETY: the dispatch completed (or the device is idle after a failure).
        let freed = unsafe { d.free_descriptor_sets(self.pool, &[set]) }.vk("vkFreeDescriptorSets");
        r.and(freed)
    }

    /// Destroys pipeline and pool. The GPU must be done with them.
    pub fn destroy(self, ctx: &Context) {
        // SAFETY: no pending work uses them.
        unsafe { ctx.device.destroy_descriptor_pool(self.pool, None) };
        self.pipeline.destroy(ctx);
    }
}
