//! An egui overlay drawn inside one of our render passes (the viewer's panel), through the
//! egui-ash-renderer crate: it keeps the overlay's pipeline, vertex buffers (one set per
//! frame in flight) and textures. Its texture uploads are submissions of their own that
//! it waits for; the caller makes sure no frame in flight still reads a texture that an
//! update rewrites ([`Overlay::set_textures`]).

use anyhow::{Context as _, Result};
use ash::vk;
use egui_ash_renderer::{Options, Renderer};

use super::{Context, Recorder, RenderPass};

pub struct Overlay {
    ctx: Context,
    renderer: Renderer,
}

impl Overlay {
    /// An overlay for draws inside `pass` (one colour attachment), with `frames_in_flight`
    /// frames recorded ahead; `srgb_target`: the attachment encodes sRGB itself, so the
    /// overlay writes linear colour.
    pub fn new(
        ctx: &Context,
        pass: &RenderPass,
        frames_in_flight: usize,
        srgb_target: bool,
    ) -> Result<Self> {
        let s = &ctx.shared;
        let renderer = Renderer::with_default_allocator(
            &s.instance,
            s.physical,
            s.device.clone(),
            pass.raw,
            Options {
                in_flight_frames: frames_in_flight,
                srgb_framebuffer: srgb_target,
                ..Options::default()
            },
        )
        .context("creating the panel's renderer (egui-ash-renderer)")?;
        Ok(Self {
            ctx: ctx.clone(),
            renderer,
        })
    }

    /// Draw into another render pass of the same attachment (a new swapchain format).
    pub fn set_render_pass(&mut self, pass: &RenderPass) -> Result<()> {
        self.renderer
            .set_render_pass(pass.raw)
            .context("rebuilding the panel's pipeline")
    }

    /// Create or update the overlay's textures (egui's font atlas). Uploads are submitted
    /// and waited for here; the caller must have waited for every frame that reads a
    /// texture an update rewrites.
    pub fn set_textures(
        &mut self,
        set: &[(egui::TextureId, egui::epaint::ImageDelta)],
    ) -> Result<()> {
        if set.is_empty() {
            return Ok(());
        }
        let s = &self.ctx.shared;
        let queue = s.queue.lock().unwrap();
        let pool = s.command_pool.lock().unwrap();
        self.renderer
            .set_textures(*queue, *pool, set)
            .context("uploading the panel's textures")
    }

    /// Free textures egui no longer uses; no frame in flight may read them.
    pub fn free_textures(&mut self, ids: &[egui::TextureId]) -> Result<()> {
        self.renderer
            .free_textures(ids)
            .context("freeing the panel's textures")
    }

    /// Record the overlay's draws into the render pass `rec` is in, over a target of
    /// `extent` pixels.
    pub fn draw(
        &mut self,
        rec: &mut Recorder,
        extent: [u32; 2],
        pixels_per_point: f32,
        primitives: &[egui::ClippedPrimitive],
    ) -> Result<()> {
        self.renderer
            .cmd_draw(
                rec.cmd,
                vk::Extent2D {
                    width: extent[0],
                    height: extent[1],
                },
                pixels_per_point,
                primitives,
            )
            .context("recording the panel")
    }
}
