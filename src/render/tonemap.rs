//! The display pass: the renderer's linear HDR frame, tone mapped and sRGB encoded into an
//! 8-bit colour attachment (a swapchain image in the viewer), with the arithmetic of
//! [`crate::tone::ToneMap`] and [`crate::tone::linear_to_srgb`] — what the PNG path does
//! on the CPU — in `glsl/tonemap.frag`. `tests/viewer.rs` checks the two agree within 1/255.

use anyhow::{ensure, Result};
use bytemuck::{Pod, Zeroable};

use crate::shaders;
use crate::tone::{ToneMap, ToneOperator};
use crate::vk::{
    self, Access, Binding, Context, DescriptorSet, Filter, Framebuffer, GraphicsDesc,
    GraphicsPipeline, Image, Recorder, RenderPass, Sampler, Use,
};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Push {
    scale: f32,
    op: u32,
    encode_srgb: u32,
    pad: u32,
}

/// Source image (by [`Image::id`]), its descriptor set and the pipeline laid out for it.
struct Bound {
    source: u64,
    set: DescriptorSet,
    pipeline: GraphicsPipeline,
}

pub struct ToneMapPass {
    ctx: Context,
    render_pass: RenderPass,
    sampler: Sampler,
    format: vk::Format,
    encode_srgb: bool,
    bound: Option<Bound>,
}

impl ToneMapPass {
    /// A pass writing `format` attachments. `target_encodes_srgb`: the format is an …_SRGB
    /// one, so the shader writes linear values and the hardware encodes; otherwise (UNORM)
    /// the shader encodes.
    pub fn new(ctx: &Context, format: vk::Format, target_encodes_srgb: bool) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            render_pass: RenderPass::new(ctx, &[format], Access::ColorAttachment, "tonemap")?,
            sampler: Sampler::new(ctx, Filter::Nearest, "tonemap nearest")?,
            format,
            encode_srgb: !target_encodes_srgb,
            bound: None,
        })
    }

    /// The attachment format the pass writes.
    pub fn format(&self) -> vk::Format {
        self.format
    }

    /// The render pass framebuffers over the targets must be made for.
    pub fn render_pass(&self) -> &RenderPass {
        &self.render_pass
    }

    /// Record the pass: `source` (linear RGBA, the renderer's frame) → `target` (layer 0,
    /// through `framebuffer`, of the same size). The descriptor set and pipeline are kept
    /// while the source image stays the same one.
    pub fn record(
        &mut self,
        rec: &mut Recorder,
        source: &Image,
        target: &Image,
        framebuffer: &Framebuffer,
        tone: &ToneMap,
    ) -> Result<()> {
        let [w, h, _] = source.extent();
        let [tw, th, _] = target.extent();
        ensure!(
            (w, h) == (tw, th),
            "tonemap source is {w}x{h}, target {tw}x{th}; they must match"
        );
        if self.bound.as_ref().map(|b| b.source) != Some(source.id()) {
            self.bound = None;
            let set = DescriptorSet::new(
                &self.ctx,
                &[Binding::Texture(source, &self.sampler)],
                "tonemap",
            )?;
            let pipeline = GraphicsPipeline::new(
                &self.ctx,
                &GraphicsDesc::fullscreen(
                    shaders::FULLSCREEN_VERT,
                    shaders::TONEMAP_FRAG,
                    &self.render_pass,
                    &set,
                    std::mem::size_of::<Push>() as u32,
                ),
                "tonemap",
            )?;
            self.bound = Some(Bound {
                source: source.id(),
                set,
                pipeline,
            });
        }
        let bound = self.bound.as_ref().expect("just bound");
        let push = Push {
            scale: tone.exposure.exp2(),
            op: match tone.operator {
                ToneOperator::None => 0,
                ToneOperator::Reinhard => 1,
                ToneOperator::Aces => 2,
            },
            encode_srgb: u32::from(self.encode_srgb),
            pad: 0,
        };
        let render_pass = &self.render_pass;
        rec.pass("tonemap", &[Use::all(source, Access::Sampled)], |rec| {
            rec.begin_render_pass(render_pass, framebuffer, &[(target, 0)])?;
            rec.bind_graphics(&bound.pipeline, &bound.set, w, h);
            rec.draw_fullscreen(&bound.pipeline, bytemuck::bytes_of(&push))?;
            rec.end_render_pass();
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_matches_the_shaders_block() {
        let host = crate::host_layout!(Push {
            scale,
            op,
            encode_srgb,
            pad
        });
        crate::vk::spirv::check_block(
            shaders::TONEMAP_FRAG,
            "Push",
            &host,
            std::mem::size_of::<Push>(),
            false,
        )
        .unwrap();
    }
}
