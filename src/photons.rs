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
//!   and the image is flux / pixel area on that plane: irradiance per unit *plane* area,
//!   the sweep's light-colour unit, so unobstructed light reads exactly `light.colour`.
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

use crate::render::sweep::MIN_FORWARD;
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
}

impl Default for PhotonOptions {
    fn default() -> Self {
        Self {
            photons_per_pixel: 64,
            step: 0.1,
            seed: 1,
            jitter: false,
            threads: 0,
        }
    }
}

impl PhotonOptions {
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
    /// Row-major, top row first: rgb = irradiance (flux per unit plane area; unobstructed
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
    clip: Option<(DVec3, f64)>,
    /// Rates (σ + −ln m / ref_step per channel) at s = 0, unclipped and clipped.
    rate0: [f64; 3],
    rate0_clipped: [f64; 3],
    exterior_transparent: bool,
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

/// Normalised [0,1] values as the GPU texture returns them.
fn normalised_values(volume: &Volume) -> Vec<f32> {
    match &volume.voxels {
        Voxels::U8(v) => v.iter().map(|&x| x as f32 / 255.0).collect(),
        Voxels::U16(v) => v.iter().map(|&x| x as f32 / 65535.0).collect(),
        Voxels::F32(_) => bytemuck::pod_collect_to_vec(&volume.texel_bytes()),
    }
}

fn lut(tab: &[f32], s: f64) -> f64 {
    let x = s.clamp(0.0, 1.0) * (tab.len() - 1) as f64;
    let i = (x as usize).min(tab.len() - 2);
    let f = x - i as f64;
    tab[i] as f64 * (1.0 - f) + tab[i + 1] as f64 * f
}

fn lut3(tab: &[[f32; 3]], s: f64) -> [f64; 3] {
    let x = s.clamp(0.0, 1.0) * (tab.len() - 1) as f64;
    let i = (x as usize).min(tab.len() - 2);
    let f = x - i as f64;
    std::array::from_fn(|c| tab[i][c] as f64 * (1.0 - f) + tab[i + 1][c] as f64 * f)
}

/// Table entries a lookup of any s in [lo, hi] can touch with a non-zero weight.
fn lut_range(lo: f64, hi: f64) -> std::ops::RangeInclusive<usize> {
    let n = TF_SAMPLES as usize;
    let a = (lo.clamp(0.0, 1.0) * (n - 1) as f64).floor() as usize;
    let b = (hi.clamp(0.0, 1.0) * (n - 1) as f64).ceil() as usize;
    a.min(n - 1)..=b.min(n - 1)
}

/// Slab test: (t_enter, t_exit) of the line p + t d with the box [lo, hi].
fn ray_box(p: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> (f64, f64) {
    let mut t0 = f64::NEG_INFINITY;
    let mut t1 = f64::INFINITY;
    for k in 0..3 {
        if d[k] != 0.0 {
            let a = (lo[k] - p[k]) / d[k];
            let b = (hi[k] - p[k]) / d[k];
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        } else if p[k] < lo[k] || p[k] > hi[k] {
            return (f64::INFINITY, f64::NEG_INFINITY);
        }
    }
    (t0, t1)
}

fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

fn uniform(h: u64) -> f64 {
    (h >> 11) as f64 / (1u64 << 53) as f64
}

impl Field {
    /// The field of `volume` with `tf`, the eta scale and the clipping plane of `opts`.
    pub fn new(volume: &Volume, tf: &TransferFunctions, opts: &RenderOptions) -> Result<Self> {
        volume.validate()?;
        opts.sweep.validate()?;
        let dims = volume.dims.map(|d| d as usize);
        let values = normalised_values(volume);
        let half = Vec3::from(volume.normalised_extent()).as_dvec3() * 0.5;
        let ref_step = volume.min_voxel_size() as f64;
        let k = opts.sweep.eta_scale;
        let (l0, l1) = tf.texels();
        let eta: Vec<f32> = l1
            .iter()
            .map(|t| {
                if k == 1.0 {
                    t[3]
                } else {
                    1.0 + k * (t[3] - 1.0)
                }
            })
            .collect();
        let alpha: Vec<f32> = l0.iter().map(|t| t[3]).collect();
        let medium: Vec<[f32; 3]> = l1.iter().map(|t| [t[0], t[1], t[2]]).collect();
        let clip = opts
            .sweep
            .clip
            .map(|(n, o)| (n.normalize().as_dvec3(), o as f64));
        let tex_per_world = DVec3::splat(0.5) / half;
        let n = DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64);
        let vox_scale = tex_per_world * n;
        let vox_offset = 0.5 * n - 0.5;
        let b = BRICK as f64;
        let g0 = -0.5 - b;
        let nb = dims.map(|d| (d + 2 * BRICK).div_ceil(BRICK));
        let grid_lo = (DVec3::splat(g0) - vox_offset) / vox_scale;
        let grid_hi = (DVec3::new(
            g0 + nb[0] as f64 * b,
            g0 + nb[1] as f64 * b,
            g0 + nb[2] as f64 * b,
        ) - vox_offset)
            / vox_scale;
        let mut f = Self {
            dims,
            values,
            tex_per_world,
            half,
            ref_step,
            eta,
            alpha,
            medium,
            clip,
            rate0: [0.0; 3],
            rate0_clipped: [0.0; 3],
            exterior_transparent: false,
            g0,
            nb,
            flags: Vec::new(),
            vox_scale,
            vox_offset,
            grid_lo,
            grid_hi,
            eps: 1e-6 * ref_step,
        };
        f.rate0 = f.rate_of(0.0, false);
        f.rate0_clipped = f.rate_of(0.0, true);
        f.exterior_transparent = f.rate0 == [0.0; 3] && f.rate0_clipped == [0.0; 3];
        f.flags = f.brick_flags();
        Ok(f)
    }

    fn brick_flags(&self) -> Vec<u8> {
        let [nx, ny, nz] = self.nb;
        let b = BRICK as f64;
        let h = GRADIENT_STEP;
        let mut flags = vec![0u8; nx * ny * nz];
        for jz in 0..nz {
            for jy in 0..ny {
                for jx in 0..nx {
                    let j = [jx, jy, jz];
                    let mut outside = false;
                    let mut inside = true;
                    let mut range = [(0usize, 0usize); 3];
                    for k in 0..3 {
                        let n = self.dims[k] as f64;
                        let lo = self.g0 + j[k] as f64 * b - h;
                        let hi = self.g0 + (j[k] + 1) as f64 * b + h;
                        if lo < -0.5 || hi > n - 0.5 {
                            outside = true;
                        }
                        if lo > n - 0.5 || hi < -0.5 {
                            inside = false;
                        }
                        let a = lo.max(-0.5).floor().clamp(0.0, n - 1.0) as usize;
                        let c = (hi.min(n - 0.5).floor() + 1.0).clamp(0.0, n - 1.0) as usize;
                        range[k] = (a, c);
                    }
                    let (mut smin, mut smax) = if outside {
                        (0.0f64, 0.0f64)
                    } else {
                        (f64::INFINITY, f64::NEG_INFINITY)
                    };
                    if inside {
                        for z in range[2].0..=range[2].1 {
                            for y in range[1].0..=range[1].1 {
                                let row = (z * self.dims[1] + y) * self.dims[0];
                                for x in range[0].0..=range[0].1 {
                                    let v = self.values[row + x] as f64;
                                    smin = smin.min(v);
                                    smax = smax.max(v);
                                }
                            }
                        }
                    }
                    let r = lut_range(smin, smax);
                    let e0 = self.eta[*r.start()];
                    let mut fl = 0;
                    if self.eta[r.clone()].iter().all(|&e| e == e0) {
                        fl |= ETA_CONST;
                    }
                    if self.alpha[r.clone()].iter().all(|&a| a == 0.0)
                        && self.medium[r].iter().all(|m| *m == [1.0; 3])
                    {
                        fl |= TRANSPARENT;
                    }
                    flags[(jz * ny + jy) * nx + jx] = fl;
                }
            }
        }
        flags
    }

    /// The smallest voxel side in world units.
    pub fn ref_step(&self) -> f32 {
        self.ref_step as f32
    }

    /// Half extent of the volume box in world units.
    pub fn half_extent(&self) -> Vec3 {
        self.half.as_vec3()
    }

    fn texel(&self, x: usize, y: usize, z: usize) -> f64 {
        self.values[(z * self.dims[1] + y) * self.dims[0] + x] as f64
    }

    /// Scalar value at texture coordinate t: trilinear, clamp to edge, 0 outside [0,1]³.
    fn value_tex(&self, t: DVec3) -> f64 {
        if t.x < 0.0 || t.y < 0.0 || t.z < 0.0 || t.x > 1.0 || t.y > 1.0 || t.z > 1.0 {
            return 0.0;
        }
        let mut i0 = [0usize; 3];
        let mut i1 = [0usize; 3];
        let mut w = [0f64; 3];
        for k in 0..3 {
            let n = self.dims[k];
            let x = t[k] * n as f64 - 0.5;
            let f = x.floor();
            w[k] = x - f;
            let i = f as i64;
            i0[k] = i.clamp(0, n as i64 - 1) as usize;
            i1[k] = (i + 1).clamp(0, n as i64 - 1) as usize;
        }
        let c = |x: usize, y: usize, z: usize| self.texel(x, y, z);
        let x00 = c(i0[0], i0[1], i0[2]) * (1.0 - w[0]) + c(i1[0], i0[1], i0[2]) * w[0];
        let x10 = c(i0[0], i1[1], i0[2]) * (1.0 - w[0]) + c(i1[0], i1[1], i0[2]) * w[0];
        let x01 = c(i0[0], i0[1], i1[2]) * (1.0 - w[0]) + c(i1[0], i0[1], i1[2]) * w[0];
        let x11 = c(i0[0], i1[1], i1[2]) * (1.0 - w[0]) + c(i1[0], i1[1], i1[2]) * w[0];
        let y0 = x00 * (1.0 - w[1]) + x10 * w[1];
        let y1 = x01 * (1.0 - w[1]) + x11 * w[1];
        y0 * (1.0 - w[2]) + y1 * w[2]
    }

    fn tex(&self, p: DVec3) -> DVec3 {
        p * self.tex_per_world + 0.5
    }

    /// Scalar value s at a world position (0 outside the box).
    pub fn value(&self, p: Vec3) -> f32 {
        self.value_tex(self.tex(p.as_dvec3())) as f32
    }

    /// η at a world position.
    pub fn eta_at(&self, p: Vec3) -> f32 {
        lut(&self.eta, self.value_tex(self.tex(p.as_dvec3()))) as f32
    }

    fn eta_w(&self, p: DVec3) -> f64 {
        lut(&self.eta, self.value_tex(self.tex(p)))
    }

    /// ∇η (world units) by central differences GRADIENT_STEP voxels apart.
    fn grad_eta(&self, p: DVec3) -> DVec3 {
        let t = self.tex(p);
        if let Some(g) = self.grad_eta_in_cell(t) {
            return g;
        }
        let mut g = DVec3::ZERO;
        for k in 0..3 {
            let h = GRADIENT_STEP / self.dims[k] as f64;
            let mut e = DVec3::ZERO;
            e[k] = h;
            let a = lut(&self.eta, self.value_tex(t + e));
            let b = lut(&self.eta, self.value_tex(t - e));
            g[k] = (a - b) / (2.0 * h) * self.tex_per_world[k];
        }
        g
    }

    /// [`Self::grad_eta`] when all six stencil points lie in the box and in one trilinear
    /// cell (the common case): the same values from one fetch of the cell's corners.
    fn grad_eta_in_cell(&self, t: DVec3) -> Option<DVec3> {
        let hv = GRADIENT_STEP;
        let mut i0 = [0usize; 3];
        let mut i1 = [0usize; 3];
        let mut w = [0f64; 3];
        for k in 0..3 {
            let n = self.dims[k];
            let h = hv / n as f64;
            if t[k] - h < 0.0 || t[k] + h > 1.0 {
                return None;
            }
            let x = t[k] * n as f64 - 0.5;
            let f = x.floor();
            w[k] = x - f;
            if w[k] < hv || w[k] > 1.0 - hv {
                return None;
            }
            let i = f as i64;
            i0[k] = i.clamp(0, n as i64 - 1) as usize;
            i1[k] = (i + 1).clamp(0, n as i64 - 1) as usize;
        }
        let c = |x: usize, y: usize, z: usize| self.texel(x, y, z);
        let v = [
            c(i0[0], i0[1], i0[2]),
            c(i1[0], i0[1], i0[2]),
            c(i0[0], i1[1], i0[2]),
            c(i1[0], i1[1], i0[2]),
            c(i0[0], i0[1], i1[2]),
            c(i1[0], i0[1], i1[2]),
            c(i0[0], i1[1], i1[2]),
            c(i1[0], i1[1], i1[2]),
        ];
        let tri = |w: [f64; 3]| {
            let x00 = v[0] * (1.0 - w[0]) + v[1] * w[0];
            let x10 = v[2] * (1.0 - w[0]) + v[3] * w[0];
            let x01 = v[4] * (1.0 - w[0]) + v[5] * w[0];
            let x11 = v[6] * (1.0 - w[0]) + v[7] * w[0];
            let y0 = x00 * (1.0 - w[1]) + x10 * w[1];
            let y1 = x01 * (1.0 - w[1]) + x11 * w[1];
            y0 * (1.0 - w[2]) + y1 * w[2]
        };
        let mut g = DVec3::ZERO;
        for k in 0..3 {
            let (mut a, mut b) = (w, w);
            a[k] += hv;
            b[k] -= hv;
            let h = hv / self.dims[k] as f64;
            g[k] = (lut(&self.eta, tri(a)) - lut(&self.eta, tri(b))) / (2.0 * h)
                * self.tex_per_world[k];
        }
        Some(g)
    }

    fn clipped(&self, p: DVec3) -> bool {
        match self.clip {
            Some((n, o)) => n.dot(p) > o,
            None => false,
        }
    }

    /// −d(ln flux)/ds per channel for the value s.
    fn rate_of(&self, s: f64, clipped: bool) -> [f64; 3] {
        let sigma = if clipped {
            0.0
        } else {
            let a = lut(&self.alpha, s).clamp(0.0, 1.0);
            -(1.0 - a).ln() / self.ref_step
        };
        let m = lut3(&self.medium, s);
        std::array::from_fn(|c| sigma - m[c].clamp(0.0, 1.0).ln() / self.ref_step)
    }

    fn rate(&self, p: DVec3) -> [f64; 3] {
        self.rate_of(self.value_tex(self.tex(p)), self.clipped(p))
    }

    fn add_rate(log_t: &mut [f64; 3], r: [f64; 3], len: f64) {
        if len > 0.0 {
            for c in 0..3 {
                if r[c] > 0.0 {
                    log_t[c] -= r[c] * len;
                }
            }
        }
    }

    /// Attenuation along the chord a→b of arc length `len` (two-point Gauss–Legendre).
    fn integrate_chord(&self, a: DVec3, b: DVec3, len: f64, log_t: &mut [f64; 3]) {
        const G: f64 = 0.288_675_134_594_812_9; // 1 / (2 sqrt 3)
        for tau in [0.5 - G, 0.5 + G] {
            Self::add_rate(log_t, self.rate(a + (b - a) * tau), 0.5 * len);
        }
    }

    fn in_box(&self, p: DVec3) -> bool {
        p.abs().cmple(self.half).all()
    }

    /// Attenuation along the straight segment p + t d, t in [0, len], split where the
    /// integrand jumps (box faces, clipping plane); uniform outside the box.
    fn attenuate_straight(&self, p: DVec3, d: DVec3, len: f64, h: f64, log_t: &mut [f64; 3]) {
        if len <= 0.0 {
            return;
        }
        let mut cuts = [0.0, len, len, len, len];
        let mut n = 2;
        let (t0, t1) = ray_box(p, d, -self.half, self.half);
        for t in [t0, t1] {
            if t > 0.0 && t < len {
                cuts[n] = t;
                n += 1;
            }
        }
        if let Some((cn, co)) = self.clip {
            let dn = cn.dot(d);
            if dn != 0.0 {
                let t = (co - cn.dot(p)) / dn;
                if t > 0.0 && t < len {
                    cuts[n] = t;
                    n += 1;
                }
            }
        }
        let cuts = &mut cuts[..n];
        cuts.sort_by(f64::total_cmp);
        for w in cuts.windows(2) {
            let (a, b) = (w[0], w[1]);
            if b <= a {
                continue;
            }
            let mid = p + d * (0.5 * (a + b));
            if !self.in_box(mid) {
                let r = if self.clipped(mid) {
                    self.rate0_clipped
                } else {
                    self.rate0
                };
                Self::add_rate(log_t, r, b - a);
                continue;
            }
            let steps = ((b - a) / h).ceil().max(1.0);
            let dt = (b - a) / steps;
            for i in 0..steps as usize {
                let s0 = a + i as f64 * dt;
                self.integrate_chord(p + d * s0, p + d * (s0 + dt), dt, log_t);
            }
        }
    }

    /// Brick index and voxel-space bounds of the brick holding p, None outside the grid.
    fn brick_at(&self, p: DVec3) -> Option<(usize, DVec3, DVec3)> {
        let x = p * self.vox_scale + self.vox_offset;
        let b = BRICK as f64;
        let mut j = [0usize; 3];
        for k in 0..3 {
            let f = ((x[k] - self.g0) / b).floor();
            if !(f >= 0.0 && f < self.nb[k] as f64) {
                return None;
            }
            j[k] = f as usize;
        }
        let lo = DVec3::new(
            self.g0 + j[0] as f64 * b,
            self.g0 + j[1] as f64 * b,
            self.g0 + j[2] as f64 * b,
        );
        Some(((j[2] * self.nb[1] + j[1]) * self.nb[0] + j[0], lo, lo + b))
    }

    fn flags_at(&self, p: DVec3) -> u8 {
        self.brick_at(p)
            .map(|(i, _, _)| self.flags[i])
            .unwrap_or(if self.exterior_transparent {
                ETA_CONST | TRANSPARENT
            } else {
                ETA_CONST
            })
    }

    /// World distance along unit d from p to the exit of the brick with voxel bounds lo, hi.
    fn brick_exit(&self, p: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> f64 {
        let x = p * self.vox_scale + self.vox_offset;
        let dv = d * self.vox_scale;
        let mut t = f64::INFINITY;
        for k in 0..3 {
            if dv[k] > 0.0 {
                t = t.min((hi[k] - x[k]) / dv[k]);
            } else if dv[k] < 0.0 {
                t = t.min((lo[k] - x[k]) / dv[k]);
            }
        }
        t.max(0.0)
    }

    /// Distance along unit d to the next place where the integrand jumps (box face,
    /// clipping plane), infinity if none.
    fn next_cut(&self, p: DVec3, d: DVec3) -> f64 {
        let tiny = 1e-9;
        let mut best = f64::INFINITY;
        let (t0, t1) = ray_box(p, d, -self.half, self.half);
        if t0 <= t1 {
            for t in [t0, t1] {
                if t > tiny {
                    best = best.min(t);
                }
            }
        }
        if let Some((cn, co)) = self.clip {
            let dn = cn.dot(d);
            if dn != 0.0 {
                let t = (co - cn.dot(p)) / dn;
                if t > tiny {
                    best = best.min(t);
                }
            }
        }
        best
    }

    fn rk4(&self, p: DVec3, v: DVec3, h: f64) -> (DVec3, DVec3) {
        let k1x = v.normalize();
        let k1v = self.grad_eta(p);
        let v2 = v + 0.5 * h * k1v;
        let k2x = v2.normalize();
        let k2v = self.grad_eta(p + 0.5 * h * k1x);
        let v3 = v + 0.5 * h * k2v;
        let k3x = v3.normalize();
        let k3v = self.grad_eta(p + 0.5 * h * k2x);
        let v4 = v + h * k3v;
        let k4x = v4.normalize();
        let k4v = self.grad_eta(p + h * k3x);
        (
            p + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
            v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
        )
    }

    fn max_iterations(&self, h: f64) -> u64 {
        let diag = (self.grid_hi - self.grid_lo).length();
        (50.0 * diag / h) as u64 + 100_000
    }

    /// Trace from p with v = η d until the target plane is crossed moving forward; the
    /// plane's normal is the view direction (for the steepness statistic).
    fn trace(&self, mut p: DVec3, mut v: DVec3, target: Target, h: f64, cutoff: bool) -> Trace {
        let ln_cut = FLUX_CUTOFF.ln();
        let mut log_t = [0.0f64; 3];
        let mut min_forward = f64::INFINITY;
        let mut length = 0.0;
        let max_iter = self.max_iterations(h);
        let eps = self.eps;
        let mut end = End::Lost;
        for _ in 0..max_iter {
            let speed = v.length();
            if speed.is_nan() || speed <= 0.0 || !p.is_finite() {
                break;
            }
            let d = v / speed;
            let dz = d.dot(target.n);
            min_forward = min_forward.min(dz);
            let zrel = target.n.dot(p) - target.c;
            let t_plane = if dz > 0.0 { -zrel / dz } else { f64::INFINITY };
            match self.brick_at(p) {
                None => {
                    let (t0, t1) = ray_box(p, d, self.grid_lo, self.grid_hi);
                    let t_grid = if t0 >= 0.0 && t0 <= t1 {
                        t0
                    } else {
                        f64::INFINITY
                    };
                    if t_plane <= t_grid {
                        if !t_plane.is_finite() {
                            end = End::Backward;
                            break;
                        }
                        if !self.exterior_transparent {
                            self.attenuate_straight(p, d, t_plane, h, &mut log_t);
                        }
                        p += d * t_plane;
                        length += t_plane;
                        end = End::Plane;
                        break;
                    }
                    let t = t_grid + eps;
                    if !self.exterior_transparent {
                        self.attenuate_straight(p, d, t, h, &mut log_t);
                    }
                    p += d * t;
                    length += t;
                }
                Some((i, lo, hi)) if self.flags[i] & ETA_CONST != 0 => {
                    let t_exit = self.brick_exit(p, d, lo, hi) + eps;
                    let t = t_exit.min(t_plane);
                    if self.flags[i] & TRANSPARENT == 0 {
                        self.attenuate_straight(p, d, t, h, &mut log_t);
                    }
                    p += d * t;
                    length += t;
                    if t_plane <= t_exit {
                        end = End::Plane;
                        break;
                    }
                }
                Some((i, _, _)) => {
                    let hh = self.next_cut(p, d).clamp(h * 1e-3, h);
                    let (p1, v1) = self.rk4(p, v, hh);
                    let z1 = target.n.dot(p1) - target.c;
                    let frac = if z1 >= 0.0 { zrel / (zrel - z1) } else { 1.0 };
                    let q = p + (p1 - p) * frac;
                    if self.flags[i] & TRANSPARENT == 0 || self.flags_at(p1) & TRANSPARENT == 0 {
                        self.integrate_chord(p, q, hh * frac, &mut log_t);
                    }
                    length += hh * frac;
                    if z1 >= 0.0 {
                        p = q;
                        v = v + (v1 - v) * frac;
                        end = End::Plane;
                        break;
                    }
                    p = p1;
                    v = v1;
                }
            }
            if cutoff && log_t.iter().all(|&l| l < ln_cut) {
                end = End::Absorbed;
                break;
            }
        }
        if let Some(&l) = log_t.iter().find(|l| l.is_nan()) {
            let _ = l;
            log_t = [f64::NEG_INFINITY; 3];
        }
        Trace {
            end,
            p,
            v,
            log_t,
            min_forward,
            length,
        }
    }

    /// Traces one ray from the world point `origin` along the world direction `direction`
    /// (starting with v = η(origin)·direction) until it crosses the view-aligned plane at
    /// view depth `depth` of `camera` moving forward; `step` is the RK4 step in voxels.
    /// Light is not cut off by absorption (see the transmittance). None if the ray turns
    /// back and never reaches the plane (or hits the iteration limit).
    pub fn trace_ray(
        &self,
        camera: &Camera,
        origin: Vec3,
        direction: Vec3,
        depth: f32,
        step: f32,
    ) -> Result<Option<RayEnd>> {
        ensure!(
            step.is_finite() && step > 0.0,
            "ray step {step} must be a positive number of voxels"
        );
        ensure!(
            direction.is_finite() && direction.length() > 0.0,
            "ray direction {direction:?} must be a finite non-zero vector"
        );
        let (eye, forward, _, _) = camera.frame();
        let target = Target {
            n: forward.as_dvec3(),
            c: depth as f64 + forward.as_dvec3().dot(eye.as_dvec3()),
        };
        let p = origin.as_dvec3();
        ensure!(
            target.n.dot(p) < target.c,
            "ray origin {origin:?} is already at or beyond view depth {depth}"
        );
        let v = direction.as_dvec3().normalize() * self.eta_w(p);
        let t = self.trace(p, v, target, step as f64 * self.ref_step, false);
        if t.end != End::Plane {
            return Ok(None);
        }
        Ok(Some(RayEnd {
            position: t.p.as_vec3(),
            direction: t.v.normalize().as_vec3(),
            eta: t.v.length() as f32,
            transmittance: t.log_t.map(|l| l.exp() as f32),
            length: t.length as f32,
        }))
    }
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

/// Irradiance of the scene's directional light on the view-aligned plane at view depth
/// `depth` (see the module documentation), as a W × H image of `opts`.
pub fn trace_irradiance(
    volume: &Volume,
    tf: &TransferFunctions,
    camera: &Camera,
    opts: &RenderOptions,
    depth: f32,
    popts: &PhotonOptions,
) -> Result<PhotonImage> {
    popts.validate()?;
    let planes = planes(volume, camera, opts)?;
    let field = Field::new(volume, tf, opts)?;
    let start = Instant::now();
    let (eye, forward, right, up) = camera.frame();
    // The f32 frame, re-orthonormalised in f64: launch and binning then map unobstructed
    // photons onto their sub-pixel cells exactly (the f32 frame's 1e-7 skew moved jittered
    // photons near cell edges into the next pixel).
    let _ = up;
    let eye = eye.as_dvec3();
    let forward = forward.as_dvec3().normalize();
    let right = (right.as_dvec3() - forward * right.as_dvec3().dot(forward)).normalize();
    let up = right.cross(forward);
    let travel = (-opts.sweep.light.towards.normalize()).as_dvec3();
    let d = DVec3::new(travel.dot(right), travel.dot(up), travel.dot(forward));
    if d.z < MIN_FORWARD as f64 {
        bail!(
            "the light must come from the viewer's side: light travelling against the view \
             direction cannot be propagated by the sweep (light direction makes {:.1}° with \
             the view direction; at most {:.1}° is supported)",
            d.z.clamp(-1.0, 1.0).acos().to_degrees(),
            (MIN_FORWARD as f64).acos().to_degrees()
        );
    }
    let z_l = (planes.first_depth - planes.spacing) as f64;
    let z_k = depth as f64;
    ensure!(
        depth.is_finite() && z_k > z_l,
        "depth {depth} must lie beyond the light's start plane at depth {z_l:.4} (one plane \
         spacing in front of the volume)"
    );
    let (w, h) = (opts.width as usize, opts.height as usize);
    let tanf = (camera.fov_y.to_radians() as f64 * 0.5).tan();
    let aspect = w as f64 / h as f64;
    let half_w = z_k * tanf * aspect;
    let half_h = z_k * tanf;
    let (px, py) = (2.0 * half_w / w as f64, 2.0 * half_h / h as f64);
    let k = popts.per_axis() as f64;
    let (dx, dy) = (px / k, py / k);
    let shift = DVec3::new(d.x / d.z, d.y / d.z, 0.0) * (z_k - z_l);
    // Launch rectangle: back-projections of the plane's corners and the box corners.
    let back = |q: DVec3| (q.x - d.x / d.z * (q.z - z_l), q.y - d.y / d.z * (q.z - z_l));
    let mut pts = Vec::new();
    for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        pts.push(back(DVec3::new(sx * half_w, sy * half_h, z_k)));
    }
    let half = field.half;
    for i in 0..8 {
        let c = DVec3::new(
            if i & 1 == 0 { -half.x } else { half.x },
            if i & 2 == 0 { -half.y } else { half.y },
            if i & 4 == 0 { -half.z } else { half.z },
        ) - eye;
        pts.push(back(DVec3::new(c.dot(right), c.dot(up), c.dot(forward))));
    }
    let (xmin, xmax) = pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
        (a.0.min(p.0), a.1.max(p.0))
    });
    let (ymin, ymax) = pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
        (a.0.min(p.1), a.1.max(p.1))
    });
    // Landing x of column i: -half_w + (i + 0.5) dx; launch x = landing - shift.x.
    // Landing y of row j: half_h - (j + 0.5) dy; launch y = landing - shift.y.
    let i0 = ((xmin + shift.x + half_w) / dx - 0.5).floor() as i64 - 1;
    let i1 = ((xmax + shift.x + half_w) / dx - 0.5).ceil() as i64 + 1;
    let j0 = ((half_h - shift.y - ymax) / dy - 0.5).floor() as i64 - 1;
    let j1 = ((half_h - shift.y - ymin) / dy - 0.5).ceil() as i64 + 1;
    let cols = (i1 - i0 + 1) as u64;
    let rows = (j1 - j0 + 1) as u64;
    ensure!(
        cols * rows <= 1 << 36,
        "{} photons are too many; use fewer photons per pixel or a smaller image",
        cols * rows
    );
    let colour = opts.sweep.light.colour.map(|c| c as f64);
    let cell = dx * dy;
    let target = Target {
        n: forward,
        c: z_k + forward.dot(eye),
    };
    let step = popts.step as f64 * field.ref_step;
    let threads = if popts.threads > 0 {
        popts.threads
    } else {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    };
    let eta_launch = |p: DVec3| field.eta_w(p);

    #[derive(Default)]
    struct Acc {
        flux: Vec<[f64; 3]>,
        counts: Vec<u32>,
        landed: u64,
        outside: u64,
        absorbed: u64,
        backward: u64,
        steep: u64,
        lost: u64,
    }
    let next_row = AtomicUsize::new(0);
    let work = || {
        let mut acc = Acc {
            flux: vec![[0.0; 3]; w * h],
            counts: vec![0; w * h],
            ..Default::default()
        };
        loop {
            let r = next_row.fetch_add(1, Ordering::Relaxed) as u64;
            if r >= rows {
                break;
            }
            let j = j0 + r as i64;
            for c in 0..cols {
                let i = i0 + c as i64;
                let (ux, uy) = if popts.jitter {
                    let hsh = splitmix(
                        popts.seed ^ splitmix((j as u64) << 32 ^ (i as u64 & 0xffff_ffff)),
                    );
                    (uniform(hsh), uniform(splitmix(hsh)))
                } else {
                    (0.5, 0.5)
                };
                let lx = -half_w + (i as f64 + ux) * dx - shift.x;
                let ly = half_h - (j as f64 + uy) * dy - shift.y;
                let p = eye + right * lx + up * ly + forward * z_l;
                let v = travel * eta_launch(p);
                let t = field.trace(p, v, target, step, true);
                if t.min_forward < MIN_FORWARD as f64 {
                    acc.steep += 1;
                }
                match t.end {
                    End::Plane => {
                        let q = t.p - eye;
                        let ux = q.dot(right) / half_w * 0.5 + 0.5;
                        let uy = -q.dot(up) / half_h * 0.5 + 0.5;
                        let (fx, fy) = ((ux * w as f64).floor(), (uy * h as f64).floor());
                        if fx >= 0.0 && fy >= 0.0 && fx < w as f64 && fy < h as f64 {
                            let idx = fy as usize * w + fx as usize;
                            for (ch, c) in colour.iter().enumerate() {
                                acc.flux[idx][ch] += c * cell * t.log_t[ch].exp();
                            }
                            acc.counts[idx] += 1;
                            acc.landed += 1;
                        } else {
                            acc.outside += 1;
                        }
                    }
                    End::Absorbed => acc.absorbed += 1,
                    End::Backward => acc.backward += 1,
                    End::Lost => acc.lost += 1,
                }
            }
        }
        acc
    };
    let parts: Vec<Acc> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads).map(|_| s.spawn(work)).collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("photon worker panicked"))
            .collect()
    });
    let mut total = Acc {
        flux: vec![[0.0; 3]; w * h],
        counts: vec![0; w * h],
        ..Default::default()
    };
    for a in parts {
        for (t, f) in total.flux.iter_mut().zip(&a.flux) {
            for ch in 0..3 {
                t[ch] += f[ch];
            }
        }
        for (t, c) in total.counts.iter_mut().zip(&a.counts) {
            *t += c;
        }
        total.landed += a.landed;
        total.outside += a.outside;
        total.absorbed += a.absorbed;
        total.backward += a.backward;
        total.steep += a.steep;
        total.lost += a.lost;
    }
    let area = px * py;
    let pixels = total
        .flux
        .iter()
        .map(|f| {
            [
                (f[0] / area) as f32,
                (f[1] / area) as f32,
                (f[2] / area) as f32,
                0.0,
            ]
        })
        .collect();
    Ok(PhotonImage {
        width: opts.width,
        height: opts.height,
        pixels,
        counts: total.counts,
        depth,
        photons_per_pixel: (k * k) as u32,
        photons: cols * rows,
        landed: total.landed,
        outside: total.outside,
        absorbed: total.absorbed,
        backward: total.backward,
        steep: total.steep,
        lost: total.lost,
        seconds: start.elapsed().as_secs_f64(),
        threads,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::Light;
    use crate::transfer::Piecewise;

    fn f32_volume(n: u32, f: impl Fn(DVec3) -> f32) -> Volume {
        let mut v = Vec::with_capacity((n as usize).pow(3));
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let p = DVec3::new(x as f64, y as f64, z as f64);
                    v.push(f((p + 0.5) / n as f64 - 0.5));
                }
            }
        }
        let mut vol = Volume::new([n; 3], [1.0; 3], Voxels::F32(v)).unwrap();
        vol.range = Some((0.0, 1.0));
        vol
    }

    fn axial() -> Camera {
        Camera {
            azimuth: 0.0,
            elevation: 0.0,
            distance: 2.2,
            fov_y: 35.0,
            ..Default::default()
        }
    }

    fn options(size: u32, towards: Vec3, colour: [f32; 3]) -> RenderOptions {
        let mut o = RenderOptions {
            width: size,
            height: size,
            ..Default::default()
        };
        o.sweep.light = Light {
            towards: towards.normalize(),
            colour,
            softness: 0.0,
        };
        o
    }

    fn popts(ppp: u32, jitter: bool) -> PhotonOptions {
        PhotonOptions {
            photons_per_pixel: ppp,
            jitter,
            threads: 2,
            ..Default::default()
        }
    }

    #[test]
    fn empty_volume_gives_the_light_colour() {
        let vol = f32_volume(32, |_| 0.0);
        let tf = TransferFunctions::default();
        let camera = Camera {
            azimuth: 30.0,
            elevation: 20.0,
            distance: 2.2,
            fov_y: 35.0,
            ..Default::default()
        };
        let colour = [0.9, 0.5, 0.25];
        let opts = options(32, Vec3::new(-0.3, 0.6, 1.0), colour);
        let p = planes(&vol, &camera, &opts).unwrap();
        let depth = p.depth(p.count / 2);
        for jitter in [false, true] {
            let img =
                trace_irradiance(&vol, &tf, &camera, &opts, depth, &popts(64, jitter)).unwrap();
            assert_eq!(img.photons_per_pixel, 64);
            assert_eq!((img.absorbed, img.backward, img.lost), (0, 0, 0));
            // The launch cells tile the pixels: unobstructed light is exact, jittered or not
            // (far inside the Poisson error 1/sqrt(64)).
            let tol = 1e-5;
            let mut mean = [0.0f64; 3];
            for px in &img.pixels {
                for c in 0..3 {
                    let rel = (px[c] / colour[c] - 1.0).abs();
                    assert!(rel < tol, "jitter {jitter}: {px:?} vs {colour:?}");
                    mean[c] += px[c] as f64 / img.pixels.len() as f64;
                }
            }
            for c in 0..3 {
                assert!((mean[c] / colour[c] as f64 - 1.0).abs() < 0.01, "{mean:?}");
            }
        }
    }

    #[test]
    fn slab_follows_beer_lambert_per_channel() {
        let vol = f32_volume(32, |_| 1.0);
        let alpha = 0.05f64;
        let m = [0.9f64, 0.95, 0.99];
        let tf = TransferFunctions {
            opacity: Piecewise::new(vec![(0.0, [0.0]), (1.0, [alpha as f32])]),
            medium: Piecewise::new(vec![
                (0.0, [1.0; 3]),
                (1.0, [m[0] as f32, m[1] as f32, m[2] as f32]),
            ]),
            ..Default::default()
        };
        let camera = axial();
        let colour = [1.0, 0.8, 0.6];
        let ref_step = vol.min_voxel_size() as f64;
        for towards in [Vec3::Z, Vec3::new(0.25, 0.1, 1.0)] {
            let opts = options(32, towards, colour);
            let p = planes(&vol, &camera, &opts).unwrap();
            let depth = p.depth(p.count - 1);
            let img =
                trace_irradiance(&vol, &tf, &camera, &opts, depth, &popts(16, false)).unwrap();
            let (eye, forward, right, up) = camera.frame();
            let travel = -towards.normalize().as_dvec3();
            let half = DVec3::splat(0.5);
            // Path length through the box of the straight line through a point of the plane.
            let path = |ux: f64, uy: f64| {
                let t = ((camera.fov_y as f64).to_radians() * 0.5).tan();
                let (nx, ny) = (2.0 * ux - 1.0, 2.0 * uy - 1.0);
                let q = eye.as_dvec3()
                    + depth as f64
                        * (forward.as_dvec3() + nx * t * right.as_dvec3() - ny * t * up.as_dvec3());
                let (t0, t1) = ray_box(q, -travel, -half, half);
                if t0 < t1 {
                    t1 - t0
                } else {
                    0.0
                }
            };
            let mut tested = 0;
            let mut worst = 0.0f64;
            for y in 0..32 {
                for x in 0..32 {
                    let (fx, fy) = (x as f64, y as f64);
                    let l = path((fx + 0.5) / 32.0, (fy + 0.5) / 32.0);
                    let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                        .map(|(a, b)| path((fx + a) / 32.0, (fy + b) / 32.0));
                    if l < 0.9 || corners.iter().any(|c| (c - l).abs() > 1e-9) {
                        continue;
                    }
                    tested += 1;
                    let px = img.pixel(x, y);
                    for c in 0..3 {
                        let want = colour[c] as f64 * ((1.0 - alpha) * m[c]).powf(l / ref_step);
                        let rel = (px[c] as f64 / want - 1.0).abs();
                        worst = worst.max(rel);
                        assert!(rel < 0.01, "pixel {x},{y} channel {c}: {} vs {want}", px[c]);
                    }
                }
            }
            assert!(tested > 100, "only {tested} pixels behind the slab");
            eprintln!("Beer-Lambert, light {towards:?}: {tested} pixels, worst {worst:.2e}");
        }
    }

    fn ball(n: u32, radius: f64, ramp_voxels: f64) -> Volume {
        let w = ramp_voxels / n as f64;
        f32_volume(n, |p| {
            (0.5 + (radius - p.length()) / w).clamp(0.0, 1.0) as f32
        })
    }

    fn glass() -> TransferFunctions {
        TransferFunctions {
            eta: Piecewise::new(vec![(0.0, [1.0]), (1.0, [1.5])]),
            ..Default::default()
        }
    }

    #[test]
    fn glass_ball_conserves_power_and_focuses_paraxially() {
        let camera = axial();
        let colour = [1.0, 0.7, 0.4];
        let r = 0.3;
        let depth = 2.2 + 0.4; // 0.1 behind the ball, inside the box, before the focus
        let tanf = (35.0f64.to_radians() * 0.5).tan();
        let pix = 2.0 * depth as f64 * tanf / 32.0;
        let opts = options(32, Vec3::Z, colour);
        let vol = ball(32, r, 2.0);
        // Power: a glass ball (1.5) in water (1.33). In air, rays grazing the 2-voxel ramp
        // orbit in it (η r has a maximum there) and some leave backwards; with the smaller
        // index step none can, so every photon must land (no absorption anywhere).
        let water = TransferFunctions {
            eta: Piecewise::new(vec![(0.0, [1.33]), (1.0, [1.5])]),
            ..Default::default()
        };
        let img = trace_irradiance(&vol, &water, &camera, &opts, depth, &popts(16, false)).unwrap();
        assert_eq!((img.absorbed, img.backward, img.lost), (0, 0, 0));
        let (mut total, mut disc, mut disc_px, mut peak) = (0.0, 0.0, 0usize, 0.0f32);
        for y in 0..32 {
            for x in 0..32 {
                let e = img.pixel(x, y)[1] as f64 * pix * pix;
                total += e;
                let c = DVec3::new(x as f64 - 15.5, y as f64 - 15.5, 0.0) * pix;
                if c.length() < r + 2.0 * pix {
                    disc += e;
                    disc_px += 1;
                } else {
                    let rel = img.pixel(x, y)[1] / colour[1] - 1.0;
                    assert!(rel.abs() < 1e-4, "straight light at {x},{y}: {rel}");
                }
                peak = peak.max(img.pixel(x, y)[1]);
            }
        }
        let incident = colour[1] as f64 * 32.0 * 32.0 * pix * pix;
        let incident_disc = colour[1] as f64 * disc_px as f64 * pix * pix;
        eprintln!(
            "power in water: viewport {:.3e}, disc {:.3e}, peak {:.2}",
            total / incident - 1.0,
            disc / incident_disc - 1.0,
            peak / colour[1]
        );
        assert!((total / incident - 1.0).abs() < 0.01);
        assert!((disc / incident_disc - 1.0).abs() < 0.01);
        assert!(
            peak > 1.5 * colour[1],
            "the ball must focus light: peak {peak}"
        );

        // In air: the flux that lands plus the photons that turned back is the incident
        // flux (up to rim rays bent out of the viewport), and only rays through the ramp
        // (R - w/2 < |y| < R + w/2 + 1 voxel of trilinear support) can turn back.
        let tf = glass();
        let img = trace_irradiance(&vol, &tf, &camera, &opts, depth, &popts(16, false)).unwrap();
        assert_eq!((img.absorbed, img.lost), (0, 0));
        let cell = pix * pix / 16.0;
        let landed: f64 = img.pixels.iter().map(|p| p[1] as f64 * pix * pix).sum();
        let back = img.backward as f64 * cell * colour[1] as f64;
        let ring = std::f64::consts::PI * ((r + 3.0 / 32.0).powi(2) - (r - 1.0 / 32.0).powi(2));
        eprintln!(
            "air: {} photons turned back ({:.1} % of the ramp ring), balance {:.2e}",
            img.backward,
            100.0 * back / (colour[1] as f64 * ring),
            (landed + back) / incident - 1.0
        );
        assert!(img.backward > 0 && back < colour[1] as f64 * ring);
        assert!(((landed + back) / incident - 1.0).abs() < 0.01);

        // Focus: 64³ ball in air, near-axis rays; paraxial focus n D / (4 (n - 1)) from
        // the centre. The trilinear field's gradient across the axis is constant within
        // each cell between voxel centres (the cell centred on the axis is flat: no
        // bending within half a voxel of it), so heights are chosen where the ray meets
        // both surfaces at cell centres: entering at 3 (6) voxels, a paraxial ray leaves
        // at 1 (2), since the front surface alone focuses 3R inside the glass. (Entering
        // at 1 or 2 voxels gives 0.496 and 0.431.) Spherical aberration of a sharp ball at
        // these heights: -0.7 % and -2.8 %.
        let vol = ball(64, r, 2.0);
        let field = Field::new(&vol, &tf, &opts).unwrap();
        let want = 1.5 * 2.0 * r / (4.0 * 0.5);
        for y in [3.0f32 / 64.0, 6.0 / 64.0] {
            let end = field
                .trace_ray(&camera, Vec3::new(0.0, y, 0.6), -Vec3::Z, 2.2 + 0.35, 0.1)
                .unwrap()
                .expect("reaches the plane");
            let (p, d) = (end.position.as_dvec3(), end.direction.as_dvec3());
            assert!(d.y < 0.0, "bent towards the axis: {d:?}");
            let cross = -(p.z - p.y / d.y * d.z);
            eprintln!(
                "ray at height {y}: crosses the axis {cross:.5} from the centre ({:+.2} % from \
                 the paraxial {want})",
                100.0 * (cross / want - 1.0)
            );
            assert!((cross / want - 1.0).abs() < 0.02, "focus {cross} vs {want}");
        }
    }

    #[test]
    fn one_cell_gradient_equals_the_six_lookups() {
        let vol = ball(16, 0.3, 2.0);
        let field = Field::new(&vol, &glass(), &RenderOptions::default()).unwrap();
        let mut fast = 0;
        for i in 0..4000u64 {
            let u = [0, 1, 2].map(|k| uniform(splitmix(i * 3 + k)) - 0.5);
            let t = field.tex(DVec3::from(u) * 1.1);
            if let Some(g) = field.grad_eta_in_cell(t) {
                fast += 1;
                let mut slow = DVec3::ZERO;
                for k in 0..3 {
                    let h = GRADIENT_STEP / 16.0;
                    let mut e = DVec3::ZERO;
                    e[k] = h;
                    slow[k] = (lut(&field.eta, field.value_tex(t + e))
                        - lut(&field.eta, field.value_tex(t - e)))
                        / (2.0 * h)
                        * field.tex_per_world[k];
                }
                assert!(
                    (g - slow).length() <= 1e-9 * (1.0 + slow.length()),
                    "{g} vs {slow}"
                );
            }
        }
        assert!(fast > 2000, "{fast}");
    }

    #[test]
    fn plane_numbers_out_of_range_are_errors() {
        let vol = f32_volume(16, |_| 0.0);
        let opts = options(8, Vec3::Z, [1.0; 3]);
        let p = planes(&vol, &axial(), &opts).unwrap();
        assert!(plane_depth(&vol, &axial(), &opts, p.count - 1).is_ok());
        let e = plane_depth(&vol, &axial(), &opts, p.count)
            .unwrap_err()
            .to_string();
        assert!(e.contains(&format!("0..{}", p.count - 1)), "{e}");
    }

    /// Measurements quoted in the module documentation (release build:
    /// `cargo test --release --lib photons::tests::measure -- --ignored --nocapture`).
    #[test]
    #[ignore]
    fn measure_tracer_error() {
        let tf = glass();
        let camera = axial();
        let opts = options(64, Vec3::new(0.2, 0.1, 1.0), [1.0; 3]);
        // Focus against the step.
        let vol = ball(64, 0.3, 2.0);
        let field = Field::new(&vol, &tf, &opts).unwrap();
        for step in [0.05f32, 0.1, 0.2, 0.4] {
            let end = field
                .trace_ray(
                    &camera,
                    Vec3::new(0.0, 3.0 / 64.0, 0.6),
                    -Vec3::Z,
                    2.55,
                    step,
                )
                .unwrap()
                .unwrap();
            let (p, d) = (end.position.as_dvec3(), end.direction.as_dvec3());
            eprintln!("step {step}: focus {:.6}", -(p.z - p.y / d.y * d.z));
        }
        // Jittered noise in the open.
        let empty = f32_volume(32, |_| 0.0);
        let img = trace_irradiance(
            &empty,
            &TransferFunctions::default(),
            &camera,
            &opts,
            2.5,
            &popts(64, true),
        )
        .unwrap();
        let rms = (img
            .pixels
            .iter()
            .map(|p| (p[0] as f64 - 1.0).powi(2))
            .sum::<f64>()
            / img.pixels.len() as f64)
            .sqrt();
        eprintln!("jittered, 64 ppp: RMS {rms:.4}");
        // Caustic convergence against photons per pixel.
        let vol = ball(64, 0.3, 2.0);
        let depth = 2.2 + 0.45;
        let reference =
            trace_irradiance(&vol, &tf, &camera, &opts, depth, &popts(1024, true)).unwrap();
        eprintln!("reference: {:.1} s", reference.seconds);
        let mean = reference.pixels.iter().map(|p| p[0] as f64).sum::<f64>()
            / reference.pixels.len() as f64;
        for ppp in [4, 16, 64, 256] {
            let img = trace_irradiance(
                &vol,
                &tf,
                &camera,
                &opts,
                depth,
                &PhotonOptions {
                    seed: 7,
                    ..popts(ppp, true)
                },
            )
            .unwrap();
            let rms = (img
                .pixels
                .iter()
                .zip(&reference.pixels)
                .map(|(a, b)| (a[0] as f64 - b[0] as f64).powi(2))
                .sum::<f64>()
                / img.pixels.len() as f64)
                .sqrt();
            eprintln!(
                "{ppp} ppp: RMS difference {:.4} of mean {mean:.3} ({:.2} %), {:.2} s, steep {}",
                rms,
                100.0 * rms / mean,
                img.seconds,
                img.steep
            );
        }
    }
}
