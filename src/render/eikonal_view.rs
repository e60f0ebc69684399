//! The eikonal model's view renderer (issue 35 item 2; seed 001, Ihrke et al., sect. 4.1
//! and 5.3): viewing rays integrated through the refractive-index field with the ray
//! equation (`glsl/ray_equation.glsl`'s `ray_rk4`, the photon tracer's integrator), lit by
//! the light simulator's fluence volume ([`super::light_simulator`]) through the
//! Henyey–Greenstein phase function, composited as the sweep composites
//! (`glsl/eikonal_view.comp` has the image formation model). The light is an input, so a
//! camera move reruns only this and a light move only the simulation.

use anyhow::{ensure, Result};
use bytemuck::{Pod, Zeroable};

use super::light_simulator::FluenceVolume;
use super::{Camera, Frame, RenderOptions, Renderer, ScatterOptions};
use crate::shaders;
use crate::vk::{self, Binding, Buffer, ComputePipeline, DescriptorSet, Memory};

/// Pixels per workgroup side (`local_size_x`, `_y` of `glsl/eikonal_view.comp`).
const GROUP: u32 = 8;

/// std140 mirror of `Params` in `glsl/eikonal_view.comp`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ViewParams {
    cam_pos: [f32; 4],
    cam_forward: [f32; 4],
    cam_right: [f32; 4],
    cam_up: [f32; 4],
    half_extent: [f32; 4],
    dims: [f32; 4],
    background: [f32; 4],
    scatter: [f32; 4],
    size: [u32; 4],
    march: [f32; 4],
}

impl Renderer {
    /// Render `camera`'s view of the volume lit by `light` (a fluence volume the light
    /// simulator made for this volume and transfer functions): `opts`' size, background,
    /// sample distance (the viewing rays' RK4 step, in reference steps), termination
    /// opacity, refractive-index scale, environment rotation and scattering options (g,
    /// albedo). The frame's timings have the GPU time of the pass ("eikonal view").
    pub fn render_eikonal_view(
        &self,
        opts: &RenderOptions,
        camera: &Camera,
        light: &FluenceVolume,
    ) -> Result<Frame> {
        let info = &self.volume_info;
        ensure!(
            light.dims == info.dims,
            "the light volume is {:?} voxels, the volume {:?}: simulate the light for this volume",
            light.dims,
            info.dims
        );
        let voxels = info.dims.iter().map(|&d| d as usize).product::<usize>();
        ensure!(
            light.fluence.len() == voxels && light.direction.len() == voxels,
            "the light volume holds {} fluence and {} direction voxels, not {voxels}",
            light.fluence.len(),
            light.direction.len()
        );
        ensure!(
            opts.width > 0 && opts.height > 0,
            "the image must be at least 1 x 1 pixels, not {} x {}",
            opts.width,
            opts.height
        );
        ensure!(
            opts.sample_distance.is_finite() && opts.sample_distance > 0.0,
            "the sample distance {} must be a positive number of voxels",
            opts.sample_distance
        );
        camera.validate()?;
        let scatter = ScatterOptions::of(opts);
        scatter.validate()?;
        let ctx = &self.ctx;

        let mut texels: Vec<[f32; 4]> = Vec::with_capacity(2 * voxels);
        for (f, d) in light.fluence.iter().zip(&light.direction) {
            texels.push([f[0], f[1], f[2], 0.0]);
            texels.push([d[0], d[1], d[2], 0.0]);
        }
        let light_buffer = Buffer::new(
            ctx,
            (texels.len() * 16) as u64,
            vk::usage::STORAGE_BUFFER | vk::usage::BUFFER_TRANSFER_DST,
            Memory::Gpu,
            "eikonal light volume",
        )?;
        let light_bytes = light_buffer.size();
        let mut staging = Buffer::new(
            ctx,
            light_bytes,
            vk::usage::BUFFER_TRANSFER_SRC,
            Memory::Upload,
            "eikonal light volume staging",
        )?;
        staging.write(0, bytemuck::cast_slice(&texels))?;

        let pixels = opts.width as u64 * opts.height as u64;
        let frame_bytes = pixels * 16;
        let frame = Buffer::new(
            ctx,
            frame_bytes,
            vk::usage::STORAGE_BUFFER | vk::usage::BUFFER_TRANSFER_SRC,
            Memory::Gpu,
            "eikonal view frame",
        )?;
        let host = Buffer::readback(ctx, frame_bytes, "eikonal view readback")?;

        let (eye, forward, right, up) = camera.frame();
        let step = opts.sample_distance * info.ref_step;
        // Steps at most: four times the box's diagonal (a ray bent back and forth by total
        // reflection inside glass is cut there, its transmittance kept as it was).
        let diagonal = 2.0 * info.half_extent.length();
        let max_steps = ((4.0 * diagonal / step).ceil() as u32).max(1);
        let params = ViewParams {
            cam_pos: [eye.x, eye.y, eye.z, (camera.fov_y.to_radians() * 0.5).tan()],
            cam_forward: forward
                .extend(opts.width as f32 / opts.height as f32)
                .into(),
            cam_right: right.extend(0.0).into(),
            cam_up: up.extend(0.0).into(),
            half_extent: info.half_extent.extend(info.ref_step).into(),
            dims: [
                info.dims[0] as f32,
                info.dims[1] as f32,
                info.dims[2] as f32,
                opts.sweep.eta_scale,
            ],
            background: opts.background,
            scatter: [
                scatter.g,
                scatter.albedo,
                step,
                opts.sweep.env_rotation.to_radians(),
            ],
            size: [opts.width, opts.height, max_steps, self.env.enabled as u32],
            march: [opts.termination_alpha, 0.0, 0.0, 0.0],
        };
        let mut uniform = Buffer::new(
            ctx,
            std::mem::size_of::<ViewParams>() as u64,
            vk::usage::UNIFORM_BUFFER,
            Memory::Upload,
            "eikonal view params",
        )?;
        uniform.write(0, bytemuck::bytes_of(&params))?;
        let set = DescriptorSet::new(
            ctx,
            &[
                Binding::Texture(&self.volume_tex, &self.volume_sampler),
                Binding::Texture(&self.tf_image, &self.linear),
                Binding::Texture(&self.env.image, &self.linear),
                Binding::Uniform(&uniform),
                Binding::Storage(&light_buffer),
                Binding::Storage(&frame),
            ],
            "eikonal view",
        )?;
        let pipeline =
            ComputePipeline::new(ctx, shaders::EIKONAL_VIEW_COMP, &set, 0, "eikonal view")?;
        let timings = ctx.execute(|rec| {
            rec.upload_to_storage(&staging, 0, &light_buffer, 0, light_bytes)?;
            rec.pass("eikonal view", &[], |rec| {
                rec.dispatch(
                    &pipeline,
                    &set,
                    &[],
                    [opts.width.div_ceil(GROUP), opts.height.div_ceil(GROUP), 1],
                )
            })?;
            rec.copy_storage_to_host(&frame, &host);
            Ok(())
        })?;
        Ok(Frame {
            width: opts.width,
            height: opts.height,
            pixels: host.read_values(pixels as usize)?,
            timings,
            max_steps,
            dumps: Vec::new(),
            sweep: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vk::spirv::check_block;

    #[test]
    fn params_match_the_shaders_block() {
        let layout = crate::host_layout!(ViewParams {
            cam_pos,
            cam_forward,
            cam_right,
            cam_up,
            half_extent,
            dims,
            background,
            scatter,
            size,
            march,
        });
        let size = std::mem::size_of::<ViewParams>();
        check_block(shaders::EIKONAL_VIEW_COMP, "Params", &layout, size, true).unwrap();
    }
}
