//! Drawing a frame on the render thread: the panel overlay, the recording of one frame
//! (render, tone map, overlay, present), screenshots and the timings in the title.

use super::preview::Quality;
use super::render_loop::RenderLoop;
use super::*;

/// Host copies of a frame for a screenshot, read once it completes.
pub(super) struct Shot {
    pub(super) png: PathBuf,
    pub(super) exr: PathBuf,
    pub(super) width: u32,
    pub(super) height: u32,
    /// The swapchain image as shown (None when its images cannot be copied from).
    pub(super) shown: Option<Buffer>,
    pub(super) bgra: bool,
    /// The renderer's linear frame.
    pub(super) linear: Buffer,
}

impl RenderLoop {
    /// The panel has changed since it was last drawn.
    pub(super) fn panel_changed(&self) -> bool {
        self.panel.lock().unwrap().generation != self.panel_drawn
    }

    /// The panel's texture updates applied (after the frames in flight, which may read
    /// the textures), and what to draw of it: None when hidden or empty.
    fn panel_overlay(&mut self) -> Result<Option<(Arc<Vec<egui::ClippedPrimitive>>, f32)>> {
        let (set, free, shapes) = {
            let mut p = self.panel.lock().unwrap();
            self.panel_drawn = p.generation;
            let shapes = (p.visible && !p.primitives.is_empty())
                .then(|| (p.primitives.clone(), p.pixels_per_point));
            (
                std::mem::take(&mut p.textures_set),
                std::mem::take(&mut p.textures_free),
                shapes,
            )
        };
        let gpu = &mut self.gpu;
        if gpu.overlay.is_none() && (shapes.is_some() || !set.is_empty()) {
            gpu.overlay = Some(Overlay::new(
                &gpu.ctx,
                gpu.tonemap.render_pass(),
                crate::vk::FRAMES_IN_FLIGHT,
                gpu.swapchain.encodes_srgb(),
            )?);
        }
        if let Some(o) = gpu.overlay.as_mut() {
            if !set.is_empty() || !free.is_empty() {
                gpu.swapchain.wait_idle()?;
                o.set_textures(&set)?;
                o.free_textures(&free)?;
            }
        }
        Ok(shapes)
    }

    /// Record and present one frame of `quality` from `source`: recorded now, or already
    /// in the renderer's slot (refined in batches, or the frame on screen again), then
    /// only tone mapped (and copied for a screenshot). The panel is drawn over it.
    pub(super) fn draw(&mut self, quality: Quality, source: Source) -> Result<()> {
        let Some([w, h]) = self.prepare_target()? else {
            return Ok(());
        };
        let (view, slot) = self.frame_view(quality, [w, h]);
        if matches!(source, Source::Record) && self.refuses(&view) {
            return Ok(());
        }
        let again = matches!(source, Source::Again);
        let overlay = self.panel_overlay()?;
        let frame_no = self.report.frames;
        let last = self
            .options
            .frames
            .map(|n| frame_no + 1 == n)
            .unwrap_or(false);
        let shot = if !again && (self.shot_requested || (last && self.options.screenshot.is_some()))
        {
            self.shot_requested = false;
            Some(self.prepare_shot(last, w, h)?)
        } else {
            None
        };
        let record = matches!(source, Source::Record);
        let (mut planes, batches) = match source {
            Source::Refined(r) => (Some(r.planes), Some(r.timings)),
            _ => (None, None),
        };
        let Gpu {
            framebuffers,
            tonemap,
            renderer,
            swapchain,
            overlay: panel,
            ..
        } = &mut self.gpu;
        let status = swapchain.frame(|rec, index, target| {
            rec.begin_scope("frame");
            let image = match record {
                false => renderer.frame_image(view.model, slot)?,
                true => {
                    let out = renderer.record(rec, slot, view.model, &view.camera, &view.opts)?;
                    planes = out.sweep.as_ref().map(|s| s.planes.count);
                    out.image
                }
            };
            let axes = view.axes.then_some(&view.camera);
            tonemap.record(rec, image, target, &framebuffers[index], &view.tone, axes)?;
            if let (Some((primitives, ppp)), Some(panel)) = (&overlay, panel.as_mut()) {
                // A second instance of the tone map's render pass: it loads what the first
                // stored, and the recorder orders the two.
                rec.begin_render_pass(tonemap.render_pass(), &framebuffers[index], &[(target, 0)])?;
                panel.draw(rec, [w, h], *ppp, primitives)?;
                rec.end_render_pass();
            }
            if let Some(shot) = &shot {
                if let Some(buf) = &shot.shown {
                    rec.copy_image_to_buffer(target, 0, buf);
                }
                rec.copy_image_to_buffer(image, 0, &shot.linear);
            }
            rec.end_scope();
            Ok(())
        })?;
        if let FrameStatus::Presented(n) = status {
            self.in_flight.insert(
                n,
                Shown {
                    index: self.report.frames,
                    planes,
                    quality,
                    batches,
                    again,
                },
            );
            self.shown = Some(quality);
            if again {
                return Ok(());
            }
            self.report.frames += 1;
            if let Some(shot) = shot {
                self.gpu.swapchain.wait_idle()?;
                write_shot(&shot)?;
            }
        }
        Ok(())
    }

    pub(super) fn prepare_shot(&mut self, last: bool, w: u32, h: u32) -> Result<Shot> {
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
    pub(super) fn collect_timings(&mut self) {
        let done = self.gpu.swapchain.take_timings();
        for (n, t) in done {
            let Some(Shown {
                index,
                planes,
                quality,
                batches,
                again,
            }) = self.in_flight.remove(&n)
            else {
                continue;
            };
            if again {
                continue;
            }
            // A frame refined in batches: its batches' times (its own is the tone map's).
            let t = batches.unwrap_or(t);
            let [w, h] = self.gpu.swapchain.extent();
            let line = format!("{}: {}", quality.describe([w, h]), summary(&t, planes));
            if let Some(ms) = t.get("frame") {
                self.report.frame_ms.push(ms);
                self.report.frame_quality.push(quality);
                if let Some(p) = self.preview.as_mut() {
                    p.observe(quality, ms, [w, h]);
                }
            }
            self.panel.lock().unwrap().status = line.clone();
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
            // Every full frame is printed: the refined one ends an interaction.
            if self.options.frames.is_some() || due || quality == Quality::Full {
                println!("frame {index}: {line}");
                self.last_print = Some(Instant::now());
            }
        }
    }
}

/// "GPU ms per frame, ms in the sweep, plane count" of one frame.
pub(super) fn summary(t: &Timings, planes: Option<u32>) -> String {
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

pub(super) fn write_shot(shot: &Shot) -> Result<()> {
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
