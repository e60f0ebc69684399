//! The interface between the renderer and its optical models. Each model lives in its own
//! folder (`ea/`, `refract/`) and reaches the renderer through three things only:
//!
//! - [`Inputs`]: the GPU resources every model may read (volume, transfer functions,
//!   preintegration table, gradient volume, environment), owned by the renderer and
//!   rebuilt there when the data changes;
//! - [`ModelPass`]: the model's own images and pipelines for one output size, which record
//!   a frame into a [`FrameTarget`];
//! - the three functions below ([`check`], [`needs_gradient`], [`make_pass`]): the only
//!   place that matches on [`Model`] to pick a model's code.
//!
//! A new model (ambient occlusion, single scattering, ambient scattering, the eikonal
//! tracer) adds a folder with a `check` and a `ModelPass`, a [`Model`] variant and one arm
//! in each function here; the CLI, viewer and benchmark go on calling
//! [`super::Renderer::render`] / [`super::Renderer::record`] with the variant.

use anyhow::{bail, ensure, Result};

use super::refract::{EnvInputs, SweepRecording};
use super::{
    ambient, ao, ea, march, refract, single, Camera, FrameTarget, Model, RenderOptions, VolumeInfo,
};
use crate::vk::{Context, Image, Recorder, Sampler};

/// The renderer's GPU resources, as every model sees them, and the frame asked for.
pub(crate) struct Inputs<'a> {
    pub camera: &'a Camera,
    /// Already checked (see [`check`]).
    pub opts: &'a RenderOptions,
    /// The frame will be read back by the same submission (counters and dumps may be
    /// copied out).
    pub read_back: bool,
    pub ctx: &'a Context,
    pub info: VolumeInfo,
    /// The scalar volume (R16/R32, linear filtering, texture coordinates over the box).
    pub volume: &'a Image,
    /// The smoothed gradient volume, if a model that needs it asked for it and it fits.
    pub gradient: Option<&'a Image>,
    /// The value ranges per brick (render::value_ranges), built with the gradient volume
    /// for the models that need that.
    pub value_ranges: Option<&'a Image>,
    /// The field texture (value, ∇η; render::field), if the sweep may use it.
    pub field: Option<&'a Image>,
    /// The extinction volume and its 3D SAT, if the model needs them (ambient models).
    pub extinction: Option<&'a super::extinction::Extinction>,
    /// The single-scattering model's transmittance cache, if it needs it.
    pub transmittance: Option<&'a super::single::TransmittanceCache>,
    /// The ambient-scattering model's preintegrated tables, if it needs them.
    pub ambient_table: Option<&'a ambient::TableTextures>,
    /// The transfer functions as a 1D-per-row image.
    pub tf: &'a Image,
    /// Whether their η function has an interior extremum (films; the sweep's films).
    pub eta_films: bool,
    pub preint: &'a Image,
    pub linear: &'a Sampler,
    /// How the models that classify samples read the volume: `linear`, or nearest for a
    /// label volume ([`crate::volume::Volume::labels`]: no blend between two labels).
    pub volume_sampler: &'a Sampler,
    pub env: EnvInputs<'a>,
}

/// What a recorded frame leaves for after its submission.
pub(crate) struct Recorded {
    /// Samples along the longest ray (ray marchers) or planes (the sweep).
    pub max_steps: u32,
    /// The sweep's statistics and the buffers its dumps and counters are read back from.
    pub sweep: Option<SweepRecording>,
}

/// One model's images and pipelines, made for one output size.
pub(crate) trait ModelPass: Send {
    /// Whether this pass can record frames asked for with `opts` (size, ray budget), or
    /// must be made anew.
    fn fits(&self, opts: &RenderOptions) -> bool;

    /// Record the frame `inputs` ask for into [`ModelPass::output`].
    fn record(&mut self, rec: &mut Recorder, inputs: &Inputs) -> Result<Recorded>;

    /// The finished frame (linear RGBA32F) once a recording has run.
    fn output(&self) -> &FrameTarget;
}

/// What `model` refuses beyond the checks every model shares (camera, options, steps).
pub(crate) fn check(
    model: Model,
    info: VolumeInfo,
    camera: &Camera,
    opts: &RenderOptions,
) -> Result<()> {
    let support = model.light_support();
    if support.max > 0 {
        ensure!(
            opts.lights.len() <= support.max,
            "{} lights given; the {} model takes {}{}",
            opts.lights.len(),
            model.name(),
            if support.max == 1 {
                "one".to_string()
            } else {
                format!("at most {}", support.max)
            },
            if support.max == 1 {
                " (several lights are the ambient-scattering model's: --model ambient)"
            } else {
                ""
            }
        );
        if let Some((i, l)) = opts
            .lights
            .iter()
            .enumerate()
            .find(|(_, l)| l.is_point() && !support.point)
        {
            bail!(
                "light {} is a {}: the {} model takes directional lights only (point \
                 lights are the ambient-scattering model's: --model ambient)",
                i + 1,
                l.describe(),
                model.name()
            );
        }
    }
    match model {
        Model::Ea | Model::Ao | Model::Single | Model::Ambient => march::check(model, opts),
        Model::Refract => refract::check_model(info, camera, opts),
    }
}

/// Whether `model` reads the gradient volume (built on its first frame).
pub(crate) fn needs_gradient(model: Model) -> bool {
    match model {
        Model::Ea | Model::Ao | Model::Single | Model::Ambient => false,
        Model::Refract => true,
    }
}

/// Whether `model` reads the extinction volume (built on its first frame, rebuilt with
/// the transfer functions), and whether it needs its 3D SAT too.
pub(crate) fn needs_extinction(model: Model) -> Option<bool> {
    match model {
        Model::Ao | Model::Ambient => Some(true),
        Model::Single => Some(false),
        Model::Ea | Model::Refract => None,
    }
}

/// Make `model`'s pass for the frames `opts` asks for.
pub(crate) fn make_pass(model: Model, inputs: &Inputs) -> Result<Box<dyn ModelPass>> {
    let opts = inputs.opts;
    Ok(match model {
        Model::Ea => Box::new(ea::EaPass::new(inputs, opts.width, opts.height)?),
        Model::Ao => Box::new(ao::AoPass::new(inputs, opts.width, opts.height)?),
        Model::Single => Box::new(single::SinglePass::new(inputs, opts.width, opts.height)?),
        Model::Ambient => Box::new(ambient::AmbientPass::new(inputs, opts.width, opts.height)?),
        Model::Refract => Box::new(refract::SweepPass::new(
            inputs,
            opts.width,
            opts.height,
            opts.sweep.light_rays,
        )?),
    })
}
