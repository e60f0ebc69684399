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
//! What is drawn ([`preview`]): while the view changes, previews at a reduced size and
//! sample distance chosen to fit a frame-time budget; once it has been still for
//! [`preview::SETTLE`], one full-quality frame, and then nothing until it changes again
//! (with `--frames`, frames go on being drawn at full quality, for scripts and tests). The
//! window's title and the log name each frame's quality and GPU time.
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

use anyhow::{anyhow, bail, Context as _, Result};
use glam::Vec3;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, KeyEvent, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::keyboard::{Key, ModifiersState, NamedKey};
use winit::window::{Window, WindowId};

use crate::light::{clamp_light, turn_light};
use crate::output;
use crate::output::ToneMap;
use crate::render::{Camera, Frame, Model, RenderOptions, Renderer, ToneMapPass, MAX_ETA_SCALE};
use crate::scene::LoadedScene;
use crate::vk::{
    Buffer, Context, ContextDesc, FrameStatus, Framebuffer, LayerView, Overlay, Swapchain,
    SwapchainDesc, Timings, ValidationLog,
};

/// Reloads the scene from its sources (the command line's options and files).
pub type SceneLoader = Box<dyn FnMut() -> Result<LoadedScene>>;

/// What the controls change and every frame reads. A change of any of it (compared as a
/// whole) starts previews.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewState {
    pub model: Model,
    pub camera: Camera,
    /// The size is replaced by the swapchain's at each frame.
    pub opts: RenderOptions,
    pub tone: ToneMap,
    /// Draw the axes marker.
    pub axes: bool,
}

/// A left-drag of (dx, dy) pixels: orbit the camera; the light stays put in the world
/// unless the camera left its cone.
pub(super) fn orbit(s: &mut ViewState, dx: f32, dy: f32) {
    let c = &mut s.camera;
    c.azimuth = (c.azimuth - dx * DRAG_DEG_PER_PIXEL).rem_euclid(360.0);
    c.elevation = (c.elevation + dy * DRAG_DEG_PER_PIXEL).clamp(-89.0, 89.0);
    let camera = s.camera;
    move_light(s.opts.light_mut(), |t| clamp_light(t, &camera));
}

/// Apply a turn of directions (`turn`: towards the light before → after, unit) to `light`:
/// a directional light's direction, or a point light's position about the volume's centre
/// at its distance.
pub(super) fn move_light(light: &mut crate::light::Light, turn: impl Fn(Vec3) -> Vec3) {
    use crate::light::LightSource;
    light.source = match light.source {
        LightSource::Directional { towards } => LightSource::Directional {
            towards: turn(towards),
        },
        LightSource::Point { position } => LightSource::Point {
            position: turn(position) * position.length(),
        },
    };
}

/// Main thread → render thread.
pub(super) enum ToRender {
    /// Stop drawing (minimised, occluded) or go on.
    Pause(bool),
    /// New data for the scene (the view state stays).
    Reload(Box<LoadedScene>),
    /// Write a screenshot of the next frame.
    Screenshot,
    /// New transfer functions (the panel's preset).
    TransferFunctions(Box<crate::transfer::TransferFunctions>),
    /// A new environment behind the volume (the panel's choice; None: the background).
    Environment(Option<Box<crate::environment::EnvironmentMap>>),
    Quit,
}

/// Render thread → main thread (wakes the event loop).
#[derive(Debug)]
pub(super) enum FromRender {
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
    /// The previews' GPU frame-time budget in ms; None: no previews, every frame full.
    pub preview_budget_ms: Option<f64>,
    /// Orbit the camera by a scripted drag of [`SCRIPTED_DRAG_PX`] before each of the
    /// first N frames (tests, scripts).
    pub drag: Option<u64>,
    /// Orbit the camera as one step of `drag` does after this many batches of the first
    /// full-quality frame rendered in batches (tests, scripts: a change of view while a
    /// frame refines).
    pub interrupt_refinement: Option<u32>,
    /// Draw the axes marker (X toggles it).
    pub axes: bool,
    /// Show the on-screen panel at the start (Tab toggles it).
    pub panel: bool,
}

/// Pixels to the right per frame of `--drag` (4 degrees of azimuth).
pub const SCRIPTED_DRAG_PX: f32 = 10.0;

/// What a viewer session leaves behind.
#[derive(Clone, Debug, Default)]
pub struct ViewReport {
    /// Frames presented.
    pub frames: u64,
    /// Warnings and errors the validation layer reported over the whole session.
    pub validation_messages: usize,
    /// GPU milliseconds of each completed frame (the "frame" scope), in order.
    pub frame_ms: Vec<f64>,
    /// The quality of each completed frame with a time, in the same order.
    pub frame_quality: Vec<preview::Quality>,
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
  M                 model: refract > ea > ao > single > ambient (cycles)
  C                 clipping plane on / off
  X                 axes marker on / off (x red, y green, z blue; darker: pointing away)
  Tab               the panel on / off (model, transfer functions, light, softness, ...)
  R                 reload the scene and transfer-function files (also automatic on change)
  P                 screenshot (PNG as shown + linear EXR)
  H                 this help
  Esc, Q            quit";

/// Degrees per pixel of a drag.
pub(super) const DRAG_DEG_PER_PIXEL: f32 = 0.4;
/// Degrees per arrow-key press.
pub(super) const KEY_LIGHT_DEG: f32 = 5.0;
pub(super) const LIMITS_SOFTNESS: (f32, f32) = (0.0, 8.0);
pub(super) const LIMITS_SAMPLE_DISTANCE: (f32, f32) = (0.25, 8.0);
pub(super) const LIMITS_ROUGHNESS: (f32, f32) = (0.01, 1.0);
pub(super) const MAX_DISTANCE: f32 = 20.0;
pub(super) const WATCH_INTERVAL: Duration = Duration::from_millis(500);
pub(super) const RESIZE_TIMEOUT: Duration = Duration::from_secs(10);

/// Open the window and run until it is closed (or `--frames` are done).
pub fn run(
    desc: ContextDesc,
    scene: LoadedScene,
    loader: SceneLoader,
    options: ViewOptions,
) -> Result<ViewReport> {
    let unset = |v: &str| std::env::var_os(v).map_or(true, |x| x.is_empty());
    let hint = "for a headless machine use Xvfb (Debian package xvfb, installed by \
                scripts/setup.sh), e.g. `xvfb-run refrakt view`";
    if unset("DISPLAY") && unset("WAYLAND_DISPLAY") && unset("WAYLAND_SOCKET") {
        bail!(
            "no display (DISPLAY and WAYLAND_DISPLAY unset): `refrakt view` opens a window; {hint}"
        );
    }
    let event_loop = EventLoop::<FromRender>::with_user_event()
        .build()
        .map_err(|e| {
            // winit's message starts with its source path; keep only its reason.
            let reason = e.to_string();
            let reason = reason
                .rsplit(": ")
                .next()
                .unwrap_or(&reason)
                .trim_end_matches('.');
            anyhow!("cannot open a window ({reason}); {hint}")
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

mod app;
mod draw;
mod panel;
pub mod preview;
mod render_loop;

use app::*;
use preview::PreviewControl;
use render_loop::*;
