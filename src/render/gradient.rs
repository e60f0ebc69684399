//! The smoothed gradient volume: the value's gradient filtered by a 3D derivative of a
//! Gaussian (σ = [`SIGMA`] voxels), one RGBA16F texel per voxel (xyz: ∂f/∂x, ∂f/∂y, ∂f/∂z
//! in value units per voxel; w: the Gaussian-smoothed value), sampled trilinearly by the
//! sweep. Built by `glsl/gradient.comp` on the GPU once per volume: it depends on the
//! volume only (the gradient of η = η_tf(value) is parallel to it whatever the transfer
//! functions), so changing the transfer functions, light or camera rebuilds nothing.
//!
//! Why: where η steps within a voxel (a face of glass) the viewing rays turn by a Snell
//! step about the face's normal, and that normal was the weakest link. Measured at 4000
//! points on the middle of a voxelised sphere's one-voxel ramp (radius 26 voxels), the
//! angle between an estimate and the true radial normal, median / 95th percentile:
//! a 3D Sobel of trilinear fetches one voxel apart (26 fetches, the previous estimate)
//! 1.47° / 2.27°; central differences of a Gaussian-smoothed value 0.71° / 1.00°
//! (σ 1.5); this volume 0.23° / 0.91° (σ 1), 0.07° / 0.50° (σ 1.5), 0.09° / 0.30° (σ 2).
//! σ 1.5 (radius 5 taps) keeps features a few voxels apart distinct (a floor slab's two
//! faces) at a quarter of Sobel's error budget; see docs/NOTES.md.
//!
//! Memory: 8 bytes per voxel, and as much again for the build's intermediate (freed after).

use anyhow::Result;

use crate::shaders;
use crate::vk::{
    self, Binding, ComputePipeline, Context, DescriptorSet, Image, ImageDesc, ImageKind, Sampler,
    Timings,
};

/// Standard deviation of the smoothing, in voxels.
pub const SIGMA: f32 = 1.5;

/// The filter's push constants (glsl/gradient.comp).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    axis: i32,
    sigma: f32,
    radius: i32,
}

pub struct GradientVolume {
    image: Image,
}

/// Whether the refractive sweep has a gradient volume.
#[derive(Clone, Debug, PartialEq)]
pub enum GradientStatus {
    /// Not needed yet (no refractive frame so far).
    Unbuilt,
    /// Built; its GPU time is in `Renderer::gradient_timings`.
    Built,
    /// It and its build's intermediate would need more than the budget (half the
    /// device's largest device-local heap): the sweep computes normals on the fly, by a
    /// 3D Sobel of the value (26 fetches, ~1.5° off a face's normal where the volume's
    /// gives 0.1°: docs/NOTES.md).
    TooLarge { needed: u64, budget: u64 },
}

impl GradientVolume {
    /// Bytes the volume and its build's intermediate take for a volume of `extent`, and
    /// the budget they must fit: half the largest device-local heap (the rest is for
    /// the volume itself, the state buffers and the frame).
    pub fn memory(ctx: &Context, extent: [u32; 3]) -> (u64, u64) {
        let voxels = extent.iter().map(|&e| e as u64).product::<u64>();
        let heap = ctx
            .info()
            .memory_heaps
            .iter()
            .filter(|(_, local)| *local)
            .map(|(size, _)| *size)
            .max()
            .unwrap_or(0);
        (2 * 8 * voxels, heap / 2)
    }

    /// Build the gradient volume of `volume` (a sampled 3D texture of the scalar value)
    /// now; returns it with the build's GPU time (scope "gradient volume").
    pub fn build(ctx: &Context, volume: &Image, sampler: &Sampler) -> Result<(Self, Timings)> {
        let format = vk::Format::R16G16B16A16_SFLOAT;
        let desc = ImageDesc::computed(ImageKind::D3, format, volume.extent(), 1);
        let image = Image::new(ctx, desc.clone(), "gradient volume")?;
        let scratch = Image::new(ctx, desc, "gradient volume (intermediate)")?;
        // Axis 0: volume -> image; axis 1: image -> scratch; axis 2: scratch -> image.
        let pairs = [(volume, &image), (&image, &scratch), (&scratch, &image)];
        let sets = pairs
            .iter()
            .enumerate()
            .map(|(axis, (src, dst))| {
                DescriptorSet::new(
                    ctx,
                    &[Binding::Texture(src, sampler), Binding::StorageImage(dst)],
                    &format!("gradient volume axis {axis}"),
                )
            })
            .collect::<Result<Vec<_>>>()?;
        let pipeline = ComputePipeline::new(
            ctx,
            shaders::GRADIENT_COMP,
            &sets[0],
            std::mem::size_of::<Push>() as u32,
            "gradient volume",
        )?;
        let [w, h, d] = volume.extent();
        let groups = [w.div_ceil(8), h.div_ceil(8), d];
        let timings = ctx.execute(|rec| {
            // The images swap roles per axis: each axis's set declares its source sampled
            // and its destination storage, and its dispatch takes them there
            // (Recorder::dispatch).
            rec.pass("gradient volume", &[], |rec| {
                for (axis, set) in sets.iter().enumerate() {
                    let push = Push {
                        axis: axis as i32,
                        sigma: SIGMA,
                        radius: (3.0 * SIGMA).ceil() as i32,
                    };
                    rec.dispatch(&pipeline, set, bytemuck::bytes_of(&push), groups)?;
                }
                // The sweep's declared sampled read transitions the result.
                Ok(())
            })
        })?;
        Ok((Self { image }, timings))
    }

    pub fn image(&self) -> &Image {
        &self.image
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_matches_the_shaders_block() {
        crate::assert_host_block!(
            shaders::GRADIENT_COMP,
            "Push",
            Push {
                axis,
                sigma,
                radius
            },
            exact_size = false
        );
    }
}
