//! `refrakt view`: a window (winit) that shows the scene, rendered every frame by the same
//! [`Renderer`] the headless `render` uses, then tone mapped on the GPU into the swapchain
//! image by [`ToneMapPass`] (the arithmetic of the PNG path). Nothing is read back to the
//! CPU except for screenshots.
//!
//! Two threads. The main thread runs the winit event loop: input changes the shared view
//! state ([`ViewState`]: model, camera, render options, tone map), and actions (pause,
//! reload, screenshot, quit) go to the render thread as messages. The render thread owns
//! the swapchain, renderer and tone-map pass and draws frame after frame, each with the
//! view state as it is when the frame is recorded ("every change takes effect on the next
//! frame"). It is a thread of its own because presentation may block until the frame is
//! rendered (Mesa's software WSI does, so on lavapipe a 512² sweep would freeze the window
//! for seconds per frame); the event loop never waits for the GPU.
//!
//! Per frame: the renderer's recording (preintegration if the transfer functions changed,
//! sweep or EA) and the tone-map pass go into one command buffer with the swapchain's
//! acquire/present synchronization ([`Swapchain::frame`]); up to
//! [`crate::vk::FRAMES_IN_FLIGHT`] frames are in flight. Everything that could free
//! something a frame in flight uses (resize, reload, a new environment) first waits until
//! the device is idle.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender, TryRecvError};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant, SystemTime};

use anyhow::{anyhow, Context as _, Result};
use glam::Vec3;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, KeyEvent, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::keyboard::{Key, ModifiersState, NamedKey};
use winit::window::{Window, WindowId};

use crate::output;
use crate::output::ToneMap;
use crate::render::{Camera, Frame, Model, RenderOptions, Renderer, ToneMapPass, MAX_ETA_SCALE};
use crate::scene::LoadedScene;
use crate::vk::{
    Buffer, Context, ContextDesc, FrameStatus, Framebuffer, LayerView, Swapchain, SwapchainDesc,
    Timings, ValidationLog,
};

/// Reloads the scene from its sources (the command line's options and files).
pub type SceneLoader = Box<dyn FnMut() -> Result<LoadedScene>>;

/// What the controls change and every frame reads.
#[derive(Clone, Debug)]
pub struct ViewState {
    pub model: Model,
    pub camera: Camera,
    /// The size is replaced by the swapchain's at each frame.
    pub opts: RenderOptions,
    pub tone: ToneMap,
}

/// Main thread → render thread.
enum ToRender {
    /// Stop drawing (minimised, occluded) or go on.
    Pause(bool),
    /// New data for the scene (the view state stays).
    Reload(Box<LoadedScene>),
    /// Write a screenshot of the next frame.
    Screenshot,
    Quit,
}

/// Render thread → main thread (wakes the event loop).
#[derive(Debug)]
enum FromRender {
    /// The render thread has ended (--frames done, quit, or an error it returns).
    Finished,
}

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
    scene: LoadedScene,
    loader: SceneLoader,
    options: ViewOptions,
) -> Result<ViewReport> {
    let event_loop = EventLoop::<FromRender>::with_user_event()
        .build()
        .map_err(|e| {
            anyhow!(
                "cannot open a window: {e}. `refrakt view` needs a display (X11 or Wayland; \
                 DISPLAY or WAYLAND_DISPLAY); for a headless machine use Xvfb (Debian package \
                 xvfb, installed by scripts/setup.sh), e.g. `xvfb-run refrakt view`"
            )
        })?;
    let proxy = event_loop.create_proxy();
    let mut app = App::new(desc, scene, loader, options, proxy);
    let looped = event_loop.run_app(&mut app);
    // The render thread holds everything on the GPU; it ends on Quit (or has ended).
    if let Some(tx) = &app.to_render {
        let _ = tx.send(ToRender::Quit);
    }
    let mut report = ViewReport::default();
    let mut error = app.error.take();
    if let Some(handle) = app.render_thread.take() {
        match handle.join() {
            Ok((r, result)) => {
                report = r;
                if let (Err(e), None) = (result, &error) {
                    error = Some(e);
                }
            }
            Err(_) => error = error.or(Some(anyhow!("the render thread panicked"))),
        }
    }
    report.validation_messages = app.validation.as_ref().map(|l| l.count()).unwrap_or(0);
    // The window goes last, on this thread.
    drop(app);
    looped.map_err(|e| anyhow!("window event loop: {e}"))?;
    match error {
        Some(e) => Err(e),
        None => Ok(report),
    }
}

/// Everything on the GPU, owned by the render thread. Dropped in field order after
/// [`Gpu::drop`] waited for the device: what the frames use, then the swapchain, the
/// context (device, surface).
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
        if self.swapchain.format() != self.tonemap.format() {
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

/// The render thread: draws frames until told to quit or `--frames` are done.
struct RenderLoop {
    gpu: Gpu,
    state: Arc<Mutex<ViewState>>,
    rx: Receiver<ToRender>,
    options: ViewOptions,
    scene_name: String,
    volume: crate::volume::Volume,
    report: ViewReport,
    paused: bool,
    shot_requested: bool,
    shot_counter: u32,
    resize_done: bool,
    /// Planes of each frame in flight, for the title once its timings arrive.
    planes: HashMap<u64, Option<u32>>,
    last_print: Option<Instant>,
    last_check_error: Option<String>,
}

impl RenderLoop {
    fn run(&mut self) -> Result<()> {
        loop {
            if !self.messages()? {
                return Ok(());
            }
            if self.done() {
                self.gpu.swapchain.wait_idle()?;
                self.collect_timings();
                return Ok(());
            }
            self.draw()?;
            self.collect_timings();
        }
    }

    /// Handle what the main thread sent; false once told to quit. Blocks while paused
    /// (or while the window has no area), so a minimised window costs nothing.
    fn messages(&mut self) -> Result<bool> {
        loop {
            let size = self.gpu.window.inner_size();
            let idle = self.paused || size.width == 0 || size.height == 0;
            let msg = if idle {
                match self.rx.recv_timeout(Duration::from_millis(250)) {
                    Ok(m) => m,
                    Err(RecvTimeoutError::Timeout) => continue,
                    Err(RecvTimeoutError::Disconnected) => return Ok(false),
                }
            } else {
                match self.rx.try_recv() {
                    Ok(m) => m,
                    Err(TryRecvError::Empty) => return Ok(true),
                    Err(TryRecvError::Disconnected) => return Ok(false),
                }
            };
            match msg {
                ToRender::Pause(p) => self.paused = p,
                ToRender::Reload(scene) => self.reload(*scene)?,
                ToRender::Screenshot => self.shot_requested = true,
                ToRender::Quit => return Ok(false),
            }
        }
    }

    fn done(&self) -> bool {
        self.options
            .frames
            .map(|n| self.report.frames >= n)
            .unwrap_or(false)
    }

    fn reload(&mut self, new: LoadedScene) -> Result<()> {
        let gpu = &mut self.gpu;
        gpu.swapchain.wait_idle()?;
        if new.volume != self.volume {
            gpu.renderer = Renderer::new(&gpu.ctx, &new.volume, &new.tf)?;
            self.volume = new.volume;
        } else {
            gpu.renderer.set_transfer_functions(&new.tf)?;
        }
        gpu.renderer.set_environment(new.env.as_ref())?;
        self.scene_name = new.name;
        Ok(())
    }

    /// --resize: ask for the size before frame N and wait (up to RESIZE_TIMEOUT) until the
    /// window has it.
    fn scripted_resize(&mut self) {
        let Some((size, at)) = self.options.resize else {
            return;
        };
        if at != self.report.frames || self.resize_done {
            return;
        }
        self.resize_done = true;
        let window = &self.gpu.window;
        let _ = window.request_inner_size(PhysicalSize::new(size[0], size[1]));
        let deadline = Instant::now() + RESIZE_TIMEOUT;
        loop {
            let s = window.inner_size();
            if [s.width, s.height] == size {
                return;
            }
            if Instant::now() >= deadline {
                eprintln!(
                    "warning: the window did not take the size {}x{} within {:?}; going on",
                    size[0], size[1], RESIZE_TIMEOUT
                );
                return;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// Record and present one frame.
    fn draw(&mut self) -> Result<()> {
        self.scripted_resize();
        let size = self.gpu.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(());
        }
        let gpu = &mut self.gpu;
        if gpu.swapchain.is_stale() || gpu.swapchain.extent() != [size.width, size.height] {
            gpu.swapchain.recreate([size.width, size.height])?;
            gpu.rebuild_targets()?;
        }
        let [w, h] = gpu.swapchain.extent();
        let mut view = self.state.lock().unwrap().clone();
        view.opts.width = w;
        view.opts.height = h;
        // Controls keep every value in range; anything left (a reloaded scene the renderer
        // refuses) is reported once and nothing is drawn until it changes.
        if let Err(e) = gpu.renderer.check(view.model, &view.camera, &view.opts) {
            let msg = format!("{e:#}");
            if self.last_check_error.as_deref() != Some(&msg) {
                eprintln!("cannot render: {msg}");
                self.last_check_error = Some(msg);
            }
            std::thread::sleep(Duration::from_millis(100));
            return Ok(());
        }
        self.last_check_error = None;
        let frame_no = self.report.frames;
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
        let mut planes = None;
        let Gpu {
            framebuffers,
            tonemap,
            renderer,
            swapchain,
            ..
        } = &mut self.gpu;
        let status = swapchain.frame(|rec, index, target| {
            rec.begin_scope("frame");
            let out = renderer.record(rec, view.model, &view.camera, &view.opts)?;
            planes = out.sweep.as_ref().map(|s| s.planes.count);
            tonemap.record(rec, out.image, target, &framebuffers[index], &view.tone)?;
            if let Some(shot) = &shot {
                if let Some(buf) = &shot.shown {
                    rec.copy_image_to_buffer(target, 0, buf);
                }
                rec.copy_image_to_buffer(out.image, 0, &shot.linear);
            }
            rec.end_scope();
            Ok(())
        })?;
        if let FrameStatus::Presented(n) = status {
            self.planes.insert(n, planes);
            self.report.frames += 1;
            if let Some(shot) = shot {
                self.gpu.swapchain.wait_idle()?;
                write_shot(&shot)?;
            }
        }
        Ok(())
    }

    fn prepare_shot(&mut self, last: bool, w: u32, h: u32) -> Result<Shot> {
        let (png, exr) = match (&self.options.screenshot, last) {
            (Some(path), true) => match output::format_for(path)? {
                output::ImageFormat::Png => (path.clone(), path.with_extension("exr")),
                output::ImageFormat::Exr => (path.with_extension("png"), path.clone()),
            },
            _ => loop {
                self.shot_counter += 1;
                let stem = format!("refrakt-{}-{:03}", self.scene_name, self.shot_counter);
                let png = self.options.screenshot_dir.join(format!("{stem}.png"));
                if !png.exists() {
                    break (png.clone(), png.with_extension("exr"));
                }
            },
        };
        let gpu = &self.gpu;
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
        let done = self.gpu.swapchain.take_timings();
        for (n, t) in done {
            let planes = self.planes.remove(&n).flatten();
            let line = summary(&t, planes);
            if let Some(ms) = t.get("frame") {
                self.report.frame_ms.push(ms);
            }
            let [w, h] = self.gpu.swapchain.extent();
            let model = self.state.lock().unwrap().model;
            self.gpu.window.set_title(&format!(
                "refrakt view: {} ({}) {w}x{h} | {line}",
                self.scene_name,
                model.name()
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
}

/// Mouse and keyboard state between events.
#[derive(Default)]
struct Input {
    cursor: Option<(f64, f64)>,
    orbiting: bool,
    lighting: bool,
    modifiers: ModifiersState,
}

/// The main thread: window, events, controls.
struct App {
    desc: ContextDesc,
    /// Until the render thread takes it.
    scene: Option<LoadedScene>,
    loader: SceneLoader,
    options: ViewOptions,
    proxy: EventLoopProxy<FromRender>,
    state: Arc<Mutex<ViewState>>,
    window: Option<Arc<Window>>,
    to_render: Option<Sender<ToRender>>,
    render_thread: Option<JoinHandle<(ViewReport, Result<()>)>>,
    validation: Option<Arc<ValidationLog>>,
    error: Option<anyhow::Error>,
    input: Input,
    /// Half the volume box's diagonal: the camera stays outside it.
    volume_radius: f32,
    /// The clipping plane C toggles when there was none on the command line.
    clip_default: Option<(Vec3, f32)>,
    paused: bool,
    minimised: bool,
    occluded: bool,
    last_watch: Instant,
    watched: Vec<(PathBuf, Option<SystemTime>)>,
    last_minimised_poll: Instant,
}

fn mtime(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

impl App {
    fn new(
        desc: ContextDesc,
        scene: LoadedScene,
        loader: SceneLoader,
        options: ViewOptions,
        proxy: EventLoopProxy<FromRender>,
    ) -> Self {
        let watched = scene.files.iter().map(|f| (f.clone(), mtime(f))).collect();
        let state = ViewState {
            model: scene.model,
            camera: scene.camera,
            opts: scene.opts.clone(),
            tone: scene.tone,
        };
        Self {
            clip_default: scene.opts.sweep.clip,
            volume_radius: 0.5 * Vec3::from(scene.volume.normalised_extent()).length(),
            desc,
            scene: Some(scene),
            loader,
            options,
            proxy,
            state: Arc::new(Mutex::new(state)),
            window: None,
            to_render: None,
            render_thread: None,
            validation: None,
            error: None,
            input: Input::default(),
            paused: false,
            minimised: false,
            occluded: false,
            last_watch: Instant::now(),
            watched,
            last_minimised_poll: Instant::now(),
        }
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        if self.error.is_none() {
            self.error = Some(e);
        }
        event_loop.exit();
    }

    fn send(&self, msg: ToRender) {
        if let Some(tx) = &self.to_render {
            // A closed channel means the render thread has ended; its result arrives with
            // FromRender::Finished.
            let _ = tx.send(msg);
        }
    }

    /// Window, context, swapchain, renderer, tone-map pass; then the render thread.
    fn start(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let scene = self.scene.take().expect("started once");
        let attrs = Window::default_attributes()
            .with_title(format!("refrakt view: {}", scene.name))
            .with_inner_size(PhysicalSize::new(scene.opts.width, scene.opts.height));
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .context("creating the window")?,
        );
        self.window = Some(window.clone());
        let mut desc = self.desc.clone();
        desc.window = Some(window.clone());
        let ctx = Context::new(&desc)?;
        self.validation = Some(ctx.validation_log());
        let size = window.inner_size();
        let swapchain = Swapchain::new(
            &ctx,
            SwapchainDesc {
                size: [size.width.max(1), size.height.max(1)],
                vsync: self.options.vsync,
            },
        )?;
        let mut renderer = Renderer::new(&ctx, &scene.volume, &scene.tf)?;
        renderer.set_environment(scene.env.as_ref())?;
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
        let (tx, rx) = mpsc::channel();
        let mut render = RenderLoop {
            gpu,
            state: self.state.clone(),
            rx,
            options: self.options.clone(),
            scene_name: scene.name,
            volume: scene.volume,
            report: ViewReport::default(),
            paused: false,
            shot_requested: false,
            shot_counter: 0,
            resize_done: false,
            planes: HashMap::new(),
            last_print: None,
            last_check_error: None,
        };
        let proxy = self.proxy.clone();
        let handle = std::thread::Builder::new()
            .name("refrakt render".into())
            .spawn(move || {
                let result = render.run();
                let report = std::mem::take(&mut render.report);
                // Everything on the GPU goes before the main thread reads the validation
                // log (and before the window, which the main thread drops last).
                drop(render);
                let _ = proxy.send_event(FromRender::Finished);
                (report, result)
            })
            .context("starting the render thread")?;
        self.to_render = Some(tx);
        self.render_thread = Some(handle);
        Ok(())
    }

    fn update_pause(&mut self) {
        let paused = self.minimised || self.occluded;
        if paused != self.paused {
            self.paused = paused;
            self.send(ToRender::Pause(paused));
        }
    }

    fn reload(&mut self) {
        let started = Instant::now();
        match (self.loader)() {
            Ok(new) => {
                self.watched = new.files.iter().map(|f| (f.clone(), mtime(f))).collect();
                self.volume_radius = 0.5 * Vec3::from(new.volume.normalised_extent()).length();
                println!(
                    "reloaded the {} scene (transfer functions {}) in {:.0} ms",
                    new.name,
                    new.tf.name,
                    started.elapsed().as_secs_f64() * 1e3
                );
                self.send(ToRender::Reload(Box::new(new)));
            }
            Err(e) => eprintln!("reload failed, keeping the current scene: {e:#}"),
        }
    }

    fn watch(&mut self) {
        if !self.options.watch || self.last_watch.elapsed() < WATCH_INTERVAL {
            return;
        }
        self.last_watch = Instant::now();
        let changed = self
            .watched
            .iter()
            .find(|(p, t)| mtime(p) != *t)
            .map(|(p, _)| p.clone());
        if let Some(p) = changed {
            println!("{} changed on disk; reloading", p.display());
            self.reload();
        }
    }

    fn light_moved(&mut self, yaw: f32, pitch: f32) {
        let mut s = self.state.lock().unwrap();
        let camera = s.camera;
        let l = &mut s.opts.sweep.light.towards;
        *l = turn_light(*l, &camera, yaw, pitch);
    }

    fn key(&mut self, event: &KeyEvent, event_loop: &ActiveEventLoop) {
        if event.state != ElementState::Pressed {
            return;
        }
        let step = |v: &mut f32, d: f32, (lo, hi): (f32, f32)| *v = (*v + d).clamp(lo, hi);
        let mut said = None;
        match &event.logical_key {
            Key::Named(NamedKey::Escape) => event_loop.exit(),
            Key::Named(NamedKey::ArrowLeft) => self.light_moved(-KEY_LIGHT_DEG, 0.0),
            Key::Named(NamedKey::ArrowRight) => self.light_moved(KEY_LIGHT_DEG, 0.0),
            Key::Named(NamedKey::ArrowUp) => self.light_moved(0.0, KEY_LIGHT_DEG),
            Key::Named(NamedKey::ArrowDown) => self.light_moved(0.0, -KEY_LIGHT_DEG),
            Key::Character(c) => {
                let c = c.to_lowercase();
                match c.as_str() {
                    "q" => event_loop.exit(),
                    "r" => self.reload(),
                    "p" => {
                        self.send(ToRender::Screenshot);
                        said = Some("screenshot at the next frame".into());
                    }
                    "h" => println!("{KEY_MAP}"),
                    "c" => {
                        let mut st = self.state.lock().unwrap();
                        if st.opts.sweep.clip.is_some() {
                            st.opts.sweep.clip = None;
                            said = Some("clipping off".into());
                        } else {
                            // The command line's plane, else one through the centre facing
                            // the camera (cuts the near half away).
                            let (eye, ..) = st.camera.frame();
                            let plane = *self.clip_default.get_or_insert((eye.normalize(), 0.0));
                            st.opts.sweep.clip = Some(plane);
                            said = Some(format!(
                                "clipping on: n = ({:.2}, {:.2}, {:.2}), offset {:.2}",
                                plane.0.x, plane.0.y, plane.0.z, plane.1
                            ));
                        }
                    }
                    _ => {
                        let mut st = self.state.lock().unwrap();
                        let ViewState { model, opts, .. } = &mut *st;
                        let s = &mut opts.sweep;
                        match c.as_str() {
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
                            ";" | ":" => {
                                step(&mut s.roughness, -0.05, LIMITS_ROUGHNESS);
                                said = Some(format!("roughness {:.2}", s.roughness));
                            }
                            "'" | "\"" => {
                                step(&mut s.roughness, 0.05, LIMITS_ROUGHNESS);
                                said = Some(format!("roughness {:.2}", s.roughness));
                            }
                            "," | "<" | "." | ">" => {
                                let f = if matches!(c.as_str(), "," | "<") {
                                    1.0 / 1.25
                                } else {
                                    1.25
                                };
                                opts.sample_distance = (opts.sample_distance * f)
                                    .clamp(LIMITS_SAMPLE_DISTANCE.0, LIMITS_SAMPLE_DISTANCE.1);
                                said = Some(format!("sample distance {:.3}", opts.sample_distance));
                            }
                            "m" => {
                                *model = match *model {
                                    Model::Refract => Model::Ea,
                                    Model::Ea => Model::Refract,
                                };
                                said = Some(format!("model {}", model.name()));
                            }
                            _ => {}
                        }
                    }
                }
            }
            _ => {}
        }
        if let Some(msg) = said {
            println!("{msg}");
        }
    }

    fn window_event_inner(&mut self, event_loop: &ActiveEventLoop, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                // The render thread follows the window's size by itself.
                self.minimised = size.width == 0 || size.height == 0;
                self.update_pause();
            }
            WindowEvent::Occluded(o) => {
                self.occluded = o;
                self.update_pause();
            }
            WindowEvent::ModifiersChanged(m) => self.input.modifiers = m.state(),
            WindowEvent::KeyboardInput { event, .. } => self.key(&event, event_loop),
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
                        let mut s = self.state.lock().unwrap();
                        let c = &mut s.camera;
                        c.azimuth = (c.azimuth - dx * DRAG_DEG_PER_PIXEL).rem_euclid(360.0);
                        c.elevation = (c.elevation + dy * DRAG_DEG_PER_PIXEL).clamp(-89.0, 89.0);
                        // The light stays put in the world unless the camera left its cone.
                        let camera = s.camera;
                        let l = &mut s.opts.sweep.light.towards;
                        *l = clamp_light(*l, &camera);
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
                let min = self.volume_radius + 0.05;
                let c = &mut self.state.lock().unwrap().camera;
                c.distance = (c.distance * 0.9f32.powf(steps)).clamp(min, MAX_DISTANCE);
            }
            _ => {}
        }
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

impl ApplicationHandler<FromRender> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() || self.error.is_some() {
            return;
        }
        if let Err(e) = self.start(event_loop) {
            self.fail(event_loop, e);
        }
    }

    fn user_event(&mut self, event_loop: &ActiveEventLoop, event: FromRender) {
        match event {
            // Done, quit or failed: run() joins the thread and reports.
            FromRender::Finished => event_loop.exit(),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        if self.window.is_some() {
            self.window_event_inner(event_loop, event);
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(window) = self.window.clone() else {
            return;
        };
        self.watch();
        // A minimised X11 window may get no event at all; poll its state a few times a
        // second (the render thread sleeps meanwhile).
        if self.last_minimised_poll.elapsed() >= Duration::from_millis(250) {
            self.last_minimised_poll = Instant::now();
            let size = window.inner_size();
            self.minimised =
                window.is_minimized() == Some(true) || size.width == 0 || size.height == 0;
            self.update_pause();
        }
        // Wake up for the file watch and the minimised poll; input wakes us anyway.
        event_loop.set_control_flow(ControlFlow::WaitUntil(
            Instant::now() + Duration::from_millis(250),
        ));
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
