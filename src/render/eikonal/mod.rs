//! The eikonal model (`--model eikonal`, issue 35; seed 001, Ihrke et al., *Eikonal
//! Rendering*): the light simulated first, as adaptive wavefronts through the
//! refractive-index field ([`super::light_simulator`], sect. 4.2 and 5.2), into a light
//! volume (fluence and mean direction per voxel); then every view rendered from it by
//! viewing rays integrated with the ray equation (`glsl/eikonal_view.comp`, sect. 4.1 and
//! 5.3, with its image formation model).
//!
//! Unlike the sweep, light and view are independent: the light may come from any
//! direction (behind the camera too), there may be several lights, directional or point
//! (their wavefronts add), and moving the camera reruns only the view. The light volume
//! is the model's state ([`LightVolume`]): simulated again, outside the frame's recording
//! (the simulation reads the list's size back between submissions), when the lights, the
//! transfer functions or the refractive-index scale change; its GPU time is the frame's
//! scope [`SIMULATION_SCOPE`], what a light or transfer-function change costs this model.
//! Changing g, the albedo or the camera rebuilds nothing. With dispersion (`--abbe`,
//! [`dispersion`]) each colour channel's light is a wavefront of its own and viewing rays
//! through glass are traced once per channel. Faces reflect by Fresnel (`--reflections`,
//! on by default as for the sweep): the first face's reflected ray is traced through the
//! volume, the others look up the environment. What a ray sees where it leaves the box is
//! averaged over the pixel's footprint (the neighbouring pixels' exit directions, the
//! summed-area table), as the sweep's composite does; the ambient level
//! (`SweepOptions::ambient`) and an optional emission ([`EMISSION`]) complete the image
//! formation model.

use anyhow::{ensure, Result};
use bytemuck::{Pod, Zeroable};

use super::light_simulator::{self, FieldInputs, SimulationStats, WavefrontSettings};
use super::march::{RayMarchPass, RAY_MARCHER};
use super::model::{Inputs, ModelPass, ModelState, ModelStateDecl, OpticalModel, Recorded, Shared};
use super::LightSupport;
use super::ModelOption;
use super::{RenderOptions, ScatterOptions, SCATTER_ALBEDO, SCATTER_G};
use crate::shaders;
use crate::vk::{self, Binding, Buffer, Memory, Recorder, Timings};

pub mod dispersion;

/// `--emission` (scene key `emission`): the image formation model's optional emission
/// (seed 001 sect. 4.1): every sample also emits its transfer-function colour times this,
/// per unit opacity, as the emission–absorption model's samples do (1: the EA image added
/// to the scattered light).
pub static EMISSION: ModelOption = ModelOption {
    flag: "--emission",
    value_name: "E",
    help: "Emission: every sample also emits its transfer-function colour times E (0 to \
           1000; 1 adds the emission-absorption image to the scattered light, 0 none)",
    default: 0.0,
    integer: false,
    check: |v| {
        ensure!(
            (0.0..=1000.0).contains(&v),
            "the emission must be from 0 to 1000"
        );
        Ok(())
    },
};

/// `--cubic-eta` (scene key `cubic_eta`): η from the cubic B-spline of the values, for
/// the light simulation and the viewing rays alike (glsl/ray_equation.glsl, RAY_CUBIC).
pub static CUBIC_ETA: ModelOption = ModelOption {
    flag: "--cubic-eta",
    value_name: "0|1",
    help: "1: the refractive index from the cubic B-spline of the values (smooth glass, as \
           `refrakt reference` takes it by default), for the light simulation and the viewing \
           rays; 0: trilinear, as the photon tracer takes it (its iso-surfaces are corrugated \
           at the voxels' period, which scatters what is seen through glass into speckle). \
           Cubic takes about twice the view's time and 1.4 times the light simulation's \
           (lavapipe, measured at 64³)",
    default: 0.0,
    integer: true,
    check: |v| {
        ensure!(
            v == 0.0 || v == 1.0,
            "0 (trilinear) or 1 (cubic B-spline) only"
        );
        Ok(())
    },
};

/// Whether `opts` asks for cubic η ([`CUBIC_ETA`]).
pub fn cubic_eta(opts: &RenderOptions) -> bool {
    opts.model_option(&CUBIC_ETA) == 1.0
}

/// The timings scope of the light simulation (all lights).
pub const SIMULATION_SCOPE: &str = "light simulation";

/// Bytes of the light volume per voxel: fluence and direction, a vec4 each.
const VOXEL_BYTES: u64 = 32;

/// The light volume the view reads, keyed by what it was simulated for.
pub struct LightVolume {
    buffer: Buffer,
    /// The lights, η scale and transfer-function change it holds (None: not simulated).
    key: Option<String>,
    /// The last simulation's GPU timings, until a frame takes them.
    timings: Timings,
    /// Each light's simulation statistics, the last time it was simulated.
    stats: Vec<SimulationStats>,
}

impl LightVolume {
    fn bytes(extent: [u32; 3]) -> u64 {
        VOXEL_BYTES * extent.iter().map(|&e| e as u64).product::<u64>()
    }

    /// An empty light volume for the renderer's volume, refused where the device cannot
    /// bind it as one storage buffer.
    pub(crate) fn new(shared: &Shared) -> Result<Self> {
        let bytes = Self::bytes(shared.info.dims);
        let range = shared.ctx.info().limits.max_storage_buffer_range as u64;
        let [x, y, z] = shared.info.dims;
        ensure!(
            bytes <= range,
            "the light volume of a {x}x{y}x{z} volume takes {} MiB ({VOXEL_BYTES} bytes a \
             voxel); device '{}' binds at most {} MiB as one storage buffer \
             (maxStorageBufferRange): use a smaller volume (--scale)",
            bytes >> 20,
            shared.ctx.info().name,
            range >> 20
        );
        let buffer = Buffer::new(
            shared.ctx,
            bytes,
            vk::usage::STORAGE_BUFFER | vk::usage::BUFFER_TRANSFER_DST,
            Memory::Gpu,
            "eikonal light volume",
        )?;
        Ok(Self {
            buffer,
            key: None,
            timings: Timings::default(),
            stats: Vec::new(),
        })
    }

    /// The statistics of the last simulation, one per light.
    pub fn stats(&self) -> &[SimulationStats] {
        &self.stats
    }

    /// The buffer the light is read from (glsl/light_volume.glsl).
    pub(crate) fn buffer(&self) -> &Buffer {
        &self.buffer
    }

    /// Its device bytes.
    pub(crate) fn device_bytes(&self) -> u64 {
        self.buffer.size()
    }

    /// The last simulation's GPU timings, until a frame takes them.
    pub(crate) fn take_timings(&mut self) -> Timings {
        std::mem::take(&mut self.timings)
    }

    /// Simulate every light of `opts` (their fluence and luminance-weighted directions
    /// add) and upload the sum, unless the volume holds these lights already.
    pub(crate) fn update(&mut self, shared: &Shared, opts: &RenderOptions) -> Result<()> {
        /// What the light volume depends on besides the volume (a renderer holds one).
        fn key(shared: &Shared, opts: &RenderOptions) -> String {
            format!(
                "{:?} eta scale {:?} tf change {} abbe {} cubic {}",
                opts.lights,
                opts.sweep.eta_scale,
                shared.tf_changes,
                opts.model_option(&dispersion::ABBE),
                cubic_eta(opts)
            )
        }

        let key = key(shared, opts);
        if self.key.as_ref() == Some(&key) {
            return Ok(());
        }
        let inputs = FieldInputs {
            ctx: shared.ctx,
            info: shared.info,
            volume: shared.volume,
            volume_sampler: shared.volume_sampler,
            tf: shared.tf,
            linear: shared.linear,
        };
        let settings = WavefrontSettings {
            fluence: true,
            gradient: if cubic_eta(opts) {
                light_simulator::RayGradient::Cubic
            } else {
                light_simulator::RayGradient::Differences
            },
            ..Default::default()
        };
        let voxels = self.buffer.size() / VOXEL_BYTES;
        let mut fluence = vec![[0.0f32; 3]; voxels as usize];
        // Σ luminance × direction, divided by the summed luminance below.
        let mut weighted = vec![[0.0f32; 3]; voxels as usize];
        let mut stats = Vec::new();
        let mut ms = 0.0;
        // With dispersion each colour channel's light is a wavefront of its own, through
        // the field of that channel's η (dispersion.rs), and gives the volume that
        // channel alone; without, one wavefront carries all three.
        let runs: Vec<(RenderOptions, Option<usize>)> = match dispersion::channel_eta_scales(opts)?
        {
            None => vec![(opts.clone(), None)],
            Some(scales) => (0..3)
                .map(|c| {
                    let mut o = opts.clone();
                    o.sweep.eta_scale = scales[c];
                    (o, Some(c))
                })
                .collect(),
        };
        for (index, light) in opts.lights.iter().enumerate() {
            for (run_opts, only) in &runs {
                let label = SimulationStats {
                    light: index,
                    channel: *only,
                    ..Default::default()
                }
                .label();
                let report = |cycle: u32, most: u32, live: u32| {
                    if let Some(p) = shared.progress {
                        p(&format!(
                            "light simulation, {label}: cycle {cycle} of at most {most}, \
                             {live} patches live"
                        ));
                    }
                };
                let sim = light_simulator::simulate(
                    &inputs,
                    run_opts,
                    light,
                    &settings,
                    &[],
                    Some(&report),
                )?;
                let volume = sim.fluence.as_ref().expect("asked for the fluence volume");
                let channels = match only {
                    Some(c) => *c..*c + 1,
                    None => 0..3,
                };
                for ((f, w), (e, d)) in fluence
                    .iter_mut()
                    .zip(weighted.iter_mut())
                    .zip(volume.fluence.iter().zip(&volume.direction))
                {
                    for c in channels.clone() {
                        // The direction weighted by the channel's share of the luminance.
                        let lum = LUMINANCE[c] * e[c];
                        f[c] += e[c];
                        for (wk, dk) in w.iter_mut().zip(d) {
                            *wk += lum * dk;
                        }
                    }
                }
                ms += sim.stats.gpu_ms;
                stats.push(SimulationStats {
                    light: index,
                    channel: *only,
                    ..sim.stats
                });
            }
        }
        let mut texels: Vec<[f32; 4]> = Vec::with_capacity(2 * fluence.len());
        for (f, w) in fluence.iter().zip(&weighted) {
            let lum = luminance(*f);
            let d = if lum > 0.0 {
                w.map(|c| c / lum)
            } else {
                [0.0; 3]
            };
            texels.push([f[0], f[1], f[2], 0.0]);
            texels.push([d[0], d[1], d[2], 0.0]);
        }
        let ctx = shared.ctx;
        let mut staging = Buffer::new(
            ctx,
            self.buffer.size(),
            vk::usage::BUFFER_TRANSFER_SRC,
            Memory::Upload,
            "eikonal light volume staging",
        )?;
        staging.write(0, bytemuck::cast_slice(&texels))?;
        let size = self.buffer.size();
        ctx.execute(|rec| rec.upload_to_storage(&staging, 0, &self.buffer, 0, size))?;
        self.timings = Timings {
            scopes: vec![(SIMULATION_SCOPE.to_string(), ms)],
        };
        self.stats = stats;
        self.key = Some(key);
        Ok(())
    }
}

impl ModelState for LightVolume {
    fn prepare(&mut self, shared: &Shared, opts: &RenderOptions) -> Result<bool> {
        self.update(shared, opts)?;
        // The same buffer: the passes' sets stay valid.
        Ok(false)
    }

    fn take_timings(&mut self) -> Timings {
        LightVolume::take_timings(self)
    }

    fn bytes(&self) -> u64 {
        self.device_bytes()
    }

    fn simulation_stats(&self) -> &[SimulationStats] {
        self.stats()
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

/// Rec. 709 luminance weights.
const LUMINANCE: [f32; 3] = [0.2126, 0.7152, 0.0722];

fn luminance(c: [f32; 3]) -> f32 {
    LUMINANCE[0] * c[0] + LUMINANCE[1] * c[1] + LUMINANCE[2] * c[2]
}

/// std140 mirror of `Params` in glsl/eikonal_view.comp (ea.comp's block, then the
/// model's).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    march: super::march::MarchParams,
    field: [f32; 4],
    scatter: [f32; 4],
    /// The refractive-index scale per colour channel (all three the same without
    /// dispersion).
    eta_scales: [f32; 4],
    /// Steps at most per ray, colour channels traced apart, 1 with Fresnel reflections,
    /// 1 with the environment filtered over each pixel's footprint.
    steps: [u32; 4],
    /// The ambient level (rgb; [`super::SweepOptions::ambient`]); w: the emission.
    ambient: [f32; 4],
    /// The environment's summed-area table's mean offset.
    env_mean: [f32; 4],
}

pub(super) struct EikonalPass {
    march: RayMarchPass,
    /// Whether its pipeline takes cubic η (specialization constant 0, VIEW_CUBIC).
    cubic: bool,
}

impl EikonalPass {
    pub fn new(inputs: &Inputs) -> Result<Self> {
        let light = inputs.state::<LightVolume>()?;
        let cubic = cubic_eta(inputs.opts);
        Ok(Self {
            march: RayMarchPass::with_constants::<Params>(
                inputs,
                shaders::EIKONAL_VIEW_COMP,
                "eikonal view",
                &[
                    Binding::Texture(inputs.env.map, inputs.linear),
                    Binding::Storage(&light.buffer),
                    Binding::Texture(inputs.env.sat, inputs.linear),
                ],
                &[cubic as u32],
            )?,
            cubic,
        })
    }
}

/// The eikonal model's declaration (listed in render/registry.rs).
pub(crate) static EIKONAL: OpticalModel = OpticalModel {
    name: "eikonal",
    summary: "Eikonal rendering (Ihrke et al.): the light simulated as adaptive wavefronts into a light volume, then viewing rays along the ray equation; lights from any direction, several, point lights, dispersion (--light, --g, --albedo, --abbe).",
    lights: LightSupport {
        max: super::limits::MAX_LIGHTS,
        point: true,
    },
    phase_function: true,
    // The refractive-index scale, the Fresnel reflections at faces, the environment behind
    // (filtered over the pixel's footprint) and the ambient level, as the sweep's.
    flags: &[
        "--eta-scale",
        "--reflections",
        "--env",
        "--env-rotation",
        "--ambient-level",
    ],
    make_pass: |inputs| Ok(Box::new(EikonalPass::new(inputs)?)),
    options: &[
        &SCATTER_G,
        &SCATTER_ALBEDO,
        &dispersion::ABBE,
        &EMISSION,
        &CUBIC_ETA,
    ],
    rebuild_scopes: &[SIMULATION_SCOPE],
    state: Some(ModelStateDecl {
        what: "the light volume",
        bytes: LightVolume::bytes,
        make: |shared| Ok(Box::new(LightVolume::new(shared)?)),
    }),
    experimental: Some(
        "its light simulation takes minutes on lavapipe (the default 128³ scene about five \
         and a half) and a list near the device's patch budget (issue 35)",
    ),
    ..RAY_MARCHER
};

impl ModelPass for EikonalPass {
    fn fits(&self, opts: &RenderOptions) -> bool {
        self.march.fits(opts) && self.cubic == cubic_eta(opts)
    }

    fn output(&self) -> &crate::render::FrameTarget {
        self.march.output()
    }

    fn record(&mut self, rec: &mut Recorder, inputs: &Inputs) -> Result<Recorded> {
        let (opts, info) = (inputs.opts, inputs.info);
        ensure!(
            opts.sweep.clip.is_none(),
            "the eikonal model takes no clipping plane"
        );
        let _light = inputs.state::<LightVolume>()?;
        let scatter = ScatterOptions::of(opts);
        // Steps at most: four times the box's diagonal at the sample distance, and as
        // many again for the shorter steps at faces (a ray bent back and forth by total
        // reflection inside glass is cut there).
        let step = opts.sample_distance * info.ref_step;
        let max_steps = ((16.0 * info.half_extent.length() / step).ceil() as u32).max(1);
        // With dispersion a viewing ray that meets refractive matter is traced once per
        // colour channel, each through its own field.
        let (eta_scales, channels) = match dispersion::channel_eta_scales(opts)? {
            Some([r, g, b]) => ([r, g, b, 0.0], 3),
            None => ([opts.sweep.eta_scale; 4], 1),
        };
        let mut recorded = self.march.record(rec, inputs, |march| Params {
            march,
            field: info.dims_and(opts.sweep.eta_scale),
            scatter: [
                scatter.g,
                scatter.albedo,
                opts.sweep.env_rotation.to_radians(),
                if inputs.env.enabled { 1.0 } else { 0.0 },
            ],
            eta_scales,
            steps: [
                max_steps,
                channels,
                opts.sweep.reflections as u32,
                opts.sweep.env_footprint as u32,
            ],
            ambient: [
                opts.sweep.ambient[0],
                opts.sweep.ambient[1],
                opts.sweep.ambient[2],
                opts.model_option(&EMISSION) as f32,
            ],
            env_mean: inputs.env.mean,
        })?;
        recorded.max_steps = max_steps;
        Ok(recorded)
    }
}

crate::render::march::test_blocks_match_the_shaders!(
    params: shaders::EIKONAL_VIEW_COMP, Params { field, scatter, eta_scales, steps, ambient, env_mean }
);
