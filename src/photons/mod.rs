//! Reference CPU photon tracer: the oracle for the plane sweep's light transport (caustics,
//! shadows, absorbed power). It solves the same model as the sweep with none of the
//! sweep's approximations (no semi-Lagrangian resampling, no per-plane gain bound, no
//! direction limit, no filter), so `light-colour@K` dumps can be compared with it pixel for
//! pixel.
//!
//! # Model (identical conventions to `glsl/sweep_common.glsl`)
//!
//! * World: the volume box is centred at the origin with half extent
//!   `normalised_extent() / 2`; texture coordinates `t = w / (2 half) + 0.5`, voxel `i`'s
//!   centre at `t = (i + 0.5) / N`, clamp-to-edge trilinear interpolation of the values the
//!   GPU texture holds (u8 / 255, u16 / 65535, f32 through `Volume::texel_bytes`), and
//!   `s = 0` outside `[0,1]³` (`value_at_tex`).
//! * Transfer functions are looked up post-interpolatively in the same 4096-sample tables
//!   the GPU filters (`TransferFunctions::texels`, linear between samples). η' = 1 + k(η − 1)
//!   with the sweep's `eta_scale` k. Extinction σ(s) = −ln(1 − α(s)) / ref_step and the
//!   medium's log-attenuation ln m(s) / ref_step per channel (α and m are per reference
//!   step = the smallest voxel side); α = 1 or m = 0 stop the light. The clipping plane
//!   zeroes σ where n·p > offset (n normalised, as the GPU does); the medium stays.
//! * Rays: d/ds(η dx/ds) = ∇η, integrated with classical RK4 in (x, v = η dx/ds) with
//!   dx/ds = v/|v| (equal to v/η on the exact solution, where |v| = η is invariant; it keeps
//!   s an exact arc length, which the attenuation integral needs). ∇η is the central
//!   difference of the exact field η(s(x)), [`GRADIENT_STEP`] voxels apart. The attenuation
//!   integral uses two-point Gauss–Legendre per step on the step's chord, and steps are cut
//!   at the box faces and the clipping plane, where the integrand jumps.
//! * Empty space is skipped exactly: the box plus a one-brick margin is divided into
//!   bricks of 4³ voxels; a brick where η is constant over the values its trilinear and
//!   gradient stencils can see is crossed in one straight segment (with the attenuation
//!   integrated along it when it absorbs); outside the bricks the field is uniform (s = 0),
//!   so rays go straight, with analytic attenuation.
//! * Light: directional, travelling along −`towards`. Photons start on the view-aligned
//!   plane one plane spacing in front of the box (where the sweep's light starts, plane
//!   −1) with v = η·d, on a regular grid of k × k photons per pixel of the target plane
//!   (k = round(√photons_per_pixel)) that covers the back-projections along the light of
//!   the target plane's view rectangle and of the box corners. The grid is aligned so that
//!   unobstructed photons land on the sub-pixel centres of the target plane (optionally
//!   jittered, stratified, with a seeded hash). Each photon carries colour × its launch cell
//!   area; photons are box-binned where they first cross the target plane moving forward,
//!   and the image is flux / pixel area on that plane, each photon's flux weighted by
//!   cos θ₀ / cos θ (θ its angle to the view axis where it lands, θ₀ the light's): the
//!   fluence, what the sweep's light planes hold, so unobstructed light reads exactly
//!   `light.colour`. With `plane_flux` the weight is 1: irradiance per unit *plane* area,
//!   whose sum over a plane is the power through it.
//!
//! # The tracer's own error
//!
//! Measured with the unit tests below and `measure_tracer_error` (ignored; release build,
//! `cargo test --release --lib photons::tests::measure -- --ignored --nocapture`), 2026-11-22:
//!
//! * Unobstructed light: exact up to f32 rounding (asserted < 1e-5 relative), jittered or
//!   not: the k × k launch cells of a pixel tile it, so every unobstructed photon lands in
//!   its own pixel (`empty_volume_gives_the_light_colour`, oblique light and camera).
//! * Absorption and media: Beer–Lambert through a 32-voxel slab, axial and oblique light,
//!   per channel within 9e-7 relative (`slab_follows_beer_lambert_per_channel`).
//! * Power: a glass ball (1.5 in water 1.33, 32³, 2-voxel ramp) conserves the flux over the
//!   viewport to 1.5e-9 and over its shadow disc to 8e-9
//!   (`glass_ball_conserves_power_and_focuses_paraxially`). In air, rays grazing the ramp
//!   orbit in it (η r has a maximum inside a thin ramp) and some leave backwards: counted
//!   as `backward`, they and the landed flux add up to the incident flux within 0.2 % (the
//!   rest are rim rays bent out of the viewport).
//! * Integration step: the focus of a ray through a 64³ ball lens (η 1.5, R = 19.2 voxels,
//!   2-voxel ramp) moves by 1e-4 relative between steps of 0.05, 0.1, 0.2 and 0.4 voxels
//!   (0.449701, 0.449700, 0.449658, 0.449686; paraxial n D / 4(n−1) = 0.45).
//! * Binning: box bins of one pixel. Where light is redistributed the image is a histogram
//!   of the photons landing per pixel, relative error ~ 1/√(landed) (the CLI prints the
//!   median over lit pixels). RMS difference of a 64² caustic image (64³ ball, oblique
//!   light, jittered) from a 1024-photons-per-pixel one, as % of the mean: 11.8 % (4 per
//!   pixel), 6.6 % (16), 2.3 % (64), 1.1 % (256, this one half reference noise).
//! * Thin η features: the glass-floor transfer function puts an η spike 1 → 1.5 → 1 into
//!   the floor's one-voxel surface ramp (η falls back over 0.1 voxel). RK4 through it is
//!   only first order (kinks of the piecewise-linear field): a photon of sphere-on-floor
//!   32³ leaves the floor with |v| − η = 4e-3 (direction 1.7 mrad off) at the default step,
//!   1.7e-4 at 0.05, 2.4e-5 at 0.0125 and 4e-7 at 0.001 voxel; step halving on |Δv| did no
//!   better per unit time than a smaller uniform `--step`, so for such TFs pass a smaller
//!   step. The flux it carries matched a straight-line quadrature to 1e-3.
//! * Crossing points of curved steps are interpolated linearly within one step.
//! * The field itself (shared with the GPU, not an error of the tracer): ∂s/∂y of trilinear
//!   interpolation is constant across each cell between voxel centres, so the cell on the
//!   axis of a voxelised lens is flat: a ray entering a 64³ ball 1 voxel off the axis
//!   focuses at 0.496, 2 voxels off at 0.431 (paraxial 0.45); 3 and 6 voxels, which meet
//!   the back surface at cell centres, give 0.4497 and 0.4475.
//!
//! Speed (release, 2 threads on the shared, loaded 2-core machine): 445k photons,
//! sphere-on-floor 64³ at 128², 16 per pixel, in 6.5–12.5 s (13 s of CPU); the 64² ×
//! 1024-per-pixel caustic above in 103 s.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::{bail, ensure, Result};
use glam::{DVec3, Vec3};

use crate::render::limits::MIN_FORWARD;
use crate::render::{Camera, Planes, RenderOptions};
use crate::transfer::{TransferFunctions, TF_SAMPLES};
use crate::volume::{Volume, Voxels};

/// Central-difference distance of ∇η, in voxels.
pub const GRADIENT_STEP: f64 = 0.05;
/// Photons whose flux falls below this fraction of their start are dropped (absorbed).
pub const FLUX_CUTOFF: f64 = 1e-6;
/// Brick side in voxels for empty-space skipping.
const BRICK: usize = 4;
const ETA_CONST: u8 = 1;
const TRANSPARENT: u8 = 2;

/// Options of the photon tracer.
#[derive(Clone, Debug)]
pub struct PhotonOptions {
    /// Photons per pixel of the target plane; the grid takes round(√n) per axis.
    pub photons_per_pixel: u32,
    /// RK4 step in voxels (smallest voxel sides).
    pub step: f32,
    /// Seed of the jitter.
    pub seed: u64,
    /// Jitter each photon within its launch cell (stratified) instead of the cell centre.
    pub jitter: bool,
    /// Worker threads; 0 = all available.
    pub threads: usize,
    /// Refuse, before tracing, a job whose estimated RK4 steps (photons × straight path
    /// length / step) exceed this; `None`: no limit (the library's default; the command
    /// line sets [`PhotonOptions::DEFAULT_MAX_STEPS`]).
    pub max_steps: Option<f64>,
    /// Tally the flux per unit plane area (what crosses the plane; the sweep's
    /// `SweepOptions::plane_flux`) instead of the fluence (false, the default, what the
    /// sweep's light planes hold): each photon's flux × cos θ₀ / cos θ, θ its angle to the
    /// view axis where it lands and θ₀ the light's, cos θ taken no smaller than 0.1 as
    /// the sweep takes it (glsl/light_splat_ray.glsl; the sweep drops rays beyond 84°).
    pub plane_flux: bool,
}

impl Default for PhotonOptions {
    fn default() -> Self {
        Self {
            photons_per_pixel: 64,
            step: 0.1,
            seed: 1,
            jitter: false,
            threads: 0,
            max_steps: None,
            plane_flux: false,
        }
    }
}

impl PhotonOptions {
    /// The command line's limit: 10¹² estimated RK4 steps, about 40 minutes on 2 cores.
    /// Measured: the default scene's plane 60 at 64×64, 16 photons per pixel, step 0.01
    /// (1.50·10⁹ estimated steps) took 7.4 CPU-seconds, 2·10⁸ per CPU-second (release
    /// build, 2 cores of the CI machine type; photons outside the volume cost less).
    pub const DEFAULT_MAX_STEPS: f64 = 1e12;

    pub fn validate(&self) -> Result<()> {
        ensure!(
            (1..=1 << 20).contains(&self.photons_per_pixel),
            "photons per pixel {} must be between 1 and {}",
            self.photons_per_pixel,
            1 << 20
        );
        ensure!(
            self.step.is_finite() && self.step > 0.0 && self.step <= 4.0,
            "photon step {} must be in (0, 4] voxels",
            self.step
        );
        Ok(())
    }

    /// Photons per axis of one pixel.
    pub fn per_axis(&self) -> u32 {
        ((self.photons_per_pixel as f64).sqrt().round() as u32).max(1)
    }
}

/// The irradiance on one view-aligned plane.
#[derive(Clone, Debug)]
pub struct PhotonImage {
    pub width: u32,
    pub height: u32,
    /// Row-major, top row first: rgb = fluence (or flux per unit plane area with
    /// `PhotonOptions::plane_flux`; unobstructed
    /// light = the light's colour), a = 0. The layout of `render --dump light-colour@K`.
    pub pixels: Vec<[f32; 4]>,
    /// Photons that landed in each pixel.
    pub counts: Vec<u32>,
    /// View depth of the plane.
    pub depth: f32,
    /// Photons per pixel actually used (k², k = round(√requested)).
    pub photons_per_pixel: u32,
    /// Photons launched.
    pub photons: u64,
    /// Photons that crossed the plane inside the viewport.
    pub landed: u64,
    /// Photons that crossed the plane outside the viewport.
    pub outside: u64,
    /// Photons whose flux fell below [`FLUX_CUTOFF`] of their start.
    pub absorbed: u64,
    /// Photons that turned back (total internal reflection) and never reached the plane.
    pub backward: u64,
    /// Photons whose direction turned more than the sweep allows from the view direction
    /// at some point (forward component below MIN_FORWARD); the sweep cannot follow them.
    pub steep: u64,
    /// Photons stopped by the iteration limit (should be 0).
    pub lost: u64,
    /// Wall-clock seconds of the trace.
    pub seconds: f64,
    pub threads: usize,
}

impl PhotonImage {
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Relative standard error of an unobstructed pixel, 1/√(photons per pixel) (the
    /// Poisson bound; the aligned grid without jitter is exact there).
    pub fn unobstructed_error(&self) -> f64 {
        1.0 / (self.photons_per_pixel as f64).sqrt()
    }

    /// Median over pixels that received photons of 1/√(photons landed in the pixel).
    pub fn median_lit_error(&self) -> f64 {
        let mut c: Vec<u32> = self.counts.iter().copied().filter(|&c| c > 0).collect();
        if c.is_empty() {
            return f64::NAN;
        }
        c.sort_unstable();
        1.0 / (c[c.len() / 2] as f64).sqrt()
    }

    /// A few lines for the command line.
    pub fn summary(&self) -> String {
        let max = self.counts.iter().copied().max().unwrap_or(0);
        format!(
            "photons: {} traced ({} per pixel, {} threads) in {:.2} s; {} landed in the \
             viewport, {} outside it, {} absorbed, {} turned back, {} lost\n\
             steep: {} photons turned more than {:.1}° from the view direction (the sweep \
             limits directions there)\n\
             statistical error: 1/sqrt(N) = {:.2} % per pixel{}; median over lit \
             pixels {:.2} % (most photons in one pixel: {max})",
            self.photons,
            self.photons_per_pixel,
            self.threads,
            self.seconds,
            self.landed,
            self.outside,
            self.absorbed,
            self.backward,
            self.lost,
            self.steep,
            (MIN_FORWARD as f64).acos().to_degrees(),
            100.0 * self.unobstructed_error(),
            " (unobstructed light is exact: the launch cells tile the pixels)",
            100.0 * self.median_lit_error(),
        )
    }
}

/// Where a ray traced by [`Field::trace_ray`] met the target plane.
#[derive(Clone, Copy, Debug)]
pub struct RayEnd {
    /// World position on the plane.
    pub position: Vec3,
    /// World direction there (unit).
    pub direction: Vec3,
    /// |v| there (η of the medium the ray is in, up to integration error).
    pub eta: f32,
    /// Fraction of the light surviving the path, per channel.
    pub transmittance: [f32; 3],
    /// Arc length travelled.
    pub length: f32,
}

/// How a trace ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum End {
    Plane,
    Backward,
    Absorbed,
    Lost,
}

struct Trace {
    end: End,
    p: DVec3,
    v: DVec3,
    log_t: [f64; 3],
    min_forward: f64,
    length: f64,
}

/// A target plane: points with dot(n, p) = c.
#[derive(Clone, Copy)]
struct Target {
    n: DVec3,
    c: f64,
}

/// The volume's scalar field with the transfer functions, ready for tracing.
pub struct Field {
    dims: [usize; 3],
    values: Vec<f32>,
    /// Texture coordinate = world * tex_per_world + 0.5.
    tex_per_world: DVec3,
    half: DVec3,
    ref_step: f64,
    eta: Vec<f32>,
    alpha: Vec<f32>,
    medium: Vec<[f32; 3]>,
    /// The transfer function's colour (what the matter returns of the light it receives).
    colour: Vec<[f32; 3]>,
    clip: Option<(DVec3, f64)>,
    /// Rates (σ + −ln m / ref_step per channel) at s = 0, unclipped and clipped.
    rate0: [f64; 3],
    rate0_clipped: [f64; 3],
    exterior_transparent: bool,
    /// η from the cubic B-spline of the values ([`Field::use_cubic_eta`]).
    cubic_eta: bool,
    // Bricks: voxel coordinate x = t N - 0.5; brick j covers [g0 + jB, g0 + (j+1)B).
    g0: f64,
    nb: [usize; 3],
    flags: Vec<u8>,
    /// Voxel coordinate = world * vox_scale + vox_offset.
    vox_scale: DVec3,
    vox_offset: DVec3,
    grid_lo: DVec3,
    grid_hi: DVec3,
    eps: f64,
}

/// [`Field::trace_ray`] for a single ray (builds the field each call; build a [`Field`]
/// once for many rays).
#[allow(clippy::too_many_arguments)]
pub fn trace_ray(
    volume: &Volume,
    tf: &TransferFunctions,
    camera: &Camera,
    opts: &RenderOptions,
    origin: Vec3,
    direction: Vec3,
    depth: f32,
    step: f32,
) -> Result<Option<RayEnd>> {
    Field::new(volume, tf, opts)?.trace_ray(camera, origin, direction, depth, step)
}

/// The sweep's planes for this volume, camera and sample distance.
pub fn planes(volume: &Volume, camera: &Camera, opts: &RenderOptions) -> Result<Planes> {
    camera.validate()?;
    opts.validate()?;
    let e = Vec3::from(volume.normalised_extent()) * 0.5;
    Planes::for_box(camera, e, opts.sample_distance * volume.min_voxel_size())
}

/// View depth of the sweep's plane `plane` (0-based), an error naming the range if the
/// frame has no such plane.
pub fn plane_depth(
    volume: &Volume,
    camera: &Camera,
    opts: &RenderOptions,
    plane: u32,
) -> Result<f32> {
    let p = planes(volume, camera, opts)?;
    ensure!(
        plane < p.count,
        "--plane {plane}: this frame has planes 0..{} (sample distance {})",
        p.count - 1,
        opts.sample_distance
    );
    Ok(p.depth(plane))
}

mod field;
mod irradiance;
pub mod reference;
#[cfg(test)]
mod tests;

use field::*;
pub use irradiance::trace_irradiance;
pub use reference::{render_reference, ReferenceImage, ReferenceOptions};
