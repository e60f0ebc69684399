//! Command recording, submission, barriers and GPU timestamp scopes.
//!
//! One [`Recorder`] is one primary command buffer: a whole frame is recorded into it and
//! submitted once ([`Context::execute`]). Named scopes write a timestamp pair and a debug
//! label, so RenderDoc/Nsight captures and the printed GPU milliseconds use the same names.

use std::ffi::CString;
use std::ops::Range;

use anyhow::{bail, Result};
use ash::vk;

use super::barriers::plan_transitions;
use super::pipeline::PipelineCore;
use super::resources::color_range;
use super::{Access, Buffer, ComputePipeline, Context, DescriptorSet, Image};

mod dispatch;
mod draw;
pub use draw::{Area, BufferUse};
mod submit;
mod timings;

pub(crate) use timings::create_query_pool;
use timings::*;
pub use timings::{PendingTimings, Timings};

/// How a pass uses an image (see [`Recorder::pass`]).
pub struct Use<'a> {
    pub image: &'a Image,
    pub layers: Range<u32>,
    pub access: Access,
}

impl<'a> Use<'a> {
    /// Every layer of `image`, used as `access`.
    pub fn all(image: &'a Image, access: Access) -> Self {
        Self {
            image,
            layers: 0..image.desc().layers,
            access,
        }
    }
}

struct Scope {
    name: String,
    begin: u32,
    end: Option<u32>,
}

pub struct Recorder<'a> {
    ctx: &'a Context,
    pub(crate) cmd: vk::CommandBuffer,
    queries: Option<vk::QueryPool>,
    next_query: u32,
    scopes: Vec<Scope>,
    open: Vec<usize>,
    /// Progress marks, when the submission reports progress ([`Context::execute_observed`]):
    /// `None` records none.
    marks: Option<Marks>,
}

/// The progress marks of an observed recording: the fraction of its long work each mark
/// stands for, in order. Mark k is a 1 written into word k of `buffer` (host-visible,
/// zeroed) once the GPU has finished every command recorded before it.
pub(crate) struct Marks {
    pub(crate) buffer: vk::Buffer,
    pub(crate) fractions: Vec<f64>,
}

/// The most progress marks a recording writes: a bar with 2 % steps. Each costs a buffer
/// fill between two barriers (a bubble of microseconds on a GPU).
pub(crate) const MAX_MARKS: u64 = 50;

impl Recorder<'_> {
    fn device(&self) -> &ash::Device {
        self.ctx.device()
    }

    /// Open a named timing scope (and debug label). Scopes nest.
    pub fn begin_scope(&mut self, name: &str) {
        if let Some(dd) = &self.ctx.shared.debug_device {
            let cname = CString::new(name).unwrap_or_default();
            let label = vk::DebugUtilsLabelEXT::default().label_name(&cname);
            // SAFETY: recording command buffer.
            unsafe { dd.cmd_begin_debug_utils_label(self.cmd, &label) };
        }
        let begin = self.write_timestamp();
        self.scopes.push(Scope {
            name: name.to_owned(),
            begin: begin.unwrap_or(u32::MAX),
            end: None,
        });
        self.open.push(self.scopes.len() - 1);
    }

    pub fn end_scope(&mut self) {
        let Some(idx) = self.open.pop() else { return };
        let end = self.write_timestamp();
        self.scopes[idx].end = end;
        if let Some(dd) = &self.ctx.shared.debug_device {
            // SAFETY: matches the begin label above.
            unsafe { dd.cmd_end_debug_utils_label(self.cmd) };
        }
    }

    /// Say that `done` of `total` units of this recording's long work (the planes of a
    /// sweep) are recorded so far. When the submission reports progress, a mark is
    /// written each time `done / total` passes another of [`MAX_MARKS`] steps; once the
    /// GPU has executed it, the host sees the fraction while it waits for the rest. A
    /// no-op otherwise (the marks would cost barriers for nothing).
    ///
    /// Why a buffer and not a timestamp query: lavapipe (Mesa 22.3) reports no query of a
    /// running submission as available (measured: every mark of a 24 s frame turned
    /// available at its end), while a fill into host-visible memory is there as soon as
    /// it has run: a breadcrumb, as crash-dump tools leave them.
    pub fn progress(&mut self, done: u32, total: u32) {
        let Some(marks) = self.marks.as_ref() else {
            return;
        };
        if total == 0 || marks.fractions.len() as u64 >= MAX_MARKS {
            return;
        }
        let step = (done.min(total) as u64 * MAX_MARKS) / total as u64;
        let fraction = step as f64 / MAX_MARKS as f64;
        let last = marks.fractions.last().copied().unwrap_or(0.0);
        if fraction <= last {
            return;
        }
        let (buffer, word) = (marks.buffer, marks.fractions.len() as u64);
        // Everything recorded so far, then the fill; the fill's write made available to
        // the host.
        let before = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .dst_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)];
        let after = [vk::BufferMemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
            .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::HOST)
            .dst_access_mask(vk::AccessFlags2::HOST_READ)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .buffer(buffer)
            .offset(4 * word)
            .size(4)];
        // SAFETY: recording; the word lies in the marks buffer (MAX_MARKS words), which
        // outlives the submission.
        unsafe {
            let device = self.device();
            device.cmd_pipeline_barrier2(
                self.cmd,
                &vk::DependencyInfo::default().memory_barriers(&before),
            );
            device.cmd_fill_buffer(self.cmd, buffer, 4 * word, 4, 1);
            device.cmd_pipeline_barrier2(
                self.cmd,
                &vk::DependencyInfo::default().buffer_memory_barriers(&after),
            );
        }
        if let Some(m) = self.marks.as_mut() {
            m.fractions.push(fraction);
        }
    }

    fn write_timestamp(&mut self) -> Option<u32> {
        let pool = self.queries?;
        if self.next_query >= MAX_QUERIES {
            return None;
        }
        let q = self.next_query;
        self.next_query += 1;
        // Measured on lavapipe (Mesa 22.3): once a graphics pipeline has run in the process,
        // llvmpipe defers a timestamp until its next flush, so the timestamp opening a compute
        // scope was stamped after the dispatch had run (0.05 ms reported for a 44 ms pass).
        // A full execution dependency on both sides makes the timestamp land where it was
        // recorded on every driver; it costs a bubble per scope boundary, a handful per frame.
        let barrier = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let dep = vk::DependencyInfo::default().memory_barriers(&barrier);
        // SAFETY: query index within the pool, which was reset at the start of recording.
        unsafe {
            self.device().cmd_pipeline_barrier2(self.cmd, &dep);
            self.device().cmd_write_timestamp2(
                self.cmd,
                vk::PipelineStageFlags2::ALL_COMMANDS,
                pool,
                q,
            );
            self.device().cmd_pipeline_barrier2(self.cmd, &dep);
        };
        Some(q)
    }

    /// Make `layers` of `image` ready for `to`, with a barrier derived from the state the
    /// previous use left. Read-after-read in the same layout needs no barrier and gets none.
    pub fn transition(&mut self, image: &Image, layers: Range<u32>, to: Access) {
        self.transition_many(&[(image, layers, to)]);
    }

    /// One pass, declared: its timestamp scope and debug label `name`, the barriers its
    /// declared image uses need (one batch, from each image's tracked state), then `body`,
    /// which records the pass's work. Passes say what they read and write; synchronization
    /// and timing follow from that here. (The sweep's per-plane barriers inside its
    /// scope stay explicit: they change roles layer by layer.)
    pub fn pass<R>(
        &mut self,
        name: &str,
        uses: &[Use<'_>],
        body: impl FnOnce(&mut Self) -> Result<R>,
    ) -> Result<R> {
        self.begin_scope(name);
        let items: Vec<(&Image, Range<u32>, Access)> = uses
            .iter()
            .map(|u| (u.image, u.layers.clone(), u.access))
            .collect();
        self.transition_many(&items);
        let result = body(self);
        self.end_scope();
        result
    }

    /// Several transitions in one vkCmdPipelineBarrier2 (in the sweep: one per role change
    /// per plane instead of one per image).
    pub fn transition_many(&mut self, items: &[(&Image, Range<u32>, Access)]) {
        let mut barriers = Vec::new();
        for (image, layers, to) in items {
            image_barriers(image, layers.clone(), *to, &mut barriers);
        }
        if !barriers.is_empty() {
            let dep = vk::DependencyInfo::default().image_memory_barriers(&barriers);
            // SAFETY: recording; barriers reference live images.
            unsafe { self.device().cmd_pipeline_barrier2(self.cmd, &dep) };
        }
    }

    /// Record that `layers` are now used as `to` WITHOUT a barrier. Only for tests that prove
    /// synchronization validation catches a missing barrier; rendering never calls it.
    pub fn assume_without_barrier(&mut self, image: &Image, layers: Range<u32>, to: Access) {
        let mut state = image.layer_state.lock().unwrap();
        for l in layers {
            state[l as usize] = to;
        }
    }

    /// Transition every layer of `image`.
    pub fn transition_all(&mut self, image: &Image, to: Access) {
        self.transition(image, 0..image.desc.layers, to);
    }

    /// Copy tightly packed texels from `buffer` into one layer of `image`.
    pub fn copy_buffer_to_image(&mut self, buffer: &Buffer, image: &Image, layer: u32) {
        self.transition(image, layer..layer + 1, Access::TransferDst);
        let region = buffer_image_copy(image, layer);
        // SAFETY: the image layer is in TRANSFER_DST_OPTIMAL after the transition.
        unsafe {
            self.device().cmd_copy_buffer_to_image(
                self.cmd,
                buffer.raw,
                image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
            )
        };
    }

    /// Copy one layer of `image` into `buffer` and make it visible to the host.
    pub fn copy_image_to_buffer(&mut self, image: &Image, layer: u32, buffer: &Buffer) {
        self.transition(image, layer..layer + 1, Access::TransferSrc);
        let region = buffer_image_copy(image, layer);
        // SAFETY: layer is in TRANSFER_SRC_OPTIMAL after the transition.
        unsafe {
            self.device().cmd_copy_image_to_buffer(
                self.cmd,
                image.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                buffer.raw,
                &[region],
            );
            let barrier = vk::BufferMemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::COPY)
                .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::HOST)
                .dst_access_mask(vk::AccessFlags2::HOST_READ)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .buffer(buffer.raw)
                .offset(0)
                .size(vk::WHOLE_SIZE);
            let barriers = [barrier];
            let dep = vk::DependencyInfo::default().buffer_memory_barriers(&barriers);
            self.device().cmd_pipeline_barrier2(self.cmd, &dep);
        }
    }

    /// Scale one layer of `src` onto one layer of `dst` (each layer whole), filtering
    /// linearly where `linear` (the caller checks the source format can be filtered) and
    /// taking the nearest texel otherwise. Both are 2D images or 2D arrays.
    pub fn blit_layer(
        &mut self,
        src: &Image,
        src_layer: u32,
        dst: &Image,
        dst_layer: u32,
        linear: bool,
    ) {
        self.transition_many(&[
            (src, src_layer..src_layer + 1, Access::TransferSrc),
            (dst, dst_layer..dst_layer + 1, Access::TransferDst),
        ]);
        let corner = |image: &Image| {
            let [w, h, _] = image.desc.extent;
            [
                vk::Offset3D::default(),
                vk::Offset3D {
                    x: w as i32,
                    y: h as i32,
                    z: 1,
                },
            ]
        };
        let layer = |l: u32| vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: l,
            layer_count: 1,
        };
        let region = vk::ImageBlit {
            src_subresource: layer(src_layer),
            src_offsets: corner(src),
            dst_subresource: layer(dst_layer),
            dst_offsets: corner(dst),
        };
        let filter = if linear {
            vk::Filter::LINEAR
        } else {
            vk::Filter::NEAREST
        };
        // SAFETY: the layers are in TRANSFER_SRC / TRANSFER_DST_OPTIMAL after the
        // transition; the regions lie within both images.
        unsafe {
            self.device().cmd_blit_image(
                self.cmd,
                src.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                dst.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
                filter,
            )
        };
    }

    /// Write `bytes` into a uniform buffer (made with [`Buffer::uniform`]) as part of the
    /// command stream, between a barrier after every earlier shader read of it and one
    /// before every later read. Parameters written this way belong to the submission that
    /// records them, so several submissions may be in flight (the viewer) without a race
    /// between a host write and a GPU read.
    pub fn update_uniform(&mut self, buffer: &Buffer, bytes: &[u8]) -> Result<()> {
        if bytes.is_empty() || bytes.len() % 4 != 0 || bytes.len() > 65536 {
            bail!(
                "uniform update of {} bytes: must be a non-zero multiple of 4, at most 65536",
                bytes.len()
            );
        }
        if bytes.len() as u64 > buffer.size() {
            bail!(
                "uniform update of {} bytes overruns a {}-byte buffer",
                bytes.len(),
                buffer.size()
            );
        }
        let shaders = vk::PipelineStageFlags2::VERTEX_SHADER
            | vk::PipelineStageFlags2::FRAGMENT_SHADER
            | vk::PipelineStageFlags2::COMPUTE_SHADER;
        let barrier = |src_stage, src_access, dst_stage, dst_access| {
            buffer_barrier(buffer, src_stage, src_access, dst_stage, dst_access)
        };
        // Write-after-read: earlier reads (this or an earlier submission) finish first.
        let before = [barrier(
            shaders,
            vk::AccessFlags2::UNIFORM_READ,
            vk::PipelineStageFlags2::COPY,
            vk::AccessFlags2::TRANSFER_WRITE,
        )];
        let after = [barrier(
            vk::PipelineStageFlags2::COPY,
            vk::AccessFlags2::TRANSFER_WRITE,
            shaders,
            vk::AccessFlags2::UNIFORM_READ,
        )];
        // SAFETY: recording; the buffer was created with TRANSFER_DST usage (Buffer::uniform)
        // and the size and alignment were checked above.
        unsafe {
            let d = self.device();
            d.cmd_pipeline_barrier2(
                self.cmd,
                &vk::DependencyInfo::default().buffer_memory_barriers(&before),
            );
            d.cmd_update_buffer(self.cmd, buffer.raw, 0, bytes);
            d.cmd_pipeline_barrier2(
                self.cmd,
                &vk::DependencyInfo::default().buffer_memory_barriers(&after),
            );
        }
        Ok(())
    }
}

fn image_barriers<'a>(
    image: &Image,
    layers: Range<u32>,
    to: Access,
    out: &mut Vec<vk::ImageMemoryBarrier2<'a>>,
) {
    tracked_barriers(image.raw, &image.layer_state, layers, to, out);
}

/// The barriers taking `layers` of the image `raw`, whose layers' state is `state`, to
/// `to` (barriers::plan_transitions), with `state` updated.
pub(super) fn tracked_barriers<'a>(
    raw: vk::Image,
    state: &std::sync::Mutex<Vec<Access>>,
    layers: Range<u32>,
    to: Access,
    out: &mut Vec<vk::ImageMemoryBarrier2<'a>>,
) {
    let mut state = state.lock().unwrap();
    for (range, from) in plan_transitions(&mut state, layers, to) {
        out.push(
            vk::ImageMemoryBarrier2::default()
                .src_stage_mask(from.stage())
                .src_access_mask(from.access())
                .dst_stage_mask(to.stage())
                .dst_access_mask(to.access())
                .old_layout(from.layout())
                .new_layout(to.layout())
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(raw)
                .subresource_range(color_range(range.start, range.end - range.start)),
        );
    }
}

fn buffer_image_copy(image: &Image, layer: u32) -> vk::BufferImageCopy {
    let [w, h, d] = image.desc.extent;
    vk::BufferImageCopy {
        buffer_offset: 0,
        buffer_row_length: 0,
        buffer_image_height: 0,
        image_subresource: vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: layer,
            layer_count: 1,
        },
        image_offset: vk::Offset3D::default(),
        image_extent: vk::Extent3D {
            width: w,
            height: h,
            depth: d,
        },
    }
}

impl<'a> Recorder<'a> {
    /// Begin recording into `cmd` (a reset or fresh primary command buffer of this
    /// context's pool), resetting `queries` for the scopes.
    pub(crate) fn begin(
        ctx: &'a Context,
        cmd: vk::CommandBuffer,
        queries: Option<vk::QueryPool>,
        marks: Option<vk::Buffer>,
    ) -> Result<Self> {
        let device = ctx.device();
        // SAFETY: the caller owns `cmd` and it is not in use by the GPU.
        unsafe {
            device.begin_command_buffer(
                cmd,
                &vk::CommandBufferBeginInfo::default()
                    .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )?;
            if let Some(q) = queries {
                device.cmd_reset_query_pool(cmd, q, 0, MAX_QUERIES);
            }
        }
        Ok(Recorder {
            ctx,
            cmd,
            queries,
            next_query: 0,
            scopes: Vec::new(),
            open: Vec::new(),
            marks: marks.map(|buffer| Marks {
                buffer,
                fractions: Vec::new(),
            }),
        })
    }

    /// Close any open scopes and end the command buffer, ready for submission.
    pub(crate) fn finish(mut self) -> Result<PendingTimings> {
        while !self.open.is_empty() {
            self.end_scope();
        }
        // SAFETY: recording, every scope closed.
        unsafe { self.device().end_command_buffer(self.cmd) }?;
        Ok(PendingTimings {
            scopes: std::mem::take(&mut self.scopes),
            used: self.next_query,
            marks: self.marks.take().map(|m| m.fractions).unwrap_or_default(),
        })
    }
}

fn buffer_barrier(
    buffer: &Buffer,
    src_stage: vk::PipelineStageFlags2,
    src_access: vk::AccessFlags2,
    dst_stage: vk::PipelineStageFlags2,
    dst_access: vk::AccessFlags2,
) -> vk::BufferMemoryBarrier2<'static> {
    raw_buffer_barrier(buffer.raw, src_stage, src_access, dst_stage, dst_access)
}

pub(super) fn raw_buffer_barrier(
    buffer: vk::Buffer,
    src_stage: vk::PipelineStageFlags2,
    src_access: vk::AccessFlags2,
    dst_stage: vk::PipelineStageFlags2,
    dst_access: vk::AccessFlags2,
) -> vk::BufferMemoryBarrier2<'static> {
    vk::BufferMemoryBarrier2::default()
        .src_stage_mask(src_stage)
        .src_access_mask(src_access)
        .dst_stage_mask(dst_stage)
        .dst_access_mask(dst_access)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .buffer(buffer)
        .offset(0)
        .size(vk::WHOLE_SIZE)
}
