//! What a frame is asked for and what it returns: the render options (size, sampling,
//! background, early termination, the lights, the models' options) and the frame.

use anyhow::{ensure, Context, Result};
use glam::Vec3;

use super::*;

/// Most samples (ray-marcher steps or sweep planes) one ray may take. Far more than any
/// useful sample distance needs (a 1024³ volume at sample distance 0.1 takes ~18k); it
/// stops a typo like 1e-9 from occupying the device for minutes or losing it.
pub const MAX_STEPS: u64 = 1 << 16;

/// Steps a ray through a box with this half extent takes at `sample_distance`.
pub fn steps_for(half_extent: Vec3, ref_step: f32, sample_distance: f32) -> u64 {
    let diag = 2.0 * half_extent.length() as f64;
    (diag / (sample_distance as f64 * ref_step as f64)).ceil() as u64
}

#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    /// Step between samples, in units of the smallest voxel side (thesis chapter 6).
    pub sample_distance: f32,
    /// Look segments up in the preintegration table instead of sampling the TF.
    pub preintegrated: bool,
    /// Linear RGBA behind the volume.
    pub background: [f32; 4],
    /// Stop marching once accumulated opacity reaches this (EA).
    pub termination_alpha: f32,
    /// Light, specular, clipping and diagnostics of the refractive model.
    pub sweep: SweepOptions,
    /// The models' declared options' values ([`super::ModelOption`]; the ambient-
    /// occlusion model's radius, the scattering models' phase function...), each model
    /// reading its own through its typed view ([`ScatterOptions::of`]).
    pub models: ModelOptions,
    /// The lights, the main one first (the only one of the models that take one; see
    /// [`Model::light_support`]): never empty, at most [`super::limits::MAX_LIGHTS`].
    pub lights: Vec<Light>,
}

/// How the scattering models' media scatter light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScatterOptions {
    /// Henyey–Greenstein anisotropy g in (−1, 1): 0 isotropic, > 0 forward scattering.
    pub g: f32,
    /// Scattering albedo Λ = σ_s / σ_t in [0, 1] (the transfer function's colour is the
    /// medium's scattering colour).
    pub albedo: f32,
}

/// Largest |g| of the phase function (at ±1 it is a delta: no longer a phase function a
/// table or a cache can hold).
pub const MAX_ANISOTROPY: f32 = 0.99;

impl Default for ScatterOptions {
    fn default() -> Self {
        // The declared defaults (the flags' and scene keys').
        Self {
            g: SCATTER_G.default as f32,
            albedo: SCATTER_ALBEDO.default as f32,
        }
    }
}

/// `--g` (scene key `g`): [`ScatterOptions::g`], an option of both scattering models.
pub static SCATTER_G: ModelOption = ModelOption {
    flag: "--g",
    value_name: "G",
    help: "Scattering: Henyey-Greenstein anisotropy of the phase function, -0.99 to 0.99; \
           0 isotropic, positive forward scattering",
    default: 0.0,
    integer: false,
    check: |v| {
        ScatterOptions {
            g: v as f32,
            ..Default::default()
        }
        .validate()
    },
};

/// `--albedo` (scene key `albedo`): [`ScatterOptions::albedo`], an option of both
/// scattering models.
pub static SCATTER_ALBEDO: ModelOption = ModelOption {
    flag: "--albedo",
    value_name: "ALBEDO",
    help: "Scattering: albedo, the fraction of the extinguished light that is scattered, \
           0-1",
    // Ament et al.'s table is built for an albedo of 0.9.
    default: 0.9,
    integer: false,
    check: |v| {
        ScatterOptions {
            albedo: v as f32,
            ..Default::default()
        }
        .validate()
    },
};

impl ScatterOptions {
    /// The scattering options `opts` asks for (the declared options' values).
    pub fn of(opts: &RenderOptions) -> Self {
        Self {
            g: opts.model_option(&SCATTER_G) as f32,
            albedo: opts.model_option(&SCATTER_ALBEDO) as f32,
        }
    }

    /// Ask these in `opts` (refused as the flags would be).
    pub fn set_in(&self, opts: &mut RenderOptions) -> Result<()> {
        opts.models.set(&SCATTER_G, self.g as f64)?;
        opts.models.set(&SCATTER_ALBEDO, self.albedo as f64)
    }

    pub fn validate(&self) -> Result<()> {
        ensure!(
            self.g.is_finite() && self.g.abs() <= MAX_ANISOTROPY,
            "phase-function anisotropy g = {} must be in [-{MAX_ANISOTROPY}, {MAX_ANISOTROPY}]",
            self.g
        );
        ensure!(
            self.albedo.is_finite() && (0.0..=1.0).contains(&self.albedo),
            "albedo {} must be in [0, 1] (a medium cannot scatter more light than it removes)",
            self.albedo
        );
        Ok(())
    }
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            sample_distance: 1.0,
            preintegrated: true,
            background: [0.08, 0.08, 0.1, 1.0],
            termination_alpha: 0.99,
            sweep: SweepOptions::default(),
            models: Default::default(),
            // The default camera's default light (thesis scenes set their own).
            lights: vec![Light::for_camera(&crate::camera::Camera::default())],
        }
    }
}

impl RenderOptions {
    /// The main light: the first of [`Self::lights`] (which `validate` keeps non-empty).
    pub fn light(&self) -> &Light {
        &self.lights[0]
    }

    /// The main light, to change.
    pub fn light_mut(&mut self) -> &mut Light {
        &mut self.lights[0]
    }

    pub fn validate(&self) -> Result<()> {
        if !(self.sample_distance.is_finite() && self.sample_distance > 0.0) {
            bail!(
                "sample distance must be a positive number, got {}",
                self.sample_distance
            );
        }
        ensure!(
            self.width > 0 && self.height > 0 && self.width <= 16384 && self.height <= 16384,
            "image size {}x{} must be between 1 and 16384 per side",
            self.width,
            self.height
        );
        ensure!(
            self.background.iter().all(|c| c.is_finite() && *c >= 0.0),
            "background colour {:?} must be finite and non-negative",
            self.background
        );
        ensure!(
            self.sweep
                .ambient
                .iter()
                .all(|c| c.is_finite() && *c >= 0.0),
            "ambient irradiance {:?} must be finite and non-negative",
            self.sweep.ambient
        );
        ensure!(
            (0.0..=1.0).contains(&self.termination_alpha),
            "termination alpha {} must be in [0, 1]",
            self.termination_alpha
        );
        ensure!(
            !self.lights.is_empty(),
            "no light given: every frame has at least its main light"
        );
        ensure!(
            self.lights.len() <= super::limits::MAX_LIGHTS,
            "{} lights given; at most {} (the ambient-scattering model's limit; the others \
             take one)",
            self.lights.len(),
            super::limits::MAX_LIGHTS
        );
        for (i, l) in self.lights.iter().enumerate() {
            l.validate().with_context(|| format!("light {}", i + 1))?;
        }
        self.sweep.validate()
    }
}

/// A rendered image: linear RGBA f32, row-major, top row first.
#[derive(Clone, Debug)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
    pub timings: Timings,
    /// Samples along the longest ray (EA) or planes (sweep), for reporting.
    pub max_steps: u32,
    /// State buffers the sweep was asked to copy out.
    pub dumps: Vec<Dump>,
    /// Plane count and traffic of the sweep.
    pub sweep: Option<SweepStats>,
}

impl Frame {
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixels[(y * self.width + x) as usize]
    }
}
