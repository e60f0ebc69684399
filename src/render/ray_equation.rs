//! The ray equation on the GPU (`glsl/ray_equation.glsl`): rays through the volume's
//! refractive-index field, integrated with RK4 in world space with the CPU photon
//! tracer's conventions (`photons`, "Model"), with their attenuation per channel. It is
//! the integrator issue 35's light simulator (the wavefront's corners, seed 001 eqs.
//! 14–15) and view renderer (eqs. 11–12) are to be built on; [`Renderer::trace_rays_on_gpu`]
//! traces a list of rays to a plane, which is how tests/ray_equation.rs holds it to the
//! CPU tracer and to closed forms, and [`Renderer::advance_wavefront_on_gpu`] advances
//! wavefront particles for a time (the equi-temporal form the light simulator needs).

use anyhow::{ensure, Result};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::{RenderOptions, Renderer};
use crate::shaders;
use crate::vk::{self, Binding, Buffer, ComputePipeline, DescriptorSet, Memory};

/// Rays per workgroup (`local_size_x` of `glsl/ray_equation_probe.comp`).
const GROUP: u32 = 64;

/// `glsl/ray_equation_probe.comp`'s push constants.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ProbePush {
    half_extent: [f32; 4],
    dims: [f32; 4],
    target: [f32; 4],
    step: f32,
    max_steps: u32,
    count: u32,
    mode: u32,
}

/// How the probe advances its rays (`mode` in `glsl/ray_equation_probe.comp`).
#[derive(Clone, Copy)]
enum Advance {
    /// Arc-length steps until the target plane (mode 0).
    ToPlane(TargetPlane),
    /// A fixed number of equi-temporal steps (seed 001 eqs. 14–15; mode 1).
    ForTime,
}

/// A ray to trace: world origin and direction (any length but zero).
#[derive(Clone, Copy, Debug)]
pub struct RayStart {
    pub origin: Vec3,
    pub direction: Vec3,
}

/// Where a ray traced on the GPU met the target plane.
#[derive(Clone, Copy, Debug)]
pub struct GpuRayEnd {
    /// World position on the plane.
    pub position: Vec3,
    /// Unit direction there.
    pub direction: Vec3,
    /// |v| = η there, up to the integration's error.
    pub eta: f32,
    /// Fraction of the light surviving the path, per channel.
    pub transmittance: [f32; 3],
    /// Arc length travelled.
    pub length: f32,
}

/// The plane a trace ends on: points x with `normal · x = offset` (world units; `normal`
/// unit), reached from the side where `normal · x < offset`.
#[derive(Clone, Copy, Debug)]
pub struct TargetPlane {
    pub normal: Vec3,
    pub offset: f32,
}

impl Renderer {
    /// Trace `rays` through the volume's field (the transfer functions' η with `opts`'
    /// refractive-index scale; no clipping plane) to `target`, in RK4 steps of `step`
    /// voxels (reference steps), at most `max_steps` each; `None` for a ray that left the
    /// box moving away from the plane or ran out of steps.
    pub fn trace_rays_on_gpu(
        &self,
        opts: &RenderOptions,
        rays: &[RayStart],
        target: TargetPlane,
        step: f32,
        max_steps: u32,
    ) -> Result<Vec<Option<GpuRayEnd>>> {
        ensure!(
            target.normal.is_finite() && (target.normal.length() - 1.0).abs() < 1e-4,
            "target plane normal {:?} must be a unit vector",
            target.normal
        );
        self.probe(opts, rays, Advance::ToPlane(target), step, max_steps)
    }

    /// Advance wavefront particles (`rays`: positions and directions) for `steps` RK4
    /// steps of the equi-temporal ray equation (seed 001 eqs. 14–15), each an optical path
    /// of `dt` voxels (reference steps): every particle ends `steps · dt` of optical path
    /// from its start, so particles launched on a wavefront end on one.
    pub fn advance_wavefront_on_gpu(
        &self,
        opts: &RenderOptions,
        rays: &[RayStart],
        dt: f32,
        steps: u32,
    ) -> Result<Vec<GpuRayEnd>> {
        let ends = self.probe(opts, rays, Advance::ForTime, dt, steps)?;
        Ok(ends
            .into_iter()
            .map(|e| e.expect("a wavefront particle always ends"))
            .collect())
    }

    /// The probe's dispatch: `max_steps` steps of `step` voxels, `how` says of what.
    fn probe(
        &self,
        opts: &RenderOptions,
        rays: &[RayStart],
        how: Advance,
        step: f32,
        max_steps: u32,
    ) -> Result<Vec<Option<GpuRayEnd>>> {
        ensure!(
            step.is_finite() && step > 0.0,
            "ray step {step} must be a positive number of voxels"
        );
        ensure!(
            opts.sweep.clip.is_none(),
            "the GPU ray tracer takes no clipping plane"
        );
        let ctx = &self.ctx;
        let count = rays.len();
        let slots = count.max(1);
        let mut starts: Vec<[f32; 4]> = Vec::with_capacity(2 * slots);
        for r in rays {
            ensure!(
                r.origin.is_finite() && r.direction.is_finite() && r.direction.length() > 0.0,
                "ray {r:?}: origin and direction must be finite, the direction non-zero"
            );
            starts.push(r.origin.extend(0.0).into());
            starts.push(r.direction.extend(0.0).into());
        }
        starts.resize(2 * slots, [0.0, 0.0, 0.0, 0.0]);
        let mut input = Buffer::new(
            ctx,
            (starts.len() * 16) as u64,
            vk::usage::STORAGE_BUFFER,
            Memory::Upload,
            "ray equation starts",
        )?;
        input.write(0, bytemuck::cast_slice(&starts))?;
        let out_bytes = (3 * slots * 16) as u64;
        let output = Buffer::new(
            ctx,
            out_bytes,
            vk::usage::STORAGE_BUFFER | vk::usage::BUFFER_TRANSFER_SRC,
            Memory::Gpu,
            "ray equation ends",
        )?;
        let host = Buffer::readback(ctx, out_bytes, "ray equation readback")?;
        let set = DescriptorSet::new(
            ctx,
            &[
                Binding::Texture(&self.volume_tex, &self.volume_sampler),
                Binding::Texture(&self.tf_image, &self.linear),
                Binding::Storage(&input),
                Binding::Storage(&output),
            ],
            "ray equation",
        )?;
        // Specialization constant 0: cubic η (the eikonal model's `--cubic-eta`).
        let pipeline = ComputePipeline::with_constants(
            ctx,
            shaders::RAY_EQUATION_PROBE_COMP,
            &set,
            std::mem::size_of::<ProbePush>() as u32,
            &[super::eikonal::cubic_eta(opts) as u32],
            "ray equation",
        )?;
        let info = &self.volume_info;
        let push = ProbePush {
            half_extent: info.half_extent.extend(info.ref_step).into(),
            dims: info.dims_and(opts.sweep.eta_scale),
            target: match how {
                Advance::ToPlane(t) => t.normal.extend(t.offset).into(),
                Advance::ForTime => [0.0; 4],
            },
            step: step * info.ref_step,
            max_steps,
            count: count as u32,
            mode: match how {
                Advance::ToPlane(_) => 0,
                Advance::ForTime => 1,
            },
        };
        ctx.execute(|rec| {
            rec.pass("ray equation", &[], |rec| {
                rec.dispatch(
                    &pipeline,
                    &set,
                    bytemuck::bytes_of(&push),
                    [(slots as u32).div_ceil(GROUP), 1, 1],
                )
            })?;
            rec.copy_storage_to_host(&output, &host);
            Ok(())
        })?;
        let ends: Vec<[f32; 4]> = host.read_values(3 * count)?;
        Ok(ends
            .chunks_exact(3)
            .map(|e| {
                (e[2][3] > 0.5).then(|| GpuRayEnd {
                    position: Vec3::new(e[0][0], e[0][1], e[0][2]),
                    direction: Vec3::new(e[1][0], e[1][1], e[1][2]),
                    eta: e[1][3],
                    transmittance: [e[2][0], e[2][1], e[2][2]],
                    length: e[0][3],
                })
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn probe_push_matches_the_shaders_block() {
        crate::assert_host_block!(
            shaders::RAY_EQUATION_PROBE_COMP,
            "Push",
            ProbePush {
                half_extent,
                dims,
                target,
                step,
                max_steps,
                count,
                mode
            },
            exact_size = false
        );
    }
}
