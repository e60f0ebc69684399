//! Descriptor sets and pipelines.
//!
//! A [`DescriptorSet`] owns its layout and pool: refrakt binds one set per pass and never
//! updates it while a frame is being recorded, so the simplest ownership is the right one.

use anyhow::{ensure, Context as _, Result};
use ash::vk;

use std::ops::Range;

use super::resources::{TrackedBuffer, TrackedImage};
use super::{Access, Buffer, Context, Image, LayerView, Sampler};

/// One binding of a descriptor set, in binding order (binding i = slice index i).
#[derive(Clone, Copy)]
pub enum Binding<'a> {
    /// Combined image sampler over the image's full view, in SHADER_READ_ONLY_OPTIMAL.
    Texture(&'a Image, &'a Sampler),
    /// Combined image sampler over one layer of an array, in the layout of the given
    /// access (`Access::Sampled` or `Access::SampledGeneral`).
    LayerTexture(&'a LayerView, &'a Sampler, Access),
    /// Combined image sampler over the image's full view (all layers of an array), in the
    /// layout of the given access (`Access::SampledGeneral` for the ping-pong images,
    /// whose other layer is an attachment meanwhile).
    ArrayTexture(&'a Image, &'a Sampler, Access),
    /// Storage image over the full view, in GENERAL.
    StorageImage(&'a Image),
    Uniform(&'a Buffer),
    Storage(&'a Buffer),
}

pub struct DescriptorSet {
    ctx: Context,
    pub(crate) layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    pub(crate) raw: vk::DescriptorSet,
    /// The images the set binds and the use each binding declares: a dispatch with the
    /// set takes them there first ([`crate::vk::Recorder::dispatch`]).
    pub(crate) images: Vec<BoundImage>,
    /// The storage buffers the set binds (read and written by its dispatches).
    pub(crate) storage_buffers: Vec<TrackedBuffer>,
    /// Whether its dispatches take the barriers its bindings declare (the default) or its
    /// user records them itself ([`DescriptorSet::with_explicit_barriers`]).
    pub(crate) explicit_barriers: bool,
    name: String,
}

/// An image (or layers of one) a set binds, and how its binding uses it.
pub(crate) struct BoundImage {
    pub(crate) image: TrackedImage,
    pub(crate) layers: Range<u32>,
    pub(crate) access: Access,
}

impl Binding<'_> {
    /// The image this binding reads or writes, the layers, and the use its descriptor
    /// declares (a sampled binding's layout, a storage image's GENERAL read and write).
    fn image_use(&self) -> Option<BoundImage> {
        let all = |img: &Image| 0..img.desc().layers;
        let (image, layers, access) = match *self {
            Binding::Texture(img, _) => (img.tracked(), all(img), Access::Sampled),
            Binding::LayerTexture(view, _, access) => {
                (view.image.clone(), view.layer..view.layer + 1, access)
            }
            Binding::ArrayTexture(img, _, access) => (img.tracked(), all(img), access),
            Binding::StorageImage(img) => (img.tracked(), all(img), Access::ComputeStorage),
            Binding::Uniform(_) | Binding::Storage(_) => return None,
        };
        Some(BoundImage {
            image,
            layers,
            access,
        })
    }
}

impl DescriptorSet {
    pub fn new(ctx: &Context, bindings: &[Binding<'_>], name: &str) -> Result<Self> {
        Self::check_ranges(ctx, bindings, name)?;
        let device = ctx.device();
        let stages = vk::ShaderStageFlags::COMPUTE
            | vk::ShaderStageFlags::FRAGMENT
            | vk::ShaderStageFlags::VERTEX;
        let ty = |b: &Binding| match b {
            Binding::Texture(..) | Binding::LayerTexture(..) | Binding::ArrayTexture(..) => {
                vk::DescriptorType::COMBINED_IMAGE_SAMPLER
            }
            Binding::StorageImage(_) => vk::DescriptorType::STORAGE_IMAGE,
            Binding::Uniform(_) => vk::DescriptorType::UNIFORM_BUFFER,
            Binding::Storage(_) => vk::DescriptorType::STORAGE_BUFFER,
        };
        let layout_bindings: Vec<_> = bindings
            .iter()
            .enumerate()
            .map(|(i, b)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i as u32)
                    .descriptor_type(ty(b))
                    .descriptor_count(1)
                    .stage_flags(stages)
            })
            .collect();
        // SAFETY: valid device; infos reference locals.
        let layout = unsafe {
            device.create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default().bindings(&layout_bindings),
                None,
            )
        }?;
        let sizes: Vec<_> = bindings
            .iter()
            .map(|b| vk::DescriptorPoolSize {
                ty: ty(b),
                descriptor_count: 1,
            })
            .collect();
        let pool = unsafe {
            device.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default()
                    .max_sets(1)
                    .pool_sizes(&sizes),
                None,
            )
        }?;
        let layouts = [layout];
        let raw = unsafe {
            device.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default()
                    .descriptor_pool(pool)
                    .set_layouts(&layouts),
            )
        }?[0];
        let set = Self {
            ctx: ctx.clone(),
            layout,
            pool,
            raw,
            images: bindings.iter().filter_map(Binding::image_use).collect(),
            storage_buffers: bindings
                .iter()
                .filter_map(|b| match b {
                    Binding::Storage(buf) => Some(buf.tracked()),
                    _ => None,
                })
                .collect(),
            explicit_barriers: false,
            name: name.to_owned(),
        };
        set.write(bindings);
        ctx.set_name(raw, name);
        ctx.set_name(layout, name);
        Ok(set)
    }

    /// Every buffer is bound whole, and a binding may not exceed the device's range for
    /// its kind (maxStorageBufferRange: 128 MiB on lavapipe; maxUniformBufferRange): a
    /// larger one is refused here, with the buffer named, rather than bound past the
    /// limit (which the validation layer reports and a driver need not honour).
    fn check_ranges(ctx: &Context, bindings: &[Binding<'_>], name: &str) -> Result<()> {
        let limits = ctx.info().limits;
        for (i, b) in bindings.iter().enumerate() {
            let (buf, limit, what) = match b {
                Binding::Storage(buf) => (
                    buf,
                    limits.max_storage_buffer_range,
                    "maxStorageBufferRange",
                ),
                Binding::Uniform(buf) => (
                    buf,
                    limits.max_uniform_buffer_range,
                    "maxUniformBufferRange",
                ),
                _ => continue,
            };
            ensure!(
                buf.size() <= limit as u64,
                "descriptor set '{name}', binding {i}: buffer '{}' is {} bytes, more than \
                 device '{}' binds at once ({limit} bytes, {what})",
                buf.name(),
                buf.size(),
                ctx.info().name
            );
        }
        Ok(())
    }

    /// This set's dispatches take no barriers from its bindings: its user records them
    /// (the plane sweep, whose sets bind both layers of the ping-pong images, one read and
    /// one written per plane, so no single use per binding describes them).
    pub fn with_explicit_barriers(mut self) -> Self {
        self.explicit_barriers = true;
        self
    }

    pub(crate) fn name(&self) -> &str {
        &self.name
    }

    fn write(&self, bindings: &[Binding<'_>]) {
        let image_infos: Vec<[vk::DescriptorImageInfo; 1]> = bindings
            .iter()
            .map(|b| match b {
                Binding::Texture(img, s) => [vk::DescriptorImageInfo {
                    sampler: s.raw,
                    image_view: img.view,
                    image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                }],
                Binding::LayerTexture(view, s, access) => [vk::DescriptorImageInfo {
                    sampler: s.raw,
                    image_view: view.raw,
                    image_layout: access.layout(),
                }],
                Binding::ArrayTexture(img, s, access) => [vk::DescriptorImageInfo {
                    sampler: s.raw,
                    image_view: img.view,
                    image_layout: access.layout(),
                }],
                Binding::StorageImage(img) => [vk::DescriptorImageInfo {
                    sampler: vk::Sampler::null(),
                    image_view: img.view,
                    image_layout: vk::ImageLayout::GENERAL,
                }],
                _ => [vk::DescriptorImageInfo::default()],
            })
            .collect();
        let buffer_infos: Vec<[vk::DescriptorBufferInfo; 1]> = bindings
            .iter()
            .map(|b| match b {
                Binding::Uniform(buf) | Binding::Storage(buf) => [vk::DescriptorBufferInfo {
                    buffer: buf.raw,
                    offset: 0,
                    range: vk::WHOLE_SIZE,
                }],
                _ => [vk::DescriptorBufferInfo::default()],
            })
            .collect();
        let writes: Vec<_> = bindings
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let w = vk::WriteDescriptorSet::default()
                    .dst_set(self.raw)
                    .dst_binding(i as u32);
                match b {
                    Binding::Texture(..)
                    | Binding::LayerTexture(..)
                    | Binding::ArrayTexture(..) => w
                        .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                        .image_info(&image_infos[i]),
                    Binding::StorageImage(_) => w
                        .descriptor_type(vk::DescriptorType::STORAGE_IMAGE)
                        .image_info(&image_infos[i]),
                    Binding::Uniform(_) => w
                        .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                        .buffer_info(&buffer_infos[i]),
                    Binding::Storage(_) => w
                        .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                        .buffer_info(&buffer_infos[i]),
                }
            })
            .collect();
        // SAFETY: the set is not in use by pending work while being written.
        unsafe { self.ctx.device().update_descriptor_sets(&writes, &[]) };
    }
}

impl Drop for DescriptorSet {
    fn drop(&mut self) {
        // SAFETY: not in use by pending GPU work.
        unsafe {
            self.ctx.device().destroy_descriptor_pool(self.pool, None);
            self.ctx
                .device()
                .destroy_descriptor_set_layout(self.layout, None);
        }
    }
}

pub(crate) fn shader_module(ctx: &Context, spirv: &[u8], name: &str) -> Result<vk::ShaderModule> {
    let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
        .with_context(|| format!("shader '{name}' is not valid SPIR-V"))?;
    // SAFETY: valid device; code is SPIR-V produced by build.rs.
    let module = unsafe {
        ctx.device()
            .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None)
    }?;
    ctx.set_name(module, name);
    Ok(module)
}

/// What compute and graphics pipelines share: the handle, its layout (one descriptor set,
/// one push-constant range) and the name used in errors and debug labels.
pub(crate) struct PipelineCore {
    ctx: Context,
    pub(crate) raw: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    pub(crate) push_size: u32,
    pub(crate) name: String,
}

impl PipelineCore {
    /// Take the result of vkCreate*Pipelines; on failure free the layout and say which
    /// pipeline failed.
    pub(crate) fn finish(
        ctx: &Context,
        result: std::result::Result<Vec<vk::Pipeline>, (Vec<vk::Pipeline>, vk::Result)>,
        layout: vk::PipelineLayout,
        push_size: u32,
        name: &str,
        kind: &str,
    ) -> Result<Self> {
        let raw = match result {
            Ok(p) => p[0],
            Err((_, e)) => {
                // SAFETY: the layout was made for this pipeline and nothing else uses it.
                unsafe { ctx.device().destroy_pipeline_layout(layout, None) };
                return Err(e).with_context(|| format!("creating {kind} pipeline '{name}'"));
            }
        };
        ctx.set_name(raw, name);
        Ok(Self {
            ctx: ctx.clone(),
            raw,
            layout,
            push_size,
            name: name.to_owned(),
        })
    }
}

impl Drop for PipelineCore {
    fn drop(&mut self) {
        // SAFETY: not in use by pending GPU work.
        unsafe {
            self.ctx.device().destroy_pipeline(self.raw, None);
            self.ctx.device().destroy_pipeline_layout(self.layout, None);
        }
    }
}

/// A compute pipeline with one descriptor set and optional push constants.
pub struct ComputePipeline {
    pub(crate) core: PipelineCore,
}

impl ComputePipeline {
    pub fn new(
        ctx: &Context,
        spirv: &[u8],
        set: &DescriptorSet,
        push_size: u32,
        name: &str,
    ) -> Result<Self> {
        Self::with_constants(ctx, spirv, set, push_size, &[], name)
    }

    /// As [`ComputePipeline::new`], with specialization constants: `constants[i]` is the
    /// 32-bit value of `constant_id = i`.
    pub fn with_constants(
        ctx: &Context,
        spirv: &[u8],
        set: &DescriptorSet,
        push_size: u32,
        constants: &[u32],
        name: &str,
    ) -> Result<Self> {
        let device = ctx.device();
        let layout = pipeline_layout(ctx, set, push_size)?;
        let module = match shader_module(ctx, spirv, name) {
            Ok(m) => m,
            Err(e) => {
                // SAFETY: created above, unused.
                unsafe { device.destroy_pipeline_layout(layout, None) };
                return Err(e);
            }
        };
        let entries = specialization_entries(constants);
        let spec = vk::SpecializationInfo::default()
            .map_entries(&entries)
            .data(bytemuck::cast_slice(constants));
        let mut stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main");
        if !constants.is_empty() {
            stage = stage.specialization_info(&spec);
        }
        let info = vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(layout);
        // SAFETY: valid module and layout.
        let result =
            unsafe { device.create_compute_pipelines(vk::PipelineCache::null(), &[info], None) };
        unsafe { device.destroy_shader_module(module, None) };
        Ok(Self {
            core: PipelineCore::finish(ctx, result, layout, push_size, name, "compute")?,
        })
    }
}

/// The map of 32-bit specialization constants: `constants[i]` is `constant_id = i`.
pub(crate) fn specialization_entries(constants: &[u32]) -> Vec<vk::SpecializationMapEntry> {
    (0..constants.len() as u32)
        .map(|i| vk::SpecializationMapEntry {
            constant_id: i,
            offset: 4 * i,
            size: 4,
        })
        .collect()
}

/// Every pipeline layout declares one push-constant range visible to all stages refrakt uses.
pub(crate) const PUSH_STAGES: vk::ShaderStageFlags = vk::ShaderStageFlags::from_raw(
    vk::ShaderStageFlags::COMPUTE.as_raw()
        | vk::ShaderStageFlags::FRAGMENT.as_raw()
        | vk::ShaderStageFlags::VERTEX.as_raw(),
);

pub(crate) fn pipeline_layout(
    ctx: &Context,
    set: &DescriptorSet,
    push_size: u32,
) -> Result<vk::PipelineLayout> {
    let max_push = ctx.info().limits.max_push_constants_size;
    anyhow::ensure!(
        push_size <= max_push,
        "push constants of {push_size} bytes exceed the device limit of {max_push}"
    );
    let ranges = [vk::PushConstantRange {
        stage_flags: PUSH_STAGES,
        offset: 0,
        size: push_size,
    }];
    let layouts = [set.layout];
    let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(&layouts);
    if push_size > 0 {
        info = info.push_constant_ranges(&ranges);
    }
    // SAFETY: valid device and set layout.
    Ok(unsafe { ctx.device().create_pipeline_layout(&info, None) }?)
}
