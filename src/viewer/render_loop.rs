//! The render thread: the swapchain, the renderer and the tone-map pass; previews while
//! the view changes and a full frame once it is still, each with the view state as it is
//! when the frame is recorded; screenshots.

use super::panel::PanelFrame;
use super::preview::{next_frame, PreviewControl, Quality, CALIBRATION};
use super::*;
use crate::render::{Model, PlaneBatch, Slot};
use crate::vk::{Image, ImageDesc, ImageKind};

/// How long the render thread sleeps between looks at the view while it has nothing to
/// draw (the refined frame is shown and the view has not changed).
const IDLE_POLL: Duration = Duration::from_millis(10);

/// Everything on the GPU, owned by the render thread. Dropped in field order after
/// [`Gpu::drop`] waited for the device: what the frames use, then the swapchain, the
/// context (device, surface).
pub(super) struct Gpu {
    /// The panel's renderer, made when the panel first has something to draw.
    pub(super) overlay: Option<Overlay>,
    pub(super) framebuffers: Vec<Framebuffer>,
    pub(super) views: Vec<LayerView>,
    pub(super) tonemap: ToneMapPass,
    pub(super) renderer: Renderer,
    pub(super) swapchain: Swapchain,
    pub(super) ctx: Context,
    pub(super) window: Arc<Window>,
}

impl Drop for Gpu {
    fn drop(&mut self) {
        let _ = self.swapchain.wait_idle();
    }
}

impl Gpu {
    /// Framebuffers over the current swapchain images (after a (re)creation).
    pub(super) fn rebuild_targets(&mut self) -> Result<()> {
        self.framebuffers.clear();
        self.views.clear();
        if self.swapchain.format() != self.tonemap.format() {
            self.tonemap = ToneMapPass::new(
                &self.ctx,
                self.swapchain.format(),
                self.swapchain.encodes_srgb(),
            )?;
            if let Some(o) = self.overlay.as_mut() {
                o.set_render_pass(self.tonemap.render_pass())?;
            }
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

/// The render thread: draws frames until told to quit or `--frames` are done.
pub(super) struct RenderLoop {
    pub(super) gpu: Gpu,
    pub(super) state: Arc<Mutex<ViewState>>,
    pub(super) rx: Receiver<ToRender>,
    pub(super) options: ViewOptions,
    pub(super) scene_name: String,
    pub(super) volume: crate::volume::Volume,
    pub(super) report: ViewReport,
    pub(super) paused: bool,
    pub(super) shot_requested: bool,
    pub(super) shot_counter: u32,
    pub(super) resize_done: bool,
    /// Planes and quality of each frame in flight, for the title once its timings arrive,
    /// and the timings of its batches when it was refined in batches (its own timings
    /// then cover only the tone map).
    pub(super) in_flight: HashMap<u64, Shown>,
    pub(super) last_print: Option<Instant>,
    pub(super) last_check_error: Option<String>,
    /// The previews' rung; None when previews are off.
    pub(super) preview: Option<PreviewControl>,
    /// The view (with the window's size) as last looked at, and since when it is so.
    pub(super) seen: Option<ViewState>,
    pub(super) changed_at: Instant,
    /// A full-quality frame of `seen` has been drawn.
    pub(super) refined: bool,
    /// The frame the scripted drag last moved the camera before.
    pub(super) last_drag: Option<u64>,
    /// `--interrupt-refinement` has moved the camera.
    pub(super) interrupted: bool,
    /// The panel as the main thread last left it, and the generation drawn last.
    pub(super) panel: Arc<Mutex<PanelFrame>>,
    pub(super) panel_drawn: u64,
    /// The quality of the frame on screen (None before the first and after a reload).
    pub(super) shown: Option<Quality>,
}

/// A presented frame whose timings have not arrived yet.
pub(super) struct Shown {
    /// The frame's number in the log ([`ViewReport::frames`] before it; frames shown
    /// again for the panel are not counted).
    pub(super) index: u64,
    pub(super) planes: Option<u32>,
    pub(super) quality: Quality,
    /// A frame refined in batches: their timings (its own cover the tone map only).
    pub(super) batches: Option<Timings>,
    /// The frame on screen drawn again for the panel: not a frame of its own.
    pub(super) again: bool,
}

/// Where the image a frame shows comes from.
pub(super) enum Source {
    /// Recorded into the frame's command buffer.
    Record,
    /// Rendered in batches already ([`RenderLoop::refine`]).
    Refined(Refined),
    /// The frame on screen, shown again (the panel changed).
    Again,
}

/// A full-quality frame rendered in batches and waiting in the renderer's
/// [`Slot::Main`] image to be presented: its batches' GPU timings and plane count.
pub(super) struct Refined {
    pub(super) timings: Timings,
    pub(super) planes: u32,
}

/// How many batches' plane count may grow by per batch: the first batch's one plane can
/// carry one-off costs (a first use compiles the pass's shaders on a CPU device), and the
/// planes near the volume's middle cover more pixels than the first ones.
const BATCH_GROWTH: u32 = 4;

impl RenderLoop {
    pub(super) fn run(&mut self) -> Result<()> {
        self.preintegrate()?;
        self.warm_up()?;
        loop {
            if !self.messages()? {
                return Ok(());
            }
            if self.done() {
                self.gpu.swapchain.wait_idle()?;
                self.collect_timings();
                return Ok(());
            }
            self.scripted_drag();
            match self.next_quality() {
                Some(Quality::Full) if self.refines_in_batches() => {
                    if !self.refine()? {
                        return Ok(());
                    }
                }
                Some(quality) => {
                    self.draw(quality, Source::Record)?;
                    if quality == Quality::Full {
                        self.refined = true;
                    }
                }
                None => match self.shown {
                    Some(q) if self.panel_changed() => self.draw(q, Source::Again)?,
                    _ => std::thread::sleep(IDLE_POLL),
                },
            }
            self.collect_timings();
        }
    }

    /// Build the preintegration table for new transfer functions in a submission of its
    /// own (seconds on a CPU device), so that no preview carries it.
    fn preintegrate(&mut self) -> Result<()> {
        let t = self.gpu.renderer.update_preintegration()?;
        if let Some(ms) = t.get("preintegration") {
            println!("preintegration table: {ms:.1} ms GPU");
        }
        Ok(())
    }

    /// The view a frame of `quality` renders in a window of `window` pixels, and the
    /// renderer's slot for it.
    pub(super) fn frame_view(&self, quality: Quality, window: [u32; 2]) -> (ViewState, Slot) {
        let mut view = self.state.lock().unwrap().clone();
        [view.opts.width, view.opts.height] = quality.size(window);
        view.opts.sample_distance *= quality.sample_factor();
        if let Quality::Preview(_) = quality {
            // The forward transport's light rays twice as far apart: a quarter of them (on
            // a GPU their splat is most of the frame).
            let s = &mut view.opts.sweep.light_spacing;
            *s = (*s * 2.0).min(crate::render::MAX_LIGHT_SPACING.max(*s));
        }
        let slot = match quality {
            Quality::Full => Slot::Main,
            Quality::Preview(k) => Slot::Preview(k),
        };
        (view, slot)
    }

    /// Before the first frame: render the calibration rungs off screen, each twice (a
    /// CPU device such as llvmpipe compiles a pipeline's shaders when it first runs them,
    /// inside the frame: about 2 s for the sweep's on an empty Mesa shader cache), fit the
    /// previews' cost model to the second times and run the rung it chooses once, so that
    /// no interaction waits for a compilation.
    fn warm_up(&mut self) -> Result<()> {
        if self.preview.is_none() {
            return Ok(());
        }
        let window = self.gpu.swapchain.extent();
        let mut times = Vec::new();
        for k in CALIBRATION {
            let quality = Quality::Preview(k);
            let Some(_) = self.render_off_screen(quality)? else {
                // The renderer refuses the view; draw() reports it.
                return Ok(());
            };
            if let Some(ms) = self.render_off_screen(quality)? {
                times.push((quality, ms));
            }
        }
        let Some(preview) = self.preview.as_mut() else {
            return Ok(());
        };
        let mut start = preview.calibrate(&times, window);
        // The model is a straight line through two cheap rungs, and the rung it picks
        // can cost more than it says (lavapipe: the plane count is not the sample
        // distance's exact fraction, and the light's rays grow with the pixels). Time the
        // chosen rung itself (the second run: the first may compile) and step down while
        // it is over the budget, so the first preview of an interaction fits.
        while !times.iter().any(|&(q, _)| q == start) {
            self.render_off_screen(start)?;
            let Some(ms) = self.render_off_screen(start)? else {
                break;
            };
            times.push((start, ms));
            let Some(preview) = self.preview.as_mut() else {
                return Ok(());
            };
            preview.observe(start, ms, window);
            if ms <= preview.budget_ms() {
                break;
            }
            start = preview.quality();
        }
        let said: Vec<String> = times
            .iter()
            .map(|(q, ms)| format!("{} {ms:.1} ms", q.describe(window)))
            .collect();
        println!(
            "previews: {}; starting with {}",
            said.join(", "),
            start.describe(window)
        );
        Ok(())
    }

    /// Render a frame of `quality` and tone map it into an image of the swapchain's size
    /// and format that nobody sees; its GPU milliseconds, None if the renderer refuses
    /// the view.
    fn render_off_screen(&mut self, quality: Quality) -> Result<Option<f64>> {
        let window = self.gpu.swapchain.extent();
        let (view, slot) = self.frame_view(quality, window);
        let gpu = &mut self.gpu;
        if gpu
            .renderer
            .check(view.model, &view.camera, &view.opts)
            .is_err()
        {
            return Ok(None);
        }
        let [w, h] = window;
        let target = Image::new(
            &gpu.ctx,
            ImageDesc {
                kind: ImageKind::D2,
                format: gpu.swapchain.format(),
                extent: [w, h, 1],
                layers: 1,
                usage: crate::vk::usage::COLOR_ATTACHMENT,
            },
            "off-screen target",
        )?;
        let target_view = target.layer_view(0)?;
        let framebuffer = Framebuffer::new(
            &gpu.ctx,
            gpu.tonemap.render_pass(),
            &[&target_view],
            w,
            h,
            "off-screen framebuffer",
        )?;
        let Gpu {
            ctx,
            renderer,
            tonemap,
            ..
        } = gpu;
        let t = ctx.execute(|rec| {
            rec.begin_scope("frame");
            let out = renderer.record(rec, slot, view.model, &view.camera, &view.opts)?;
            let axes = view.axes.then_some(&view.camera);
            tonemap.record(rec, out.image, &target, &framebuffer, &view.tone, axes)?;
            rec.end_scope();
            Ok(())
        })?;
        Ok(t.get("frame"))
    }

    /// --drag: before each of the first N frames, move the camera as a left-drag of
    /// SCRIPTED_DRAG_PX to the right does.
    fn scripted_drag(&mut self) {
        if self
            .options
            .drag
            .is_some_and(|n| self.report.frames < n && !self.dragged(self.report.frames))
        {
            orbit(&mut self.state.lock().unwrap(), SCRIPTED_DRAG_PX, 0.0);
            self.last_drag = Some(self.report.frames);
        }
    }

    /// The scripted drag moved the camera before frame `n` already (a frame that was not
    /// presented is drawn again with the same view).
    fn dragged(&self, n: u64) -> bool {
        self.last_drag == Some(n)
    }

    /// Full frames of the refractive model are rendered in batches of planes while
    /// previews are on: the view can change while one renders (seconds on a CPU device).
    fn refines_in_batches(&self) -> bool {
        self.preview.is_some() && self.state.lock().unwrap().model == Model::Refract
    }

    /// Render a full-quality frame of the refractive model in batches of planes, each
    /// submitted and waited for on its own (`SweepOptions::batch`), looking at the view
    /// between them: when it changed, the frame is abandoned (the next previews start at
    /// once: an interaction waits for one batch, not a frame), and once the last batch
    /// is done the frame is presented. A batch is sized by the last one's GPU time per
    /// plane to take about the previews' budget. False once told to quit.
    fn refine(&mut self) -> Result<bool> {
        let Some([w, h]) = self.prepare_target()? else {
            return Ok(true);
        };
        let (view, slot) = self.frame_view(Quality::Full, [w, h]);
        if self.refuses(&view) {
            return Ok(true);
        }
        let budget = self
            .preview
            .as_ref()
            .map_or(super::preview::DEFAULT_BUDGET_MS, |p| p.budget_ms());
        let mut timings = Timings::default();
        let (mut start, mut len, mut batches) = (0u32, 1u32, 0u32);
        loop {
            let mut batch = view.clone();
            batch.opts.sweep.batch = Some(PlaneBatch {
                start,
                end: start + len,
            });
            let Gpu { ctx, renderer, .. } = &mut self.gpu;
            let mut planes = None;
            let t = ctx.execute(|rec| {
                rec.begin_scope("frame");
                let out = renderer.record(rec, slot, batch.model, &batch.camera, &batch.opts)?;
                planes = out.sweep.as_ref().map(|s| s.planes.count);
                rec.end_scope();
                Ok(())
            })?;
            let n = planes.context("the refractive model's frame has planes")?;
            let ms = t.get("frame").unwrap_or(0.0);
            timings.extend(t);
            batches += 1;
            start = (start + len).min(n);
            if start == n {
                self.draw(
                    Quality::Full,
                    Source::Refined(Refined { timings, planes: n }),
                )?;
                self.refined = true;
                return Ok(true);
            }
            let per_plane = (ms / len as f64).max(1e-3);
            len = ((budget / per_plane) as u32).clamp(1, len * BATCH_GROWTH);
            if !self.messages()? {
                return Ok(false);
            }
            self.scripted_interrupt(batches);
            let changed = self.view_changed();
            if !changed && self.panel_changed() {
                // The panel answers while the frame refines (the frame on screen again).
                if let Some(q) = self.shown {
                    self.draw(q, Source::Again)?;
                }
            }
            if changed {
                println!(
                    "refinement abandoned after {start} of {n} planes ({batches} batches, \
                     {:.1} ms GPU): the view changed",
                    timings.get("frame").unwrap_or(0.0)
                );
                return Ok(true);
            }
        }
    }

    /// --interrupt-refinement N: after the N-th batch of the first refinement, move the
    /// camera as one step of --drag does.
    fn scripted_interrupt(&mut self, batches: u32) {
        if !self.interrupted && self.options.interrupt_refinement == Some(batches) {
            self.interrupted = true;
            orbit(&mut self.state.lock().unwrap(), SCRIPTED_DRAG_PX, 0.0);
        }
    }

    /// The view as the controls left it, at the window's size.
    fn current_view(&self) -> ViewState {
        let size = self.gpu.window.inner_size();
        let mut view = self.state.lock().unwrap().clone();
        view.opts.width = size.width;
        view.opts.height = size.height;
        view
    }

    /// The view (or the window's size) differs from the one last looked at.
    fn view_changed(&self) -> bool {
        self.seen.as_ref() != Some(&self.current_view())
    }

    /// What to draw next: a preview while the view changes (and for SETTLE after), then a
    /// full frame; None once that is shown and the view has not changed since (with
    /// `--frames`, full frames go on). Screenshots and the last frame of `--frames` are
    /// full.
    fn next_quality(&mut self) -> Option<Quality> {
        let view = self.current_view();
        if self.seen.as_ref() != Some(&view) {
            if let (Some(p), Some(seen)) = (self.preview.as_mut(), &self.seen) {
                if seen.model != view.model {
                    // The rungs' times were the other model's.
                    p.forget();
                }
            }
            self.seen = Some(view);
            self.changed_at = Instant::now();
            self.refined = false;
        }
        let last = self
            .options
            .frames
            .is_some_and(|n| self.report.frames + 1 == n);
        next_frame(
            self.preview.as_ref().map(|p| p.quality()),
            self.changed_at.elapsed(),
            self.refined,
            self.options.frames.is_some(),
            self.shot_requested || last,
        )
    }

    /// Handle what the main thread sent; false once told to quit. Blocks while paused
    /// (or while the window has no area), so a minimised window costs nothing.
    pub(super) fn messages(&mut self) -> Result<bool> {
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
                ToRender::TransferFunctions(tf) => {
                    self.gpu.swapchain.wait_idle()?;
                    self.gpu.renderer.set_transfer_functions(&tf)?;
                    // Drawn again: previews, then a full frame.
                    self.seen = None;
                    self.preintegrate()?;
                }
                ToRender::Environment(map) => {
                    self.gpu.swapchain.wait_idle()?;
                    self.gpu.renderer.set_environment(map.as_deref())?;
                    // Drawn again: previews, then a full frame.
                    self.seen = None;
                }
                ToRender::Quit => return Ok(false),
            }
        }
    }

    pub(super) fn done(&self) -> bool {
        self.options
            .frames
            .map(|n| self.report.frames >= n)
            .unwrap_or(false)
    }

    pub(super) fn reload(&mut self, new: LoadedScene) -> Result<()> {
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
        // A new renderer has no frames to show again.
        self.shown = None;
        // New data under an unchanged view: draw it (previews, then a full frame), and
        // learn its costs anew.
        self.seen = None;
        if let Some(p) = self.preview.as_mut() {
            p.forget();
        }
        self.preintegrate()
    }

    /// --resize: ask for the size before frame N and wait (up to RESIZE_TIMEOUT) until the
    /// window has it.
    pub(super) fn scripted_resize(&mut self) {
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

    /// The swapchain at the window's size (recreated if it is not), or None while the
    /// window has no area.
    pub(super) fn prepare_target(&mut self) -> Result<Option<[u32; 2]>> {
        self.scripted_resize();
        let size = self.gpu.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(None);
        }
        let gpu = &mut self.gpu;
        if gpu.swapchain.is_stale() || gpu.swapchain.extent() != [size.width, size.height] {
            gpu.swapchain.recreate([size.width, size.height])?;
            gpu.rebuild_targets()?;
        }
        Ok(Some(gpu.swapchain.extent()))
    }

    /// The renderer refuses `view`. Controls keep every value in range; anything left (a
    /// reloaded scene the renderer refuses) is reported once and nothing is drawn until it
    /// changes.
    pub(super) fn refuses(&mut self, view: &ViewState) -> bool {
        if let Err(e) = self
            .gpu
            .renderer
            .check(view.model, &view.camera, &view.opts)
        {
            let msg = format!("{e:#}");
            if self.last_check_error.as_deref() != Some(&msg) {
                eprintln!("cannot render: {msg}");
                self.last_check_error = Some(msg);
            }
            std::thread::sleep(Duration::from_millis(100));
            return true;
        }
        self.last_check_error = None;
        false
    }
}
