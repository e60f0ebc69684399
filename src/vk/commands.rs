//! Command recording, submission, barriers and GPU timestamp scopes.
//!
//! One [`Recorder`] is one primary command buffer: a whole frame is recorded into it and
//! submitted once ([`Context::execute`]). Named scopes write a timestamp pair and a debug
//! label, so RenderDoc/Nsight captures and the printed GPU milliseconds use the same names.

use std::ffi::CString;
use std::ops::Range;

use anyhow::{bail, Context as _, Result};
use ash::vk;

use super::barriers::plan_transitions;
use super::pipeline::PUSH_STAGES;
use super::resources::color_range;
use super::{
    Access, Buffer, ComputePipeline, Context, DescriptorSet, Framebuffer, GraphicsPipeline, Image,
    Memory, RenderPass,
};

const MAX_QUERIES: u32 = 256;

/// GPU time of each named scope, in recording order, in milliseconds.
#[derive(Clone, Debug, Default)]
pub struct Timings {
    pub scopes: Vec<(String, f64)>,
}

impl Timings {
    /// Sum of all scopes with this name.
    pub fn get(&self, name: &str) -> Option<f64> {
        let v: Vec<f64> = self
            .scopes
            .iter()
            .filter(|(n, _)| n == name)
            .map(|(_, t)| *t)
            .collect();
        (!v.is_empty()).then(|| v.iter().sum())
    }
    pub fn extend(&mut self, other: Timings) {
        self.scopes.extend(other.scopes);
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
}

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

    /// Bind a compute pipeline with its set, push constants, and dispatch `groups`.
    pub fn dispatch(
        &mut self,
        pipeline: &ComputePipeline,
        set: &DescriptorSet,
        push: &[u8],
        groups: [u32; 3],
    ) -> Result<()> {
        let d = self.device();
        // SAFETY: recording; pipeline, layout and set are alive and compatible.
        unsafe {
            d.cmd_bind_pipeline(self.cmd, vk::PipelineBindPoint::COMPUTE, pipeline.core.raw);
            d.cmd_bind_descriptor_sets(
                self.cmd,
                vk::PipelineBindPoint::COMPUTE,
                pipeline.core.layout,
                0,
                &[set.raw],
                &[],
            );
        }
        self.push_constants(
            pipeline.core.layout,
            pipeline.core.push_size,
            &pipeline.core.name,
            push,
        )?;
        // SAFETY: recording with a compute pipeline bound.
        unsafe {
            self.device()
                .cmd_dispatch(self.cmd, groups[0], groups[1], groups[2])
        };
        Ok(())
    }
}

impl Recorder<'_> {
    /// Bring `attachments` (image, layer) into the pass's attachment state and begin it.
    /// The pass itself performs no layout transitions, so this is the only barrier.
    pub fn begin_render_pass(
        &mut self,
        pass: &RenderPass,
        framebuffer: &Framebuffer,
        attachments: &[(&Image, u32)],
    ) -> Result<()> {
        if attachments.len() != pass.attachments {
            bail!(
                "render pass has {} attachments, {} images given",
                pass.attachments,
                attachments.len()
            );
        }
        let items: Vec<_> = attachments
            .iter()
            .map(|(image, layer)| (*image, *layer..*layer + 1, pass.access))
            .collect();
        self.transition_many(&items);
        let clears =
            vec![vk::ClearValue::default(); if pass.clears { pass.attachments } else { 0 }];
        let info = vk::RenderPassBeginInfo::default()
            .render_pass(pass.raw)
            .framebuffer(framebuffer.raw)
            .render_area(vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent: framebuffer.extent,
            })
            .clear_values(&clears);
        // SAFETY: recording; pass and framebuffer are compatible (checked at creation).
        unsafe {
            self.device()
                .cmd_begin_render_pass(self.cmd, &info, vk::SubpassContents::INLINE);
        }
        Ok(())
    }

    /// Bind a full-screen graphics pipeline, its descriptor set and a viewport/scissor of
    /// `width` × `height`. Bindings persist across render passes of this command buffer, so
    /// a sequence of draws (the plane sweep) binds once and then only pushes constants.
    pub fn bind_graphics(
        &mut self,
        pipeline: &GraphicsPipeline,
        set: &DescriptorSet,
        width: u32,
        height: u32,
    ) {
        let d = self.device();
        // SAFETY: recording; pipeline, layout and set are alive and compatible.
        unsafe {
            d.cmd_bind_pipeline(self.cmd, vk::PipelineBindPoint::GRAPHICS, pipeline.core.raw);
            d.cmd_bind_descriptor_sets(
                self.cmd,
                vk::PipelineBindPoint::GRAPHICS,
                pipeline.core.layout,
                0,
                &[set.raw],
                &[],
            );
        }
        self.set_viewport(width, height);
    }

    /// Viewport and scissor of `width` × `height` for the following draws (a pass whose
    /// attachments differ in size from the previous one's).
    pub fn set_viewport(&mut self, width: u32, height: u32) {
        let d = self.device();
        // SAFETY: recording; viewport and scissor are dynamic in every graphics pipeline.
        unsafe {
            d.cmd_set_viewport(
                self.cmd,
                0,
                &[vk::Viewport {
                    x: 0.0,
                    y: 0.0,
                    width: width as f32,
                    height: height as f32,
                    min_depth: 0.0,
                    max_depth: 1.0,
                }],
            );
            d.cmd_set_scissor(
                self.cmd,
                0,
                &[vk::Rect2D {
                    offset: vk::Offset2D::default(),
                    extent: vk::Extent2D { width, height },
                }],
            );
        }
    }

    /// Switch to `pipeline`, keeping the descriptor set, viewport and scissor that
    /// [`Self::bind_graphics`] bound. `pipeline` must have been made from the same
    /// descriptor set and push size as the one bound there (compatible layouts), so the
    /// set stays valid: see [`GraphicsPipeline::new`].
    pub fn bind_pipeline(&mut self, pipeline: &GraphicsPipeline) {
        // SAFETY: recording; the pipeline is alive; its layout is compatible with the bound
        // set's (the caller's contract above), so the set binding persists.
        unsafe {
            self.device().cmd_bind_pipeline(
                self.cmd,
                vk::PipelineBindPoint::GRAPHICS,
                pipeline.core.raw,
            )
        };
    }

    /// Push constants for `pipeline` (bound with [`Self::bind_graphics`]) and draw one
    /// full-screen triangle inside the current render pass.
    pub fn draw_fullscreen(&mut self, pipeline: &GraphicsPipeline, push: &[u8]) -> Result<()> {
        self.draw(pipeline, push, 3)
    }

    /// Push constants for the bound `pipeline` and draw `vertices` vertices (generated by
    /// its vertex shader) inside the current render pass.
    pub fn draw(&mut self, pipeline: &GraphicsPipeline, push: &[u8], vertices: u32) -> Result<()> {
        self.push_constants(
            pipeline.core.layout,
            pipeline.core.push_size,
            &pipeline.core.name,
            push,
        )?;
        // SAFETY: recording inside a render pass compatible with the bound pipeline.
        unsafe { self.device().cmd_draw(self.cmd, vertices, 1, 0, 0) };
        Ok(())
    }

    /// Zero a storage buffer that shaders accumulate into (counters), after every earlier
    /// shader access to it and before every later one.
    pub fn clear_storage(&mut self, buffer: &Buffer) {
        let shaders = vk::PipelineStageFlags2::VERTEX_SHADER
            | vk::PipelineStageFlags2::FRAGMENT_SHADER
            | vk::PipelineStageFlags2::COMPUTE_SHADER;
        let rw = vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE;
        let before = [buffer_barrier(
            buffer,
            shaders | vk::PipelineStageFlags2::COPY,
            rw | vk::AccessFlags2::TRANSFER_READ,
            vk::PipelineStageFlags2::ALL_TRANSFER,
            vk::AccessFlags2::TRANSFER_WRITE,
        )];
        let after = [buffer_barrier(
            buffer,
            vk::PipelineStageFlags2::ALL_TRANSFER,
            vk::AccessFlags2::TRANSFER_WRITE,
            shaders,
            rw,
        )];
        // SAFETY: recording; the buffer has TRANSFER_DST usage (the caller's), whole size.
        unsafe {
            let d = self.device();
            d.cmd_pipeline_barrier2(
                self.cmd,
                &vk::DependencyInfo::default().buffer_memory_barriers(&before),
            );
            d.cmd_fill_buffer(self.cmd, buffer.raw, 0, vk::WHOLE_SIZE, 0);
            d.cmd_pipeline_barrier2(
                self.cmd,
                &vk::DependencyInfo::default().buffer_memory_barriers(&after),
            );
        }
    }

    /// Copy a storage buffer that shaders wrote into a host-visible `dst` (made with
    /// [`Buffer::readback`]) and make it visible to the host.
    pub fn copy_storage_to_host(&mut self, src: &Buffer, dst: &Buffer) {
        let shaders = vk::PipelineStageFlags2::VERTEX_SHADER
            | vk::PipelineStageFlags2::FRAGMENT_SHADER
            | vk::PipelineStageFlags2::COMPUTE_SHADER;
        let before = [buffer_barrier(
            src,
            shaders,
            vk::AccessFlags2::SHADER_STORAGE_WRITE,
            vk::PipelineStageFlags2::COPY,
            vk::AccessFlags2::TRANSFER_READ,
        )];
        let after = [buffer_barrier(
            dst,
            vk::PipelineStageFlags2::COPY,
            vk::AccessFlags2::TRANSFER_WRITE,
            vk::PipelineStageFlags2::HOST,
            vk::AccessFlags2::HOST_READ,
        )];
        let region = vk::BufferCopy {
            src_offset: 0,
            dst_offset: 0,
            size: src.size().min(dst.size()),
        };
        // SAFETY: recording; src has TRANSFER_SRC and dst TRANSFER_DST usage, sizes checked.
        unsafe {
            let d = self.device();
            d.cmd_pipeline_barrier2(
                self.cmd,
                &vk::DependencyInfo::default().buffer_memory_barriers(&before),
            );
            d.cmd_copy_buffer(self.cmd, src.raw, dst.raw, &[region]);
            d.cmd_pipeline_barrier2(
                self.cmd,
                &vk::DependencyInfo::default().buffer_memory_barriers(&after),
            );
        }
    }

    fn push_constants(
        &mut self,
        layout: vk::PipelineLayout,
        size: u32,
        name: &str,
        push: &[u8],
    ) -> Result<()> {
        if push.len() as u32 != size {
            bail!(
                "pipeline '{name}' takes {size} bytes of push constants, got {}",
                push.len()
            );
        }
        if !push.is_empty() {
            // SAFETY: recording; the range matches the layout's (checked above).
            unsafe {
                self.device()
                    .cmd_push_constants(self.cmd, layout, PUSH_STAGES, 0, push)
            };
        }
        Ok(())
    }

    pub fn end_render_pass(&mut self) {
        // SAFETY: matches begin_render_pass.
        unsafe { self.device().cmd_end_render_pass(self.cmd) };
    }
}

fn image_barriers<'a>(
    image: &Image,
    layers: Range<u32>,
    to: Access,
    out: &mut Vec<vk::ImageMemoryBarrier2<'a>>,
) {
    let mut state = image.layer_state.lock().unwrap();
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
                .image(image.raw)
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

/// The timestamp scopes of a finished recording, resolved into [`Timings`] once the
/// submission has completed ([`PendingTimings::resolve`]).
pub struct PendingTimings {
    scopes: Vec<Scope>,
    used: u32,
}

impl PendingTimings {
    /// Read the timestamps from `queries` (the pool the recording used). Call only after
    /// the submission has completed.
    pub(crate) fn resolve(self, ctx: &Context, queries: Option<vk::QueryPool>) -> Result<Timings> {
        let mut timings = Timings::default();
        let (Some(q), true) = (queries, self.used > 0) else {
            return Ok(timings);
        };
        let mut raw = vec![0u64; self.used as usize];
        // SAFETY: `used` queries were written and the work has completed.
        unsafe {
            ctx.device().get_query_pool_results(
                q,
                0,
                &mut raw,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }?;
        let period = ctx.info().limits.timestamp_period as f64;
        for s in self.scopes {
            if let (Some(e), true) = (s.end, s.begin != u32::MAX) {
                let ticks = raw[e as usize].saturating_sub(raw[s.begin as usize]);
                timings.scopes.push((s.name, ticks as f64 * period * 1e-6));
            }
        }
        Ok(timings)
    }
}

/// A timestamp query pool large enough for one recording's scopes (None when the device
/// has no timestamps).
pub(crate) fn create_query_pool(ctx: &Context) -> Result<Option<vk::QueryPool>> {
    if !ctx.info().timestamps {
        return Ok(None);
    }
    let info = vk::QueryPoolCreateInfo::default()
        .query_type(vk::QueryType::TIMESTAMP)
        .query_count(MAX_QUERIES);
    // SAFETY: valid device.
    Ok(Some(unsafe {
        ctx.device().create_query_pool(&info, None)
    }?))
}

impl<'a> Recorder<'a> {
    /// Begin recording into `cmd` (a reset or fresh primary command buffer of this
    /// context's pool), resetting `queries` for the scopes.
    pub(crate) fn begin(
        ctx: &'a Context,
        cmd: vk::CommandBuffer,
        queries: Option<vk::QueryPool>,
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
        })
    }
}

impl Context {
    /// Record a command buffer with `record`, submit it, wait for it, and return the GPU
    /// time of each scope the recording opened.
    pub fn execute(&self, record: impl FnOnce(&mut Recorder) -> Result<()>) -> Result<Timings> {
        let device = self.device();
        let pool = *self.shared.command_pool.lock().unwrap();
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // The pool is shared by all threads using this context; allocation and freeing hold
        // its lock, recording happens on a buffer nobody else sees.
        let cmd = {
            let _guard = self.shared.command_pool.lock().unwrap();
            // SAFETY: the pool lock is held.
            unsafe { device.allocate_command_buffers(&alloc) }?[0]
        };
        let queries = match create_query_pool(self) {
            Ok(q) => q,
            Err(e) => {
                let _guard = self.shared.command_pool.lock().unwrap();
                // SAFETY: never submitted.
                unsafe { device.free_command_buffers(pool, &[cmd]) };
                return Err(e);
            }
        };
        let result = (|| -> Result<Timings> {
            let mut rec = Recorder::begin(self, cmd, queries)?;
            record(&mut rec)?;
            let pending = rec.finish()?;
            // SAFETY: recording finished; fence waited before anything is read or freed.
            unsafe {
                let fence = device.create_fence(&vk::FenceCreateInfo::default(), None)?;
                let cmd_infos = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
                let submit = vk::SubmitInfo2::default().command_buffer_infos(&cmd_infos);
                let submitted = {
                    let queue = self.shared.queue.lock().unwrap();
                    device.queue_submit2(*queue, &[submit], fence)
                };
                let waited =
                    submitted.and_then(|_| device.wait_for_fences(&[fence], true, u64::MAX));
                device.destroy_fence(fence, None);
                waited.context("GPU submission failed (device lost?)")?;
            }
            pending.resolve(self, queries)
        })();
        // SAFETY: the submission (if any) has completed or failed; nothing references these.
        unsafe {
            if let Some(q) = queries {
                device.destroy_query_pool(q, None);
            }
            let _guard = self.shared.command_pool.lock().unwrap();
            device.free_command_buffers(pool, &[cmd]);
        }
        result
    }

    /// Upload tightly packed texels into one layer of `image`; the layer ends up ready for
    /// sampling.
    pub fn upload_image(&self, image: &Image, layer: u32, bytes: &[u8]) -> Result<()> {
        let expected = image.layer_bytes()?;
        if bytes.len() as u64 != expected {
            bail!(
                "upload to '{}' has {} bytes, one layer is {expected}",
                image.name(),
                bytes.len()
            );
        }
        let mut staging = Buffer::new(
            self,
            expected,
            vk::BufferUsageFlags::TRANSFER_SRC,
            Memory::Upload,
            "staging upload",
        )?;
        staging.write(0, bytes)?;
        self.execute(|rec| {
            rec.copy_buffer_to_image(&staging, image, layer);
            rec.transition(image, layer..layer + 1, Access::Sampled);
            Ok(())
        })?;
        Ok(())
    }

    /// Read one layer of `image` back to the host as tightly packed texels.
    pub fn read_image(&self, image: &Image, layer: u32) -> Result<Vec<u8>> {
        let size = image.layer_bytes()?;
        let staging = Buffer::new(
            self,
            size,
            vk::BufferUsageFlags::TRANSFER_DST,
            Memory::Readback,
            "staging readback",
        )?;
        self.execute(|rec| {
            rec.copy_image_to_buffer(image, layer, &staging);
            Ok(())
        })?;
        Ok(staging.mapped()?[..size as usize].to_vec())
    }
}

fn buffer_barrier(
    buffer: &Buffer,
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
        .buffer(buffer.raw)
        .offset(0)
        .size(vk::WHOLE_SIZE)
}
