//! The display pass: the renderer's linear HDR frame, tone mapped and sRGB encoded into an
//! 8-bit colour attachment (a swapchain image in the viewer), with the arithmetic of
//! [`crate::tone::ToneMap`] and [`crate::tone::linear_to_srgb`] — what the PNG path does
//! on the CPU — in `glsl/tonemap.frag`. `tests/viewer.rs` checks the two agree within 1/255.
//!
//! The source may be smaller than the target: the viewer's previews are rendered at a
//! fraction of the window's size and shown magnified (bilinear between the source's pixel
//! centres). At equal sizes each pixel is its source texel, exactly. The viewer also draws
//! a small axes marker into a corner (the world's x, y, z as red, green, blue lines).

use anyhow::{ensure, Result};
use bytemuck::{Pod, Zeroable};

use crate::camera::Camera;
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
    /// 1: draw the axes marker.
    axes: u32,
    /// The target's size in pixels (the source's comes from the image).
    target: [u32; 2],
    pad: [u32; 2],
    /// The world's x, y and z axes on the screen: (right, down, towards the viewer)
    /// components of each unit axis.
    axis: [[f32; 4]; 3],
}

/// Source images the pass keeps descriptor sets for (the viewer's full frame and preview).
const BOUND_SOURCES: usize = 4;

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
    /// Most recently used first.
    bound: Vec<Bound>,
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
            bound: Vec::new(),
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
    /// through `framebuffer`), magnified when the source is smaller, with the axes marker
    /// of `axes`' view when given. Descriptor sets and pipelines are kept for the last few
    /// source images.
    pub fn record(
        &mut self,
        rec: &mut Recorder,
        source: &Image,
        target: &Image,
        framebuffer: &Framebuffer,
        tone: &ToneMap,
        axes: Option<&Camera>,
    ) -> Result<()> {
        let [w, h, _] = source.extent();
        let [tw, th, _] = target.extent();
        ensure!(
            w <= tw && h <= th,
            "tonemap source is {w}x{h}, larger than its target {tw}x{th}"
        );
        match self.bound.iter().position(|b| b.source == source.id()) {
            Some(i) => {
                let b = self.bound.remove(i);
                self.bound.insert(0, b);
            }
            None => {
                self.bound.truncate(BOUND_SOURCES - 1);
                let b = self.bind(source)?;
                self.bound.insert(0, b);
            }
        }
        let bound = &self.bound[0];
        let mut axis = [[0.0; 4]; 3];
        if let Some(camera) = axes {
            let (_, forward, right, up) = camera.frame();
            for (a, world) in axis
                .iter_mut()
                .zip([glam::Vec3::X, glam::Vec3::Y, glam::Vec3::Z])
            {
                *a = [right.dot(world), -up.dot(world), -forward.dot(world), 0.0];
            }
        }
        let push = Push {
            scale: tone.exposure.exp2(),
            op: match tone.operator {
                ToneOperator::None => 0,
                ToneOperator::Reinhard => 1,
                ToneOperator::Aces => 2,
            },
            encode_srgb: u32::from(self.encode_srgb),
            axes: u32::from(axes.is_some()),
            target: [tw, th],
            pad: [0; 2],
            axis,
        };
        let render_pass = &self.render_pass;
        rec.pass("tonemap", &[Use::all(source, Access::Sampled)], |rec| {
            rec.begin_render_pass(render_pass, framebuffer, &[(target, 0)])?;
            rec.bind_graphics(&bound.pipeline, &bound.set, tw, th);
            rec.draw_fullscreen(&bound.pipeline, bytemuck::bytes_of(&push))?;
            rec.end_render_pass();
            Ok(())
        })
    }

    /// A descriptor set over `source` and a pipeline laid out for it.
    fn bind(&self, source: &Image) -> Result<Bound> {
        {
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
            Ok(Bound {
                source: source.id(),
                set,
                pipeline,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_matches_the_shaders_block() {
        crate::assert_host_block!(
            shaders::TONEMAP_FRAG,
            "Push",
            Push {
                scale,
                op,
                encode_srgb,
                axes,
                target,
                pad,
                axis
            },
            exact_size = false
        );
    }
}
