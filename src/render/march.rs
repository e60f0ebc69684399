//! The emission–absorption ray march every ray-marched model shares (`glsl/march.glsl`;
//! EA, AO, single and ambient scattering differ only in how a segment is lit): its
//! parameter block ([`MarchParams`]) and the pass skeleton each model's pass wraps ([`RayMarchPass`],
//! [`delegate_to_march`]). Shared machinery, so it lives here and not in a model's
//! folder (issue 34).

use anyhow::Result;
use bytemuck::{Pod, Zeroable};

use super::model::{no_state_buffers, Inputs, OpticalModel, Recorded};
use super::{FrameTarget, LightSupport, RenderOptions};
use crate::vk::{Binding, Buffer, ComputePipeline, DescriptorSet, Recorder};

/// std140 mirror of `Params` in glsl/ea.comp: what the shared march (glsl/march.glsl)
/// reads, also the head of the AO model's block.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct MarchParams {
    cam_pos: [f32; 4],
    cam_forward: [f32; 4],
    cam_right: [f32; 4],
    cam_up: [f32; 4],
    box_half: [f32; 4],
    background: [f32; 4],
    march: [f32; 4],
    size: [u32; 4],
}

impl MarchParams {
    /// The camera, box and march of the frame `inputs` ask for, into a `width` × `height`
    /// image.
    pub(crate) fn new(inputs: &Inputs, width: u32, height: u32) -> Self {
        let (info, camera, opts) = (inputs.info, inputs.camera, inputs.opts);
        let (eye, forward, right, up) = camera.frame();
        let tan_half = (camera.fov_y.to_radians() * 0.5).tan();
        let aspect = width as f32 / height as f32;
        Self {
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
            size: [width, height, 0, 0],
        }
    }
}

/// The host layout of [`MarchParams`] for `spirv::check_block` (each model's block puts
/// its own members after it: [`check_params_block`]).
#[cfg(test)]
fn march_layout() -> Vec<(&'static str, usize, usize)> {
    crate::host_layout!(MarchParams {
        cam_pos,
        cam_forward,
        cam_right,
        cam_up,
        box_half,
        background,
        march,
        size,
    })
}

/// Checks a ray-marched model's `Params` block in `spirv` against the host's: the
/// march's members, then `own` (the model's, from `host_layout!`), `size` bytes in all.
#[cfg(test)]
pub(crate) fn check_params_block(
    spirv: &[u8],
    own: Vec<(&'static str, usize, usize)>,
    size: usize,
) {
    let mut host = march_layout();
    host.extend(own);
    crate::vk::spirv::check_block(spirv, "Params", &host, size, true).unwrap();
}

/// [`check_params_block`] of a model's `Params` struct with its own listed fields:
/// `assert_params_block!(shaders::AO_COMP, Params { light, light_colour, dims })`.
#[cfg(test)]
macro_rules! assert_params_block {
    ($spirv:expr, $ty:ident { $($field:ident),* $(,)? }) => {
        $crate::render::march::check_params_block(
            $spirv,
            $crate::host_layout!($ty { $($field),* }),
            std::mem::size_of::<$ty>(),
        )
    };
}
#[cfg(test)]
pub(crate) use assert_params_block;

/// What a ray-marched model declares unless its declaration says otherwise (each ends
/// with `..RAY_MARCHER`): unlit, no phase function, neither the gradient nor the
/// extinction volume, no state buffers to dump, no options, other flags, rebuilds or
/// state of its own. Its name, summary and pass it always gives.
pub(crate) const RAY_MARCHER: OpticalModel = OpticalModel {
    name: "",
    summary: "",
    lights: LightSupport::NONE,
    phase_function: false,
    gradient: false,
    extinction: None,
    check: no_state_buffers,
    make_pass: |_| anyhow::bail!("a ray-marched model's declaration gives its pass"),
    options: &[],
    flags: &[],
    rebuild_scopes: &[],
    state: None,
    more_lights: None,
    experimental: None,
};

/// A ray-marched model's test that its host blocks match its shaders: its `Params` block
/// (`params:`, [`assert_params_block`]) and each push-constant struct of its own kernels
/// (`push:`, the whole block, exact size). One test per model, at the module's level:
/// `test_blocks_match_the_shaders!(params: SPV, Params { a, b }; push: SPV2, Push { c });`.
macro_rules! test_blocks_match_the_shaders {
    (params: $spirv:expr, $ty:ident { $($field:ident),* $(,)? }
     $(; push: $push_spirv:expr, $push:ident { $($push_field:ident),* $(,)? })* $(;)?) => {
        #[cfg(test)]
        #[test]
        fn blocks_match_the_shaders() {
            $crate::render::march::assert_params_block!($spirv, $ty { $($field),* });
            $(
                $crate::assert_host_block!(
                    $push_spirv,
                    "Push",
                    $push { $($push_field),* },
                    exact_size = true
                );
            )*
        }
    };
}
pub(crate) use test_blocks_match_the_shaders;

/// What every ray-marched model's pass has: its parameter block, frame, descriptor set
/// (bindings 0–4 as glsl/march.glsl's users declare them: params, volume, transfer
/// functions, preintegration table, frame; then the model's own) and compute pipeline.
/// `ModelPass::fits` and `ModelPass::output` of a pass that renders through its `march`
/// field (a [`RayMarchPass`]): such a pass is remade exactly when its march must be, and
/// its frame is the march's.
macro_rules! delegate_to_march {
    () => {
        fn fits(&self, opts: &$crate::render::RenderOptions) -> bool {
            self.march.fits(opts)
        }

        fn output(&self) -> &$crate::render::FrameTarget {
            self.march.output()
        }
    };
}
pub(crate) use delegate_to_march;

pub(crate) struct RayMarchPass {
    params: Buffer,
    output: FrameTarget,
    set: DescriptorSet,
    pipeline: ComputePipeline,
    width: u32,
    height: u32,
    /// The timings scope of the march ("ea raymarch", ...).
    scope: String,
}

impl RayMarchPass {
    /// `P` is the shader's `Params` block; `extra` are the bindings from 5 on.
    pub(crate) fn new<P: Pod>(
        inputs: &Inputs,
        spirv: &[u8],
        name: &str,
        extra: &[Binding<'_>],
    ) -> Result<Self> {
        Self::with_constants::<P>(inputs, spirv, name, extra, &[])
    }

    /// [`RayMarchPass::new`] with the pipeline's specialization constants 0, 1, ...
    pub(crate) fn with_constants<P: Pod>(
        inputs: &Inputs,
        spirv: &[u8],
        name: &str,
        extra: &[Binding<'_>],
        constants: &[u32],
    ) -> Result<Self> {
        let (ctx, sampler) = (inputs.ctx, inputs.linear);
        let (width, height) = (inputs.opts.width, inputs.opts.height);
        let params = Buffer::uniform::<P>(ctx, &format!("{name} params"))?;
        let output = FrameTarget::new(ctx, width, height, &format!("{name} frame"))?;
        let mut bindings = vec![
            Binding::Uniform(&params),
            Binding::Texture(inputs.volume, inputs.volume_sampler),
            Binding::Texture(inputs.tf, sampler),
            Binding::Texture(inputs.preint, sampler),
            Binding::StorageImage(&output.image),
        ];
        bindings.extend_from_slice(extra);
        let set = DescriptorSet::new(ctx, &bindings, name)?;
        let scope = format!("{name} raymarch");
        let pipeline = ComputePipeline::with_constants(ctx, spirv, &set, 0, constants, &scope)?;
        Ok(Self {
            params,
            output,
            set,
            pipeline,
            width,
            height,
            scope,
        })
    }

    pub(crate) fn fits(&self, opts: &RenderOptions) -> bool {
        (self.width, self.height) == (opts.width, opts.height)
    }

    pub(crate) fn output(&self) -> &FrameTarget {
        &self.output
    }

    /// Record the march with the shader's block `P`, which `params` makes from the
    /// frame's camera, box and march ([`MarchParams`], for this pass's size) and the
    /// model's own fields. The most steps a ray takes is the box diagonal's.
    pub(crate) fn record<P: Pod>(
        &self,
        rec: &mut Recorder,
        inputs: &Inputs,
        params: impl FnOnce(MarchParams) -> P,
    ) -> Result<Recorded> {
        let (info, opts) = (inputs.info, inputs.opts);
        let params = params(MarchParams::new(inputs, self.width, self.height));
        rec.update_uniform(&self.params, bytemuck::bytes_of(&params))?;
        // The set binds the volume, tf, preintegration table, output and what the model
        // adds: its bindings declare their uses (Recorder::dispatch).
        let groups = [self.width.div_ceil(8), self.height.div_ceil(8), 1];
        rec.pass(&self.scope, &[], |rec| {
            rec.dispatch(&self.pipeline, &self.set, &[], groups)
        })?;
        Ok(Recorded {
            max_steps: super::steps_for(info.half_extent, info.ref_step, opts.sample_distance)
                as u32,
            readback: None,
        })
    }
}
