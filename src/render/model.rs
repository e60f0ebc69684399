//! The interface between the renderer and its optical models. Each model lives in its own
//! folder (`ea/`, `ao/`, `single/`, `ambient/`, `refract/`) and reaches the renderer
//! through three things only:
//!
//! - [`Inputs`]: the GPU resources every model may read (volume, transfer functions,
//!   preintegration table, gradient volume, environment), owned by the renderer and
//!   rebuilt there when the data changes;
//! - [`ModelPass`]: the model's own images and pipelines for one output size, which record
//!   a frame into a [`FrameTarget`];
//! - [`OpticalModel`]: what the model declares from its folder (name, lights, the shared
//!   data it reads, its checks, its pass), one `static` per model, listed once in
//!   render/registry.rs ([`Model::declaration`]).
//!
//! A new model adds a folder with its declaration and its `ModelPass`, a [`Model`] variant
//! and its line in the registry; the CLI, viewer and benchmark go on calling
//! [`super::Renderer::render`] / [`super::Renderer::record`] with the variant. (Its own
//! options, flags and scene keys are not declared from its folder yet: issue 34 item 1.)

use anyhow::{bail, ensure, Result};

use super::extinction::Extinction;
use super::model_options::ModelOption;
use super::target::EnvInputs;
use super::{Camera, FrameTarget, LightSupport, Model, RenderOptions, VolumeInfo};
use super::{Dump, SweepStats};
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
    /// The model's own persistent data ([`OpticalModel::state`]), if it has any.
    pub state: Option<&'a dyn ModelState>,
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

impl<'a> Inputs<'a> {
    /// The model's own state as its type `S`, or an error naming what is missing.
    pub fn state<S: ModelState>(&self) -> Result<&'a S> {
        self.state
            .and_then(|s| s.as_any().downcast_ref::<S>())
            .ok_or_else(|| anyhow::anyhow!("the model's state is missing or of another model"))
    }
}

/// What the renderer owns that a model's state may be made from and kept up to date with.
pub(crate) struct Shared<'a> {
    pub ctx: &'a Context,
    pub info: VolumeInfo,
    /// The extinction volume, for a model that declared it ([`OpticalModel::extinction`]).
    pub extinction: Option<&'a Extinction>,
    pub linear: &'a Sampler,
    /// The scalar volume and how the models read it, the transfer functions' image, and
    /// how many times they have been replaced (a state made from them compares it).
    pub volume: &'a Image,
    pub volume_sampler: &'a Sampler,
    pub tf: &'a Image,
    pub tf_changes: u64,
    /// Where work that runs outside a frame's recording and can take long (the eikonal
    /// light simulation) reports how far it is ([`super::Renderer::set_build_progress`]).
    pub progress: Option<&'a super::BuildProgress>,
}

/// A model's own persistent data, kept across frames and shared by the viewer's slots
/// (the single-scattering model's transmittance cache, the ambient-scattering model's
/// tables): made on the model's first frame by [`OpticalModel::state`] and kept up to
/// date by the two hooks, so that the renderer knows no model's data by name.
pub(crate) trait ModelState: std::any::Any + Send {
    /// Outside any recording, before a frame asked for with `opts`: load or make what it
    /// needs. True when what the passes bind changed (the renderer then remakes them).
    fn prepare(&mut self, _shared: &Shared, _opts: &RenderOptions) -> Result<bool> {
        Ok(false)
    }
    /// In the frame's recording, before the model's pass: rebuild what changed.
    fn record_update(
        &mut self,
        _rec: &mut Recorder,
        _shared: &Shared,
        _opts: &RenderOptions,
    ) -> Result<()> {
        Ok(())
    }
    /// The GPU timings of what `prepare` ran since the last frame took them (a frame's
    /// timings begin with them).
    fn take_timings(&mut self) -> crate::vk::Timings {
        crate::vk::Timings::default()
    }
    /// Device bytes it holds (counted against the budget the extinction volume shares).
    fn bytes(&self) -> u64 {
        0
    }
    /// The statistics of its last light simulation, one per light (the eikonal light
    /// volume's), if it simulates light.
    fn simulation_stats(&self) -> &[super::light_simulator::SimulationStats] {
        &[]
    }
    fn as_any(&self) -> &dyn std::any::Any;
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any;
}

/// What a recorded frame leaves for after its submission.
pub(crate) struct Recorded {
    /// Samples along the longest ray (ray marchers) or planes (the sweep).
    pub max_steps: u32,
    /// What the model's frame leaves to read back (the sweep's statistics, counters and
    /// dumps); None for a model that leaves nothing.
    pub readback: Option<Box<dyn FrameReadback>>,
}

/// What a model's frame leaves to read once its submission has completed, behind a
/// trait so that the renderer does not know the model's recording by type.
pub(crate) trait FrameReadback: Send {
    /// The frame's statistics and state dumps, read from the buffers the recording
    /// copied them into (`width` × `height`: the frame's size).
    fn read(self: Box<Self>, width: u32, height: u32) -> Result<(Option<SweepStats>, Vec<Dump>)>;
    /// The statistics as recorded, reading nothing back (the viewer's frames, whose
    /// submissions are still in flight).
    fn unread(self: Box<Self>) -> Option<SweepStats>;
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

/// What an optical model declares, from its own folder (a `static`): its name, the
/// lights it takes, what it reads of the renderer's shared data, what it refuses, and its
/// pass. The one list of models is [`Model::declaration`] (render/registry.rs).
pub(crate) struct OpticalModel {
    /// The name `--model`, scene files and reports use.
    pub name: &'static str,
    /// One sentence for `--help`: what it renders and its own flags.
    pub summary: &'static str,
    /// How many lights it takes and whether point lights are among them.
    pub lights: LightSupport,
    /// More lights it takes with some of its settings (the sweep's eikonal light
    /// transport), if any.
    pub more_lights: Option<MoreLights>,
    /// Whether it has a phase function (a phase-function change applies).
    pub phase_function: bool,
    /// Whether it reads the gradient volume (built on its first frame).
    pub gradient: bool,
    /// Whether it reads the extinction volume (built on its first frame, rebuilt with the
    /// transfer functions), and whether it needs its 3D SAT too.
    pub extinction: Option<bool>,
    /// What it refuses beyond the checks every model shares (camera, options, steps, and
    /// the lights against `lights`); [`no_state_buffers`] for a model without the
    /// sweep's state.
    pub check: fn(&OpticalModel, VolumeInfo, &Camera, &RenderOptions) -> Result<()>,
    /// Its pass for the frames `inputs.opts` asks for.
    pub make_pass: fn(&Inputs) -> Result<Box<dyn ModelPass>>,
    /// Its own options ([`ModelOption`]: flag, scene key, default, check), each a
    /// `static` in its folder (or a shared one, as the scattering pair): the CLI and scene
    /// files offer them from here.
    pub options: &'static [&'static ModelOption],
    /// The other command-line flags it takes beyond those every model takes (camera,
    /// size, sampling, tone...) and the light's, which every lit model takes: the sweep's
    /// settings, the ambient table. With its options, the CLI refuses a flag given with a
    /// model that does not take it, naming the models that do.
    pub flags: &'static [&'static str],
    /// The timestamp scopes of what it rebuilds only when its inputs change (outside the
    /// frame's "render" scope; see `render::rebuild_scopes`).
    pub rebuild_scopes: &'static [&'static str],
    /// Its own persistent data, made on its first frame (after the extinction volume),
    /// with the device bytes it will take for a volume of this extent (checked against
    /// the budget first); None: it has none.
    pub state: Option<ModelStateDecl>,
    /// Why the model is left out of `bench models` (unless `--models` names it) and of
    /// the viewer's model key (too slow or too fragile yet to run unasked on every row),
    /// if it is; `render --model` and the viewer's list still offer it.
    pub experimental: Option<&'static str>,
}

/// The lights a model takes with some of its settings: [`OpticalModel::more_lights`].
pub(crate) struct MoreLights {
    pub lights: LightSupport,
    /// Whether these settings are given.
    pub when: fn(&RenderOptions) -> bool,
    /// The settings, as a user gives them ("--light-transport eikonal").
    pub how: &'static str,
}

/// How a model's state is made: [`OpticalModel::state`].
pub(crate) struct ModelStateDecl {
    /// What it is, for errors ("the transmittance cache").
    pub what: &'static str,
    /// Device bytes for a volume of this extent.
    pub bytes: fn([u32; 3]) -> u64,
    pub make: fn(&Shared) -> Result<Box<dyn ModelState>>,
}

/// The check of a model that has no state buffers (every ray marcher): dumps of them are
/// the sweep's.
pub(crate) fn no_state_buffers(
    model: &OpticalModel,
    _info: VolumeInfo,
    _camera: &Camera,
    opts: &RenderOptions,
) -> Result<()> {
    ensure!(
        opts.sweep.dumps.is_empty(),
        "state-buffer dumps are the refractive sweep's (--model refract); the {} ray \
         marcher has no state buffers",
        model.name
    );
    Ok(())
}

/// What `model` refuses beyond the checks every model shares (camera, options, steps).
pub(crate) fn check(
    model: Model,
    info: VolumeInfo,
    camera: &Camera,
    opts: &RenderOptions,
) -> Result<()> {
    let declared = model.declaration();
    let support = match &declared.more_lights {
        Some(more) if (more.when)(opts) => more.lights,
        _ => declared.lights,
    };
    // What the model would take with other settings, for the refusals.
    let other = declared.more_lights.as_ref().filter(|m| !(m.when)(opts));
    let more = other
        .map(|m| format!("; with {} it takes up to {}", m.how, m.lights.max))
        .unwrap_or_default();
    let more_point = other
        .filter(|m| m.lights.point)
        .map(|m| format!("; with {} it takes point lights too", m.how))
        .unwrap_or_default();
    if support.max > 0 {
        ensure!(
            opts.lights.len() <= support.max,
            "{} lights given; the {} model takes {}{}{more}",
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
                 lights are the ambient-scattering model's: --model ambient){more_point}",
                i + 1,
                l.describe(),
                model.name()
            );
        }
    }
    (declared.check)(declared, info, camera, opts)
}
