//! Volumetric ambient occlusion (`--model ao`, issue 17 item 1): the SAT method Ament et
//! al. (seed 002) compare their ambient scattering against (Schlegel et al.). The
//! emission–absorption march of the EA model (`glsl/march.glsl`), each segment's emission
//! lit by the ambient light that reaches it through the surrounding medium and by an
//! unshadowed directional light through the gradient (`glsl/ao.comp`).
//!
//! The ambient light is the transmittance over a radius around the sample, the
//! extinction at each distance estimated from nested cubes of voxels (`glsl/ao.glsl`):
//! their sums come from the 3D summed-area table ([`super::sat3d`]) of the extinction
//! volume σ_t = −ln(1 − α_tf) per reference step ([`super::extinction`]), both rebuilt on
//! the GPU in the frame's recording when the transfer functions change (scopes
//! [`super::extinction::EXTINCTION_SCOPE`] and [`super::sat3d::SCOPE`]: what a transfer-function change costs
//! this model, reported like the preintegration table's). Path lengths are in voxels,
//! taken as reference steps: exact for cubic voxels, an approximation for anisotropic ones.

use anyhow::{ensure, Result};
use bytemuck::{Pod, Zeroable};

use super::cached::CachedImage;
use super::extinction::Extinction;
use super::march::{delegate_to_march, RayMarchPass, RAY_MARCHER};
use super::model::{Inputs, ModelPass, OpticalModel, Recorded};
use super::model_options::ModelOption;
use super::{LightSupport, RenderOptions};

use crate::shaders;
use crate::vk::{self, Binding, Filter, ImageDesc, ImageKind, Recorder, Sampler};

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
        // The declared defaults (the flags' and scene keys').
        Self {
            radius: AO_RADIUS.default as u32,
            diffuse: AO_DIFFUSE.default as f32,
        }
    }
}

/// Largest [`AoOptions::radius`].
pub const MAX_RADIUS: u32 = 256;

/// `--ao-radius` (scene key `ao_radius`): [`AoOptions::radius`].
pub static AO_RADIUS: ModelOption = ModelOption {
    flag: "--ao-radius",
    value_name: "VOXELS",
    help: "Ambient occlusion: half-size, in voxels, of the largest cube around a sample \
           whose extinction occludes it; a power of two (the cubes double from 1)",
    default: 16.0,
    integer: true,
    check: |v| {
        AoOptions {
            radius: v as u32,
            ..Default::default()
        }
        .validate()
    },
};

/// `--ao-diffuse` (scene key `ao_diffuse`): [`AoOptions::diffuse`].
pub static AO_DIFFUSE: ModelOption = ModelOption {
    flag: "--ao-diffuse",
    value_name: "W",
    help: "Ambient occlusion: weight of the light's Lambert term (gradient normal, \
           unshadowed) against the ambient term, 0-1",
    default: 0.5,
    integer: false,
    check: |v| {
        AoOptions {
            diffuse: v as f32,
            ..Default::default()
        }
        .validate()
    },
};

impl AoOptions {
    /// The options `opts` asks of this model (its declared options' values).
    pub fn of(opts: &RenderOptions) -> Self {
        Self {
            radius: opts.model_option(&AO_RADIUS) as u32,
            diffuse: opts.model_option(&AO_DIFFUSE) as f32,
        }
    }

    /// Ask these of the model in `opts` (refused as the flags would be).
    pub fn set_in(&self, opts: &mut RenderOptions) -> Result<()> {
        opts.models.set(&AO_RADIUS, self.radius as f64)?;
        opts.models.set(&AO_DIFFUSE, self.diffuse as f64)
    }

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

/// The ambient-occlusion model's part of the renderer's interface.
impl super::Renderer {
    /// The ambient occlusion the AO model computes (`glsl/ao.glsl`) at `points` (texture
    /// coordinates of the volume box) with `opts`' radius, of the current transfer
    /// functions (the extinction volume and its table are made or rebuilt first, in their
    /// own submission): the model's occlusion, evaluated on the GPU, for checks against
    /// closed forms.
    pub fn ambient_occlusion_at(
        &mut self,
        points: &[[f32; 3]],
        opts: &AoOptions,
    ) -> Result<Vec<f32>> {
        opts.validate()?;
        self.ensure_extinction(super::Model::Ao)?;
        let e = self.extinction.as_mut().expect("made above");
        if self.extinction_dirty {
            let (_volume, _tf) = (&self.volume_tex, &self.tf_image);
            self.ctx.execute(|rec| e.record_build(rec))?;
            self.extinction_dirty = false;
        }
        e.occlusion_on_gpu(&self.ctx, points, opts.shells())
    }
}

/// std140 mirror of `Params` in glsl/ao.comp (ea.comp's block, then the model's).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    march: super::march::MarchParams,
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
    /// The occlusion at every voxel centre (`glsl/ao_cache.comp`), keyed by the extinction
    /// build and shell count it holds.
    cache: CachedImage,
}

fn extinction<'a>(inputs: &Inputs<'a>) -> Result<&'a Extinction> {
    inputs
        .extinction
        .ok_or_else(|| anyhow::anyhow!("the AO model needs the extinction volume"))
}

impl AoPass {
    pub fn new(inputs: &Inputs) -> Result<Self> {
        let ctx = inputs.ctx;
        let sat = extinction(inputs)?.sat()?;
        let nearest = Sampler::new(ctx, Filter::Nearest, "ao table")?;
        let desc = ImageDesc::computed(
            ImageKind::D3,
            vk::Format::R32_SFLOAT,
            inputs.volume.extent(),
            1,
        );
        let cache = CachedImage::new(
            ctx,
            desc,
            &[Binding::Texture(sat.image(), &nearest)],
            shaders::AO_CACHE_COMP,
            std::mem::size_of::<CachePush>(),
            "occlusion cache",
        )?;
        let march = RayMarchPass::new::<Params>(
            inputs,
            shaders::AO_COMP,
            "ao",
            &[Binding::Texture(cache.image(), inputs.linear)],
        )?;
        Ok(Self {
            march,
            _nearest: nearest,
            cache,
        })
    }
}

/// The ambient-occlusion model's declaration (listed in render/registry.rs).
pub(crate) static AO: OpticalModel = OpticalModel {
    name: "ao",
    summary: "Volumetric ambient occlusion (3D summed-area table of extinction) with a Lambert term from --light (Ament et al.'s comparison; --ao-radius, --ao-diffuse).",
    // One directional light: the unshadowed diffuse term through the gradient.
    lights: LightSupport::ONE_DIRECTIONAL,
    extinction: Some(true),
    make_pass: |inputs| Ok(Box::new(AoPass::new(inputs)?)),
    options: &[&AO_RADIUS, &AO_DIFFUSE],
    rebuild_scopes: &[CACHE_SCOPE],
    ..RAY_MARCHER
};

impl ModelPass for AoPass {
    delegate_to_march!();

    fn record(&mut self, rec: &mut Recorder, inputs: &Inputs) -> Result<Recorded> {
        let (info, opts) = (inputs.info, inputs.opts);
        let ambient = extinction(inputs)?;
        let [x, y, z] = info.dims.map(|d| d as i32);
        let builds = ambient.builds();
        let ao = AoOptions::of(opts);
        let shells = ao.shells();
        let sat = ambient.sat()?;
        let push = CachePush {
            dims: [x, y, z, shells],
            inv_scale: sat.inv_scale(),
            pad: [0.0; 3],
        };
        self.cache.record(
            rec,
            CACHE_SCOPE,
            vec![builds as u32, (builds >> 32) as u32, shells as u32],
            bytemuck::bytes_of(&push),
        )?;
        let towards = opts.light().towards().normalize();
        let c = opts.light().colour;
        self.march.record(rec, inputs, |march| Params {
            march,
            light: [towards.x, towards.y, towards.z, ao.diffuse],
            light_colour: [c[0], c[1], c[2], 0.0],
            dims: [x, y, z, 0],
        })
    }
}

crate::render::march::test_blocks_match_the_shaders!(
    params: shaders::AO_COMP, Params { light, light_colour, dims };
    push: shaders::AO_CACHE_COMP, CachePush { dims, inv_scale, pad }
);

#[cfg(test)]
mod tests {
    use super::*;

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
