//! Volumetric ambient occlusion (`--model ao`, issue 17 item 1): the SAT method Ament et
//! al. (seed 002) compare their ambient scattering against (Schlegel et al.). The
//! emission–absorption march of the EA model (`glsl/march.glsl`), each segment's emission
//! lit by the ambient light that reaches it through the surrounding medium and by an
//! unshadowed directional light through the gradient (`glsl/ao.comp`).
//!
//! The ambient light is the transmittance over a radius around the sample, the
//! extinction at each distance estimated from nested cubes of voxels (`glsl/ao.glsl`):
//! their sums come from the 3D summed-area table ([`super::sat3d`]) of the extinction
//! volume σ_t = −ln(1 − α_tf) per reference step (`glsl/extinction.comp`), both rebuilt on
//! the GPU in the frame's recording when the transfer functions change (scopes
//! [`EXTINCTION_SCOPE`] and [`super::sat3d::SCOPE`]: what a transfer-function change costs
//! this model, reported like the preintegration table's). Path lengths are in voxels,
//! taken as reference steps: exact for cubic voxels, an approximation for anisotropic ones.

use anyhow::{ensure, Result};
use bytemuck::{Pod, Zeroable};

use super::ea::{delegate_to_march, RayMarchPass};
use super::model::{Inputs, ModelPass, Recorded};
use super::sat3d::Sat3d;

use crate::shaders;
use crate::vk::{
    self, Access, Binding, ComputePipeline, Context, DescriptorSet, Filter, Image, ImageDesc,
    ImageKind, Recorder, Sampler, Use,
};

/// The timings scope of the extinction volume's build.
pub const EXTINCTION_SCOPE: &str = "extinction volume";

/// Largest extinction per voxel the volume holds (`glsl/extinction.comp`: α < 1 − 10⁻⁶):
/// the SAT's bound.
pub const MAX_EXTINCTION: f32 = 13.9;

/// Options of the ambient-occlusion model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AoOptions {
    /// Half-size, in voxels, of the largest cube the occlusion looks at (a power of two:
    /// the cubes double from 1).
    pub radius: u32,
    /// Weight of the directional light's Lambert term against the ambient term, in [0, 1].
    pub diffuse: f32,
}

impl Default for AoOptions {
    fn default() -> Self {
        Self {
            radius: 16,
            diffuse: 0.5,
        }
    }
}

/// Largest [`AoOptions::radius`].
pub const MAX_RADIUS: u32 = 256;

impl AoOptions {
    pub fn validate(&self) -> Result<()> {
        ensure!(
            self.radius.is_power_of_two() && self.radius <= MAX_RADIUS,
            "ambient-occlusion radius {} must be a power of two from 1 to {MAX_RADIUS} voxels \
             (the occlusion cubes double in size)",
            self.radius
        );
        ensure!(
            self.diffuse.is_finite() && (0.0..=1.0).contains(&self.diffuse),
            "diffuse weight {} must be in [0, 1]",
            self.diffuse
        );
        Ok(())
    }

    /// The nested cubes beyond the sample's voxel: half-sizes 1, 2, 4, ..., radius.
    pub fn shells(&self) -> i32 {
        self.radius.trailing_zeros() as i32 + 1
    }
}

/// The extinction volume of the current transfer functions and, for the models that
/// average it over boxes, its 3D summed-area table: the input of the scattering and
/// occlusion models, owned by the renderer.
pub struct Extinction {
    extinction: Image,
    set: DescriptorSet,
    pipeline: ComputePipeline,
    sat: Option<Sat3d>,
    /// Builds so far: what the caches made from it (render::single) compare with.
    builds: u64,
}

impl Extinction {
    /// Bytes it takes for a volume of `extent`: 4 per voxel of extinction, 8 more with the
    /// table.
    pub fn bytes(extent: [u32; 3], with_sat: bool) -> u64 {
        let per_voxel = if with_sat { 12 } else { 4 };
        per_voxel * extent.iter().map(|&e| e as u64).product::<u64>()
    }

    /// Made empty; [`Extinction::record_build`] fills it.
    pub fn new(ctx: &Context, volume: &Image, tf: &Image, sampler: &Sampler) -> Result<Self> {
        let desc = ImageDesc::computed(ImageKind::D3, vk::Format::R32_SFLOAT, volume.extent(), 1);
        let extinction = Image::new(ctx, desc, "extinction volume")?;
        let set = DescriptorSet::new(
            ctx,
            &[
                Binding::Texture(volume, sampler),
                Binding::Texture(tf, sampler),
                Binding::StorageImage(&extinction),
            ],
            "extinction volume",
        )?;
        let pipeline =
            ComputePipeline::new(ctx, shaders::EXTINCTION_COMP, &set, 0, "extinction volume")?;
        Ok(Self {
            extinction,
            set,
            pipeline,
            sat: None,
            builds: 0,
        })
    }

    /// Add the summed-area table (empty: the next [`Extinction::record_build`] fills it).
    pub fn add_sat(&mut self, ctx: &Context) -> Result<()> {
        if self.sat.is_none() {
            self.sat = Some(Sat3d::new(ctx, &self.extinction)?);
        }
        Ok(())
    }

    /// The extinction volume (R32F, σ_t per reference step).
    pub fn image(&self) -> &Image {
        &self.extinction
    }

    /// Compute the extinction of `volume` through `tf` and rebuild the table (if any) from
    /// it.
    pub fn record_build(&mut self, rec: &mut Recorder, volume: &Image, tf: &Image) -> Result<()> {
        let [w, h, d] = self.extinction.extent();
        let uses = [
            Use::all(volume, Access::Sampled),
            Use::all(tf, Access::Sampled),
            Use::all(&self.extinction, Access::ComputeStorage),
        ];
        rec.pass(EXTINCTION_SCOPE, &uses, |rec| {
            rec.dispatch(
                &self.pipeline,
                &self.set,
                &[],
                [w.div_ceil(8), h.div_ceil(8), d],
            )
        })?;
        self.builds += 1;
        match &mut self.sat {
            Some(sat) => sat.record_rebuild(rec, &self.extinction, MAX_EXTINCTION),
            None => Ok(()),
        }
    }

    /// How many times it was built (each transfer-function change adds one).
    pub fn builds(&self) -> u64 {
        self.builds
    }

    /// The summed-area table, if [`Extinction::add_sat`] made one.
    pub fn sat(&self) -> Result<&Sat3d> {
        self.sat
            .as_ref()
            .ok_or_else(|| anyhow::anyhow!("the extinction volume has no summed-area table"))
    }

    /// The ambient occlusion `glsl/ao.glsl` computes at each point (texture coordinates)
    /// with `shells` cubes, evaluated on the GPU: for tests against closed forms.
    pub fn occlusion_on_gpu(
        &self,
        ctx: &Context,
        points: &[[f32; 3]],
        shells: i32,
    ) -> Result<Vec<f32>> {
        let texels: Vec<[f32; 4]> = points.iter().map(|p| [p[0], p[1], p[2], 0.0]).collect();
        self.sat()?.probe(
            ctx,
            shaders::AO_PROBE_COMP,
            bytemuck::cast_slice(&texels),
            points.len(),
            shells,
        )
    }
}

/// std140 mirror of `Params` in glsl/ao.comp (ea.comp's block, then the model's).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    march: super::ea::MarchParams,
    light: [f32; 4],
    light_colour: [f32; 4],
    dims: [i32; 4],
}

/// `glsl/ao_cache.comp`'s push constants.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CachePush {
    dims: [i32; 4],
    inv_scale: f32,
    pad: [f32; 3],
}

/// The timings scope of the occlusion cache's build.
pub const CACHE_SCOPE: &str = "occlusion cache";

pub(super) struct AoPass {
    march: RayMarchPass,
    /// Kept for the cache's set (the table is read with texelFetch through it).
    _nearest: Sampler,
    /// The occlusion at every voxel centre (`glsl/ao_cache.comp`), with the extinction
    /// build and shell count it holds.
    cache: Image,
    cache_set: DescriptorSet,
    cache_pipeline: ComputePipeline,
    cache_for: Option<(u64, i32)>,
}

fn extinction<'a>(inputs: &Inputs<'a>) -> Result<&'a Extinction> {
    inputs
        .extinction
        .ok_or_else(|| anyhow::anyhow!("the AO model needs the extinction volume"))
}

impl AoPass {
    pub fn new(inputs: &Inputs, width: u32, height: u32) -> Result<Self> {
        let ctx = inputs.ctx;
        let sat = extinction(inputs)?.sat()?;
        let nearest = Sampler::new(ctx, Filter::Nearest, "ao table")?;
        let desc = ImageDesc::computed(
            ImageKind::D3,
            vk::Format::R32_SFLOAT,
            inputs.volume.extent(),
            1,
        );
        let cache = Image::new(ctx, desc, "occlusion cache")?;
        let cache_set = DescriptorSet::new(
            ctx,
            &[
                Binding::Texture(sat.image(), &nearest),
                Binding::StorageImage(&cache),
            ],
            "occlusion cache",
        )?;
        let cache_pipeline = ComputePipeline::new(
            ctx,
            shaders::AO_CACHE_COMP,
            &cache_set,
            std::mem::size_of::<CachePush>() as u32,
            "occlusion cache",
        )?;
        let march = RayMarchPass::new::<Params>(
            inputs,
            width,
            height,
            shaders::AO_COMP,
            "ao",
            &[Binding::Texture(&cache, inputs.linear)],
        )?;
        Ok(Self {
            march,
            _nearest: nearest,
            cache,
            cache_set,
            cache_pipeline,
            cache_for: None,
        })
    }
}

impl ModelPass for AoPass {
    delegate_to_march!();

    fn record(&mut self, rec: &mut Recorder, inputs: &Inputs) -> Result<Recorded> {
        let (info, opts) = (inputs.info, inputs.opts);
        let ambient = extinction(inputs)?;
        let [x, y, z] = info.dims.map(|d| d as i32);
        let key = (ambient.builds(), opts.ao.shells());
        if self.cache_for != Some(key) {
            let sat = ambient.sat()?;
            let push = CachePush {
                dims: [x, y, z, key.1],
                inv_scale: sat.inv_scale(),
                pad: [0.0; 3],
            };
            let uses = [
                Use::all(sat.image(), Access::Sampled),
                Use::all(&self.cache, Access::ComputeStorage),
            ];
            let [w, h, d] = info.dims;
            rec.pass(CACHE_SCOPE, &uses, |rec| {
                rec.dispatch(
                    &self.cache_pipeline,
                    &self.cache_set,
                    bytemuck::bytes_of(&push),
                    [w.div_ceil(8), h.div_ceil(8), d],
                )
            })?;
            self.cache_for = Some(key);
        }
        let towards = opts.light().towards().normalize();
        let c = opts.light().colour;
        let (width, height) = self.march.size();
        let p = Params {
            march: super::ea::MarchParams::new(inputs, width, height),
            light: [towards.x, towards.y, towards.z, opts.ao.diffuse],
            light_colour: [c[0], c[1], c[2], 0.0],
            dims: [x, y, z, 0],
        };
        self.march
            .record(rec, inputs, bytemuck::bytes_of(&p), &[&self.cache])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cache_push_matches_the_shaders_block() {
        crate::vk::spirv::check_block(
            shaders::AO_CACHE_COMP,
            "Push",
            &crate::host_layout!(CachePush {
                dims,
                inv_scale,
                pad
            }),
            std::mem::size_of::<CachePush>(),
            true,
        )
        .unwrap();
    }

    #[test]
    fn params_match_the_shaders_block() {
        let mut host = crate::render::ea::march_layout();
        for (name, offset, size) in crate::host_layout!(Params {
            light,
            light_colour,
            dims,
        }) {
            host.push((name, offset, size));
        }
        crate::vk::spirv::check_block(
            shaders::AO_COMP,
            "Params",
            &host,
            std::mem::size_of::<Params>(),
            true,
        )
        .unwrap();
    }

    #[test]
    fn radii_are_powers_of_two_and_give_their_shells() {
        for (radius, shells) in [(1, 1), (2, 2), (16, 5), (256, 9)] {
            let o = AoOptions {
                radius,
                ..Default::default()
            };
            o.validate().unwrap();
            assert_eq!(o.shells(), shells);
        }
        for radius in [0, 3, 12, 512] {
            let o = AoOptions {
                radius,
                ..Default::default()
            };
            let e = o.validate().unwrap_err().to_string();
            assert!(e.contains("power of two"), "{e}");
        }
    }
}
