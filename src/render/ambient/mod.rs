//! Ambient scattering (`--model ambient`, issue 17 item 3): Ament et al.'s model (seed
//! 002) of multiple scattering on a mesoscopic scale. Three steps, each cached and rebuilt
//! only when what it depends on changes:
//!
//! 1. the **ambient extinction volume** σ̃_t (sect. 4.2.1, eq. 13): the mean extinction over
//!    a cube with the volume of the ambient sphere S_r around every voxel, from the
//!    extinction volume's 3D summed-area table (`glsl/ambient_extinction.comp`, scope
//!    [`EXTINCTION_SCOPE`]; depends on the transfer functions and the radius);
//! 2. the **radiance cache** (sect. 3.2.2, 4.2.2): the light front of every light at every
//!    cache voxel (half the volume's resolution, as the paper's), marched from the light in
//!    tubes of radius r with steps of 2r (`glsl/radiance_cache.comp`, scope
//!    [`CACHE_SCOPE`]; depends on σ̃_t, the lights and g);
//! 3. **ambient ray casting** (sect. 4.2.3, Algorithm 1, `glsl/ambient.comp`): the
//!    emission–absorption march of the other ray marchers, each sample lit through the
//!    preintegrated tables ([`table`]) with the view-dependent angle, per light.
//!
//! Where we depart from the paper, and why (physics, not taste): the table is the
//! in-scattered radiance at the ambient sphere's *centre* under a collimated unit front,
//! with the front scattered once at the centre left out of it and added analytically
//! (exact at every anisotropy, where a table of a peaked phase function would blur it);
//! the tube-marching factor is the sphere's own transmission of a front (1 in empty space),
//! not the radial table entry at θ = 0 the paper multiplies by (eq. 16), which is
//! p_HG(0; g)/(4π) in empty space. [`table`] defines both quantities.
//!
//! Radii are in reference steps (smallest voxel sides), like the AO model's; the ambient
//! extinction, like the extinction volume, per reference step, so s = r·σ̃_t.

pub mod table;

use anyhow::{ensure, Result};
use bytemuck::{Pod, Zeroable};

use super::cached::CachedImage;
use super::march::{delegate_to_march, RayMarchPass, RAY_MARCHER};
use super::model::{Inputs, ModelPass, ModelState, ModelStateDecl, OpticalModel, Recorded, Shared};
use super::model_options::ModelOption;
use super::LightSupport;
use super::{RenderOptions, ScatterOptions, SCATTER_ALBEDO, SCATTER_G};
use crate::light::LightSource;
use crate::shaders;
use crate::vk::{self, Binding, Context, Filter, Image, ImageDesc, ImageKind, Recorder, Sampler};
use table::{AmbientTable, TableParams};

/// The timings scope of the ambient extinction volume's build.
pub const EXTINCTION_SCOPE: &str = "ambient extinction";
/// The timings scope of the radiance cache's build.
pub const CACHE_SCOPE: &str = "radiance cache";

/// Most lights the model takes (the main light and three more: one cache channel each;
/// defined once for Rust and the shaders).
pub use crate::render::limits::MAX_LIGHTS;
/// Smallest and largest ambient radius, in reference steps.
pub const MIN_RADIUS: f32 = 0.5;
pub const MAX_RADIUS: f32 = 64.0;

/// `(4π/3)^(1/3)`: the side of the cube with the volume of the unit sphere (eq. 13).
const CUBE_PER_RADIUS: f32 = 1.611_991_9;

/// Options of the ambient-scattering model (its phase function and albedo are
/// [`super::ScatterOptions`], its lights [`RenderOptions::lights`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmbientOptions {
    /// Radius r of the ambient sphere, in reference steps: the scale of the soft shadows
    /// and the translucency (the paper shows 2 to 14 voxels).
    pub radius: f32,
}

impl Default for AmbientOptions {
    fn default() -> Self {
        // The declared default (the flag's and scene key's).
        Self {
            radius: AMBIENT_RADIUS.default as f32,
        }
    }
}

/// `--ambient-radius` (scene key `ambient_radius`): [`AmbientOptions::radius`].
pub static AMBIENT_RADIUS: ModelOption = ModelOption {
    flag: "--ambient-radius",
    value_name: "VOXELS",
    help: "Ambient scattering: radius r of the sphere around each sample in which light \
           scatters, in voxels, 0.5-64: the size of the soft shadows and of the translucency",
    default: 6.0,
    integer: false,
    check: |v| AmbientOptions { radius: v as f32 }.validate(),
};

impl AmbientOptions {
    /// The options `opts` asks of this model (its declared options' values).
    pub fn of(opts: &RenderOptions) -> Self {
        Self {
            radius: opts.model_option(&AMBIENT_RADIUS) as f32,
        }
    }

    /// Ask these of the model in `opts` (refused as the flag would be).
    pub fn set_in(&self, opts: &mut RenderOptions) -> Result<()> {
        opts.models.set(&AMBIENT_RADIUS, self.radius as f64)
    }

    pub fn validate(&self) -> Result<()> {
        ensure!(
            self.radius.is_finite() && (MIN_RADIUS..=MAX_RADIUS).contains(&self.radius),
            "ambient radius {} must be in [{MIN_RADIUS}, {MAX_RADIUS}] voxels",
            self.radius
        );
        Ok(())
    }
}

/// The preintegrated tables on the GPU: the scattered radiance as a 3D image
/// [θ, s, g] and the scattered part of the sphere's transmission (the table's minus the
/// direct e^(−2s), which `glsl/radiance_cache.comp` adds exactly) as a 2D image [s, g],
/// both R32F.
pub struct TableTextures {
    params: TableParams,
    scattered: Image,
    transmission: Image,
    /// Set by the caller ([`super::Renderer::set_ambient_table`]) rather than chosen for
    /// the frame's albedo.
    explicit: bool,
}

impl TableTextures {
    pub fn new(ctx: &Context, table: &AmbientTable, explicit: bool) -> Result<Self> {
        let p = table.params;
        let scattered_transmission: Vec<f32> = table
            .transmission
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                let s = p.s(i as u32 % p.s_bins);
                (t as f64 - (-2.0 * s).exp()) as f32
            })
            .collect();
        let upload = |extent: [u32; 3], kind, data: &[f32], name| -> Result<Image> {
            let image = Image::new(
                ctx,
                ImageDesc {
                    kind,
                    format: vk::Format::R32_SFLOAT,
                    extent,
                    layers: 1,
                    usage: vk::usage::SAMPLED | vk::usage::TRANSFER_DST,
                },
                name,
            )?;
            ctx.upload_image(&image, 0, bytemuck::cast_slice(data))?;
            Ok(image)
        };
        Ok(Self {
            params: p,
            scattered: upload(
                [p.theta_bins, p.s_bins, p.g_bins],
                ImageKind::D3,
                &table.scattered,
                "ambient table",
            )?,
            transmission: upload(
                [p.s_bins, p.g_bins, 1],
                ImageKind::D2,
                &scattered_transmission,
                "ambient transmission",
            )?,
            explicit,
        })
    }

    pub fn params(&self) -> &TableParams {
        &self.params
    }

    pub fn is_explicit(&self) -> bool {
        self.explicit
    }

    fn dims(&self) -> [f32; 4] {
        let p = &self.params;
        [
            p.theta_bins as f32,
            p.s_bins as f32,
            p.g_bins as f32,
            p.s_max,
        ]
    }
}

/// The lights of a frame as the shaders take them: xyz towards the light (unit) or its
/// position, w = 1 for a point light; and their colours.
pub(crate) fn lights(
    opts: &RenderOptions,
) -> (usize, [[f32; 4]; MAX_LIGHTS], [[f32; 4]; MAX_LIGHTS]) {
    let mut at = [[0.0; 4]; MAX_LIGHTS];
    let mut colours = [[0.0; 4]; MAX_LIGHTS];
    let mut n = 0;
    for (j, l) in opts.lights.iter().take(MAX_LIGHTS).enumerate() {
        at[j] = match l.source {
            LightSource::Directional { towards } => {
                let t = towards.normalize();
                [t.x, t.y, t.z, 0.0]
            }
            LightSource::Point { position: p } => [p.x, p.y, p.z, 1.0],
        };
        colours[j] = [l.colour[0], l.colour[1], l.colour[2], 0.0];
        n = j + 1;
    }
    (n, at, colours)
}

/// `glsl/ambient_extinction.comp`'s push constants.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ExtinctionPush {
    dims: [i32; 4],
    inv_scale: f32,
    side: f32,
    pad: [f32; 2],
}

/// `glsl/radiance_cache.comp`'s push constants.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CachePush {
    lights: [[f32; 4]; MAX_LIGHTS],
    half_extent: [f32; 4],
    table: [f32; 4],
    misc: [f32; 4],
}

/// std140 mirror of `Params` in glsl/ambient.comp (ea.comp's block, then the model's).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    march: super::march::MarchParams,
    lights: [[f32; 4]; MAX_LIGHTS],
    colours: [[f32; 4]; MAX_LIGHTS],
    ambient: [f32; 4],
    table: [f32; 4],
    counts: [u32; 4],
}

pub(super) struct AmbientPass {
    march: RayMarchPass,
    /// Kept for the ambient extinction's set (the SAT is read with texelFetch through it).
    _nearest: Sampler,
    /// σ̃_t per reference step at every voxel centre (R32F, the volume's resolution).
    extinction: CachedImage,
    /// The light fronts, one channel per light (RGBA32F, half the volume's resolution).
    radiance: CachedImage,
}

fn inputs_of<'a>(
    inputs: &Inputs<'a>,
) -> Result<(&'a super::extinction::Extinction, &'a TableTextures)> {
    let e = inputs.extinction.ok_or_else(|| {
        anyhow::anyhow!("the ambient-scattering model needs the extinction volume")
    })?;
    let t = inputs.state::<AmbientTables>()?.table()?;
    Ok((e, t))
}

/// The radiance cache's size: half the volume's per axis, rounded up.
pub fn cache_extent(dims: [u32; 3]) -> [u32; 3] {
    dims.map(|d| d.div_ceil(2).max(1))
}

impl AmbientPass {
    pub fn new(inputs: &Inputs) -> Result<Self> {
        let ctx = inputs.ctx;
        let (ext, table) = inputs_of(inputs)?;
        let nearest = Sampler::new(ctx, Filter::Nearest, "ambient SAT")?;
        let extent = inputs.volume.extent();
        let extinction = CachedImage::new(
            ctx,
            ImageDesc::computed(ImageKind::D3, vk::Format::R32_SFLOAT, extent, 1),
            &[Binding::Texture(ext.sat()?.image(), &nearest)],
            shaders::AMBIENT_EXTINCTION_COMP,
            std::mem::size_of::<ExtinctionPush>(),
            EXTINCTION_SCOPE,
        )?;
        let radiance = CachedImage::new(
            ctx,
            ImageDesc::computed(
                ImageKind::D3,
                vk::Format::R32G32B32A32_SFLOAT,
                cache_extent(extent),
                1,
            ),
            &[
                Binding::Texture(extinction.image(), inputs.linear),
                Binding::Texture(&table.transmission, inputs.linear),
            ],
            shaders::RADIANCE_CACHE_COMP,
            std::mem::size_of::<CachePush>(),
            CACHE_SCOPE,
        )?;
        let march = RayMarchPass::new::<Params>(
            inputs,
            shaders::AMBIENT_COMP,
            "ambient",
            &[
                Binding::Texture(extinction.image(), inputs.linear),
                Binding::Texture(radiance.image(), inputs.linear),
                Binding::Texture(&table.scattered, inputs.linear),
            ],
        )?;
        Ok(Self {
            march,
            _nearest: nearest,
            extinction,
            radiance,
        })
    }
}

/// The ambient-scattering model's declaration (listed in render/registry.rs).
pub(crate) static AMBIENT: OpticalModel = OpticalModel {
    name: "ambient",
    summary: "Ambient scattering (Ament et al.): multiple scattering in a sphere around each sample from a preintegrated Monte-Carlo table, soft shadows and translucency by tube marching; up to four lights, directional or point (--light repeated, --g, --albedo, --ambient-radius).",
    // Up to MAX_LIGHTS, directional or point: each is marched through its tubes.
    lights: LightSupport {
        max: MAX_LIGHTS,
        point: true,
    },
    phase_function: true,
    extinction: Some(true),
    make_pass: |inputs| Ok(Box::new(AmbientPass::new(inputs)?)),
    options: &[&SCATTER_G, &SCATTER_ALBEDO, &AMBIENT_RADIUS],
    // Its table is a file the front end loads or builds (`Renderer::set_ambient_table`).
    flags: &["--ambient-table"],
    rebuild_scopes: &[EXTINCTION_SCOPE, CACHE_SCOPE],
    state: Some(ModelStateDecl {
        what: "the ambient-scattering tables",
        // The tables are a few MB whatever the volume.
        bytes: |_| 0,
        make: |_| Ok(Box::new(AmbientTables::default())),
    }),
    ..RAY_MARCHER
};

/// The model's state: the tables in use, set by the caller
/// ([`super::Renderer::set_ambient_table`]) or loaded for the frame's albedo.
#[derive(Default)]
pub struct AmbientTables {
    table: Option<TableTextures>,
}

impl AmbientTables {
    fn table(&self) -> Result<&TableTextures> {
        self.table
            .as_ref()
            .ok_or_else(|| anyhow::anyhow!("the ambient-scattering model needs its table"))
    }
}

impl ModelState for AmbientTables {
    /// Load the table for the frame's albedo if the one loaded is not for it (the default
    /// parameters; built on first use, then read from the disk cache: see
    /// [`table::load_or_build`]); a table the caller set for another albedo is an error.
    fn prepare(&mut self, shared: &Shared, opts: &RenderOptions) -> Result<bool> {
        let albedo = ScatterOptions::of(opts).albedo;
        if let Some(t) = &self.table {
            if t.params().albedo == albedo {
                return Ok(false);
            }
            ensure!(
                !t.is_explicit(),
                "the ambient-scattering table in use was built for albedo {}, the frame asks \
                 for {albedo}: build one for it (refrakt precompute ambient --albedo {albedo}) \
                 or leave the albedo at the table's",
                t.params().albedo
            );
        }
        let params = TableParams {
            albedo,
            ..Default::default()
        };
        log::info!("ambient-scattering table for albedo {albedo}: loading or building");
        let (table, _) = table::load_or_build(&params, None, 0, &|_, _| {})?;
        self.table = Some(TableTextures::new(shared.ctx, &table, false)?);
        Ok(true)
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

/// The ambient-scattering model's part of the renderer's interface.
impl super::Renderer {
    /// Use `table` for the ambient-scattering model's frames from now on (instead of the
    /// default table for the frame's albedo, built or loaded from the disk cache): frames
    /// whose albedo differs from the table's are refused.
    pub fn set_ambient_table(&mut self, table: &AmbientTable) -> Result<()> {
        table.params.validate()?;
        let textures = TableTextures::new(self.context(), table, true)?;
        let state = self.model_state(super::Model::Ambient)?;
        let tables = state
            .as_any_mut()
            .downcast_mut::<AmbientTables>()
            .expect("the ambient model's state");
        tables.table = Some(textures);
        self.remove_passes(super::Model::Ambient);
        Ok(())
    }

    /// The parameters of the ambient-scattering table in use, if one is loaded.
    pub fn ambient_table_params(&self) -> Option<TableParams> {
        let state = self.existing_model_state(super::Model::Ambient)?;
        let tables = state.as_any().downcast_ref::<AmbientTables>()?;
        tables.table.as_ref().map(|t| *t.params())
    }
}

impl ModelPass for AmbientPass {
    delegate_to_march!();

    fn record(&mut self, rec: &mut Recorder, inputs: &Inputs) -> Result<Recorded> {
        let (info, opts) = (inputs.info, inputs.opts);
        let (ext, table) = inputs_of(inputs)?;
        let sat = ext.sat()?;
        let radius = AmbientOptions::of(opts).radius;
        let [x, y, z] = info.dims.map(|d| d as i32);
        let push = ExtinctionPush {
            dims: [x, y, z, 0],
            inv_scale: sat.inv_scale(),
            side: radius * CUBE_PER_RADIUS,
            pad: [0.0; 2],
        };
        // What each cache was built from: the extinction's build count and the radius; then
        // that, the lights, g and the table.
        let ext_key = vec![
            ext.builds() as u32,
            (ext.builds() >> 32) as u32,
            radius.to_bits(),
        ];
        self.extinction.record(
            rec,
            EXTINCTION_SCOPE,
            ext_key.clone(),
            bytemuck::bytes_of(&push),
        )?;
        let (n, at, colours) = lights(opts);
        let r_world = radius * info.ref_step;
        let scatter = ScatterOptions::of(opts);
        let g = scatter.g;
        let h = info.half_extent;
        let cache_push = CachePush {
            lights: at,
            half_extent: [h.x, h.y, h.z, r_world],
            table: table.dims(),
            misc: [g, radius, n as f32, 0.0],
        };
        let mut cache_key = ext_key;
        cache_key.extend(
            bytemuck::cast_slice::<_, u32>(&[cache_push])
                .iter()
                .copied(),
        );
        cache_key.push(table.scattered.id() as u32);
        self.radiance
            .record(rec, CACHE_SCOPE, cache_key, bytemuck::bytes_of(&cache_push))?;
        self.march.record(rec, inputs, |march| Params {
            march,
            lights: at,
            colours,
            ambient: [r_world, radius, g, scatter.albedo],
            table: table.dims(),
            counts: [n as u32, 0, 0, 0],
        })
    }
}

crate::render::march::test_blocks_match_the_shaders!(
    params: shaders::AMBIENT_COMP, Params { lights, colours, ambient, table, counts };
    push: shaders::RADIANCE_CACHE_COMP, CachePush { lights, half_extent, table, misc };
    push: shaders::AMBIENT_EXTINCTION_COMP, ExtinctionPush { dims, inv_scale, side, pad }
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radius_limits_are_refused_by_name() {
        for r in [0.0, 0.4, 65.0, f32::NAN] {
            let e = AmbientOptions { radius: r }
                .validate()
                .unwrap_err()
                .to_string();
            assert!(e.contains("ambient radius"), "{e}");
        }
        AmbientOptions { radius: 0.5 }.validate().unwrap();
        AmbientOptions { radius: 64.0 }.validate().unwrap();
    }
}
