//! Render passes, framebuffers and graphics pipelines for full-screen passes.
//!
//! Passes whose output a later pass samples use a `VkRenderPass` rather than dynamic
//! rendering: the Debian validation layer (1.3.239) tracks synchronization hazards on
//! render-pass attachments only (measured), and we want sync validation to vouch for them.
//! The render pass performs no layout transitions (initial = subpass = final layout);
//! attachments are brought into that layout by `Recorder::transition` before the pass, so
//! every barrier stays explicit and visible in one place.

use anyhow::{ensure, Context as _, Result};
use ash::vk;

use super::pipeline::{pipeline_layout, shader_module, specialization_entries, PipelineCore};
use super::{Access, Context, DescriptorSet, LayerView};

pub struct RenderPass {
    ctx: Context,
    pub(crate) raw: vk::RenderPass,
    pub(crate) attachments: usize,
    pub(crate) access: Access,
    /// The pass clears its attachments to zero when it begins (accumulation targets).
    pub(crate) clears: bool,
}

impl RenderPass {
    /// One subpass writing `formats.len()` colour attachments. `access` is the state the
    /// attachments are in during the pass: `Access::ColorAttachment`, or
    /// `Access::AttachmentGeneral` for image arrays whose layers are rendered to and sampled
    /// in alternation.
    pub fn new(ctx: &Context, formats: &[vk::Format], access: Access, name: &str) -> Result<Self> {
        Self::create(ctx, formats, access, false, name)
    }

    /// Like [`RenderPass::new`], but every attachment is cleared to zero when the pass
    /// begins: for passes that accumulate into their attachments with additive blending.
    pub fn cleared(
        ctx: &Context,
        formats: &[vk::Format],
        access: Access,
        name: &str,
    ) -> Result<Self> {
        Self::create(ctx, formats, access, true, name)
    }

    fn create(
        ctx: &Context,
        formats: &[vk::Format],
        access: Access,
        clears: bool,
        name: &str,
    ) -> Result<Self> {
        ensure!(
            matches!(access, Access::ColorAttachment | Access::AttachmentGeneral),
            "render pass attachments must be in ColorAttachment or AttachmentGeneral state"
        );
        let max = ctx.info().limits.max_color_attachments as usize;
        ensure!(
            !formats.is_empty() && formats.len() <= max,
            "render pass '{name}' wants {} colour attachments; the device allows 1..={max}",
            formats.len()
        );
        let layout = access.layout();
        let attachments: Vec<_> = formats
            .iter()
            .map(|&format| {
                vk::AttachmentDescription::default()
                    .format(format)
                    .samples(vk::SampleCountFlags::TYPE_1)
                    // LOAD although full-screen passes overwrite every pixel: sync validation
                    // counts DONT_CARE as a write at vkCmdBeginRenderPass, and the plane sweep's
                    // descriptor set statically uses the views of both layers, so the layer
                    // being written would be reported as read-after-write (measured with the
                    // Debian layer 1.3.239). On immediate-mode GPUs and lavapipe LOAD is free.
                    .load_op(if clears {
                        vk::AttachmentLoadOp::CLEAR
                    } else {
                        vk::AttachmentLoadOp::LOAD
                    })
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
                    .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
                    .initial_layout(layout)
                    .final_layout(layout)
            })
            .collect();
        let refs: Vec<_> = (0..formats.len() as u32)
            .map(|i| vk::AttachmentReference {
                attachment: i,
                layout,
            })
            .collect();
        let subpass = vk::SubpassDescription::default()
            .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
            .color_attachments(&refs);
        let subpasses = [subpass];
        let info = vk::RenderPassCreateInfo::default()
            .attachments(&attachments)
            .subpasses(&subpasses);
        // SAFETY: valid device; info references locals.
        let raw = unsafe { ctx.device().create_render_pass(&info, None) }
            .with_context(|| format!("creating render pass '{name}'"))?;
        ctx.set_name(raw, name);
        Ok(Self {
            ctx: ctx.clone(),
            raw,
            attachments: formats.len(),
            access,
            clears,
        })
    }
}

impl Drop for RenderPass {
    fn drop(&mut self) {
        // SAFETY: not in use by pending GPU work.
        unsafe { self.ctx.device().destroy_render_pass(self.raw, None) };
    }
}

pub struct Framebuffer {
    ctx: Context,
    pub(crate) raw: vk::Framebuffer,
    pub(crate) extent: vk::Extent2D,
}

impl Framebuffer {
    /// A framebuffer over single-layer views (one per attachment of `pass`).
    pub fn new(
        ctx: &Context,
        pass: &RenderPass,
        views: &[&LayerView],
        width: u32,
        height: u32,
        name: &str,
    ) -> Result<Self> {
        ensure!(
            views.len() == pass.attachments,
            "framebuffer '{name}' has {} views for a pass of {} attachments",
            views.len(),
            pass.attachments
        );
        let raws: Vec<vk::ImageView> = views.iter().map(|v| v.raw).collect();
        let info = vk::FramebufferCreateInfo::default()
            .render_pass(pass.raw)
            .attachments(&raws)
            .width(width)
            .height(height)
            .layers(1);
        // SAFETY: views belong to this device and match the pass.
        let raw = unsafe { ctx.device().create_framebuffer(&info, None) }
            .with_context(|| format!("creating framebuffer '{name}'"))?;
        ctx.set_name(raw, name);
        Ok(Self {
            ctx: ctx.clone(),
            raw,
            extent: vk::Extent2D { width, height },
        })
    }
}

impl Drop for Framebuffer {
    fn drop(&mut self) {
        // SAFETY: not in use by pending GPU work.
        unsafe { self.ctx.device().destroy_framebuffer(self.raw, None) };
    }
}

/// How a [`GraphicsPipeline`] assembles and blends what its vertex shader generates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Primitives {
    /// Triangles written over the attachments (no blending): full-screen passes.
    Triangles,
    /// Points (the vertex shader writes gl_PointSize; sizes above 1 need the device's
    /// `largePoints`) added onto the attachments: ONE + ONE blending of every channel.
    AdditivePoints,
}

/// A graphics pipeline without vertex buffers (the vertex shader generates its geometry
/// from gl_VertexIndex), with dynamic viewport and scissor.
pub struct GraphicsPipeline {
    pub(crate) core: PipelineCore,
}

/// What a graphics pipeline is made from (everything but its name).
#[derive(Clone, Copy)]
pub struct GraphicsDesc<'a> {
    /// SPIR-V of the vertex and fragment shaders.
    pub vertex: &'a [u8],
    pub fragment: &'a [u8],
    pub pass: &'a RenderPass,
    pub set: &'a DescriptorSet,
    pub push_size: u32,
    pub primitives: Primitives,
    /// Both shaders' specialization constants: `constants[i]` is the 32-bit value
    /// of `constant_id = i` (a bool is 0 or 1). The driver compiles the pipeline with them
    /// folded in, so a branch on one costs nothing (llvmpipe runs both sides of a branch
    /// on a uniform otherwise).
    pub constants: &'a [u32],
}

impl<'a> GraphicsDesc<'a> {
    /// One full-screen triangle per draw, no blending, no specialization constants.
    pub fn fullscreen(
        vertex: &'a [u8],
        fragment: &'a [u8],
        pass: &'a RenderPass,
        set: &'a DescriptorSet,
        push_size: u32,
    ) -> Self {
        Self {
            vertex,
            fragment,
            pass,
            set,
            push_size,
            primitives: Primitives::Triangles,
            constants: &[],
        }
    }
}

impl GraphicsPipeline {
    /// Pipelines made from the same descriptor set and push size have compatible layouts:
    /// [`crate::vk::Recorder::bind_pipeline`] switches between them without rebinding the
    /// set (on lavapipe a set bind per plane costs ~4 ms and 3 MB; a pipeline switch with
    /// the set left bound costs almost nothing, measured).
    pub fn new(ctx: &Context, desc: &GraphicsDesc, name: &str) -> Result<Self> {
        let GraphicsDesc {
            vertex,
            fragment,
            pass,
            set,
            push_size,
            primitives,
            constants,
        } = *desc;
        let device = ctx.device();
        let entries = specialization_entries(constants);
        let spec = vk::SpecializationInfo::default()
            .map_entries(&entries)
            .data(bytemuck::cast_slice(constants));
        let layout = pipeline_layout(ctx, set, push_size)?;
        let vs = shader_module(ctx, vertex, &format!("{name} vs"))?;
        let fs = match shader_module(ctx, fragment, &format!("{name} fs")) {
            Ok(m) => m,
            Err(e) => {
                // SAFETY: created above, unused.
                unsafe {
                    device.destroy_shader_module(vs, None);
                    device.destroy_pipeline_layout(layout, None);
                }
                return Err(e);
            }
        };
        let stages = [
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::VERTEX)
                .module(vs)
                .name(c"main")
                .specialization_info(&spec),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::FRAGMENT)
                .module(fs)
                .name(c"main")
                .specialization_info(&spec),
        ];
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
        let assembly =
            vk::PipelineInputAssemblyStateCreateInfo::default().topology(match primitives {
                Primitives::Triangles => vk::PrimitiveTopology::TRIANGLE_LIST,
                Primitives::AdditivePoints => vk::PrimitiveTopology::POINT_LIST,
            });
        let viewport = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let blend_attachments: Vec<_> = (0..pass.attachments)
            .map(|_| {
                let state = vk::PipelineColorBlendAttachmentState::default()
                    .color_write_mask(vk::ColorComponentFlags::RGBA);
                match primitives {
                    Primitives::Triangles => state.blend_enable(false),
                    Primitives::AdditivePoints => state
                        .blend_enable(true)
                        .src_color_blend_factor(vk::BlendFactor::ONE)
                        .dst_color_blend_factor(vk::BlendFactor::ONE)
                        .color_blend_op(vk::BlendOp::ADD)
                        .src_alpha_blend_factor(vk::BlendFactor::ONE)
                        .dst_alpha_blend_factor(vk::BlendFactor::ONE)
                        .alpha_blend_op(vk::BlendOp::ADD),
                }
            })
            .collect();
        let blend =
            vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(layout)
            .render_pass(pass.raw)
            .subpass(0);
        // SAFETY: all referenced state lives until the call returns.
        let result =
            unsafe { device.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) };
        unsafe {
            device.destroy_shader_module(vs, None);
            device.destroy_shader_module(fs, None);
        }
        Ok(Self {
            core: PipelineCore::finish(ctx, result, layout, push_size, name, "graphics")?,
        })
    }
}
