//! The main thread's winit application: input to view state and messages, file watching,
//! the window's title and size.

use super::panel::{EnvChoice, Panel, PanelAction};
use super::*;
use crate::environment::EnvironmentMap;

/// Mouse and keyboard state between events.
#[derive(Default)]
pub(super) struct Input {
    pub(super) cursor: Option<(f64, f64)>,
    pub(super) orbiting: bool,
    pub(super) lighting: bool,
    pub(super) modifiers: ModifiersState,
}

/// The main thread: window, events, controls.
pub(super) struct App {
    pub(super) desc: ContextDesc,
    /// Until the render thread takes it.
    pub(super) scene: Option<LoadedScene>,
    pub(super) loader: SceneLoader,
    pub(super) options: ViewOptions,
    pub(super) proxy: EventLoopProxy<FromRender>,
    pub(super) state: Arc<Mutex<ViewState>>,
    pub(super) window: Option<Arc<Window>>,
    pub(super) to_render: Option<Sender<ToRender>>,
    pub(super) render_thread: Option<JoinHandle<(ViewReport, Result<()>)>>,
    pub(super) validation: Option<Arc<ValidationLog>>,
    pub(super) error: Option<anyhow::Error>,
    pub(super) input: Input,
    /// Half the volume box's diagonal: the camera stays outside it.
    pub(super) volume_radius: f32,
    /// The clipping plane C toggles when there was none on the command line.
    pub(super) clip_default: Option<(Vec3, f32)>,
    pub(super) paused: bool,
    pub(super) minimised: bool,
    pub(super) occluded: bool,
    pub(super) last_watch: Instant,
    pub(super) watched: Vec<(PathBuf, Option<SystemTime>)>,
    pub(super) last_minimised_poll: Instant,
    /// The on-screen panel (made with the window).
    pub(super) panel: Option<Panel>,
    /// The scene's own environment, for the panel's "the scene's" choice.
    pub(super) scene_env: Option<EnvironmentMap>,
}

pub(super) fn mtime(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

impl App {
    pub(super) fn new(
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
            axes: options.axes,
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
            panel: None,
            scene_env: None,
        }
    }

    pub(super) fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        if self.error.is_none() {
            self.error = Some(e);
        }
        event_loop.exit();
    }

    pub(super) fn send(&self, msg: ToRender) {
        if let Some(tx) = &self.to_render {
            // A closed channel means the render thread has ended; its result arrives with
            // FromRender::Finished.
            let _ = tx.send(msg);
        }
    }

    /// Window, context, swapchain, renderer, tone-map pass; then the render thread.
    pub(super) fn start(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
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
        self.scene_env = scene.env.clone();
        let panel = Panel::new(
            &window,
            self.options.panel,
            self.volume_radius,
            (scene.env_name.clone(), scene.env.is_none()),
        );
        let panel_frame = panel.shared.clone();
        self.panel = Some(panel);
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
            overlay: None,
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
            in_flight: HashMap::new(),
            last_print: None,
            last_check_error: None,
            preview: self.options.preview_budget_ms.map(PreviewControl::new),
            seen: None,
            changed_at: Instant::now(),
            refined: false,
            last_drag: None,
            interrupted: false,
            panel: panel_frame,
            panel_drawn: 0,
            shown: None,
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

    pub(super) fn update_pause(&mut self) {
        let paused = self.minimised || self.occluded;
        if paused != self.paused {
            self.paused = paused;
            self.send(ToRender::Pause(paused));
        }
    }

    pub(super) fn reload(&mut self) {
        let started = Instant::now();
        match (self.loader)() {
            Ok(new) => {
                self.watched = new.files.iter().map(|f| (f.clone(), mtime(f))).collect();
                self.volume_radius = 0.5 * Vec3::from(new.volume.normalised_extent()).length();
                self.scene_env = new.env.clone();
                if let Some(p) = self.panel.as_mut() {
                    p.set_radius(self.volume_radius);
                    p.set_scene_env((new.env_name.clone(), new.env.is_none()));
                }
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

    pub(super) fn watch(&mut self) {
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

    pub(super) fn light_moved(&mut self, yaw: f32, pitch: f32) {
        let mut s = self.state.lock().unwrap();
        let camera = s.camera;
        super::move_light(s.opts.light_mut(), |t| turn_light(t, &camera, yaw, pitch));
    }

    pub(super) fn key(&mut self, event: &KeyEvent, event_loop: &ActiveEventLoop) {
        if event.state != ElementState::Pressed {
            return;
        }
        let step = |v: &mut f32, d: f32, (lo, hi): (f32, f32)| *v = (*v + d).clamp(lo, hi);
        let mut said = None;
        match &event.logical_key {
            Key::Named(NamedKey::Escape) => event_loop.exit(),
            Key::Named(NamedKey::Tab) => {
                if let Some(p) = self.panel.as_mut() {
                    let on = p.toggle();
                    said = Some(format!("panel {}", if on { "on" } else { "off" }));
                }
            }
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
                    "x" => {
                        let mut st = self.state.lock().unwrap();
                        st.axes = !st.axes;
                        said = Some(format!(
                            "axes marker {}",
                            if st.axes { "on" } else { "off" }
                        ));
                    }
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
                        // The main light's softness (a field apart from the sweep's
                        // options, so both can be borrowed).
                        let softness = &mut opts.lights[0].softness;
                        let s = &mut opts.sweep;
                        match c.as_str() {
                            "[" | "{" => {
                                step(softness, -0.25, LIMITS_SOFTNESS);
                                said = Some(format!("softness {:.2}", softness));
                            }
                            "]" | "}" => {
                                step(softness, 0.25, LIMITS_SOFTNESS);
                                said = Some(format!("softness {:.2}", softness));
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
                                *model = model.next();
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

    pub(super) fn window_event_inner(&mut self, event_loop: &ActiveEventLoop, event: WindowEvent) {
        // The panel sees every event first; input it takes (the pointer over it, a slider
        // being dragged, a key while a widget has focus) does not reach the view.
        let taken = match (self.panel.as_mut(), self.window.as_ref()) {
            (Some(p), Some(w)) => p.on_event(w, &event),
            _ => false,
        };
        if taken {
            match event {
                WindowEvent::CursorMoved { position, .. } => {
                    self.input.cursor = Some((position.x, position.y));
                    return;
                }
                WindowEvent::MouseInput { .. }
                | WindowEvent::MouseWheel { .. }
                | WindowEvent::KeyboardInput { .. } => return,
                _ => {}
            }
        }
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
                        orbit(&mut self.state.lock().unwrap(), dx, dy);
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
        let mut actions = Vec::new();
        let animating = match self.panel.as_mut() {
            Some(p) => p.update(&window, &self.state, &mut actions),
            None => false,
        };
        for action in actions {
            match action {
                PanelAction::TransferFunctions(name) => {
                    match crate::transfer::TransferFunctions::load(&name) {
                        Ok(tf) => {
                            println!("transfer functions: {name}");
                            self.send(ToRender::TransferFunctions(Box::new(tf)));
                        }
                        Err(e) => eprintln!("transfer functions {name}: {e:#}"),
                    }
                }
                PanelAction::Environment(choice) => {
                    let map = match choice {
                        EnvChoice::Scene => Ok(self.scene_env.clone()),
                        EnvChoice::Sky => {
                            EnvironmentMap::procedural(EnvironmentMap::SKY_WIDTH).map(Some)
                        }
                        EnvChoice::None => Ok(None),
                    };
                    match map {
                        Ok(map) => {
                            println!(
                                "environment: {}",
                                match choice {
                                    EnvChoice::Scene => "the scene's",
                                    EnvChoice::Sky => "sky",
                                    EnvChoice::None => "none (the background colour)",
                                }
                            );
                            self.send(ToRender::Environment(map.map(Box::new)));
                        }
                        Err(e) => eprintln!("environment: {e:#}"),
                    }
                }
            }
        }
        // A minimised X11 window may get no event at all; poll its state a few times a
        // second (the render thread sleeps meanwhile).
        if self.last_minimised_poll.elapsed() >= Duration::from_millis(250) {
            self.last_minimised_poll = Instant::now();
            let size = window.inner_size();
            self.minimised =
                window.is_minimized() == Some(true) || size.width == 0 || size.height == 0;
            self.update_pause();
        }
        // Wake up for the file watch, the minimised poll and the panel's status line
        // (input wakes us anyway), soon while the panel animates.
        let wait = if animating { 16 } else { 250 };
        event_loop.set_control_flow(ControlFlow::WaitUntil(
            Instant::now() + Duration::from_millis(wait),
        ));
    }
}
