//! The baseline emission–absorption ray marcher (`glsl/ea.comp`), the reference every
//! refractive image is compared against.

use anyhow::Result;
use bytemuck::{Pod, Zeroable};

use super::{Camera, FrameTarget, RenderOptions, VolumeInfo};
use crate::shaders;
use crate::vk::{
    Access, Binding, Buffer, ComputePipeline, Context, DescriptorSet, Image, Recorder, Sampler, Use,
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
    output: FrameTarget,
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
        let params = Buffer::uniform::<Params>(ctx, "ea params")?;
        let output = FrameTarget::new(ctx, width, height, "ea frame")?;
        let set = DescriptorSet::new(
            ctx,
            &[
                Binding::Uniform(&params),
                Binding::Texture(volume, sampler),
                Binding::Texture(tf, sampler),
                Binding::Texture(preint, sampler),
                Binding::StorageImage(&output.image),
            ],
            "ea",
        )?;
        let pipeline = ComputePipeline::new(ctx, shaders::EA_COMP, &set, 0, "ea raymarch")?;
        Ok(Self {
            params,
            output,
            set,
            pipeline,
            width,
            height,
        })
    }

    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The finished frame (linear RGBA32F) once a recording has run.
    pub fn output(&self) -> &FrameTarget {
        &self.output
    }

    /// Record the ray march into [`EaPass::output`]; returns the most steps a ray takes.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        rec: &mut Recorder,
        info: VolumeInfo,
        camera: &Camera,
        opts: &RenderOptions,
        volume: &Image,
        tf: &Image,
        preint: &Image,
    ) -> Result<u32> {
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
        rec.update_uniform(&self.params, bytemuck::bytes_of(&p))?;
        let uses = [
            Use::all(volume, Access::Sampled),
            Use::all(tf, Access::Sampled),
            Use::all(preint, Access::Sampled),
            Use::all(&self.output.image, Access::ComputeStorage),
        ];
        let groups = [self.width.div_ceil(8), self.height.div_ceil(8), 1];
        rec.pass("ea raymarch", &uses, |rec| {
            rec.dispatch(&self.pipeline, &self.set, &[], groups)
        })?;
        // Longest possible ray through the box, in steps: the box diagonal.
        Ok(super::steps_for(info.half_extent, info.ref_step, opts.sample_distance) as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_match_the_shaders_block() {
        let host = crate::host_layout!(Params {
            cam_pos,
            cam_forward,
            cam_right,
            cam_up,
            box_half,
            background,
            march,
            size,
        });
        crate::vk::spirv::check_block(
            shaders::EA_COMP,
            "Params",
            &host,
            std::mem::size_of::<Params>(),
            true,
        )
        .unwrap();
    }
}
