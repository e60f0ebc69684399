//! Single scattering with shadows (`--model single`, issue 17 item 2): the model Ament et
//! al. (seed 002) show beside ambient scattering — directional light attenuated on its way
//! to each sample (hard shadows), scattered once towards the eye by a Henyey–Greenstein
//! phase function (`glsl/single.comp`).
//!
//! The light's attenuation comes from a transmittance cache, a 3D image at the volume's
//! resolution ([`TransmittanceCache`], `glsl/transmittance.comp`), marched from every voxel
//! to the box's face through the extinction volume (`glsl/extinction.comp`). It depends
//! on the transfer functions (through the extinction) and on the light's direction, and is
//! rebuilt in the frame's recording when either changed (scope [`CACHE_SCOPE`]: what a
//! transfer-function or light change costs this model). The phase function is evaluated
//! per sample, so changing g rebuilds nothing.

use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::cached::CachedImage;
use super::extinction::Extinction;
use super::march::{delegate_to_march, RayMarchPass, RAY_MARCHER};
use super::model::{Inputs, ModelPass, ModelState, ModelStateDecl, OpticalModel, Recorded, Shared};
use super::LightSupport;
use super::{RenderOptions, ScatterOptions, VolumeInfo, SCATTER_ALBEDO, SCATTER_G};
use crate::shaders;
use crate::vk::{self, Binding, Context, Image, ImageDesc, ImageKind, Recorder, Sampler};

/// The timings scope of the transmittance cache's build.
pub const CACHE_SCOPE: &str = "transmittance cache";

/// `glsl/transmittance.comp`'s push constants.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CachePush {
    towards: [f32; 4],
    half_extent: [f32; 4],
}

/// The transmittance of the directional light to every voxel centre, keyed by the light
/// direction and the extinction build it holds.
pub struct TransmittanceCache {
    cache: CachedImage,
}

impl TransmittanceCache {
    /// Bytes it takes for a volume of `extent`.
    pub fn bytes(extent: [u32; 3]) -> u64 {
        4 * extent.iter().map(|&e| e as u64).product::<u64>()
    }

    pub fn new(ctx: &Context, extinction: &Extinction, sampler: &Sampler) -> Result<Self> {
        let extent = extinction.image().extent();
        let desc = ImageDesc::computed(ImageKind::D3, vk::Format::R32_SFLOAT, extent, 1);
        let cache = CachedImage::new(
            ctx,
            desc,
            &[Binding::Texture(extinction.image(), sampler)],
            shaders::TRANSMITTANCE_COMP,
            std::mem::size_of::<CachePush>(),
            "transmittance cache",
        )?;
        Ok(Self { cache })
    }

    /// What a build for the light from `towards` through `extinction` is keyed by.
    fn key(towards: Vec3, extinction: &Extinction) -> Vec<u32> {
        let b = extinction.builds();
        vec![
            towards.x.to_bits(),
            towards.y.to_bits(),
            towards.z.to_bits(),
            b as u32,
            (b >> 32) as u32,
        ]
    }

    /// Rebuild for the light from `towards` (unit, world) through `extinction`, unless it
    /// holds that already.
    pub(crate) fn record_build(
        &mut self,
        rec: &mut Recorder,
        extinction: &Extinction,
        info: VolumeInfo,
        towards: Vec3,
    ) -> Result<()> {
        let push = CachePush {
            towards: [towards.x, towards.y, towards.z, info.ref_step],
            half_extent: [
                info.half_extent.x,
                info.half_extent.y,
                info.half_extent.z,
                0.0,
            ],
        };
        self.cache.record(
            rec,
            CACHE_SCOPE,
            Self::key(towards, extinction),
            bytemuck::bytes_of(&push),
        )?;
        Ok(())
    }

    pub fn image(&self) -> &Image {
        self.cache.image()
    }
}

/// The unit light direction the cache is built for, from the frame's options.
pub(crate) fn light_towards(opts: &RenderOptions) -> Vec3 {
    opts.light().towards().normalize()
}

/// std140 mirror of `Params` in glsl/single.comp (ea.comp's block, then the model's).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    march: super::march::MarchParams,
    light: [f32; 4],
    light_colour: [f32; 4],
}

pub(super) struct SinglePass {
    march: RayMarchPass,
}

impl SinglePass {
    pub fn new(inputs: &Inputs) -> Result<Self> {
        let cache = transmittance(inputs)?;
        Ok(Self {
            march: RayMarchPass::new::<Params>(
                inputs,
                shaders::SINGLE_COMP,
                "single",
                &[Binding::Texture(cache.image(), inputs.linear)],
            )?,
        })
    }
}

fn transmittance<'a>(inputs: &Inputs<'a>) -> Result<&'a TransmittanceCache> {
    inputs.state::<TransmittanceCache>()
}

/// The cache is the model's state: made on its first frame, rebuilt in a frame's recording
/// when the light's direction or the extinction changed.
impl ModelState for TransmittanceCache {
    fn record_update(
        &mut self,
        rec: &mut Recorder,
        shared: &Shared,
        opts: &RenderOptions,
    ) -> Result<()> {
        let e = extinction_of(shared)?;
        self.record_build(rec, e, shared.info, light_towards(opts))
    }

    fn bytes(&self) -> u64 {
        Self::bytes(self.image().extent())
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

fn extinction_of<'a>(shared: &Shared<'a>) -> Result<&'a Extinction> {
    shared
        .extinction
        .ok_or_else(|| anyhow::anyhow!("the single-scattering model needs the extinction volume"))
}

/// The single-scattering model's declaration (listed in render/registry.rs).
pub(crate) static SINGLE: OpticalModel = OpticalModel {
    name: "single",
    summary: "Single scattering with hard shadows from a transmittance cache, Henyey-Greenstein phase function (--light, --g, --albedo).",
    // One directional light: the transmittance cache is built for one direction.
    lights: LightSupport::ONE_DIRECTIONAL,
    phase_function: true,
    // The extinction volume, no SAT: the cache marches it.
    extinction: Some(false),
    make_pass: |inputs| Ok(Box::new(SinglePass::new(inputs)?)),
    options: &[&SCATTER_G, &SCATTER_ALBEDO],
    rebuild_scopes: &[CACHE_SCOPE],
    state: Some(ModelStateDecl {
        what: "the transmittance cache",
        bytes: TransmittanceCache::bytes,
        make: |shared| {
            let e = extinction_of(shared)?;
            Ok(Box::new(TransmittanceCache::new(shared.ctx, e, shared.linear)?))
        },
    }),
    ..RAY_MARCHER
};

impl ModelPass for SinglePass {
    delegate_to_march!();

    fn record(&mut self, rec: &mut Recorder, inputs: &Inputs) -> Result<Recorded> {
        let opts = inputs.opts;
        let _cache = transmittance(inputs)?;
        let towards = light_towards(opts);
        let c = opts.light().colour;
        let scatter = ScatterOptions::of(opts);
        self.march.record(rec, inputs, |march| Params {
            march,
            light: [towards.x, towards.y, towards.z, scatter.g],
            light_colour: [c[0], c[1], c[2], scatter.albedo],
        })
    }
}

crate::render::march::test_blocks_match_the_shaders!(
    params: shaders::SINGLE_COMP, Params { light, light_colour };
    push: shaders::TRANSMITTANCE_COMP, CachePush { towards, half_extent }
);
