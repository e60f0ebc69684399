//! The baseline emission–absorption ray marcher (`glsl/ea.comp`), the reference every
//! refractive image is compared against.

use anyhow::{ensure, Result};
use bytemuck::{Pod, Zeroable};

use super::model::{Inputs, ModelPass, Recorded};
use super::{FrameTarget, RenderOptions};
use crate::shaders;
use crate::vk::{Access, Binding, Buffer, ComputePipeline, DescriptorSet, Recorder, Use};

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

/// What the EA model refuses that every model accepts.
pub(super) fn check(opts: &RenderOptions) -> Result<()> {
    ensure!(
        opts.sweep.dumps.is_empty(),
        "state-buffer dumps are the refractive sweep's (--model refract); the EA ray \
         marcher has no state buffers"
    );
    Ok(())
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
    pub fn new(inputs: &Inputs, width: u32, height: u32) -> Result<Self> {
        let ctx = inputs.ctx;
        let sampler = inputs.linear;
        let params = Buffer::uniform::<Params>(ctx, "ea params")?;
        let output = FrameTarget::new(ctx, width, height, "ea frame")?;
        let set = DescriptorSet::new(
            ctx,
            &[
                Binding::Uniform(&params),
                Binding::Texture(inputs.volume, sampler),
                Binding::Texture(inputs.tf, sampler),
                Binding::Texture(inputs.preint, sampler),
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
}

impl ModelPass for EaPass {
    fn fits(&self, opts: &RenderOptions) -> bool {
        (self.width, self.height) == (opts.width, opts.height)
    }

    fn output(&self) -> &FrameTarget {
        &self.output
    }

    /// The ray march; the most steps a ray takes is the box diagonal's.
    fn record(&mut self, rec: &mut Recorder, inputs: &Inputs) -> Result<Recorded> {
        let (info, camera, opts) = (inputs.info, inputs.camera, inputs.opts);
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
            Use::all(inputs.volume, Access::Sampled),
            Use::all(inputs.tf, Access::Sampled),
            Use::all(inputs.preint, Access::Sampled),
            Use::all(&self.output.image, Access::ComputeStorage),
        ];
        let groups = [self.width.div_ceil(8), self.height.div_ceil(8), 1];
        rec.pass("ea raymarch", &uses, |rec| {
            rec.dispatch(&self.pipeline, &self.set, &[], groups)
        })?;
        Ok(Recorded {
            max_steps: super::steps_for(info.half_extent, info.ref_step, opts.sample_distance)
                as u32,
            sweep: None,
        })
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
