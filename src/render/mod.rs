//! The renderer: GPU resources for a volume and its transfer functions, and the passes that
//! turn them into an image. Passes are built from `crate::vk` pieces; nothing here calls
//! raw Vulkan.

//!
//! Layout: the renderer's shared inputs (uploads, preintegration table, gradient volume,
//! environment SAT) are files here; each optical model is a folder (`ea/`, `refract/`)
//! behind the interface in `model.rs`, declared in `registry.rs` (the one place that
//! lists the models; re-exported here, so `render::ao` is the folder `render/ao/`).

mod cached;
pub mod extinction;
pub mod field;
pub mod gradient;
pub mod light_simulator;
/// Limits shared with the shaders (build.rs defines each as a GLSL macro).
pub mod limits;
mod march;
mod model;
mod model_options;
mod options;
pub mod preintegration;
pub mod ray_equation;
mod registry;
pub mod sat;
pub mod sat3d;
mod shared;
mod target;
mod tonemap;
pub mod upload;
pub mod value_ranges;

use std::collections::HashMap;

use anyhow::{bail, ensure, Result};

use glam::Vec3;
use model::{Inputs, ModelPass, Recorded};

pub use crate::camera::Camera;
use crate::environment::EnvironmentMap;
use crate::transfer::TransferFunctions;
use crate::vk::{
    self, Buffer, Context, Filter, Image, ImageDesc, ImageKind, Recorder, Sampler, Timings,
};
use crate::volume::Volume;
pub use model_options::{declared_options, find_option, ModelOption, ModelOptions};
pub use options::*;
// The registry: `Model`, `LightSupport` and the models' folders (`render::ao`, ...).
pub use registry::*;
pub use sat::SummedAreaTable;

pub use preintegration::{PreintegrationTable, TABLE_SIZE};
pub use refract::{
    Clamps, Deposit, Dump, Gather, Levers, Light, LightTransport, PlaneBatch, Planes, Region,
    Splat, StateBuffer, SweepOptions, SweepPath, SweepStats, MAX_ETA_SCALE, MAX_LIGHT_RAYS,
    MAX_LIGHT_SPACING,
};
pub(crate) use target::FrameTarget;
use target::{EnvInputs, Environment};
pub use tonemap::ToneMapPass;

/// The timestamp scopes of what the renderer itself rebuilds only when its inputs change
/// (volume, transfer functions, environment), outside a frame's "render" scope; the
/// models declare their own ([`rebuild_scopes`]).
const SHARED_REBUILD_SCOPES: [&str; 7] = [
    "gradient volume",
    "value ranges",
    "environment SAT",
    "preintegration",
    "field texture",
    extinction::EXTINCTION_SCOPE,
    sat3d::SCOPE,
];

/// The timestamp scopes of everything rebuilt only when its inputs change (volume,
/// transfer functions, environment, light), outside a frame's "render" scope: the
/// renderer's and every model's (`OpticalModel::rebuild_scopes`). What a
/// transfer-function or light change costs is the sum of these in the first frame after
/// it (nested scopes, like the SAT's per-axis ones, are not listed).
pub fn rebuild_scopes() -> Vec<&'static str> {
    let models = Model::ALL
        .iter()
        .flat_map(|m| m.declaration().rebuild_scopes.iter().copied());
    SHARED_REBUILD_SCOPES.into_iter().chain(models).collect()
}

/// GPU state for one volume and its transfer functions.
pub struct Renderer {
    ctx: Context,
    volume_info: VolumeInfo,
    volume_tex: Image,
    /// Built when the refractive sweep first needs it (the EA model does not), if it fits.
    gradient: Option<gradient::GradientVolume>,
    gradient_status: gradient::GradientStatus,
    gradient_budget: Option<u64>,
    gradient_timings: Timings,
    /// The value ranges per brick (render::value_ranges): the sweep's empty-space test for
    /// the light rays, built with the gradient volume (a few KB, always fits).
    value_ranges: Option<value_ranges::ValueRanges>,
    /// The field texture (value, ∇η) for the sweep's `field` lever: made with the gradient
    /// volume when it fits beside it, rebuilt with the transfer functions.
    field: Option<field::FieldTexture>,
    field_checked: bool,
    field_dirty: bool,
    /// The extinction volume and its 3D SAT, for the ambient models: made on their first
    /// frame, rebuilt with the transfer functions.
    extinction: Option<extinction::Extinction>,
    extinction_dirty: bool,
    /// Each model's own persistent data ([`model::OpticalModel::state`]: the
    /// single-scattering model's transmittance cache, the ambient-scattering model's
    /// tables), made on its first frame.
    states: HashMap<Model, Box<dyn model::ModelState>>,
    tf: TransferFunctions,
    tf_image: Image,
    tf_dirty: bool,
    /// Times the transfer functions were replaced (models' states compare it).
    tf_changes: u64,
    linear: Sampler,
    /// The volume's sampler for classification: linear, nearest for a label volume.
    volume_sampler: Sampler,
    preint: PreintegrationTable,
    /// Each model's pass per slot, made on its first frame there and again when the size
    /// changes.
    passes: HashMap<(Model, Slot), Box<dyn ModelPass>>,
    env: Environment,
    /// Hears how far long work outside a frame's recording is ([`Self::set_build_progress`]).
    build_progress: Option<std::sync::Arc<BuildProgress>>,
}

/// A listener for long work a frame waits for outside its recording (the eikonal light
/// simulation: one line per submission of cycles, e.g. "light simulation, light 1: cycle
/// 48 of at most 400, 20035 patches live").
pub type BuildProgress = dyn Fn(&str) + Send + Sync;

/// Which of a model's two passes a recording uses. A pass owns its images and pipelines
/// for one frame size; the viewer alternates reduced-size previews with full frames, and
/// with one pass per model each switch would rebuild it (pipelines, state images). Both
/// slots share everything else (volume, tables, environment).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Slot {
    /// The frames [`Renderer::render`] reads back and the viewer's full-quality frames.
    #[default]
    Main,
    /// The viewer's previews while the view changes, one slot per rung of its ladder
    /// (`viewer::preview`), so that a change of rung rebuilds nothing it has built before.
    Preview(u8),
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct VolumeInfo {
    pub half_extent: Vec3,
    pub ref_step: f32,
    pub dims: [u32; 3],
}

impl VolumeInfo {
    /// The voxels per axis as floats and `w`: the shaders' `RAY_DIMS` vec4, whose w is the
    /// refractive-index scale (glsl/ray_equation.glsl).
    pub fn dims_and(&self, w: f32) -> [f32; 4] {
        let [x, y, z] = self.dims.map(|d| d as f32);
        [x, y, z, w]
    }
}

impl Renderer {
    pub fn new(ctx: &Context, volume: &Volume, tf: &TransferFunctions) -> Result<Self> {
        let volume_tex = upload::volume_texture(ctx, volume)?;
        let tf_image = upload::transfer_texture(ctx, tf)?;
        let linear = Sampler::new(ctx, Filter::Linear, "linear clamp")?;
        let volume_sampler = if volume.labels {
            Sampler::new(ctx, Filter::Nearest, "label volume (nearest)")?
        } else {
            Sampler::new(ctx, Filter::Linear, "volume (linear)")?
        };
        let preint = PreintegrationTable::new(ctx, volume.labels)?;
        let (env, _) = Environment::new(ctx, None)?;
        let e = volume.normalised_extent();
        Ok(Self {
            ctx: ctx.clone(),
            volume_info: VolumeInfo {
                half_extent: Vec3::from(e) * 0.5,
                ref_step: volume.min_voxel_size(),
                dims: volume.dims,
            },
            volume_tex,
            gradient: None,
            gradient_status: gradient::GradientStatus::Unbuilt,
            gradient_budget: None,
            gradient_timings: Timings::default(),
            value_ranges: None,
            field: None,
            field_checked: false,
            field_dirty: false,
            extinction: None,
            extinction_dirty: false,
            states: HashMap::new(),
            tf: tf.clone(),
            tf_image,
            tf_dirty: true,
            tf_changes: 0,
            build_progress: None,
            linear,
            volume_sampler,
            preint,
            passes: HashMap::new(),
            env,
        })
    }

    /// Put an environment map behind the volume (`None`: the constant background). The
    /// summed-area table is rebuilt only when the map differs; returns the GPU time of that
    /// build ("environment SAT"), empty when nothing changed.
    pub fn set_environment(&mut self, map: Option<&EnvironmentMap>) -> Result<Timings> {
        let unchanged = match map {
            Some(m) => self.env.enabled && self.env.map == *m,
            None => !self.env.enabled,
        };
        if unchanged {
            return Ok(Timings::default());
        }
        // Descriptor sets name the old images.
        self.passes.clear();
        let (env, timings) = Environment::new(&self.ctx, map)?;
        self.env = env;
        Ok(timings)
    }

    pub fn context(&self) -> &Context {
        &self.ctx
    }

    /// Replace the transfer functions. The preintegration table is rebuilt on the next
    /// render only if they actually differ.
    pub fn set_transfer_functions(&mut self, tf: &TransferFunctions) -> Result<()> {
        if *tf != self.tf {
            upload::write_transfer_texture(&self.ctx, tf, &self.tf_image)?;
            self.tf = tf.clone();
            self.tf_dirty = true;
            self.tf_changes += 1;
            self.field_dirty = true;
            self.extinction_dirty = true;
        }
        Ok(())
    }

    pub fn transfer_functions(&self) -> &TransferFunctions {
        &self.tf
    }

    /// GPU time of the gradient volume's build (scope "gradient volume"; empty until the
    /// first refractive frame builds it). Built once per renderer: it depends on the
    /// volume only.
    pub fn gradient_timings(&self) -> &Timings {
        &self.gradient_timings
    }

    /// The statistics of `model`'s last light simulation, one per light: the eikonal
    /// model's, and the sweep's with `--light-transport eikonal`; empty for the others.
    pub fn light_simulation_stats(&self, model: Model) -> Vec<light_simulator::SimulationStats> {
        self.existing_model_state(model)
            .map(|s| s.simulation_stats().to_vec())
            .unwrap_or_default()
    }

    /// Whether the sweep has its gradient volume (or computes normals on the fly).
    pub fn gradient_status(&self) -> &gradient::GradientStatus {
        &self.gradient_status
    }

    /// Bytes the gradient volume (with its build's intermediate) may take instead of half
    /// the device's largest heap; takes effect before the first refractive frame. (Tests
    /// use it to run the fallback, normals on the fly, on any device.)
    pub fn set_gradient_budget(&mut self, bytes: u64) {
        self.gradient_budget = Some(bytes);
    }

    pub fn preintegration(&self) -> &PreintegrationTable {
        &self.preint
    }

    /// Rebuild the preintegration table now if the transfer functions changed; returns the
    /// GPU timings of the build (empty if nothing was rebuilt).
    pub fn update_preintegration(&mut self) -> Result<Timings> {
        if !self.tf_dirty {
            return Ok(Timings::default());
        }
        let (preint, tf) = (&mut self.preint, &self.tf);
        let t = self.ctx.execute(|rec| preint.record_build(rec, tf))?;
        self.tf_dirty = false;
        Ok(t)
    }

    /// Rebuild the field texture now if the transfer functions changed since its last
    /// build (and it exists: the first refractive frame makes it); returns the GPU timings
    /// of the build, scope "field texture" (empty if nothing was rebuilt).
    pub fn update_field(&mut self) -> Result<Timings> {
        let (Some(field), true) = (self.field.as_mut(), self.field_dirty) else {
            return Ok(Timings::default());
        };
        let (_volume, _tf) = (&self.volume_tex, &self.tf_image);
        let t = self.ctx.execute(|rec| field.record_build(rec))?;
        self.field_dirty = false;
        Ok(t)
    }

    /// Whether the sweep has its field texture (the `field` lever can take effect).
    pub fn has_field_texture(&self) -> bool {
        self.field.is_some()
    }

    /// The field texture read back (value, ∂η/∂x, ∂η/∂y, ∂η/∂z per voxel, x fastest; the
    /// gradient in texture units), if it exists and is built (for tests and diagnostics).
    pub fn read_field_texture(&mut self) -> Result<Option<Vec<[f32; 4]>>> {
        self.update_field()?;
        match &self.field {
            Some(f) if f.builds() > 0 => {
                let bytes = self.ctx.read_image(f.image(), 0)?;
                Ok(Some(bytemuck::cast_slice(&bytes).to_vec()))
            }
            _ => Ok(None),
        }
    }

    /// The value ranges read back (render::value_ranges), once a refractive frame built
    /// them: each brick's own (min, max) and the dilated ones the sweep reads, bricks x
    /// fastest (for tests and diagnostics).
    pub fn read_value_ranges(&self) -> Result<Option<[Vec<[f32; 2]>; 2]>> {
        let Some(r) = &self.value_ranges else {
            return Ok(None);
        };
        let read = |image: &Image| -> Result<Vec<[f32; 2]>> {
            let bytes = self.ctx.read_image(image, 0)?;
            let texels: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
            Ok(texels.iter().map(|t| [t[0], t[1]]).collect())
        };
        Ok(Some([read(r.bricks())?, read(r.image())?]))
    }

    /// Everything [`Renderer::render`] and [`Renderer::record`] would refuse for these
    /// arguments, checked without recording anything: camera, options, the step limit and,
    /// for the sweep, the light's side, the camera outside the box and dump planes.
    pub fn check(&self, model: Model, camera: &Camera, opts: &RenderOptions) -> Result<()> {
        camera.validate()?;
        opts.validate()?;
        let steps = steps_for(
            self.volume_info.half_extent,
            self.volume_info.ref_step,
            opts.sample_distance,
        );
        if steps > MAX_STEPS {
            bail!(
                "sample distance {} needs up to {steps} samples per ray, more than the limit \
                 of {MAX_STEPS}; use a larger sample distance",
                opts.sample_distance
            );
        }
        model::check(model, self.volume_info, camera, opts)
    }

    /// Where long work outside a frame's recording reports how far it is (the eikonal light
    /// simulation, which can take minutes on a CPU device: a line after each submission of
    /// its cycles); None: nowhere.
    pub fn set_build_progress(&mut self, progress: Option<std::sync::Arc<BuildProgress>>) {
        self.build_progress = progress;
    }

    /// Render one frame with `model` and read it back.
    pub fn render(&mut self, model: Model, camera: &Camera, opts: &RenderOptions) -> Result<Frame> {
        self.render_inner(model, camera, opts, None)
    }

    /// [`Renderer::render`], calling `observe` while the GPU works with the fraction of
    /// the frame done (the sweep's planes; a ray-marched model reports only 0 and 1). The
    /// same frame, with a timestamp between full barriers every 2 % of the planes.
    pub fn render_observed(
        &mut self,
        model: Model,
        camera: &Camera,
        opts: &RenderOptions,
        observe: &mut dyn FnMut(f64),
    ) -> Result<Frame> {
        self.render_inner(model, camera, opts, Some(observe))
    }

    fn render_inner(
        &mut self,
        model: Model,
        camera: &Camera,
        opts: &RenderOptions,
        observe: Option<&mut dyn FnMut(f64)>,
    ) -> Result<Frame> {
        self.prepare(model, camera, opts)?;
        // What the model's state ran outside the recording (the eikonal model's light
        // simulation) comes first in the frame's timings.
        let mut timings = self
            .states
            .get_mut(&model)
            .map(|s| s.take_timings())
            .unwrap_or_default();
        let ctx = self.ctx.clone();
        let mut recorded = None;
        let record = |rec: &mut Recorder| {
            let r = self.record_frame(
                rec,
                FrameAsk {
                    slot: Slot::Main,
                    model,
                    camera,
                    opts,
                    read_back: true,
                },
            )?;
            self.target(model, Slot::Main)?.record_copy(rec);
            recorded = Some(r);
            Ok(())
        };
        let frame_timings = match observe {
            Some(observe) => ctx.execute_observed(record, observe)?,
            None => ctx.execute(record)?,
        };
        timings.scopes.extend(frame_timings.scopes);
        let recorded: Recorded = recorded.expect("recorded by execute");
        let target = self.target(model, Slot::Main)?;
        let (width, height) = (opts.width, opts.height);
        let (sweep, dumps) = match recorded.readback {
            Some(r) => r.read(width, height)?,
            None => (None, Vec::new()),
        };
        Ok(Frame {
            width,
            height,
            pixels: target.pixels()?,
            timings,
            max_steps: recorded.max_steps,
            dumps,
            sweep,
        })
    }

    /// Record one frame with `model` into `rec` (the viewer's path; [`Renderer::render`]
    /// records exactly the same and then copies the image to the host). The finished
    /// frame, linear RGBA32F, is left in the returned image for later commands of the same
    /// recording (its barriers are tracked as usual). The preintegration table is rebuilt
    /// in the same recording if the transfer functions changed. Parameters travel in the
    /// command stream, so earlier frames may still be in flight; the caller keeps the
    /// renderer alive (and must not resize or replace its inputs) until they complete.
    /// State-buffer dumps need [`Renderer::render`]. `slot`: whose pass records it, so
    /// that the viewer's previews ([`Slot::Preview`]) and full frames ([`Slot::Main`])
    /// keep their own passes and switching between their sizes rebuilds nothing.
    pub fn record(
        &mut self,
        rec: &mut Recorder,
        slot: Slot,
        model: Model,
        camera: &Camera,
        opts: &RenderOptions,
    ) -> Result<RecordedFrame<'_>> {
        ensure!(
            opts.sweep.dumps.is_empty(),
            "state-buffer dumps are read back by Renderer::render, not recorded frames"
        );
        self.prepare(model, camera, opts)?;
        let r = self.record_frame(
            rec,
            FrameAsk {
                slot,
                model,
                camera,
                opts,
                read_back: false,
            },
        )?;
        Ok(RecordedFrame {
            image: &self.target(model, slot)?.image,
            max_steps: r.max_steps,
            sweep: r.readback.and_then(|r| r.unread()),
        })
    }

    /// The linear RGBA32F image the last frame recorded with `model` in `slot` finished
    /// in (the viewer tone maps it again after a frame submitted in batches).
    pub fn frame_image(&self, model: Model, slot: Slot) -> Result<&Image> {
        Ok(&self.target(model, slot)?.image)
    }

    fn target(&self, model: Model, slot: Slot) -> Result<&FrameTarget> {
        self.passes
            .get(&(model, slot))
            .map(|p| p.output())
            .ok_or_else(|| anyhow::anyhow!("no {} frame has been recorded", model.name()))
    }

    /// Drop `model`'s passes in both slots (their descriptor sets name inputs that change).
    fn remove_passes(&mut self, model: Model) {
        self.passes.retain(|(m, _), _| *m != model);
    }

    /// Outside any recording, before a frame: check what it asks for and make what the
    /// model reads that is missing (gradient, field, extinction volume, its state).
    fn prepare(&mut self, model: Model, camera: &Camera, opts: &RenderOptions) -> Result<()> {
        self.check(model, camera, opts)?;
        self.ensure_gradient(model)?;
        self.ensure_field(model, opts)?;
        self.ensure_extinction(model)?;
        self.ensure_state(model, opts)
    }

    /// The recording shared by `render` and `record`, after [`Self::prepare`].
    fn record_frame(&mut self, rec: &mut Recorder, ask: FrameAsk) -> Result<Recorded> {
        let FrameAsk {
            slot,
            model,
            camera,
            opts,
            read_back,
        } = ask;
        if self.tf_dirty {
            self.preint.record_build(rec, &self.tf)?;
            self.tf_dirty = false;
        }
        if let (Some(field), true) = (self.field.as_mut(), self.field_dirty) {
            field.record_build(rec)?;
            self.field_dirty = false;
        }
        if let (Some(e), true) = (self.extinction.as_mut(), self.extinction_dirty) {
            e.record_build(rec)?;
            self.extinction_dirty = false;
        }
        if let Some(state) = self.states.get_mut(&model) {
            let shared = model::Shared {
                ctx: &self.ctx,
                info: self.volume_info,
                extinction: self.extinction.as_ref(),
                linear: &self.linear,
                volume: &self.volume_tex,
                volume_sampler: &self.volume_sampler,
                tf: &self.tf_image,
                tf_changes: self.tf_changes,
                progress: self.build_progress.as_deref(),
            };
            state.record_update(rec, &shared, opts)?;
        }

        let inputs = Inputs {
            camera,
            opts,
            read_back,
            ctx: &self.ctx,
            info: self.volume_info,
            volume: &self.volume_tex,
            gradient: self.gradient.as_ref().map(|g| g.image()),
            value_ranges: self.value_ranges.as_ref().map(|r| r.image()),
            field: self.field.as_ref().map(|f| f.image()),
            extinction: self.extinction.as_ref(),
            state: self.states.get(&model).map(|s| s.as_ref()),
            tf: &self.tf_image,
            eta_films: self.tf.eta_has_films(),
            preint: self.preint.image(),
            linear: &self.linear,
            volume_sampler: &self.volume_sampler,
            env: EnvInputs {
                map: &self.env.image,
                sat: &self.env.sat.table,
                mean: self.env.sat.mean,
                enabled: self.env.enabled,
            },
        };
        let passes = &mut self.passes;
        let mut record = |rec: &mut Recorder| -> Result<Recorded> {
            let key = (model, slot);
            if !passes.get(&key).is_some_and(|p| p.fits(opts)) {
                // Free the old pass's images before making the new one.
                passes.remove(&key);
                passes.insert(key, (model.declaration().make_pass)(&inputs)?);
            }
            let pass = passes.get_mut(&key).expect("just made");
            pass.record(rec, &inputs)
        };
        // The benchmark's frame time: every pass and barrier of the frame, without a table
        // rebuild (only when the transfer functions change) and without the copy out.
        rec.begin_scope("render");
        let recorded = record(rec);
        rec.end_scope();
        recorded
    }
}

/// What a frame asks of [`Renderer::record_frame`]: whose pass records it, the model, the
/// camera and options (checked), and whether the same submission reads it back.
struct FrameAsk<'a> {
    slot: Slot,
    model: Model,
    camera: &'a Camera,
    opts: &'a RenderOptions,
    read_back: bool,
}

/// A frame recorded by [`Renderer::record`].
pub struct RecordedFrame<'a> {
    /// The finished frame, linear RGBA32F (sampled, storage and transfer-source usage).
    pub image: &'a Image,
    /// Samples along the longest ray (EA) or planes (sweep).
    pub max_steps: u32,
    /// Plane count and traffic of the sweep.
    pub sweep: Option<SweepStats>,
}
