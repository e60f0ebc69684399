//! The eikonal light simulator (issue 35; seed 001, Ihrke et al., *Eikonal Rendering*,
//! sect. 4.2 and 5.2), on the GPU: a wavefront of patches, four corner particles each,
//! launched as a plane wave covering the box, advanced by the equi-temporal ray equation
//! (eqs. 14–15, `glsl/ray_equation.glsl`) through the same refractive-index field as the
//! sweep and the photon tracer, each patch carrying its flux (so its irradiance is
//! flux / area: the intensity law, eqs. 16–17) dimmed by the medium (eq. 18), split into
//! k × k where it grows past a voxel and retired where its light is spent or has left the
//! box, the list compacted and expanded on the GPU by a prefix sum (`glsl/light_wavefront*`).
//!
//! **Past the paper at foci.** The paper discards a patch whose orientation turns (it
//! crossed a focus: "non-physical caustics"). Here it is kept, with its flux, as the
//! sweep's forward transport keeps light through a focus; [`FocusPolicy::Discard`] does
//! what the paper does, so the difference can be measured ([`SimulationStats::at_foci`]).
//!
//! **What it deposits.** Receivers: planes on which the flux crossing them is counted,
//! each patch spreading its flux over the area it spans there (exact pixel coverage, as
//! the sweep's cells deposit), so a receiver reads irradiance in the light's units, as the
//! photon tracer's image does. The fluence volume: per voxel the flux × path length of
//! the stream tubes through it over its volume (the irradiance their light brings, summed
//! over crossing wavefronts, where the paper keeps the strongest) and their
//! luminance-weighted direction: what a view renderer's in-scattering reads.
//!
//! Units: positions are world units (the box centred at the origin); the step is an
//! optical path in reference steps (smallest voxel sides); a patch's flux is in the
//! light's colour × reference step², so a launched patch one reference step on a side
//! carries the light's colour.

use anyhow::{bail, ensure, Result};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::{RenderOptions, Renderer, VolumeInfo};
use crate::camera::Camera;
use crate::light::{Light, LightSource};
use crate::shaders;
use crate::vk::{self, Binding, Buffer, ComputePipeline, DescriptorSet, Memory};

/// Patches per workgroup and per scan block (`WAVEFRONT_GROUP` in the shaders).
const GROUP: u32 = 256;
/// Bytes per patch (`Patch` in glsl/light_wavefront.glsl: nine vec4).
const PATCH_BYTES: u64 = 9 * 16;
/// Words of the control buffer (`CTRL_*` in glsl/light_wavefront.glsl).
const CTRL_DISPATCH: usize = 0;
const CTRL_COUNT: usize = 8;
const CTRL_NEEDED: usize = 10;
const CTRL_WORST_SPAN: usize = 11;
const CTRL_UNSPLIT: usize = 12;
const CTRL_FOCI: usize = 13;
const CTRL_COARSE: usize = 14;
const CTRL_PEAK: usize = 15;
const CTRL_ABSORBED: usize = 16;
const CTRL_LEFT: usize = 22;
const CTRL_AT_FOCI: usize = 28;
const CTRL_DROPPED: usize = 34;
const CTRL_TORN: usize = 40;
const CTRL_DILUTED: usize = 46;
const CTRL_PATCH_CYCLES: usize = 52;
const CTRL_STRAIGHT: usize = 53;
const CTRL_WORDS: usize = 54;
/// Receiver planes at most (a patch keeps one bit per receiver in a float's mantissa).
pub const MAX_RECEIVERS: usize = 16;
/// Cycles recorded per submission: the host reads the list's size after each, to stop
/// when it is empty and to report progress.
const CYCLES_PER_SUBMIT: u32 = 8;

/// What the simulator does with a patch that crossed a focus (its orientation turned).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FocusPolicy {
    /// Keep it with its flux (the sweep's forward transport does the same): the light
    /// beyond a caustic is conserved.
    Keep,
    /// Retire it, as the paper does (sect. 5.2.3).
    Discard,
}

/// Where the wavefront's corners take the refractive index and its gradient from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayGradient {
    /// Central differences 0.05 voxel apart of η over the trilinear field, as the photon
    /// tracer and `trace_rays_on_gpu` take it: the medium the volume defines, faces
    /// and all.
    Differences,
    /// The field texture (η and ∇η per voxel, by differences one voxel apart, filtered):
    /// the paper's stored volumes (sect. 5.1); about a fifteenth of the fetches, a
    /// smoother wavefront, surfaces sharper than a voxel or two blurred.
    FieldTexture,
    /// η from the cubic B-spline of the values and its own gradient (C², as the photon
    /// tracer and the reference renderer take it with cubic η,
    /// `photons::Field::use_cubic_eta`): smooth iso-surfaces where the trilinear field's
    /// are corrugated at the voxels' period, whose micro-foci fragment the wavefront.
    Cubic,
}

/// The simulator's settings.
#[derive(Clone, Debug)]
pub struct WavefrontSettings {
    /// Optical path per RK4 step, in reference steps.
    pub step: f32,
    /// RK4 steps per cycle (each cycle ends with the tessellation analysis).
    pub substeps: u32,
    /// The launched patches' side, in reference steps (at most 1: a patch may span a
    /// voxel).
    pub launch_spacing: f32,
    /// A patch retires when every channel's transmittance is below this.
    pub threshold: f32,
    /// Splits per patch at most (a patch longer than a voxel at this level is kept whole
    /// and counted, [`SimulationStats::unsplit`]).
    pub max_level: u32,
    /// Patches the list holds at most (each of its two halves, a buffer of 144 bytes a
    /// patch): a simulation that needs more is refused, naming how many it needed.
    /// `None`: as many as the device binds as one buffer (maxStorageBufferRange; 932 032
    /// on lavapipe), at most 2^20.
    pub max_patches: Option<u32>,
    pub at_foci: FocusPolicy,
    /// Deposit into the fluence volume ([`LightSimulation::fluence`]).
    pub fluence: bool,
    /// Cycles at most; light still travelling then is reported
    /// ([`SimulationStats::live_at_end`]). `None`: enough for a straight path through
    /// the box at η 3.
    pub max_cycles: Option<u32>,
    /// A patch longer than this after a cycle (reference steps) is torn: its corners
    /// went different ways (either side of a silhouette); it is retired and its flux
    /// counted ([`SimulationStats::torn`]). At least 2.
    pub tear_span: f32,
    pub gradient: RayGradient,
    /// A patch split down to less than this part of its launched patch's flux retires
    /// (the paper's energy threshold): light fanned out beside a silhouette or after a
    /// micro-focus of a voxelised surface would otherwise multiply the list every cycle.
    /// Its flux is counted ([`SimulationStats::diluted`]). 0 to 1.
    pub min_dilution: f32,
    /// Patches whose corners' whole cycle stays where one η holds (by the volume and the
    /// transfer functions) move them in straight lines instead of integrating the ray
    /// equation (their attenuation is integrated as before): the same light to rounding,
    /// cheaper where the light crosses air, glass or an opaque floor's inside
    /// (docs/NOTES.md, "The light simulator in clear space"). Costs two 32-bit images of
    /// the volume's size. `false`: every corner is integrated (tests compare the two).
    pub clear_space: bool,
    /// A beam: only the patches whose centres lie within this radius (world units) of
    /// the line along the light through the box's centre are launched. `None`: the whole
    /// box is lit.
    pub aperture: Option<f32>,
}

impl Default for WavefrontSettings {
    fn default() -> Self {
        Self {
            step: 0.5,
            substeps: 4,
            launch_spacing: 1.0,
            threshold: 1e-4,
            max_level: 8,
            max_patches: None,
            at_foci: FocusPolicy::Keep,
            fluence: false,
            max_cycles: None,
            aperture: None,
            tear_span: 4.0,
            gradient: RayGradient::Differences,
            min_dilution: 1e-4,
            clear_space: true,
        }
    }
}

/// A plane on which the simulator counts the flux crossing it (along its normal
/// `u × v`, normalised), per pixel: pixel (i, j) is the parallelogram from
/// `origin + i u + j v` spanned by `u` and `v` (world units; `u` ⟂ `v`).
#[derive(Clone, Copy, Debug)]
pub struct Receiver {
    pub origin: Vec3,
    pub u: Vec3,
    pub v: Vec3,
    pub width: u32,
    pub height: u32,
}

impl Receiver {
    /// The plane normal to the view at `depth` in front of the eye, pixels as the
    /// frame's (and the photon tracer's `trace_irradiance`): row 0 at the top. Its normal
    /// points away from the eye.
    pub fn view_plane(camera: &Camera, width: u32, height: u32, depth: f32) -> Receiver {
        let (eye, forward, right, _) = camera.frame();
        let forward = forward.normalize();
        let right = (right - forward * right.dot(forward)).normalize();
        let up = right.cross(forward);
        let half_h = depth * (camera.fov_y.to_radians() * 0.5).tan();
        let half_w = half_h * width as f32 / height as f32;
        Receiver {
            origin: eye + forward * depth - right * half_w + up * half_h,
            u: right * (2.0 * half_w / width as f32),
            // u × v = right × (-up) = forward: the normal points away from the eye.
            v: -up * (2.0 * half_h / height as f32),
            width,
            height,
        }
    }

    fn normal(&self) -> Vec3 {
        self.u.cross(self.v).normalize()
    }
}

/// Counters of one simulation: what happened to the light, and how the list grew.
#[derive(Clone, Debug, Default)]
pub struct SimulationStats {
    /// Cycles run and RK4 steps per corner.
    pub cycles: u32,
    pub steps: u32,
    pub launched: u32,
    /// The largest list after a cycle.
    pub peak_patches: u32,
    /// The longest edge of a patch kept after the tessellation analysis, in reference
    /// steps (its parent's longest edge over its split factor).
    pub worst_span: f32,
    /// Patches longer than a voxel kept whole at the level limit (summed over cycles).
    pub unsplit: u32,
    /// Foci crossed (a patch's orientation turned), summed over patches and cycles.
    pub foci: u32,
    /// Receiver deposits too wide to cover exactly, put under their centre.
    pub coarse_deposits: u32,
    /// Flux, per channel, in the light's colour × reference step²: launched, retired
    /// below the threshold, leaving the box, carried through foci (kept or discarded
    /// per [`FocusPolicy`]), and still travelling when the cycles ran out.
    pub launched_flux: [f64; 3],
    pub absorbed: [f64; 3],
    pub left: [f64; 3],
    pub at_foci: [f64; 3],
    /// Flux retired with torn patches, and with patches split below `min_dilution`.
    pub torn: [f64; 3],
    pub diluted: [f64; 3],
    pub live_at_end: u32,
    /// Patch-cycles advanced (one patch through one cycle), all cycles.
    pub patch_cycles: u32,
    /// Of them, those whose four corners crossed clear space in straight lines
    /// ([`WavefrontSettings::clear_space`]).
    pub straight_cycles: u32,
    /// The list's size after each submission: (cycles done, patches).
    pub list_sizes: Vec<(u32, u32)>,
    /// GPU time of the whole simulation, milliseconds.
    pub gpu_ms: f64,
    /// Which of a frame's lights this wavefront was (0-based), and with dispersion which
    /// colour channel (red, green, blue) it carried; set by the light volume.
    pub light: usize,
    pub channel: Option<usize>,
}

impl SimulationStats {
    /// "light 1", or with dispersion "light 1, red (656 nm)".
    pub fn label(&self) -> String {
        match self.channel {
            None => format!("light {}", self.light + 1),
            Some(c) => format!(
                "light {}, {} ({:.0} nm)",
                self.light + 1,
                ["red", "green", "blue"][c.min(2)],
                crate::render::eikonal::dispersion::WAVELENGTHS_NM[c.min(2)]
            ),
        }
    }

    /// One line for users: how long the simulation ran, how large the list grew, and
    /// where the launched flux went (per cent, mean over the channels; the rest was
    /// absorbed on the way or still travelling).
    pub fn summary(&self) -> String {
        let share = |f: [f64; 3]| {
            let parts: Vec<f64> = f
                .iter()
                .zip(&self.launched_flux)
                .enumerate()
                .filter(|(c, (_, &l))| l > 0.0 && !matches!(self.channel, Some(only) if only != *c))
                .map(|(_, p)| p)
                .map(|(x, l)| x / l)
                .collect();
            100.0 * parts.iter().sum::<f64>() / parts.len().max(1) as f64
        };
        // A light of colour 0 launches patches that carry nothing (its shares would be
        // 0 / 0).
        let fates = if self.launched_flux.iter().any(|&l| l > 0.0) {
            format!(
                "of the light launched: {:.1} % left the box, {:.2} % retired torn, {:.2} % \
                 retired diluted (the rest absorbed, or still travelling)",
                share(self.left),
                share(self.torn),
                share(self.diluted),
            )
        } else {
            "no light launched (its colour is 0)".to_string()
        };
        format!(
            "{} cycles, {} patches launched, list peak {}, worst kept patch {:.2} voxels; \
             {fates}; {} patches still travelling at the end; {} patch-cycles, {:.1} % of \
             them straight in clear space; {:.0} ms",
            self.cycles,
            self.launched,
            self.peak_patches,
            self.worst_span,
            self.live_at_end,
            self.patch_cycles,
            100.0 * self.straight_cycles as f64 / self.patch_cycles.max(1) as f64,
            self.gpu_ms
        )
    }
}

/// The light volumes: per voxel (x fastest), the fluence (rgb, the light's irradiance
/// units) and the luminance-weighted mean direction of the light crossing it (not unit:
/// its length is 1 where one wavefront crosses, less where several do).
#[derive(Clone, Debug)]
pub struct FluenceVolume {
    pub dims: [u32; 3],
    pub fluence: Vec<[f32; 3]>,
    pub direction: Vec<[f32; 3]>,
}

/// A simulation's results.
#[derive(Clone, Debug)]
pub struct LightSimulation {
    /// Per receiver, per pixel (row-major), the irradiance (rgb) in the light's units.
    pub receivers: Vec<Vec<[f32; 3]>>,
    pub fluence: Option<FluenceVolume>,
    pub stats: SimulationStats,
}

/// The shaders' push constants (`Push` in glsl/light_wavefront.glsl).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct WavefrontPush {
    half_extent: [f32; 4],
    dims: [f32; 4],
    colour: [f32; 4],
    dt: f32,
    substeps: u32,
    capacity: u32,
    parity: u32,
    receiver_count: u32,
    max_level: u32,
    discard_at_foci: u32,
    tear_span: f32,
    min_dilution: f32,
}

/// A launched patch, as the shaders read it (`Patch`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuPatch {
    x: [[f32; 4]; 4],
    v: [[f32; 4]; 4],
    flux: [f32; 4],
}

/// A 32.32 fixed-point sum in two words (low, high), as glsl/light_splat_fixed.glsl adds.
fn fixed(lo: u32, hi: u32) -> f64 {
    ((hi as u64) << 32 | lo as u64) as i64 as f64 / 4_294_967_296.0
}

fn fixed_rgb(words: &[u32], at: usize) -> [f64; 3] {
    std::array::from_fn(|c| fixed(words[at + 2 * c], words[at + 2 * c + 1]))
}

impl WavefrontSettings {
    fn validate(&self) -> Result<()> {
        ensure!(
            self.step.is_finite() && self.step > 0.0 && self.step <= 4.0,
            "wavefront step {} must be above 0 and at most 4 reference steps",
            self.step
        );
        ensure!(
            (1..=64).contains(&self.substeps),
            "wavefront substeps {} must be 1 to 64",
            self.substeps
        );
        ensure!(
            self.launch_spacing.is_finite()
                && self.launch_spacing >= 0.05
                && self.launch_spacing <= 1.0,
            "launch spacing {} must be 0.05 to 1 reference steps",
            self.launch_spacing
        );
        ensure!(
            self.threshold.is_finite() && (0.0..1.0).contains(&self.threshold),
            "energy threshold {} must be at least 0 and below 1",
            self.threshold
        );
        ensure!(
            self.max_level <= 16,
            "max_level {} must be at most 16",
            self.max_level
        );
        if let Some(m) = self.max_patches {
            ensure!(m >= GROUP, "the patch budget {m} must be at least {GROUP}");
        }
        ensure!(
            self.tear_span.is_finite() && self.tear_span >= 2.0,
            "tear span {} must be at least 2 reference steps",
            self.tear_span
        );
        ensure!(
            (0.0..1.0).contains(&self.min_dilution),
            "min_dilution {} must be at least 0 and below 1",
            self.min_dilution
        );
        if let Some(a) = self.aperture {
            ensure!(
                a.is_finite() && a > 0.0,
                "aperture {a} must be a positive radius"
            );
        }
        Ok(())
    }
}

/// What a simulation reads: the volume, its transfer functions and their samplers (the
/// renderer's, lent by [`Renderer::simulate_light`] or by a model's state).
pub(crate) struct FieldInputs<'a> {
    pub ctx: &'a vk::Context,
    pub info: VolumeInfo,
    pub volume: &'a vk::Image,
    pub volume_sampler: &'a vk::Sampler,
    pub tf: &'a vk::Image,
    pub linear: &'a vk::Sampler,
}

impl Renderer {
    /// Simulate `light` through the volume (the transfer functions' η with `opts`'
    /// refractive-index scale; no clipping plane): count its flux on `receivers`, and
    /// fill the fluence volume when `settings.fluence`. `progress` hears (cycles done,
    /// cycles at most, patches live) after each submission.
    pub fn simulate_light(
        &self,
        opts: &RenderOptions,
        light: &Light,
        settings: &WavefrontSettings,
        receivers: &[Receiver],
        progress: Option<&dyn Fn(u32, u32, u32)>,
    ) -> Result<LightSimulation> {
        let field = FieldInputs {
            ctx: &self.ctx,
            info: self.volume_info,
            volume: &self.volume_tex,
            volume_sampler: &self.volume_sampler,
            tf: &self.tf_image,
            linear: &self.linear,
        };
        simulate(&field, opts, light, settings, receivers, progress)
    }
}

/// [`Renderer::simulate_light`] over `inputs`.
pub(crate) fn simulate(
    inputs: &FieldInputs,
    opts: &RenderOptions,
    light: &Light,
    settings: &WavefrontSettings,
    receivers: &[Receiver],
    progress: Option<&dyn Fn(u32, u32, u32)>,
) -> Result<LightSimulation> {
    settings.validate()?;
    ensure!(
        opts.sweep.clip.is_none(),
        "the light simulator takes no clipping plane"
    );
    ensure!(
        light.colour.iter().all(|c| c.is_finite() && *c >= 0.0),
        "light colour {:?} must be finite and non-negative",
        light.colour
    );
    let ctx = inputs.ctx;
    let info = &inputs.info;
    let half = info.half_extent;
    let reference = info.ref_step;
    let limit = ctx.info().limits.max_storage_buffer_range as u64;
    let wave = launch(light, settings, half, reference)?;
    // Each half of the list is a buffer of its own: it may take the whole binding range.
    let capacity = settings
        .max_patches
        .unwrap_or(((limit / PATCH_BYTES).min(1 << 20) as u32 / GROUP) * GROUP);
    let list_bytes = capacity as u64 * PATCH_BYTES;
    ensure!(
        list_bytes <= limit,
        "a patch list of {capacity} patches ({PATCH_BYTES} bytes each: {list_bytes} bytes a \
             half) is more than device '{}' binds at once ({limit} bytes); lower the patch \
             budget to at most {}",
        ctx.info().name,
        limit / PATCH_BYTES
    );
    let patches = wave.patches;
    let launched = patches.len() as u64;
    ensure!(
        launched <= capacity as u64,
        "{} needs {launched} patches ({} reference steps apart) at launch and the \
             patch budget is {capacity}; raise the budget or the launch spacing",
        light.describe(),
        settings.launch_spacing
    );
    let launched_flux: [f64; 3] =
        std::array::from_fn(|c| patches.iter().map(|p| p.flux[c] as f64).sum::<f64>());

    // Buffers.
    let storage = vk::usage::STORAGE_BUFFER;
    let list_half = |name: &str| {
        Buffer::new(
            ctx,
            list_bytes,
            storage | vk::usage::BUFFER_TRANSFER_DST,
            Memory::Gpu,
            name,
        )
    };
    let list = [
        list_half("wavefront patches (even cycles)")?,
        list_half("wavefront patches (odd cycles)")?,
    ];
    let counts = Buffer::new(
        ctx,
        capacity as u64 * 4,
        storage,
        Memory::Gpu,
        "wavefront counts",
    )?;
    let block_sums = Buffer::new(
        ctx,
        capacity.div_ceil(GROUP) as u64 * 4,
        storage,
        Memory::Gpu,
        "wavefront block sums",
    )?;
    let control = Buffer::new(
        ctx,
        CTRL_WORDS as u64 * 4,
        storage
            | vk::usage::INDIRECT_BUFFER
            | vk::usage::BUFFER_TRANSFER_DST
            | vk::usage::BUFFER_TRANSFER_SRC,
        Memory::Gpu,
        "wavefront control",
    )?;
    let control_host = Buffer::readback(ctx, CTRL_WORDS as u64 * 4, "wavefront control")?;
    let mut initial = vec![0u32; CTRL_WORDS];
    initial[CTRL_COUNT] = launched as u32;
    initial[CTRL_DISPATCH] = (launched as u32).div_ceil(GROUP);
    initial[CTRL_DISPATCH + 1] = 1;
    initial[CTRL_DISPATCH + 2] = 1;
    initial[CTRL_PEAK] = launched as u32;
    let mut staging = Buffer::new(
        ctx,
        (CTRL_WORDS * 4 + patches.len() * PATCH_BYTES as usize) as u64,
        vk::usage::BUFFER_TRANSFER_SRC,
        Memory::Upload,
        "wavefront launch",
    )?;
    staging.write(0, bytemuck::cast_slice(&initial))?;
    staging.write(CTRL_WORDS * 4, bytemuck::cast_slice(&patches))?;

    let mut geometry: Vec<[f32; 4]> = Vec::new();
    let mut pixels_total = 0u64;
    ensure!(
        receivers.len() <= MAX_RECEIVERS,
        "{} receivers: at most {MAX_RECEIVERS}",
        receivers.len()
    );
    for (k, r) in receivers.iter().enumerate() {
        ensure!(
            r.width > 0 && r.height > 0 && r.width <= 8192 && r.height <= 8192,
            "receiver {k}: {} x {} pixels (1 to 8192 each)",
            r.width,
            r.height
        );
        ensure!(
            r.origin.is_finite()
                && r.u.is_finite()
                && r.v.is_finite()
                && r.u.cross(r.v).length() > 0.0
                && r.u.dot(r.v).abs() <= 1e-4 * r.u.length() * r.v.length(),
            "receiver {k}: u {:?} and v {:?} must be finite, non-zero and at right angles",
            r.u,
            r.v
        );
        let n = r.normal();
        geometry.push(r.origin.extend(r.width as f32).into());
        geometry.push(r.u.extend(r.height as f32).into());
        geometry.push(r.v.extend(3.0 * pixels_total as f32).into());
        geometry.push(n.extend(n.dot(r.origin)).into());
        pixels_total += r.width as u64 * r.height as u64;
    }
    ensure!(
        3 * pixels_total < 1 << 24,
        "receivers of {pixels_total} pixels in all: at most 5 592 405"
    );
    geometry.resize(geometry.len().max(4), [0.0; 4]);
    let mut receiver_geometry = Buffer::new(
        ctx,
        (geometry.len() * 16) as u64,
        storage,
        Memory::Upload,
        "wavefront receivers",
    )?;
    receiver_geometry.write(0, bytemuck::cast_slice(&geometry))?;
    // A buffer of 32.32 fixed-point sums, refused (naming `what`) beyond what the device
    // binds at once.
    let sums = |bytes: u64, what: String, name: &str| -> Result<Buffer> {
        ensure!(
            bytes <= limit,
            "{what} would take {bytes} bytes of sums, more than device '{}' binds at once \
             ({limit} bytes)",
            ctx.info().name
        );
        Buffer::new(
            ctx,
            bytes,
            storage | vk::usage::BUFFER_TRANSFER_DST | vk::usage::BUFFER_TRANSFER_SRC,
            Memory::Gpu,
            name,
        )
    };
    let receiver_bytes = (pixels_total.max(1) * 3 * 8).max(16);
    let receiver_sums = sums(
        receiver_bytes,
        format!("receivers of {pixels_total} pixels"),
        "wavefront receiver sums",
    )?;
    let voxels = info.dims.iter().map(|d| *d as u64).product::<u64>();
    let fluence_bytes = if settings.fluence { voxels * 6 * 8 } else { 16 };
    let fluence_sums = sums(
        fluence_bytes,
        format!(
            "the fluence volume of {} x {} x {} voxels",
            info.dims[0], info.dims[1], info.dims[2]
        ),
        "wavefront fluence sums",
    )?;

    // The paper's stored η and ∇η volumes (sect. 5.1): the sweep's field texture,
    // built here for this simulation.
    let mut field = super::field::FieldTexture::new(ctx, inputs.volume, inputs.tf, inputs.linear)?;
    // Clear space (light_wavefront_clear.comp): each cell's η where one η holds within
    // CLEAR_REACH cells of it, built in the first submission; and its scratch image.
    // Without the fast path (compiled out) the set still binds them: one texel each.
    let cells = if settings.clear_space {
        info.dims
    } else {
        [1; 3]
    };
    let cell_image = |name: &str| {
        vk::Image::new(
            ctx,
            vk::ImageDesc::computed(vk::ImageKind::D3, vk::Format::R32_SFLOAT, cells, 1),
            name,
        )
    };
    let clear_cells = cell_image("wavefront clear cells")?;
    let clear_scratch = cell_image("wavefront clear scratch")?;
    // One set per parity: binding 2 the half the cycle reads, 12 the half it writes.
    let set_for = |parity: usize| {
        DescriptorSet::new(
            ctx,
            &[
                Binding::Texture(inputs.volume, inputs.volume_sampler),
                Binding::Texture(inputs.tf, inputs.linear),
                Binding::Storage(&list[parity]),
                Binding::Storage(&counts),
                Binding::Storage(&block_sums),
                Binding::Storage(&control),
                Binding::Storage(&receiver_sums),
                Binding::Storage(&receiver_geometry),
                Binding::Storage(&fluence_sums),
                Binding::Texture(field.image(), inputs.linear),
                Binding::StorageImage(&clear_cells),
                Binding::StorageImage(&clear_scratch),
                Binding::Storage(&list[1 - parity]),
            ],
            &format!("light simulator ({})", ["even", "odd"][parity]),
        )
    };
    let sets = [set_for(0)?, set_for(1)?];
    let set = &sets[0];
    let push_size = std::mem::size_of::<WavefrontPush>() as u32;
    // Specialization constants 0 to 4: the field texture, clear space, the clear-space
    // pass (light_wavefront_clear.comp only), the fluence deposits, cubic η.
    let constants = [
        (settings.gradient == RayGradient::FieldTexture) as u32,
        settings.clear_space as u32,
        0,
        settings.fluence as u32,
        (settings.gradient == RayGradient::Cubic) as u32,
    ];
    let pipeline = |spirv: &[u8], name: &str| {
        ComputePipeline::with_constants(ctx, spirv, set, push_size, &constants, name)
    };
    let step = pipeline(shaders::LIGHT_WAVEFRONT_STEP_COMP, "wavefront step")?;
    let scan_blocks = pipeline(
        shaders::LIGHT_WAVEFRONT_SCAN_BLOCKS_COMP,
        "wavefront scan blocks",
    )?;
    let scan_sums = pipeline(
        shaders::LIGHT_WAVEFRONT_SCAN_SUMS_COMP,
        "wavefront scan sums",
    )?;
    let emit = pipeline(shaders::LIGHT_WAVEFRONT_EMIT_COMP, "wavefront emit")?;
    // Its four passes (CLEAR_PASS, specialization constant 2).
    let clear_passes = (0..4u32)
        .map(|pass| {
            let constants = [constants[0], constants[1], pass, constants[3], constants[4]];
            ComputePipeline::with_constants(
                ctx,
                shaders::LIGHT_WAVEFRONT_CLEAR_COMP,
                set,
                push_size,
                &constants,
                &format!("wavefront clear space (pass {pass})"),
            )
        })
        .collect::<Result<Vec<_>>>()?;

    let mut push = WavefrontPush {
        half_extent: half.extend(reference).into(),
        dims: info.dims_and(opts.sweep.eta_scale),
        colour: [
            light.colour[0],
            light.colour[1],
            light.colour[2],
            settings.threshold,
        ],
        dt: settings.step * reference,
        substeps: settings.substeps,
        capacity,
        parity: 0,
        receiver_count: receivers.len() as u32,
        max_level: settings.max_level,
        discard_at_foci: (settings.at_foci == FocusPolicy::Discard) as u32,
        tear_span: settings.tear_span,
        min_dilution: settings.min_dilution,
    };
    // Enough cycles for a straight path from the launch through the box at η 3.
    let cycle_path = settings.step * reference * settings.substeps as f32;
    let max_cycles = settings
        .max_cycles
        .unwrap_or_else(|| (3.0 * wave.path / cycle_path).ceil() as u32 + 1);
    let mut stats = SimulationStats {
        launched: launched as u32,
        launched_flux,
        ..Default::default()
    };
    let mut cycle = 0u32;
    let mut words = initial.clone();
    while cycle < max_cycles {
        let first = cycle == 0;
        let n = CYCLES_PER_SUBMIT.min(max_cycles - cycle);
        let timings = ctx.execute(|rec| {
            rec.pass("light simulation", &[], |rec| {
                if first {
                    field.record_build(rec)?;
                    rec.clear_storage(&receiver_sums);
                    rec.clear_storage(&fluence_sums);
                    if settings.clear_space {
                        let groups = info.dims.map(|d| d.div_ceil(4));
                        for pass in &clear_passes {
                            rec.dispatch(pass, set, bytemuck::bytes_of(&push), groups)?;
                        }
                    }
                    rec.upload_to_storage(&staging, 0, &control, 0, CTRL_WORDS as u64 * 4)?;
                    rec.upload_to_storage(
                        &staging,
                        CTRL_WORDS as u64 * 4,
                        &list[0],
                        0,
                        patches.len() as u64 * PATCH_BYTES,
                    )?;
                }
                for c in 0..n {
                    push.parity = (cycle + c) % 2;
                    let bytes = bytemuck::bytes_of(&push);
                    let args = (CTRL_DISPATCH as u64 + 4 * push.parity as u64) * 4;
                    let set = &sets[push.parity as usize];
                    rec.dispatch_indirect(&step, set, bytes, &control, args)?;
                    rec.dispatch_indirect(&scan_blocks, set, bytes, &control, args)?;
                    rec.dispatch(&scan_sums, set, bytes, [1, 1, 1])?;
                    rec.dispatch_indirect(&emit, set, bytes, &control, args)?;
                }
                Ok(())
            })?;
            rec.copy_storage_to_host(&control, &control_host);
            Ok(())
        })?;
        stats.gpu_ms += timings.get("light simulation").unwrap_or(0.0);
        cycle += n;
        words = control_host.read_values(CTRL_WORDS)?;
        stats
            .list_sizes
            .push((cycle, words[CTRL_COUNT + (cycle % 2) as usize]));
        if let Some(p) = progress {
            p(cycle, max_cycles, words[CTRL_COUNT + (cycle % 2) as usize]);
        }
        if words[CTRL_NEEDED] > 0 {
            // The default budget is what the device binds: only a smaller volume helps.
            let remedy = match settings.max_patches {
                Some(_) => "raise the patch budget, coarsen the volume, or raise the energy \
                            threshold"
                    .to_string(),
                None => format!(
                    "that is the most device '{}' binds as one storage buffer \
                     (maxStorageBufferRange); use a smaller volume (--volume-size, --scale)",
                    ctx.info().name
                ),
            };
            bail!(
                "the light simulation needed {} patches at once, more than its budget of \
                 {capacity} ({list_bytes} bytes each half of the patch list, after {cycle} cycles); \
                 {remedy}",
                words[CTRL_NEEDED],
            );
        }
        if words[CTRL_COUNT + (cycle % 2) as usize] == 0 {
            break;
        }
    }
    stats.cycles = cycle;
    stats.steps = cycle * settings.substeps;
    stats.peak_patches = words[CTRL_PEAK];
    stats.worst_span = f32::from_bits(words[CTRL_WORST_SPAN]);
    stats.unsplit = words[CTRL_UNSPLIT];
    stats.foci = words[CTRL_FOCI];
    stats.coarse_deposits = words[CTRL_COARSE];
    stats.absorbed = fixed_rgb(&words, CTRL_ABSORBED);
    stats.left = fixed_rgb(&words, CTRL_LEFT);
    stats.at_foci = fixed_rgb(&words, CTRL_AT_FOCI);
    stats.torn = fixed_rgb(&words, CTRL_TORN);
    stats.diluted = fixed_rgb(&words, CTRL_DILUTED);
    stats.live_at_end = words[CTRL_COUNT + (cycle % 2) as usize];
    stats.patch_cycles = words[CTRL_PATCH_CYCLES];
    stats.straight_cycles = words[CTRL_STRAIGHT];
    let dropped = fixed_rgb(&words, CTRL_DROPPED);
    ensure!(
        dropped.iter().all(|d| *d == 0.0),
        "the light simulation dropped flux {dropped:?} to the patch budget"
    );

    // Read the deposits back.
    let receivers_out = if receivers.is_empty() {
        Vec::new()
    } else {
        let sums = read_words(ctx, &receiver_sums, receiver_bytes)?;
        let mut out = Vec::with_capacity(receivers.len());
        let mut base = 0usize;
        for r in receivers {
            let n = (r.width * r.height) as usize;
            out.push(
                (0..n)
                    .map(|px| {
                        std::array::from_fn(|c| {
                            let at = 2 * (base + c * n + px);
                            fixed(sums[at], sums[at + 1]) as f32
                        })
                    })
                    .collect(),
            );
            base += 3 * n;
        }
        out
    };
    let fluence = if settings.fluence {
        let sums = read_words(ctx, &fluence_sums, fluence_bytes)?;
        let n = voxels as usize;
        let channel = |q: usize, i: usize| {
            let at = 2 * (q * n + i);
            fixed(sums[at], sums[at + 1]) as f32
        };
        Some(FluenceVolume {
            dims: info.dims,
            fluence: (0..n)
                .map(|i| std::array::from_fn(|c| channel(c, i)))
                .collect(),
            direction: (0..n)
                .map(|i| {
                    let e = [channel(0, i), channel(1, i), channel(2, i)];
                    let lum = 0.2126 * e[0] + 0.7152 * e[1] + 0.0722 * e[2];
                    std::array::from_fn(|c| {
                        if lum > 0.0 {
                            channel(3 + c, i) / lum
                        } else {
                            0.0
                        }
                    })
                })
                .collect(),
        })
    } else {
        None
    };
    Ok(LightSimulation {
        receivers: receivers_out,
        fluence,
        stats,
    })
}

/// The launched wavefront: its patches, and the straight path (world units) from the
/// launch surface through the far side of the box.
struct Launch {
    patches: Vec<GpuPatch>,
    path: f32,
}

impl GpuPatch {
    /// A patch at launch: corners (counter-clockwise seen along the light), their unit
    /// directions, and its flux (the light's colour × `share`, reference-step² units).
    fn launched(corners: [Vec3; 4], directions: [Vec3; 4], share: f32, colour: [f32; 3]) -> Self {
        // v's length is set to the local η by the first step (x[3].w < 0).
        let ws = [share, 0.0, 1.0, -1.0];
        let vs = [0.0, 0.0, share, 0.0];
        GpuPatch {
            x: std::array::from_fn(|k| corners[k].extend(ws[k]).into()),
            v: std::array::from_fn(|k| directions[k].extend(vs[k]).into()),
            flux: [colour[0] * share, colour[1] * share, colour[2] * share, 0.0],
        }
    }
}

/// The wavefront `light` launches over the box (half extent `half`, reference step
/// `reference`).
fn launch(
    light: &Light,
    settings: &WavefrontSettings,
    half: Vec3,
    reference: f32,
) -> Result<Launch> {
    let bound = half.length() + 2.0 * reference;
    let side = settings.launch_spacing * reference;
    let mut patches = Vec::new();
    let path = match light.source {
        LightSource::Directional { .. } => {
            // A plane wave: square patches on a plane normal to the light, one bounding
            // radius before the box's centre, covering the box's shadow on it. Corners
            // counter-clockwise seen along the light: e1 × e2 = travel.
            let travel = light.travel();
            let helper = if travel.x.abs() < 0.9 {
                Vec3::X
            } else {
                Vec3::Y
            };
            let e1 = travel.cross(helper).normalize();
            let e2 = travel.cross(e1);
            let centre = -travel * bound;
            let (mut lo, mut hi) = (glam::Vec2::splat(f32::INFINITY), glam::Vec2::NEG_INFINITY);
            for c in box_corners(half) {
                let p = glam::Vec2::new(c.dot(e1), c.dot(e2));
                lo = lo.min(p);
                hi = hi.max(p);
            }
            lo -= glam::Vec2::splat(side);
            hi += glam::Vec2::splat(side);
            let cols = ((hi.x - lo.x) / side).ceil() as u64;
            let rows = ((hi.y - lo.y) / side).ceil() as u64;
            ensure!(
                cols * rows <= 1 << 28,
                "the plane wave would be {cols} x {rows} patches: use a larger launch spacing"
            );
            // A square patch side s square to the light carries colour × (s / reference)².
            let share = settings.launch_spacing * settings.launch_spacing;
            for j in 0..rows {
                for i in 0..cols {
                    let o = centre + e1 * (lo.x + i as f32 * side) + e2 * (lo.y + j as f32 * side);
                    if let Some(a) = settings.aperture {
                        let mid = o + (e1 + e2) * (0.5 * side);
                        if (mid - travel * mid.dot(travel)).length() > a {
                            continue;
                        }
                    }
                    let corners = [o, o + e1 * side, o + (e1 + e2) * side, o + e2 * side];
                    patches.push(GpuPatch::launched(
                        corners,
                        [travel; 4],
                        share,
                        light.colour,
                    ));
                }
            }
            2.0 * bound
        }
        LightSource::Point { position } => {
            ensure!(
                settings.aperture.is_none(),
                "an aperture shapes a directional light's beam; {} has none",
                light.describe()
            );
            ensure!(
                position.is_finite(),
                "{}: not a finite position",
                light.describe()
            );
            // A spherical wave: patches on a sphere about the light, just outside the
            // box's bounding sphere when the light is outside it (only those whose rays
            // meet that sphere), else one reference step about the light; a cube map of
            // gnomonic grids, each patch at most `side` across. The irradiance at
            // distance r is colour / r² (the light's colour is its irradiance at unit
            // distance), so a patch of area A carries colour A / r².
            let distance = position.length();
            let r0 = if distance - bound > 2.0 * reference {
                distance - bound
            } else {
                reference
            };
            // At least 32 cells a face (0.05 rad): a split places new corners on the
            // chords between old ones, inside the sphere by the patch's sagitta, which a
            // coarse launch makes large (2 x 2 cells a face put 18 % errors on a plane
            // half a box from the light; measured).
            let cells = (2.0 * r0 / side).ceil().max(32.0) as u32;
            ensure!(
                6 * cells as u64 * cells as u64 <= 1 << 28,
                "the spherical wave would be 6 x {cells}² patches: use a larger launch spacing"
            );
            let faces = [
                (Vec3::X, Vec3::Y, Vec3::Z),
                (-Vec3::X, Vec3::Z, Vec3::Y),
                (Vec3::Y, Vec3::Z, Vec3::X),
                (-Vec3::Y, Vec3::X, Vec3::Z),
                (Vec3::Z, Vec3::X, Vec3::Y),
                (-Vec3::Z, Vec3::Y, Vec3::X),
            ];
            let outside = r0 > reference;
            for (n, u, v) in faces {
                let dir = |i: u32, j: u32| {
                    let s = -1.0 + 2.0 * i as f32 / cells as f32;
                    let t = -1.0 + 2.0 * j as f32 / cells as f32;
                    (n + u * s + v * t).normalize()
                };
                for j in 0..cells {
                    for i in 0..cells {
                        let d = [dir(i, j), dir(i + 1, j), dir(i + 1, j + 1), dir(i, j + 1)];
                        let mid = (d[0] + d[1] + d[2] + d[3]).normalize();
                        // A ray from the light along `mid` misses the bounding sphere.
                        let along = -position.dot(mid);
                        if outside && (along <= 0.0 || (position + mid * along).length() > bound) {
                            continue;
                        }
                        let corners = d.map(|k| position + k * r0);
                        // Flux = intensity × solid angle: the quad's two spherical
                        // triangles (the flat quad's area / r0² fell 0.3 % short, measured).
                        let omega = solid_angle(d[0], d[1], d[2]) + solid_angle(d[0], d[2], d[3]);
                        let share = omega / (reference * reference);
                        patches.push(GpuPatch::launched(corners, d, share, light.colour));
                    }
                }
            }
            distance + bound - r0
        }
    };
    ensure!(
        !patches.is_empty(),
        "{} with aperture {:?} launches no light into the box",
        light.describe(),
        settings.aperture
    );
    Ok(Launch { patches, path })
}

/// The solid angle of the spherical triangle of unit vectors a, b, c (Van Oosterom and
/// Strackee, 1983).
fn solid_angle(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
    let numerator = a.dot(b.cross(c)).abs();
    let denominator = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
    (2.0 * numerator.atan2(denominator)) as f32
}

/// The eight corners of the box of half extent `half` centred at the origin.
fn box_corners(half: Vec3) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { -half.x } else { half.x },
            if i & 2 == 0 { -half.y } else { half.y },
            if i & 4 == 0 { -half.z } else { half.z },
        )
    })
}

/// The words of a storage buffer the GPU wrote (`bytes` of it).
fn read_words(ctx: &vk::Context, buffer: &Buffer, bytes: u64) -> Result<Vec<u32>> {
    let host = Buffer::readback(ctx, bytes, "wavefront readback")?;
    ctx.execute(|rec| {
        rec.copy_storage_to_host(buffer, &host);
        Ok(())
    })?;
    host.read_values((bytes / 4) as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The summary's shares are of the light launched: half of it left the box; a light of
    /// colour 0 launched none, which the line says instead of shares of nothing (Rust's
    /// empty float sum is -0.0: "-0.0 %" was printed).
    #[test]
    fn the_summary_says_where_the_launched_light_went() {
        let lit = SimulationStats {
            launched_flux: [2.0, 2.0, 2.0],
            left: [1.0, 1.0, 1.0],
            ..Default::default()
        };
        let line = lit.summary();
        assert!(line.contains("50.0 % left the box"), "{line}");
        let dark = SimulationStats::default().summary();
        assert!(dark.contains("no light launched"), "{dark}");
        assert!(
            !dark.contains("-0.0") && !dark.contains("left the box"),
            "{dark}"
        );
    }

    #[test]
    fn push_matches_the_shaders_block() {
        crate::assert_host_block!(
            shaders::LIGHT_WAVEFRONT_STEP_COMP,
            "Push",
            WavefrontPush {
                half_extent,
                dims,
                colour,
                dt,
                substeps,
                capacity,
                parity,
                receiver_count,
                max_level,
                discard_at_foci,
                tear_span,
                min_dilution
            },
            exact_size = false
        );
    }

    #[test]
    fn fixed_point_words_decode_signed_sums() {
        // 1.5 is (2^31, 1); -1.5 is its two's complement over 64 bits.
        assert_eq!(fixed(1 << 31, 1), 1.5);
        let neg = (-(1.5f64 * 4_294_967_296.0) as i64) as u64;
        assert_eq!(fixed(neg as u32, (neg >> 32) as u32), -1.5);
    }
}
