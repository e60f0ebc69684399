//! The extinction volume σ_t = −ln(1 − α_tf) per reference step of the current transfer
//! functions (`glsl/extinction.comp`) and, for the models that average it over boxes, its
//! 3D summed-area table ([`super::sat3d`]): the input of the occlusion and scattering
//! models (ao, single, ambient), owned by the renderer and rebuilt in a frame's recording
//! when the transfer functions change. Shared machinery, so it lives here and not in a
//! model's folder (issue 34).

use anyhow::Result;

use super::sat3d::Sat3d;
use crate::shaders;
use crate::vk::{
    self, Binding, ComputePipeline, Context, DescriptorSet, Image, ImageDesc, ImageKind, Recorder,
    Sampler,
};

/// The timings scope of the extinction volume's build.
pub const EXTINCTION_SCOPE: &str = "extinction volume";

/// Largest extinction per voxel the volume holds (`glsl/extinction.comp`: α < 1 − 10⁻⁶):
/// the SAT's bound.
pub const MAX_EXTINCTION: f32 = 13.9;

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
    pub fn record_build(&mut self, rec: &mut Recorder) -> Result<()> {
        let [w, h, d] = self.extinction.extent();
        // The set binds volume, tf and the extinction volume: its bindings declare their
        // uses (Recorder::dispatch).
        rec.pass(EXTINCTION_SCOPE, &[], |rec| {
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
