//! The baseline emission–absorption ray marcher (`glsl/ea.comp`), the reference every
//! refractive image is compared against.

use anyhow::Result;
use bytemuck::{Pod, Zeroable};

use super::{Camera, Frame, RenderOptions, VolumeInfo};
use crate::shaders;
use crate::vk::{
    self, Access, Binding, Buffer, ComputePipeline, Context, DescriptorSet, Image, ImageDesc,
    ImageKind, Memory, Sampler,
};

/// std140 mirror of `Params` in glsl/ea.comp.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    cam_pos: [f32; 4],
    cam_forward: [f32; 4],
    cam_right: [f32; 4],
    cam_up: [f32; 4],
    box_half: [f32; 4],
    background: [f32; 4],
    march: [f32; 4],
    size: [u32; 4],
}

pub(super) struct EaPass {
    params: Buffer,
    output: Image,
    readback: Buffer,
    set: DescriptorSet,
    pipeline: ComputePipeline,
    width: u32,
    height: u32,
}

impl EaPass {
    pub fn new(
        ctx: &Context,
        volume: &Image,
        tf: &Image,
        preint: &Image,
        sampler: &Sampler,
        width: u32,
        height: u32,
    ) -> Result<Self> {
        let params = Buffer::new(
            ctx,
            std::mem::size_of::<Params>() as u64,
            vk::usage::UNIFORM_BUFFER,
            Memory::Upload,
            "ea params",
        )?;
        let output = Image::new(
            ctx,
            ImageDesc {
                kind: ImageKind::D2,
                format: vk::Format::R32G32B32A32_SFLOAT,
                extent: [width, height, 1],
                layers: 1,
                usage: vk::usage::STORAGE | vk::usage::TRANSFER_SRC,
            },
            "ea frame",
        )?;
        let readback = Buffer::new(
            ctx,
            output.layer_bytes()?,
            vk::usage::BUFFER_TRANSFER_DST,
            Memory::Readback,
            "ea readback",
        )?;
        let set = DescriptorSet::new(
            ctx,
            &[
                Binding::Uniform(&params),
                Binding::Texture(volume, sampler),
                Binding::Texture(tf, sampler),
                Binding::Texture(preint, sampler),
                Binding::StorageImage(&output),
            ],
            "ea",
        )?;
        let pipeline = ComputePipeline::new(ctx, shaders::EA_COMP, &set, 0, "ea raymarch")?;
        Ok(Self {
            params,
            output,
            readback,
            set,
            pipeline,
            width,
            height,
        })
    }

    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    #[allow(clippy::too_many_arguments)]
    pub fn render(
        &mut self,
        ctx: &Context,
        info: VolumeInfo,
        camera: &Camera,
        opts: &RenderOptions,
        volume: &Image,
        tf: &Image,
        preint: &Image,
    ) -> Result<Frame> {
        let (eye, forward, right, up) = camera.frame();
        let tan_half = (camera.fov_y.to_radians() * 0.5).tan();
        let aspect = self.width as f32 / self.height as f32;
        let p = Params {
            cam_pos: [eye.x, eye.y, eye.z, tan_half],
            cam_forward: [forward.x, forward.y, forward.z, aspect],
            cam_right: [right.x, right.y, right.z, 0.0],
            cam_up: [up.x, up.y, up.z, 0.0],
            box_half: [
                info.half_extent.x,
                info.half_extent.y,
                info.half_extent.z,
                info.ref_step,
            ],
            background: opts.background,
            march: [
                opts.sample_distance,
                opts.termination_alpha,
                if opts.preintegrated { 1.0 } else { 0.0 },
                0.0,
            ],
            size: [self.width, self.height, 0, 0],
        };
        self.params.write(0, bytemuck::bytes_of(&p))?;
        let size = self.output.layer_bytes()?;
        let readback = &self.readback;
        let timings = ctx.execute(|rec| {
            rec.transition_all(volume, Access::Sampled);
            rec.transition_all(tf, Access::Sampled);
            rec.transition_all(preint, Access::Sampled);
            rec.transition_all(&self.output, Access::ComputeStorage);
            rec.begin_scope("ea raymarch");
            rec.dispatch(
                &self.pipeline,
                &self.set,
                &[],
                [self.width.div_ceil(8), self.height.div_ceil(8), 1],
            )?;
            rec.end_scope();
            rec.copy_image_to_buffer(&self.output, 0, readback);
            Ok(())
        })?;
        let pixels: Vec<[f32; 4]> =
            bytemuck::cast_slice(&readback.mapped()?[..size as usize]).to_vec();
        // Longest possible ray through the box, in steps: the box diagonal.
        let max_steps =
            super::steps_for(info.half_extent, info.ref_step, opts.sample_distance) as u32;
        Ok(Frame {
            width: self.width,
            height: self.height,
            pixels,
            timings,
            max_steps,
            dumps: Vec::new(),
            sweep: None,
        })
    }
}
