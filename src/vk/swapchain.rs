//! Presentation: the swapchain of a window's surface, frames in flight and their
//! synchronization. It knows nothing about what is drawn: [`Swapchain::frame`] hands the
//! caller a [`Recorder`] and the acquired image, and does the rest (acquire, the barrier to
//! presentation, submit, present).
//!
//! The surface belongs to the [`Context`] (made with [`super::ContextDesc::window`]), so the
//! instance and device were chosen for it. Per frame in flight: a command buffer, a
//! timestamp query pool, an "image acquired" semaphore and a fence; per swapchain image: a
//! "rendering done" semaphore (presentation waits on it, and only the next acquire of the
//! same image says the presentation engine is done with it). A frame slot is reused only
//! after its fence, so its command buffer, query pool and semaphore are free by then; GPU
//! timings of a frame are read at that point and queue up in
//! [`Swapchain::take_timings`].
//!
//! Synchronization (synchronization2): the acquired image starts in [`Access::Acquired`]
//! (UNDEFINED layout, at the stage the acquire semaphore is waited at), so the first barrier
//! the caller's recording derives chains with the semaphore wait; the frame ends with a
//! transition to PRESENT_SRC_KHR and a signal at ALL_COMMANDS that presentation waits for.

use std::collections::VecDeque;

use anyhow::{bail, Context as _, Result};
use ash::vk;

use super::barriers::ACQUIRE_WAIT_STAGE;
use super::commands::{create_query_pool, PendingTimings};
use super::{Access, Context, Image, Recorder, Timings};

/// How many frames the CPU may record ahead of the GPU.
pub const FRAMES_IN_FLIGHT: usize = 2;

/// What to build a swapchain for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SwapchainDesc {
    /// The window's inner size in pixels (used when the surface does not dictate one, as on
    /// Wayland).
    pub size: [u32; 2],
    /// FIFO presentation (no tearing, paced by the display). Off: MAILBOX, else IMMEDIATE,
    /// else FIFO when the surface offers nothing else.
    pub vsync: bool,
}

/// What became of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameStatus {
    /// Recorded, submitted and queued for presentation, with this frame number.
    Presented(u64),
    /// The swapchain no longer matches the surface (resized window): nothing was recorded;
    /// call [`Swapchain::recreate`] and try again.
    OutOfDate,
}

struct FrameSlot {
    cmd: vk::CommandBuffer,
    queries: Option<vk::QueryPool>,
    acquired: vk::Semaphore,
    fence: vk::Fence,
    /// The frame last submitted from this slot, whose timings are read once it completes.
    pending: Option<(u64, PendingTimings)>,
}

pub struct Swapchain {
    ctx: Context,
    loader: ash::khr::swapchain::Device,
    raw: vk::SwapchainKHR,
    images: Vec<Image>,
    /// Signalled by the frame that rendered image i, waited for by its presentation.
    rendered: Vec<vk::Semaphore>,
    format: vk::SurfaceFormatKHR,
    extent: [u32; 2],
    present_mode: vk::PresentModeKHR,
    usage: vk::ImageUsageFlags,
    desc: SwapchainDesc,
    pool: vk::CommandPool,
    slots: Vec<FrameSlot>,
    slot: usize,
    next_frame: u64,
    stale: bool,
    completed: VecDeque<(u64, Timings)>,
}

impl Swapchain {
    /// A swapchain for the context's window surface.
    pub fn new(ctx: &Context, desc: SwapchainDesc) -> Result<Self> {
        let surface = ctx.shared.surface.as_ref().context(
            "this context was made without a window (ContextDesc::window); it cannot present",
        )?;
        let device = ctx.device();
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.shared.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: valid device; the pool is used only by this swapchain's frames.
        let pool = unsafe { device.create_command_pool(&pool_info, None) }?;
        let mut chain = Self {
            ctx: ctx.clone(),
            loader: surface.swapchain_loader.clone(),
            raw: vk::SwapchainKHR::null(),
            images: Vec::new(),
            rendered: Vec::new(),
            format: vk::SurfaceFormatKHR::default(),
            extent: [0, 0],
            present_mode: vk::PresentModeKHR::FIFO,
            usage: vk::ImageUsageFlags::empty(),
            desc,
            pool,
            slots: Vec::new(),
            slot: 0,
            next_frame: 0,
            stale: false,
            completed: VecDeque::new(),
        };
        // From here on Drop cleans up whatever was made.
        for i in 0..FRAMES_IN_FLIGHT {
            let slot = chain.make_slot(i)?;
            chain.slots.push(slot);
        }
        chain.build(desc)?;
        Ok(chain)
    }

    fn make_slot(&self, i: usize) -> Result<FrameSlot> {
        let device = self.ctx.device();
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: valid device and pool; objects are destroyed in Drop.
        unsafe {
            let cmd = device.allocate_command_buffers(&alloc)?[0];
            let acquired = device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None)?;
            let fence = device.create_fence(
                &vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED),
                None,
            );
            let fence = match fence {
                Ok(f) => f,
                Err(e) => {
                    device.destroy_semaphore(acquired, None);
                    return Err(e.into());
                }
            };
            let queries = match create_query_pool(&self.ctx) {
                Ok(q) => q,
                Err(e) => {
                    device.destroy_semaphore(acquired, None);
                    device.destroy_fence(fence, None);
                    return Err(e);
                }
            };
            self.ctx.set_name(cmd, &format!("frame {i}"));
            self.ctx
                .set_name(acquired, &format!("frame {i} image acquired"));
            self.ctx.set_name(fence, &format!("frame {i} done"));
            Ok(FrameSlot {
                cmd,
                queries,
                acquired,
                fence,
                pending: None,
            })
        }
    }

    /// (Re)build the swapchain for `desc`, retiring the current one.
    fn build(&mut self, desc: SwapchainDesc) -> Result<()> {
        let surface = self.ctx.shared.surface.as_ref().expect("checked in new");
        let physical = self.ctx.shared.physical;
        // SAFETY: valid physical device and surface of this instance.
        let (caps, formats, modes) = unsafe {
            (
                surface
                    .loader
                    .get_physical_device_surface_capabilities(physical, surface.raw)?,
                surface
                    .loader
                    .get_physical_device_surface_formats(physical, surface.raw)?,
                surface
                    .loader
                    .get_physical_device_surface_present_modes(physical, surface.raw)?,
            )
        };
        let extent = if caps.current_extent.width == u32::MAX {
            [
                desc.size[0].clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                desc.size[1].clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            ]
        } else {
            [caps.current_extent.width, caps.current_extent.height]
        };
        if extent[0] == 0 || extent[1] == 0 {
            bail!("the window has no area (minimised?); nothing to present to");
        }
        let format = choose_format(&formats)
            .context("the surface offers no 8-bit RGBA/BGRA format with sRGB colour space")?;
        let present_mode = choose_present_mode(&modes, desc.vsync);
        let mut usage = vk::ImageUsageFlags::COLOR_ATTACHMENT;
        if !caps
            .supported_usage_flags
            .contains(vk::ImageUsageFlags::COLOR_ATTACHMENT)
        {
            bail!("the surface's images cannot be colour attachments");
        }
        for extra in [
            vk::ImageUsageFlags::TRANSFER_SRC,
            vk::ImageUsageFlags::TRANSFER_DST,
        ] {
            if caps.supported_usage_flags.contains(extra) {
                usage |= extra;
            }
        }
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let alpha = [
            vk::CompositeAlphaFlagsKHR::OPAQUE,
            vk::CompositeAlphaFlagsKHR::INHERIT,
            vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
            vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
        ]
        .into_iter()
        .find(|a| caps.supported_composite_alpha.contains(*a))
        .context("the surface supports no composite alpha mode")?;
        let transform = if caps
            .supported_transforms
            .contains(vk::SurfaceTransformFlagsKHR::IDENTITY)
        {
            vk::SurfaceTransformFlagsKHR::IDENTITY
        } else {
            caps.current_transform
        };
        let old = self.raw;
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(surface.raw)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(vk::Extent2D {
                width: extent[0],
                height: extent[1],
            })
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(transform)
            .composite_alpha(alpha)
            .present_mode(present_mode)
            .clipped(true)
            .old_swapchain(old);
        // SAFETY: valid surface; the old swapchain (if any) is idle (recreate waited).
        let raw = unsafe { self.loader.create_swapchain(&info, None) }
            .context("creating the swapchain")?;
        self.release_images();
        if old != vk::SwapchainKHR::null() {
            // SAFETY: retired by the create above; the device is idle (recreate waited).
            unsafe { self.loader.destroy_swapchain(old, None) };
        }
        self.raw = raw;
        self.ctx.set_name(raw, "swapchain");
        // SAFETY: valid swapchain.
        let raws = unsafe { self.loader.get_swapchain_images(raw) }?;
        for (i, &img) in raws.iter().enumerate() {
            self.images.push(Image::from_swapchain(
                &self.ctx,
                img,
                format.format,
                extent,
                usage,
                &format!("swapchain image {i}"),
            )?);
            // SAFETY: valid device.
            let s = unsafe {
                self.ctx
                    .device()
                    .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
            }?;
            self.ctx
                .set_name(s, &format!("swapchain image {i} rendered"));
            self.rendered.push(s);
        }
        self.format = format;
        self.extent = extent;
        self.present_mode = present_mode;
        self.usage = usage;
        self.desc = desc;
        self.stale = false;
        log::info!(
            "swapchain: {}x{} {:?} {:?}, {} images, {:?}",
            extent[0],
            extent[1],
            format.format,
            format.color_space,
            raws.len(),
            present_mode
        );
        Ok(())
    }

    /// Image views and per-image semaphores of the current swapchain; the device must be
    /// idle.
    fn release_images(&mut self) {
        self.images.clear();
        for s in self.rendered.drain(..) {
            // SAFETY: the device is idle, so no submission or presentation waits on it.
            unsafe { self.ctx.device().destroy_semaphore(s, None) };
        }
    }

    /// Rebuild for a new window size (or after [`FrameStatus::OutOfDate`]). Waits until
    /// the device is idle first, so nothing in flight uses the old images. Fails for a
    /// window with no area; the caller should not present to a minimised window.
    pub fn recreate(&mut self, size: [u32; 2]) -> Result<()> {
        self.wait_idle()?;
        self.build(SwapchainDesc {
            size,
            vsync: self.desc.vsync,
        })
    }

    /// True once presentation or acquisition reported that the swapchain no longer
    /// matches the surface (suboptimal or out of date).
    pub fn is_stale(&self) -> bool {
        self.stale
    }

    pub fn extent(&self) -> [u32; 2] {
        self.extent
    }

    pub fn format(&self) -> vk::Format {
        self.format.format
    }

    /// True when the images' format encodes sRGB on write (…_SRGB): shaders then write
    /// linear values. False for UNORM formats, where a shader must encode.
    pub fn encodes_srgb(&self) -> bool {
        matches!(
            self.format.format,
            vk::Format::B8G8R8A8_SRGB
                | vk::Format::R8G8B8A8_SRGB
                | vk::Format::A8B8G8R8_SRGB_PACK32
        )
    }

    /// True when the images' format stores blue first (BGRA), as most X11 surfaces do.
    pub fn is_bgra(&self) -> bool {
        matches!(
            self.format.format,
            vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB
        )
    }

    /// Whether the swapchain images can be copied from (screenshots).
    pub fn can_copy_from(&self) -> bool {
        self.usage.contains(vk::ImageUsageFlags::TRANSFER_SRC)
    }

    /// The images, for framebuffers (index = what [`Swapchain::frame`] passes on).
    pub fn images(&self) -> &[Image] {
        &self.images
    }

    pub fn present_mode_name(&self) -> &'static str {
        match self.present_mode {
            vk::PresentModeKHR::FIFO => "fifo (vsync)",
            vk::PresentModeKHR::FIFO_RELAXED => "fifo relaxed",
            vk::PresentModeKHR::MAILBOX => "mailbox",
            vk::PresentModeKHR::IMMEDIATE => "immediate",
            _ => "other",
        }
    }

    /// Whether the next frame slot is free (its previous frame finished on the GPU), so
    /// [`Swapchain::frame`] will not block on it. Lets an event loop stay responsive while
    /// a slow device (lavapipe) renders.
    pub fn ready(&self) -> bool {
        let fence = self.slots[self.slot].fence;
        // SAFETY: valid fence.
        matches!(
            unsafe { self.ctx.device().get_fence_status(fence) },
            Ok(true)
        )
    }

    /// Record and present one frame. `record` gets the recorder, the index of the acquired
    /// image in [`Swapchain::images`] and the image itself, in [`Access::Acquired`] state;
    /// it must keep every resource it uses alive until this frame completes. Blocks until
    /// the frame slot is free and an image is acquired. An error from `record` leaves the
    /// acquired image unpresented and the swapchain unusable: check what can be checked
    /// before.
    pub fn frame(
        &mut self,
        record: impl FnOnce(&mut Recorder, usize, &Image) -> Result<()>,
    ) -> Result<FrameStatus> {
        let device = self.ctx.device().clone();
        let slot = &mut self.slots[self.slot];
        // SAFETY: valid fence; the slot's previous submission signals it.
        unsafe { device.wait_for_fences(&[slot.fence], true, u64::MAX) }
            .context("waiting for an earlier frame (device lost?)")?;
        if let Some((n, pending)) = slot.pending.take() {
            let t = pending.resolve(&self.ctx, slot.queries)?;
            self.completed.push_back((n, t));
        }
        // SAFETY: the semaphore is unsignalled: its last acquire was waited by a submission
        // that has completed (fence above), or it was never used.
        let acquired = unsafe {
            self.loader
                .acquire_next_image(self.raw, u64::MAX, slot.acquired, vk::Fence::null())
        };
        let index = match acquired {
            Ok((index, suboptimal)) => {
                if suboptimal {
                    self.stale = true;
                }
                index as usize
            }
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.stale = true;
                return Ok(FrameStatus::OutOfDate);
            }
            Err(e) => return Err(e).context("acquiring a swapchain image"),
        };
        let image = &self.images[index];
        image.reset_state(Access::Acquired);
        // SAFETY: the fence is signalled and the slot's command buffer idle.
        unsafe {
            device.reset_command_buffer(slot.cmd, vk::CommandBufferResetFlags::empty())?;
        }
        let mut rec = Recorder::begin(&self.ctx, slot.cmd, slot.queries, None)?;
        record(&mut rec, index, image)?;
        rec.transition(image, 0..1, Access::Present);
        let pending = rec.finish()?;

        let waits = [vk::SemaphoreSubmitInfo::default()
            .semaphore(slot.acquired)
            .stage_mask(ACQUIRE_WAIT_STAGE)];
        let signals = [vk::SemaphoreSubmitInfo::default()
            .semaphore(self.rendered[index])
            .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(slot.cmd)];
        let submit = vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cmds)
            .signal_semaphore_infos(&signals);
        let queue = self.ctx.shared.queue.lock().unwrap();
        // SAFETY: the fence is signalled (waited above) and is reset only now that a
        // submission that signals it follows; everything the recording references is kept
        // alive by the caller until the fence.
        unsafe {
            device.reset_fences(&[slot.fence])?;
            device
                .queue_submit2(*queue, &[submit], slot.fence)
                .context("submitting a frame")?;
        }
        slot.pending = Some((self.next_frame, pending));
        let wait = [self.rendered[index]];
        let chains = [self.raw];
        let indices = [index as u32];
        let present = vk::PresentInfoKHR::default()
            .wait_semaphores(&wait)
            .swapchains(&chains)
            .image_indices(&indices);
        // SAFETY: the image was acquired and rendered by the submission above.
        match unsafe { self.loader.queue_present(*queue, &present) } {
            Ok(false) => {}
            Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => self.stale = true,
            Err(e) => return Err(e).context("presenting a frame"),
        }
        drop(queue);
        let n = self.next_frame;
        self.next_frame += 1;
        self.slot = (self.slot + 1) % self.slots.len();
        Ok(FrameStatus::Presented(n))
    }

    /// Wait until every submitted frame and presentation has finished, and collect their
    /// timings. Call before freeing or replacing anything a frame in flight may use.
    pub fn wait_idle(&mut self) -> Result<()> {
        self.ctx.wait_idle()?;
        let mut done = Vec::new();
        for slot in &mut self.slots {
            if let Some((n, pending)) = slot.pending.take() {
                done.push((n, pending.resolve(&self.ctx, slot.queries)?));
            }
        }
        done.sort_by_key(|(n, _)| *n);
        self.completed.extend(done);
        Ok(())
    }

    /// GPU timings of the frames that have completed since the last call, oldest first,
    /// with their frame numbers.
    pub fn take_timings(&mut self) -> Vec<(u64, Timings)> {
        self.completed.drain(..).collect()
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        let _ = self.ctx.wait_idle();
        self.release_images();
        let device = self.ctx.device();
        // SAFETY: the device is idle; nothing made here is in use.
        unsafe {
            for slot in &self.slots {
                device.destroy_semaphore(slot.acquired, None);
                device.destroy_fence(slot.fence, None);
                if let Some(q) = slot.queries {
                    device.destroy_query_pool(q, None);
                }
            }
            device.destroy_command_pool(self.pool, None);
            if self.raw != vk::SwapchainKHR::null() {
                self.loader.destroy_swapchain(self.raw, None);
            }
        }
    }
}

/// 8-bit UNORM first (the caller encodes sRGB in its shader, exactly as the PNG path does on
/// the CPU), then 8-bit sRGB formats, all in the sRGB non-linear colour space.
fn choose_format(formats: &[vk::SurfaceFormatKHR]) -> Option<vk::SurfaceFormatKHR> {
    let preferred = [
        vk::Format::B8G8R8A8_UNORM,
        vk::Format::R8G8B8A8_UNORM,
        vk::Format::B8G8R8A8_SRGB,
        vk::Format::R8G8B8A8_SRGB,
    ];
    preferred.iter().find_map(|&f| {
        formats
            .iter()
            .find(|s| s.format == f && s.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR)
            .copied()
    })
}

fn choose_present_mode(modes: &[vk::PresentModeKHR], vsync: bool) -> vk::PresentModeKHR {
    if vsync {
        return vk::PresentModeKHR::FIFO;
    }
    [vk::PresentModeKHR::MAILBOX, vk::PresentModeKHR::IMMEDIATE]
        .into_iter()
        .find(|m| modes.contains(m))
        .unwrap_or(vk::PresentModeKHR::FIFO)
}
