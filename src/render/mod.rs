//! The renderer: GPU resources for a volume and its transfer functions, and the passes that
//! turn them into an image. Passes are built from `crate::vk` pieces; nothing here calls
//! raw Vulkan.

mod ea;
pub mod gradient;
/// Limits shared with the shaders (build.rs defines each as a GLSL macro).
pub mod limits;
pub mod preintegration;
pub mod sat;
pub mod sweep;
mod tonemap;
pub mod upload;

use anyhow::{bail, ensure, Result};
use glam::Vec3;

pub use crate::camera::Camera;
use crate::environment::EnvironmentMap;
use crate::transfer::TransferFunctions;
use crate::vk::{
    self, Buffer, Context, Filter, Image, ImageDesc, ImageKind, Recorder, Sampler, Timings,
};
use crate::volume::Volume;
pub use sat::SummedAreaTable;

pub use preintegration::{PreintegrationTable, TABLE_SIZE};
pub use sweep::{
    Clamps, Dump, Light, LightTransport, Planes, StateBuffer, SweepOptions, SweepStats,
    MAX_ETA_SCALE,
};
pub use tonemap::ToneMapPass;

/// Rendering models `refrakt render --model` offers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// Emission–absorption ray marcher, the baseline.
    Ea,
    /// The refractive plane sweep (thesis ch. 4, Algorithm 1).
    Refract,
}

impl Model {
    pub fn name(self) -> &'static str {
        match self {
            Model::Ea => "ea",
            Model::Refract => "refract",
        }
    }
}

/// Most samples (ray-marcher steps or sweep planes) one ray may take. Far more than any
/// useful sample distance needs (a 1024³ volume at sample distance 0.1 takes ~18k); it
/// stops a typo like 1e-9 from occupying the device for minutes or losing it.
pub const MAX_STEPS: u64 = 1 << 16;

/// Steps a ray through a box with this half extent takes at `sample_distance`.
pub fn steps_for(half_extent: Vec3, ref_step: f32, sample_distance: f32) -> u64 {
    let diag = 2.0 * half_extent.length() as f64;
    (diag / (sample_distance as f64 * ref_step as f64)).ceil() as u64
}

#[derive(Clone, Debug)]
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
        }
    }
}

impl RenderOptions {
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
            (0.0..=1.0).contains(&self.termination_alpha),
            "termination alpha {} must be in [0, 1]",
            self.termination_alpha
        );
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
    tf: TransferFunctions,
    tf_image: Image,
    tf_dirty: bool,
    linear: Sampler,
    preint: PreintegrationTable,
    ea: Option<ea::EaPass>,
    sweep: Option<sweep::SweepPass>,
    env: Environment,
}

/// The environment map on the GPU with its summed-area table. A 2 × 1 black map stands in
/// when there is none, so the composite's descriptor set is always complete.
struct Environment {
    map: EnvironmentMap,
    image: Image,
    sat: SummedAreaTable,
    enabled: bool,
}

impl Environment {
    fn new(ctx: &Context, map: Option<&EnvironmentMap>) -> Result<(Self, Timings)> {
        let enabled = map.is_some();
        let map = match map {
            Some(m) => m.clone(),
            None => EnvironmentMap::constant(2, [0.0; 3])?,
        };
        let image = upload::environment_texture(ctx, &map)?;
        let (sat, timings) = SummedAreaTable::build(ctx, &map, &image)?;
        Ok((
            Self {
                map,
                image,
                sat,
                enabled,
            },
            timings,
        ))
    }
}

/// The RGBA32F image a pass writes its frame into, and the host buffer it is copied to.
pub(crate) struct FrameTarget {
    pub image: Image,
    readback: Buffer,
    pixels: usize,
}

impl FrameTarget {
    pub fn new(ctx: &Context, width: u32, height: u32, name: &str) -> Result<Self> {
        let image = Image::new(
            ctx,
            ImageDesc {
                kind: ImageKind::D2,
                format: vk::Format::R32G32B32A32_SFLOAT,
                extent: [width, height, 1],
                layers: 1,
                usage: vk::usage::STORAGE | vk::usage::SAMPLED | vk::usage::TRANSFER_SRC,
            },
            name,
        )?;
        let readback = Buffer::readback(ctx, image.layer_bytes()?, &format!("{name} readback"))?;
        Ok(Self {
            image,
            readback,
            pixels: width as usize * height as usize,
        })
    }

    /// Record the copy of the finished frame to the host.
    pub fn record_copy(&self, rec: &mut Recorder) {
        rec.copy_image_to_buffer(&self.image, 0, &self.readback);
    }

    /// The frame, once the submission that recorded the copy has completed.
    pub fn pixels(&self) -> Result<Vec<[f32; 4]>> {
        self.readback.read_values(self.pixels)
    }
}

/// Passes own images of the output size; keep one until the size changes.
trait SizedPass {
    fn size(&self) -> (u32, u32);
}

impl SizedPass for ea::EaPass {
    fn size(&self) -> (u32, u32) {
        ea::EaPass::size(self)
    }
}

impl SizedPass for sweep::SweepPass {
    fn size(&self) -> (u32, u32) {
        sweep::SweepPass::size(self)
    }
}

fn sized_pass<'a, P: SizedPass>(
    slot: &'a mut Option<P>,
    opts: &RenderOptions,
    make: impl FnOnce(u32, u32) -> Result<P>,
) -> Result<&'a mut P> {
    let size = (opts.width, opts.height);
    if slot.as_ref().map(|p| p.size()) != Some(size) {
        *slot = None;
        *slot = Some(make(size.0, size.1)?);
    }
    Ok(slot.as_mut().expect("just filled"))
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct VolumeInfo {
    pub half_extent: Vec3,
    pub ref_step: f32,
    pub dims: [u32; 3],
}

impl Renderer {
    pub fn new(ctx: &Context, volume: &Volume, tf: &TransferFunctions) -> Result<Self> {
        let volume_tex = upload::volume_texture(ctx, volume)?;
        let tf_image = upload::transfer_texture(ctx, tf)?;
        let linear = Sampler::new(ctx, Filter::Linear, "linear clamp")?;
        let preint = PreintegrationTable::new(ctx)?;
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
            tf: tf.clone(),
            tf_image,
            tf_dirty: true,
            linear,
            preint,
            ea: None,
            sweep: None,
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
        // The composite's descriptor set names the old images.
        self.sweep = None;
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
        if model == Model::Refract {
            // The sweep composites every segment from the preintegration table (thesis
            // sect. 4.3); sampling the transfer functions per step is the EA model's option.
            ensure!(
                opts.preintegrated,
                "sampling the transfer functions per step (no preintegration) is an option of \
                 the EA model (--model ea); the refractive sweep always integrates its \
                 segments with the preintegration table"
            );
            sweep::check(self.volume_info, camera, opts, &opts.sweep)?;
        }
        Ok(())
    }

    /// Render one frame with `model` and read it back.
    pub fn render(&mut self, model: Model, camera: &Camera, opts: &RenderOptions) -> Result<Frame> {
        self.check(model, camera, opts)?;
        self.ensure_gradient(model)?;
        let ctx = self.ctx.clone();
        let mut recorded = None;
        let timings = ctx.execute(|rec| {
            let r = self.record_inner(rec, model, camera, opts, true)?;
            self.target(model)?.record_copy(rec);
            recorded = Some(r);
            Ok(())
        })?;
        let mut recorded: Recorded = recorded.expect("recorded by execute");
        if let Some(s) = recorded.sweep.as_mut() {
            s.read_clamps()?;
        }
        let target = self.target(model)?;
        let (width, height) = (opts.width, opts.height);
        let dumps = match &recorded.sweep {
            Some(s) => s.read_dumps(width, height)?,
            None => Vec::new(),
        };
        Ok(Frame {
            width,
            height,
            pixels: target.pixels()?,
            timings,
            max_steps: recorded.max_steps,
            dumps,
            sweep: recorded.sweep.map(|s| s.stats),
        })
    }

    /// Record one frame with `model` into `rec` (the viewer's path; [`Renderer::render`]
    /// records exactly the same and then copies the image to the host). The finished
    /// frame, linear RGBA32F, is left in the returned image for later commands of the same
    /// recording (its barriers are tracked as usual). The preintegration table is rebuilt
    /// in the same recording if the transfer functions changed. Parameters travel in the
    /// command stream, so earlier frames may still be in flight; the caller keeps the
    /// renderer alive (and must not resize or replace its inputs) until they complete.
    /// State-buffer dumps need [`Renderer::render`].
    pub fn record(
        &mut self,
        rec: &mut Recorder,
        model: Model,
        camera: &Camera,
        opts: &RenderOptions,
    ) -> Result<RecordedFrame<'_>> {
        ensure!(
            opts.sweep.dumps.is_empty(),
            "state-buffer dumps are read back by Renderer::render, not recorded frames"
        );
        self.check(model, camera, opts)?;
        self.ensure_gradient(model)?;
        let r = self.record_inner(rec, model, camera, opts, false)?;
        Ok(RecordedFrame {
            image: &self.target(model)?.image,
            max_steps: r.max_steps,
            sweep: r.sweep.map(|s| s.stats),
        })
    }

    fn target(&self, model: Model) -> Result<&FrameTarget> {
        match model {
            Model::Ea => self.ea.as_ref().map(|p| p.output()),
            Model::Refract => self.sweep.as_ref().map(|p| p.output()),
        }
        .ok_or_else(|| anyhow::anyhow!("no {} frame has been recorded", model.name()))
    }

    /// Build the gradient volume if `model` needs it and it is not there yet: its own
    /// submission, waited for (once per volume; a caller's open recording is unaffected,
    /// it is submitted later).
    fn ensure_gradient(&mut self, model: Model) -> Result<()> {
        if model != Model::Refract || self.gradient_status != gradient::GradientStatus::Unbuilt {
            return Ok(());
        }
        let (needed, device_budget) =
            gradient::GradientVolume::memory(&self.ctx, self.volume_tex.extent());
        let budget = self.gradient_budget.unwrap_or(device_budget);
        if needed > budget {
            self.gradient_status = gradient::GradientStatus::TooLarge { needed, budget };
            return Ok(());
        }
        let (g, t) = gradient::GradientVolume::build(&self.ctx, &self.volume_tex, &self.linear)?;
        self.gradient = Some(g);
        self.gradient_status = gradient::GradientStatus::Built;
        self.gradient_timings = t;
        Ok(())
    }

    /// The recording shared by `render` and `record`; arguments already checked.
    fn record_inner(
        &mut self,
        rec: &mut Recorder,
        model: Model,
        camera: &Camera,
        opts: &RenderOptions,
        read_back: bool,
    ) -> Result<Recorded> {
        if self.tf_dirty {
            self.preint.record_build(rec, &self.tf)?;
            self.tf_dirty = false;
        }

        // The benchmark's frame time: every pass and barrier of the frame, without a table
        // rebuild (only when the transfer functions change) and without the copy out.
        rec.begin_scope("render");
        let recorded = self.record_passes(rec, model, camera, opts, read_back);
        rec.end_scope();
        recorded
    }

    fn record_passes(
        &mut self,
        rec: &mut Recorder,
        model: Model,
        camera: &Camera,
        opts: &RenderOptions,
        read_back: bool,
    ) -> Result<Recorded> {
        match model {
            Model::Ea => {
                let pass = sized_pass(&mut self.ea, opts, |w, h| {
                    ea::EaPass::new(
                        &self.ctx,
                        &self.volume_tex,
                        &self.tf_image,
                        self.preint.image(),
                        &self.linear,
                        w,
                        h,
                    )
                })?;
                let max_steps = pass.record(
                    rec,
                    self.volume_info,
                    camera,
                    opts,
                    &self.volume_tex,
                    &self.tf_image,
                    self.preint.image(),
                )?;
                Ok(Recorded {
                    max_steps,
                    sweep: None,
                })
            }
            Model::Refract => {
                let gradient = self.gradient.as_ref().map(|g| g.image());
                let env = sweep::EnvInputs {
                    map: &self.env.image,
                    sat: &self.env.sat.table,
                    mean: self.env.sat.mean,
                    enabled: self.env.enabled,
                };
                // The ray images are sized by the rays per pixel too.
                if self.sweep.as_ref().map(|p| p.rays_per_pixel()) != Some(opts.sweep.light_rays) {
                    self.sweep = None;
                }
                let pass = sized_pass(&mut self.sweep, opts, |w, h| {
                    sweep::SweepPass::new(
                        &self.ctx,
                        &self.volume_tex,
                        gradient,
                        &self.tf_image,
                        self.preint.image(),
                        &self.linear,
                        &env,
                        w,
                        h,
                        opts.sweep.light_rays,
                    )
                })?;
                let recording = pass.record(
                    rec,
                    &self.ctx,
                    self.volume_info,
                    self.volume_info.dims,
                    camera,
                    opts,
                    &opts.sweep,
                    [
                        &self.volume_tex,
                        gradient.unwrap_or(&self.volume_tex),
                        &self.tf_image,
                        self.preint.image(),
                    ],
                    &env,
                    read_back,
                )?;
                Ok(Recorded {
                    max_steps: recording.stats.planes.count,
                    sweep: Some(recording),
                })
            }
        }
    }
}

/// What [`Renderer::record_inner`] leaves for after the submission.
struct Recorded {
    max_steps: u32,
    sweep: Option<sweep::SweepRecording>,
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

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(azimuth: f32, elevation: f32, target: Vec3) -> Camera {
        Camera {
            azimuth,
            elevation,
            distance: 2.0,
            fov_y: 35.0,
            target,
        }
    }

    /// Screen position of `p` in units of the half field of view (0, 0 = image centre).
    fn project(c: &Camera, p: Vec3) -> (f32, f32) {
        let (eye, forward, right, up) = c.frame();
        let v = p - eye;
        let z = v.dot(forward);
        assert!(z > 0.0, "{p} is behind the camera");
        let t = (c.fov_y.to_radians() * 0.5).tan();
        (v.dot(right) / (z * t), v.dot(up) / (z * t))
    }

    fn assert_orthonormal_right_handed(c: &Camera) {
        let (_, f, r, u) = c.frame();
        for (n, v) in [("forward", f), ("right", r), ("up", u)] {
            assert!((v.length() - 1.0).abs() < 1e-6, "{n} {v} of {c:?}");
        }
        assert!(f.dot(r).abs() < 1e-6 && f.dot(u).abs() < 1e-6 && r.dot(u).abs() < 1e-6);
        assert!((r.cross(f) - u).length() < 1e-6, "{c:?}");
    }

    #[test]
    fn the_camera_orbits_and_looks_at_its_target() {
        let t = Vec3::new(0.3, -0.2, 0.1);
        let c = cam(40.0, 25.0, t);
        let (eye, forward, ..) = c.frame();
        assert!(((eye - t).length() - 2.0).abs() < 1e-5);
        assert!((forward - (t - eye).normalize()).length() < 1e-6);
        // Same orientation as the camera around the origin, translated by the target.
        let o = cam(40.0, 25.0, Vec3::ZERO);
        assert_eq!(c.frame().1, o.frame().1);
        assert!((eye - (o.eye() + t)).length() < 1e-6);
        let (x, y) = project(&c, t);
        assert!(x.abs() < 1e-6 && y.abs() < 1e-6);
        assert!(c.validate().is_ok());
        assert!(cam(0.0, 0.0, Vec3::new(f32::NAN, 0.0, 0.0))
            .validate()
            .is_err());
        assert!(cam(0.0, 0.0, Vec3::new(0.0, f32::INFINITY, 0.0))
            .validate()
            .is_err());
    }

    #[test]
    fn straight_down_and_up_views_have_a_continuous_frame() {
        let t = Vec3::new(0.1, 0.2, -0.3);
        for az in [0.0f32, 30.0, 135.0, -100.0] {
            let down = cam(az, 90.0, t);
            assert!(down.validate().is_ok());
            assert_orthonormal_right_handed(&down);
            let (eye, forward, _, up) = down.frame();
            assert_eq!(forward, Vec3::new(0.0, -1.0, 0.0));
            assert!((eye - (t + Vec3::new(0.0, 2.0, 0.0))).length() < 1e-6);
            // Screen-up is the horizontal direction the camera faced at this azimuth.
            let a = az.to_radians();
            assert!((up + Vec3::new(a.sin(), 0.0, a.cos())).length() < 1e-6);
            // A point below the target is in the middle of the image.
            let (x, y) = project(&down, t - Vec3::new(0.0, 0.7, 0.0));
            assert!(x.abs() < 1e-6 && y.abs() < 1e-6, "{x} {y}");
            let up_cam = cam(az, -90.0, t);
            assert_orthonormal_right_handed(&up_cam);
            assert_eq!(up_cam.frame().1, Vec3::Y);
            // Continuity at the poles: just below is nearly the same frame.
            for (pole, near) in [(down, cam(az, 89.999, t)), (up_cam, cam(az, -89.999, t))] {
                assert_orthonormal_right_handed(&near);
                let (a, b) = (pole.frame(), near.frame());
                for (p, q) in [(a.0, b.0), (a.1, b.1), (a.2, b.2), (a.3, b.3)] {
                    assert!((p - q).length() < 1e-4, "{p} vs {q} at azimuth {az}");
                }
            }
        }
        assert!(cam(0.0, 90.01, Vec3::ZERO).validate().is_err());
        assert!(cam(0.0, -90.01, Vec3::ZERO).validate().is_err());
    }

    #[test]
    fn frames_below_the_poles_are_unchanged() {
        // The formula every image so far was rendered with.
        for (az, el) in [
            (30.0f32, 20.0f32),
            (-45.0, 0.0),
            (200.0, -89.9),
            (10.0, 89.99),
        ] {
            let c = cam(az, el, Vec3::ZERO);
            let (a, e) = (az.to_radians(), el.to_radians());
            let eye = 2.0 * Vec3::new(a.sin() * e.cos(), e.sin(), a.cos() * e.cos());
            let forward = (-eye).normalize();
            let right = forward.cross(Vec3::Y).normalize();
            let up = right.cross(forward);
            assert_eq!(c.frame(), (eye, forward, right, up));
            assert_orthonormal_right_handed(&c);
        }
    }
}
