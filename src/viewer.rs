//! `refrakt view`: a window (winit) that shows the scene, rendered every frame by the same
//! [`Renderer`] the headless `render` uses, then tone mapped on the GPU into the swapchain
//! image by [`ToneMapPass`] (the arithmetic of the PNG path). Nothing is read back to the
//! CPU except for screenshots.
//!
//! Per frame: the renderer's recording (preintegration if the transfer functions changed,
//! sweep or EA) and the tone-map pass go into one command buffer with the swapchain's
//! acquire/present synchronization ([`Swapchain::frame`]); up to
//! [`crate::vk::FRAMES_IN_FLIGHT`] frames are in flight. Everything that could free
//! something a frame in flight uses (resize, reload, a new environment) first waits until
//! the device is idle.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant, SystemTime};

use anyhow::{anyhow, Context as _, Result};
use glam::Vec3;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, KeyEvent, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, ModifiersState, NamedKey};
use winit::window::{Window, WindowId};

use crate::output;
use crate::render::{Camera, Frame, Model, Renderer, ToneMapPass, MAX_ETA_SCALE};
use crate::scene::Scene;
use crate::vk::{
    Buffer, Context, ContextDesc, FrameStatus, Framebuffer, LayerView, Swapchain, SwapchainDesc,
    Timings, ValidationLog,
};

/// Reloads the scene from its sources (the command line's options and files).
pub type SceneLoader = Box<dyn FnMut() -> Result<Scene>>;

/// How the viewer runs, besides the scene.
#[derive(Clone, Debug)]
pub struct ViewOptions {
    /// FIFO presentation.
    pub vsync: bool,
    /// Exit after this many frames.
    pub frames: Option<u64>,
    /// With `frames`: write the last frame here (and with the other extension).
    pub screenshot: Option<PathBuf>,
    /// Ask for this window size before this frame (tests, scripts).
    pub resize: Option<([u32; 2], u64)>,
    /// Where the P key writes screenshots.
    pub screenshot_dir: PathBuf,
    /// Reload when the scene's files change on disk.
    pub watch: bool,
}

/// What a viewer session leaves behind.
#[derive(Clone, Debug, Default)]
pub struct ViewReport {
    /// Frames presented.
    pub frames: u64,
    /// Warnings and errors the validation layer reported over the whole session.
    pub validation_messages: usize,
    /// GPU milliseconds of each completed frame (the "frame" scope), in order.
    pub frame_ms: Vec<f64>,
}

/// The key map `H` prints (and the README documents).
pub const KEY_MAP: &str = "\
refrakt view keys:
  left-drag         orbit the camera
  wheel             zoom
  right-drag, arrows  move the light (kept within 80 degrees of the view direction)
  [ / ]             light softness - / +
  - / =             refractive-index scale - / +
  , / .             sample distance - / + (finer / coarser)
  ; / '             specular roughness - / +
  M                 model: refract / ea
  C                 clipping plane on / off
  R                 reload the scene and transfer-function files (also automatic on change)
  P                 screenshot (PNG as shown + linear EXR)
  H                 this help
  Esc, Q            quit";

/// Largest angle between the light and the direction back to the camera that controls
/// allow; the sweep's limit is about 84 degrees (MIN_FORWARD).
pub const MAX_LIGHT_ANGLE_DEG: f32 = 80.0;
/// Degrees per pixel of a drag.
const DRAG_DEG_PER_PIXEL: f32 = 0.4;
/// Degrees per arrow-key press.
const KEY_LIGHT_DEG: f32 = 5.0;
const LIMITS_SOFTNESS: (f32, f32) = (0.0, 8.0);
const LIMITS_SAMPLE_DISTANCE: (f32, f32) = (0.25, 8.0);
const LIMITS_ROUGHNESS: (f32, f32) = (0.01, 1.0);
const MAX_DISTANCE: f32 = 20.0;
const WATCH_INTERVAL: Duration = Duration::from_millis(500);
const RESIZE_TIMEOUT: Duration = Duration::from_secs(10);

/// `towards` (a direction to the light), moved into the cone of [`MAX_LIGHT_ANGLE_DEG`]
/// around the direction from the volume to the camera if it is outside, keeping its
/// azimuth about that axis.
pub fn clamp_light(towards: Vec3, camera: &Camera) -> Vec3 {
    let (_, forward, _, up) = camera.frame();
    let back = -forward;
    let t = towards.normalize_or(back);
    let max = MAX_LIGHT_ANGLE_DEG.to_radians();
    if t.dot(back) >= max.cos() {
        return t;
    }
    let side = (t - t.dot(back) * back).normalize_or(up);
    (max.cos() * back + max.sin() * side).normalize()
}

/// The light turned by `yaw` (to the viewer's right) and `pitch` (up) degrees in the
/// camera's frame, then clamped with [`clamp_light`].
pub fn turn_light(towards: Vec3, camera: &Camera, yaw: f32, pitch: f32) -> Vec3 {
    let (_, forward, right, up) = camera.frame();
    let back = -forward;
    let t = clamp_light(towards, camera);
    let (x, y, z) = (t.dot(right), t.dot(up), t.dot(back));
    let az = x.atan2(z) + yaw.to_radians();
    let el = (y.clamp(-1.0, 1.0).asin() + pitch.to_radians()).clamp(
        -MAX_LIGHT_ANGLE_DEG.to_radians(),
        MAX_LIGHT_ANGLE_DEG.to_radians(),
    );
    let l = el.cos() * az.sin() * right + el.sin() * up + el.cos() * az.cos() * back;
    clamp_light(l, camera)
}

/// Open the window and run until it is closed (or `--frames` are done).
pub fn run(
    desc: ContextDesc,
    scene: Scene,
    loader: SceneLoader,
    options: ViewOptions,
) -> Result<ViewReport> {
    let event_loop = EventLoop::new().map_err(|e| {
        anyhow!(
            "cannot open a window: {e}. `refrakt view` needs a display (X11 or Wayland; \
             DISPLAY or WAYLAND_DISPLAY); for a headless machine use Xvfb (Debian package \
             xvfb, installed by scripts/setup.sh), e.g. `xvfb-run refrakt view`"
        )
    })?;
    let mut app = App::new(desc, scene, loader, options);
    event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow!("window event loop: {e}"))?;
    // Everything on the GPU goes before the validation log is read.
    let log = app.gpu.as_ref().map(|g| g.ctx.validation_log());
    let gpu = app.gpu.take();
    drop(gpu);
    let mut report = app.report;
    report.validation_messages = log.map(|l: Arc<ValidationLog>| l.count()).unwrap_or(0);
    if let Some(e) = app.error {
        return Err(e);
    }
    Ok(report)
}

/// The window and everything on the GPU. Dropped in field order after [`Gpu::drop`]
/// waited for the device: what the frames use, then the swapchain, the context (device,
/// surface), and the window last.
struct Gpu {
    framebuffers: Vec<Framebuffer>,
    views: Vec<LayerView>,
    tonemap: ToneMapPass,
    renderer: Renderer,
    swapchain: Swapchain,
    ctx: Context,
    window: Arc<Window>,
}

impl Drop for Gpu {
    fn drop(&mut self) {
        let _ = self.swapchain.wait_idle();
    }
}

impl Gpu {
    /// Framebuffers over the current swapchain images (after a (re)creation).
    fn rebuild_targets(&mut self) -> Result<()> {
        self.framebuffers.clear();
        self.views.clear();
        if self.swapchain.format() != self.tonemap_format() {
            self.tonemap = ToneMapPass::new(
                &self.ctx,
                self.swapchain.format(),
                self.swapchain.encodes_srgb(),
            )?;
        }
        let [w, h] = self.swapchain.extent();
        for image in self.swapchain.images() {
            self.views.push(image.layer_view(0)?);
        }
        for (i, view) in self.views.iter().enumerate() {
            self.framebuffers.push(Framebuffer::new(
                &self.ctx,
                self.tonemap.render_pass(),
                &[view],
                w,
                h,
                &format!("swapchain framebuffer {i}"),
            )?);
        }
        Ok(())
    }

    fn tonemap_format(&self) -> crate::vk::Format {
        self.tonemap.format()
    }
}

/// Mouse and keyboard state between events.
#[derive(Default)]
struct Input {
    cursor: Option<(f64, f64)>,
    orbiting: bool,
    lighting: bool,
    modifiers: ModifiersState,
}

/// Host copies of a frame for a screenshot, read once it completes.
struct Shot {
    png: PathBuf,
    exr: PathBuf,
    width: u32,
    height: u32,
    /// The swapchain image as shown (None when its images cannot be copied from).
    shown: Option<Buffer>,
    bgra: bool,
    /// The renderer's linear frame.
    linear: Buffer,
}

struct App {
    desc: ContextDesc,
    scene: Scene,
    loader: SceneLoader,
    options: ViewOptions,
    gpu: Option<Gpu>,
    error: Option<anyhow::Error>,
    report: ViewReport,
    input: Input,
    /// The clipping plane C toggles when there was none on the command line.
    clip_default: Option<(Vec3, f32)>,
    minimised: bool,
    occluded: bool,
    swapchain_dirty: bool,
    /// A requested window size the viewer waits for (--resize), with its deadline.
    awaiting_size: Option<([u32; 2], Instant)>,
    resize_done: bool,
    shot_requested: bool,
    shot_counter: u32,
    /// Planes of each frame in flight, for the title once its timings arrive.
    planes: HashMap<u64, Option<u32>>,
    last_print: Option<Instant>,
    last_watch: Instant,
    watched: Vec<(PathBuf, Option<SystemTime>)>,
    last_check_error: Option<String>,
    last_minimised_poll: Instant,
}

fn mtime(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

impl App {
    fn new(desc: ContextDesc, scene: Scene, loader: SceneLoader, options: ViewOptions) -> Self {
        let watched = scene.files.iter().map(|f| (f.clone(), mtime(f))).collect();
        Self {
            clip_default: scene.opts.sweep.clip,
            desc,
            scene,
            loader,
            options,
            gpu: None,
            error: None,
            report: ViewReport::default(),
            input: Input::default(),
            minimised: false,
            occluded: false,
            swapchain_dirty: false,
            awaiting_size: None,
            resize_done: false,
            shot_requested: false,
            shot_counter: 0,
            planes: HashMap::new(),
            last_print: None,
            last_watch: Instant::now(),
            watched,
            last_check_error: None,
            last_minimised_poll: Instant::now(),
        }
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        if self.error.is_none() {
            self.error = Some(e);
        }
        event_loop.exit();
    }

    fn create_gpu(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let attrs = Window::default_attributes()
            .with_title(format!("refrakt view: {}", self.scene.name))
            .with_inner_size(PhysicalSize::new(
                self.scene.opts.width,
                self.scene.opts.height,
            ));
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .context("creating the window")?,
        );
        let mut desc = self.desc.clone();
        desc.window = Some(window.clone());
        let ctx = Context::new(&desc)?;
        let size = window.inner_size();
        let swapchain = Swapchain::new(
            &ctx,
            SwapchainDesc {
                size: [size.width.max(1), size.height.max(1)],
                vsync: self.options.vsync,
            },
        )?;
        let mut renderer = Renderer::new(&ctx, &self.scene.volume, &self.scene.tf)?;
        renderer.set_environment(self.scene.env.as_ref())?;
        let tonemap = ToneMapPass::new(&ctx, swapchain.format(), swapchain.encodes_srgb())?;
        println!(
            "device: {} ({}); window {}x{}, swapchain {:?}, {}",
            ctx.info().name,
            crate::vk::device_type_name(ctx.info().device_type),
            swapchain.extent()[0],
            swapchain.extent()[1],
            swapchain.format(),
            swapchain.present_mode_name()
        );
        println!("press H in the window for the keys");
        let mut gpu = Gpu {
            framebuffers: Vec::new(),
            views: Vec::new(),
            tonemap,
            renderer,
            swapchain,
            ctx,
            window,
        };
        gpu.rebuild_targets()?;
        self.gpu = Some(gpu);
        Ok(())
    }

    fn paused(&self) -> bool {
        self.minimised || self.occluded || self.awaiting_size.is_some()
    }

    /// Record and present one frame, if the window can show one.
    fn draw(&mut self) -> Result<()> {
        if self.paused() || self.done() {
            return Ok(());
        }
        let frame_no = self.report.frames;
        if let Some((size, at)) = self.options.resize {
            if at == frame_no && !self.resize_done {
                self.resize_done = true;
                let gpu = self.gpu.as_ref().expect("drawn with a window");
                let current = gpu.window.inner_size();
                if [current.width, current.height] != size {
                    let _ = gpu
                        .window
                        .request_inner_size(PhysicalSize::new(size[0], size[1]));
                    self.awaiting_size = Some((size, Instant::now() + RESIZE_TIMEOUT));
                    return Ok(());
                }
            }
        }
        let gpu = self.gpu.as_mut().expect("drawn with a window");
        let size = gpu.window.inner_size();
        if size.width == 0 || size.height == 0 {
            self.minimised = true;
            return Ok(());
        }
        if self.swapchain_dirty
            || gpu.swapchain.is_stale()
            || gpu.swapchain.extent() != [size.width, size.height]
        {
            gpu.swapchain.recreate([size.width, size.height])?;
            gpu.rebuild_targets()?;
            self.swapchain_dirty = false;
        }
        let [w, h] = gpu.swapchain.extent();
        let mut opts = self.scene.opts.clone();
        opts.width = w;
        opts.height = h;
        let model = self.scene.model;
        let camera = self.scene.camera;
        // Controls keep every value in range; anything left (a reloaded scene the renderer
        // refuses) is reported once and nothing is drawn until it changes.
        if let Err(e) = gpu.renderer.check(model, &camera, &opts) {
            let msg = format!("{e:#}");
            if self.last_check_error.as_deref() != Some(&msg) {
                eprintln!("cannot render: {msg}");
                self.last_check_error = Some(msg);
            }
            return Ok(());
        }
        self.last_check_error = None;
        let last = self
            .options
            .frames
            .map(|n| frame_no + 1 == n)
            .unwrap_or(false);
        let shot = if self.shot_requested || (last && self.options.screenshot.is_some()) {
            self.shot_requested = false;
            Some(self.prepare_shot(last, w, h)?)
        } else {
            None
        };
        let gpu = self.gpu.as_mut().expect("drawn with a window");
        let tone = self.scene.tone;
        let mut planes = None;
        let Gpu {
            framebuffers,
            tonemap,
            renderer,
            swapchain,
            ..
        } = gpu;
        let status = swapchain.frame(|rec, index, target| {
            rec.begin_scope("frame");
            let out = renderer.record(rec, model, &camera, &opts)?;
            planes = out.sweep.as_ref().map(|s| s.planes.count);
            tonemap.record(rec, out.image, target, &framebuffers[index], &tone)?;
            if let Some(shot) = &shot {
                if let Some(buf) = &shot.shown {
                    rec.copy_image_to_buffer(target, 0, buf);
                }
                rec.copy_image_to_buffer(out.image, 0, &shot.linear);
            }
            rec.end_scope();
            Ok(())
        })?;
        match status {
            FrameStatus::OutOfDate => {
                self.swapchain_dirty = true;
            }
            FrameStatus::Presented(n) => {
                self.planes.insert(n, planes);
                self.report.frames += 1;
                if let Some(shot) = shot {
                    let gpu = self.gpu.as_mut().expect("drawn with a window");
                    gpu.swapchain.wait_idle()?;
                    write_shot(&shot)?;
                }
            }
        }
        self.collect_timings();
        Ok(())
    }

    fn prepare_shot(&mut self, last: bool, w: u32, h: u32) -> Result<Shot> {
        let (png, exr) = match (&self.options.screenshot, last) {
            (Some(path), true) => {
                let other = match output::format_for(path)? {
                    output::ImageFormat::Png => path.with_extension("exr"),
                    output::ImageFormat::Exr => path.with_extension("png"),
                };
                if output::format_for(path)? == output::ImageFormat::Png {
                    (path.clone(), other)
                } else {
                    (other, path.clone())
                }
            }
            _ => loop {
                self.shot_counter += 1;
                let stem = format!("refrakt-{}-{:03}", self.scene.name, self.shot_counter);
                let png = self.options.screenshot_dir.join(format!("{stem}.png"));
                if !png.exists() {
                    break (png.clone(), png.with_extension("exr"));
                }
            },
        };
        let gpu = self.gpu.as_ref().expect("drawn with a window");
        let shown = if gpu.swapchain.can_copy_from() {
            Some(Buffer::readback(
                &gpu.ctx,
                w as u64 * h as u64 * 4,
                "screenshot (shown)",
            )?)
        } else {
            None
        };
        Ok(Shot {
            png,
            exr,
            width: w,
            height: h,
            shown,
            bgra: gpu.swapchain.is_bgra(),
            linear: Buffer::readback(&gpu.ctx, w as u64 * h as u64 * 16, "screenshot (linear)")?,
        })
    }

    /// Timings of completed frames: the window title and, at most once a second (every
    /// frame with --frames), a line on stdout.
    fn collect_timings(&mut self) {
        let Some(gpu) = self.gpu.as_mut() else {
            return;
        };
        let done = gpu.swapchain.take_timings();
        for (n, t) in done {
            let planes = self.planes.remove(&n).flatten();
            let line = summary(&t, planes);
            if let Some(ms) = t.get("frame") {
                self.report.frame_ms.push(ms);
            }
            let [w, h] = gpu.swapchain.extent();
            gpu.window.set_title(&format!(
                "refrakt view: {} ({}) {w}x{h} | {line}",
                self.scene.name,
                self.scene.model.name()
            ));
            let due = self
                .last_print
                .map(|t| t.elapsed() >= Duration::from_secs(1))
                .unwrap_or(true);
            if self.options.frames.is_some() || due {
                println!("frame {n}: {line}");
                self.last_print = Some(Instant::now());
            }
        }
    }

    fn done(&self) -> bool {
        self.options
            .frames
            .map(|n| self.report.frames >= n)
            .unwrap_or(false)
    }

    fn reload(&mut self) -> Result<()> {
        let started = Instant::now();
        let new = match (self.loader)() {
            Ok(s) => s,
            Err(e) => {
                eprintln!("reload failed, keeping the current scene: {e:#}");
                return Ok(());
            }
        };
        let gpu = self.gpu.as_mut().expect("reloaded with a window");
        gpu.swapchain.wait_idle()?;
        if new.volume != self.scene.volume {
            gpu.renderer = Renderer::new(&gpu.ctx, &new.volume, &new.tf)?;
        } else {
            gpu.renderer.set_transfer_functions(&new.tf)?;
        }
        gpu.renderer.set_environment(new.env.as_ref())?;
        // The view (camera, light, keys' settings) stays; the data is new.
        self.scene.name = new.name;
        self.scene.volume = new.volume;
        self.scene.tf = new.tf;
        self.scene.env = new.env;
        self.scene.files = new.files;
        self.watched = self
            .scene
            .files
            .iter()
            .map(|f| (f.clone(), mtime(f)))
            .collect();
        println!(
            "reloaded the {} scene (transfer functions {}) in {:.0} ms",
            self.scene.name,
            self.scene.tf.name,
            started.elapsed().as_secs_f64() * 1e3
        );
        Ok(())
    }

    fn watch(&mut self) -> Result<()> {
        if !self.options.watch || self.last_watch.elapsed() < WATCH_INTERVAL {
            return Ok(());
        }
        self.last_watch = Instant::now();
        let changed: Vec<&PathBuf> = self
            .watched
            .iter()
            .filter(|(p, t)| mtime(p) != *t)
            .map(|(p, _)| p)
            .collect();
        if let Some(p) = changed.first() {
            println!("{} changed on disk; reloading", p.display());
            self.reload()?;
        }
        Ok(())
    }

    fn light_moved(&mut self, yaw: f32, pitch: f32) {
        let l = &mut self.scene.opts.sweep.light.towards;
        *l = turn_light(*l, &self.scene.camera, yaw, pitch);
    }

    fn min_distance(&self) -> f32 {
        let e = self.scene.volume.normalised_extent();
        0.5 * Vec3::from(e).length() + 0.05
    }

    fn key(&mut self, event: &KeyEvent, event_loop: &ActiveEventLoop) -> Result<()> {
        if event.state != ElementState::Pressed {
            return Ok(());
        }
        let o = &mut self.scene.opts;
        let s = &mut o.sweep;
        let step = |v: &mut f32, d: f32, (lo, hi): (f32, f32)| *v = (*v + d).clamp(lo, hi);
        let mut said = None;
        match &event.logical_key {
            Key::Named(NamedKey::Escape) => event_loop.exit(),
            Key::Named(NamedKey::ArrowLeft) => self.light_moved(-KEY_LIGHT_DEG, 0.0),
            Key::Named(NamedKey::ArrowRight) => self.light_moved(KEY_LIGHT_DEG, 0.0),
            Key::Named(NamedKey::ArrowUp) => self.light_moved(0.0, KEY_LIGHT_DEG),
            Key::Named(NamedKey::ArrowDown) => self.light_moved(0.0, -KEY_LIGHT_DEG),
            Key::Character(c) => match c.to_lowercase().as_str() {
                "q" => event_loop.exit(),
                "[" | "{" => {
                    step(&mut s.light.softness, -0.25, LIMITS_SOFTNESS);
                    said = Some(format!("softness {:.2}", s.light.softness));
                }
                "]" | "}" => {
                    step(&mut s.light.softness, 0.25, LIMITS_SOFTNESS);
                    said = Some(format!("softness {:.2}", s.light.softness));
                }
                "-" | "_" => {
                    step(&mut s.eta_scale, -0.1, (0.0, MAX_ETA_SCALE));
                    said = Some(format!("refractive-index scale {:.2}", s.eta_scale));
                }
                "=" | "+" => {
                    step(&mut s.eta_scale, 0.1, (0.0, MAX_ETA_SCALE));
                    said = Some(format!("refractive-index scale {:.2}", s.eta_scale));
                }
                "," | "<" => {
                    o.sample_distance = (o.sample_distance / 1.25)
                        .clamp(LIMITS_SAMPLE_DISTANCE.0, LIMITS_SAMPLE_DISTANCE.1);
                    said = Some(format!("sample distance {:.3}", o.sample_distance));
                }
                "." | ">" => {
                    o.sample_distance = (o.sample_distance * 1.25)
                        .clamp(LIMITS_SAMPLE_DISTANCE.0, LIMITS_SAMPLE_DISTANCE.1);
                    said = Some(format!("sample distance {:.3}", o.sample_distance));
                }
                ";" | ":" => {
                    step(&mut s.roughness, -0.05, LIMITS_ROUGHNESS);
                    said = Some(format!("roughness {:.2}", s.roughness));
                }
                "'" | "\"" => {
                    step(&mut s.roughness, 0.05, LIMITS_ROUGHNESS);
                    said = Some(format!("roughness {:.2}", s.roughness));
                }
                "m" => {
                    self.scene.model = match self.scene.model {
                        Model::Refract => Model::Ea,
                        Model::Ea => Model::Refract,
                    };
                    said = Some(format!("model {}", self.scene.model.name()));
                }
                "c" => {
                    if s.clip.is_some() {
                        s.clip = None;
                        said = Some("clipping off".into());
                    } else {
                        // The command line's plane, else one through the centre facing the
                        // camera (cuts the near half away).
                        let plane = self.clip_default.unwrap_or_else(|| {
                            let (eye, ..) = self.scene.camera.frame();
                            (eye.normalize(), 0.0)
                        });
                        self.clip_default = Some(plane);
                        s.clip = Some(plane);
                        said = Some(format!(
                            "clipping on: n = ({:.2}, {:.2}, {:.2}), offset {:.2}",
                            plane.0.x, plane.0.y, plane.0.z, plane.1
                        ));
                    }
                }
                "r" => self.reload()?,
                "p" => {
                    self.shot_requested = true;
                    said = Some("screenshot at the next frame".into());
                }
                "h" => println!("{KEY_MAP}"),
                _ => {}
            },
            _ => {}
        }
        if let Some(msg) = said {
            println!("{msg}");
        }
        Ok(())
    }

    fn window_event_inner(
        &mut self,
        event_loop: &ActiveEventLoop,
        event: WindowEvent,
    ) -> Result<()> {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                self.minimised = size.width == 0 || size.height == 0;
                self.swapchain_dirty = true;
                if let Some((want, _)) = self.awaiting_size {
                    if [size.width, size.height] == want {
                        self.awaiting_size = None;
                    }
                }
            }
            WindowEvent::Occluded(o) => self.occluded = o,
            WindowEvent::ModifiersChanged(m) => self.input.modifiers = m.state(),
            WindowEvent::KeyboardInput { event, .. } => self.key(&event, event_loop)?,
            WindowEvent::MouseInput { state, button, .. } => {
                let down = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => self.input.orbiting = down,
                    MouseButton::Right => self.input.lighting = down,
                    _ => {}
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let (x, y) = (position.x, position.y);
                if let Some((px, py)) = self.input.cursor {
                    let (dx, dy) = ((x - px) as f32, (y - py) as f32);
                    if self.input.orbiting {
                        let c = &mut self.scene.camera;
                        c.azimuth = (c.azimuth - dx * DRAG_DEG_PER_PIXEL).rem_euclid(360.0);
                        c.elevation = (c.elevation + dy * DRAG_DEG_PER_PIXEL).clamp(-89.0, 89.0);
                        // The light stays put in the world unless the camera left its cone.
                        let l = &mut self.scene.opts.sweep.light.towards;
                        *l = clamp_light(*l, &self.scene.camera);
                    } else if self.input.lighting {
                        self.light_moved(dx * DRAG_DEG_PER_PIXEL, -dy * DRAG_DEG_PER_PIXEL);
                    }
                }
                self.input.cursor = Some((x, y));
            }
            WindowEvent::CursorLeft { .. } => self.input.cursor = None,
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 50.0,
                };
                let min = self.min_distance();
                let c = &mut self.scene.camera;
                c.distance = (c.distance * 0.9f32.powf(steps)).clamp(min, MAX_DISTANCE);
            }
            WindowEvent::RedrawRequested => self.draw()?,
            _ => {}
        }
        Ok(())
    }
}

/// "GPU ms per frame, ms in the sweep, plane count" of one frame.
fn summary(t: &Timings, planes: Option<u32>) -> String {
    let total = t.get("frame");
    let mut s = match total {
        Some(ms) => format!("{ms:.1} ms GPU"),
        None => "no GPU timestamps".to_string(),
    };
    if let Some(ms) = t.get("sweep") {
        s += &format!(", sweep {ms:.1} ms");
    }
    if let Some(ms) = t.get("ea raymarch") {
        s += &format!(", ea {ms:.1} ms");
    }
    if let Some(p) = planes {
        s += &format!(", {p} planes");
    }
    if let Some(ms) = t.get("preintegration") {
        s += &format!(" (incl. preintegration {ms:.1} ms)");
    }
    s
}

fn write_shot(shot: &Shot) -> Result<()> {
    let (w, h) = (shot.width, shot.height);
    let linear: Vec<[f32; 4]> = shot.linear.read_values(w as usize * h as usize)?;
    output::write_pixels(w, h, &linear, &shot.exr)?;
    match &shot.shown {
        Some(buf) => {
            let mut bytes: Vec<u8> = buf.read_values(w as usize * h as usize * 4)?;
            if shot.bgra {
                for px in bytes.chunks_exact_mut(4) {
                    px.swap(0, 2);
                }
            }
            image::save_buffer(&shot.png, &bytes, w, h, image::ExtendedColorType::Rgba8)
                .with_context(|| format!("writing {}", shot.png.display()))?;
        }
        None => {
            // The surface's images cannot be copied from: the PNG path's CPU tone mapping
            // of the same linear frame instead.
            let frame = Frame {
                width: w,
                height: h,
                pixels: linear,
                timings: Timings::default(),
                max_steps: 0,
                dumps: Vec::new(),
                sweep: None,
            };
            output::write(&frame, &shot.png, &output::ToneMap::default())?;
            eprintln!(
                "note: the swapchain images cannot be copied; the PNG is tone mapped on the CPU"
            );
        }
    }
    println!(
        "screenshot: {} (as shown), {} (linear)",
        shot.png.display(),
        shot.exr.display()
    );
    Ok(())
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gpu.is_some() {
            return;
        }
        if let Err(e) = self.create_gpu(event_loop) {
            self.fail(event_loop, e);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        if self.gpu.is_none() {
            return;
        }
        if let Err(e) = self.window_event_inner(event_loop, event) {
            self.fail(event_loop, e);
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if self.gpu.is_none() {
            return;
        }
        if let Err(e) = self.watch() {
            return self.fail(event_loop, e);
        }
        self.collect_timings();
        if self.done() {
            if let Some(gpu) = self.gpu.as_mut() {
                if let Err(e) = gpu.swapchain.wait_idle() {
                    return self.fail(event_loop, e);
                }
            }
            self.collect_timings();
            event_loop.exit();
            return;
        }
        if let Some((want, deadline)) = self.awaiting_size {
            if Instant::now() >= deadline {
                eprintln!(
                    "warning: the window did not take the size {}x{} within {:?}; going on",
                    want[0], want[1], RESIZE_TIMEOUT
                );
                self.awaiting_size = None;
            }
        }
        // A minimised X11 window may get no event at all; poll its state a few times a
        // second rather than render into it.
        if self.last_minimised_poll.elapsed() >= Duration::from_millis(250) {
            self.last_minimised_poll = Instant::now();
            let gpu = self.gpu.as_ref().expect("checked");
            if gpu.window.is_minimized() == Some(true) {
                self.minimised = true;
            } else if self.minimised {
                let s = gpu.window.inner_size();
                self.minimised = s.width == 0 || s.height == 0;
            }
        }
        let gpu = self.gpu.as_ref().expect("checked");
        if self.paused() {
            // Nothing to draw: sleep until an event, waking a few times a second for the
            // file watch, the minimised poll and the resize deadline.
            event_loop.set_control_flow(ControlFlow::WaitUntil(
                Instant::now() + Duration::from_millis(250),
            ));
        } else if gpu.swapchain.ready() {
            gpu.window.request_redraw();
            event_loop.set_control_flow(ControlFlow::Wait);
        } else {
            // The GPU is still on an earlier frame: stay responsive to input meanwhile.
            event_loop.set_control_flow(ControlFlow::WaitUntil(
                Instant::now() + Duration::from_millis(4),
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn angle_to_camera(t: Vec3, c: &Camera) -> f32 {
        let (_, forward, _, _) = c.frame();
        t.normalize()
            .dot(-forward)
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees()
    }

    #[test]
    fn light_is_kept_in_the_viewers_cone() {
        let c = Camera::default();
        let (_, forward, right, _) = c.frame();
        // From behind the volume: clamped to the cone's edge, on the same side.
        let behind = (forward + 0.3 * right).normalize();
        let l = clamp_light(behind, &c);
        assert!((angle_to_camera(l, &c) - MAX_LIGHT_ANGLE_DEG).abs() < 0.01);
        assert!(l.dot(right) > 0.0);
        // Inside: unchanged.
        let inside = (-forward + 0.2 * right).normalize();
        assert!((clamp_light(inside, &c) - inside).length() < 1e-6);
    }

    #[test]
    fn turning_the_light_moves_it_and_stays_in_the_cone() {
        let c = Camera::default();
        let (_, forward, right, up) = c.frame();
        let l0 = -forward;
        let l1 = turn_light(l0, &c, 20.0, 0.0);
        assert!(l1.dot(right) > 0.3, "yaw right moves the light right");
        let l2 = turn_light(l0, &c, 0.0, 20.0);
        assert!(l2.dot(up) > 0.3, "pitch up moves the light up");
        let mut l = l0;
        for _ in 0..100 {
            l = turn_light(l, &c, 7.0, 3.0);
            assert!(angle_to_camera(l, &c) <= MAX_LIGHT_ANGLE_DEG + 0.01);
        }
    }
}
