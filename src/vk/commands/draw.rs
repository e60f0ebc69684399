//! Recording render passes and draws (the plane sweep's per-plane work).

use anyhow::{bail, Result};
use ash::vk;

use crate::vk::pipeline::PUSH_STAGES;
use crate::vk::{Buffer, DescriptorSet, Framebuffer, GraphicsPipeline, Image, RenderPass};

use super::*;

/// A rectangle of pixels: a render area or scissor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Area {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

/// Who uses a storage buffer on either side of [`Recorder::buffer_handover`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BufferUse {
    /// Compute shaders read and write it.
    Compute,
    /// Draws read it: their vertex and fragment shaders, and as indirect draw commands.
    Draws,
}

impl BufferUse {
    fn stages(self) -> (vk::PipelineStageFlags2, vk::AccessFlags2) {
        match self {
            BufferUse::Compute => (
                vk::PipelineStageFlags2::COMPUTE_SHADER,
                vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE,
            ),
            BufferUse::Draws => (
                vk::PipelineStageFlags2::VERTEX_SHADER
                    | vk::PipelineStageFlags2::FRAGMENT_SHADER
                    | vk::PipelineStageFlags2::DRAW_INDIRECT,
                vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::INDIRECT_COMMAND_READ,
            ),
        }
    }
}

impl Area {
    pub fn full(width: u32, height: u32) -> Self {
        Self {
            x: 0,
            y: 0,
            width,
            height,
        }
    }

    fn rect(self) -> vk::Rect2D {
        vk::Rect2D {
            offset: vk::Offset2D {
                x: self.x as i32,
                y: self.y as i32,
            },
            extent: vk::Extent2D {
                width: self.width,
                height: self.height,
            },
        }
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
        let e = framebuffer.extent;
        self.begin_render_pass_in(
            pass,
            framebuffer,
            attachments,
            Area::full(e.width, e.height),
        )
    }

    /// [`Self::begin_render_pass`] over `area` only: pixels outside it are neither loaded,
    /// stored nor cleared (and must be scissored off the draws: [`Self::set_scissor`]).
    pub fn begin_render_pass_in(
        &mut self,
        pass: &RenderPass,
        framebuffer: &Framebuffer,
        attachments: &[(&Image, u32)],
        area: Area,
    ) -> Result<()> {
        let e = framebuffer.extent;
        if area.width == 0
            || area.height == 0
            || area.x as u64 + area.width as u64 > e.width as u64
            || area.y as u64 + area.height as u64 > e.height as u64
        {
            bail!(
                "render area {area:?} is empty or outside the framebuffer ({}x{})",
                e.width,
                e.height
            );
        }
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
            .render_area(area.rect())
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
        self.bind_with_set(vk::PipelineBindPoint::GRAPHICS, &pipeline.core, set);
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

    /// Scissor the following draws to `area` (the viewport stays).
    pub fn set_scissor(&mut self, area: Area) {
        // SAFETY: recording; scissor is dynamic in every graphics pipeline.
        unsafe { self.device().cmd_set_scissor(self.cmd, 0, &[area.rect()]) };
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
        self.push_constants(&pipeline.core, push)?;
        // SAFETY: recording inside a render pass compatible with the bound pipeline.
        unsafe { self.device().cmd_draw(self.cmd, vertices, 1, 0, 0) };
        Ok(())
    }

    /// Draw the indirect draws `draws` (indices of 16-byte VkDrawIndirectCommands a shader
    /// wrote into `commands`), in order, with `pipeline` (bound) and push constants `push`:
    /// one call where the device has `multiDrawIndirect`, else one call per draw. The
    /// buffer needs INDIRECT_BUFFER usage.
    pub fn draw_indirect(
        &mut self,
        pipeline: &GraphicsPipeline,
        push: &[u8],
        commands: &Buffer,
        draws: std::ops::Range<u32>,
    ) -> Result<()> {
        let needed = draws.end as u64 * 16;
        if needed > commands.size() {
            bail!(
                "indirect draws {draws:?} need {needed} bytes, the buffer has {}",
                commands.size()
            );
        }
        self.push_constants(&pipeline.core, push)?;
        let info = self.ctx.info();
        let per_call = if info.multi_draw_indirect {
            info.limits.max_draw_indirect_count.max(1)
        } else {
            1
        };
        let mut first = draws.start;
        while first < draws.end {
            let n = per_call.min(draws.end - first);
            // SAFETY: recording inside a render pass compatible with the bound pipeline;
            // the commands lie within the buffer (checked above); n is 1 or within the
            // device's maxDrawIndirectCount with multiDrawIndirect enabled.
            unsafe {
                self.device()
                    .cmd_draw_indirect(self.cmd, commands.raw, first as u64 * 16, n, 16)
            };
            first += n;
        }
        Ok(())
    }

    /// Order every earlier `from` access to each of `buffers` before every later `to`
    /// access, in one vkCmdPipelineBarrier2: storage buffers that one kind of pass writes
    /// and another reads, plane after plane.
    pub fn buffer_handover(&mut self, buffers: &[&Buffer], from: BufferUse, to: BufferUse) {
        let (src_stage, src_access) = from.stages();
        let (dst_stage, dst_access) = to.stages();
        let barriers: Vec<_> = buffers
            .iter()
            .map(|b| buffer_barrier(b, src_stage, src_access, dst_stage, dst_access))
            .collect();
        let dep = vk::DependencyInfo::default().buffer_memory_barriers(&barriers);
        // SAFETY: recording; the barriers reference live buffers.
        unsafe { self.device().cmd_pipeline_barrier2(self.cmd, &dep) };
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

    /// Order every earlier compute-shader access to the storage `buffer` (reads, writes,
    /// atomics) before every later one: passes that accumulate into a buffer and the pass
    /// that reads and clears it, back to back.
    pub fn compute_storage_barrier(&mut self, buffer: &Buffer) {
        self.compute_storage_barriers(&[], &[buffer]);
    }

    /// The image transitions of [`Recorder::transition_many`] and the storage barrier of
    /// [`Recorder::compute_storage_barrier`] for each of `buffers`, in one
    /// vkCmdPipelineBarrier2 (a driver may drain its queue once per call).
    pub fn compute_storage_barriers(
        &mut self,
        images: &[(&Image, Range<u32>, Access)],
        buffers: &[&Buffer],
    ) {
        let mut image_barriers_out = Vec::new();
        for (image, layers, to) in images {
            image_barriers(image, layers.clone(), *to, &mut image_barriers_out);
        }
        let rw = vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE;
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let buffer_barriers: Vec<_> = buffers
            .iter()
            .map(|b| buffer_barrier(b, compute, rw, compute, rw))
            .collect();
        if image_barriers_out.is_empty() && buffer_barriers.is_empty() {
            return;
        }
        let dep = vk::DependencyInfo::default()
            .image_memory_barriers(&image_barriers_out)
            .buffer_memory_barriers(&buffer_barriers);
        // SAFETY: recording; the barriers reference live images and buffers.
        unsafe { self.device().cmd_pipeline_barrier2(self.cmd, &dep) };
    }

    /// Copy `size` bytes from `src` (host-written, made with `Memory::Upload` and
    /// TRANSFER_SRC usage) at `src_offset` into the storage buffer `dst` (TRANSFER_DST
    /// usage) at `dst_offset`, after every earlier shader access to `dst` and before every
    /// later compute access: a shader's initial data uploaded within the recording.
    pub fn upload_to_storage(
        &mut self,
        src: &Buffer,
        src_offset: u64,
        dst: &Buffer,
        dst_offset: u64,
        size: u64,
    ) -> Result<()> {
        if src_offset + size > src.size() || dst_offset + size > dst.size() {
            bail!(
                "copy of {size} bytes from byte {src_offset} of '{}' ({} bytes) to byte \
                 {dst_offset} of '{}' ({} bytes) is out of range",
                src.name(),
                src.size(),
                dst.name(),
                dst.size()
            );
        }
        if size == 0 {
            return Ok(());
        }
        let shaders = vk::PipelineStageFlags2::VERTEX_SHADER
            | vk::PipelineStageFlags2::FRAGMENT_SHADER
            | vk::PipelineStageFlags2::COMPUTE_SHADER;
        let rw = vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE;
        let before = [buffer_barrier(
            dst,
            shaders | vk::PipelineStageFlags2::DRAW_INDIRECT,
            rw | vk::AccessFlags2::INDIRECT_COMMAND_READ,
            vk::PipelineStageFlags2::COPY,
            vk::AccessFlags2::TRANSFER_WRITE,
        )];
        let after = [buffer_barrier(
            dst,
            vk::PipelineStageFlags2::COPY,
            vk::AccessFlags2::TRANSFER_WRITE,
            vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::DRAW_INDIRECT,
            rw | vk::AccessFlags2::INDIRECT_COMMAND_READ,
        )];
        let region = vk::BufferCopy {
            src_offset,
            dst_offset,
            size,
        };
        // The host wrote src before submission, which vkQueueSubmit makes visible; the
        // region lies within both buffers (checked above).
        self.copy_between_barriers(&before, src, dst, region, &after);
        Ok(())
    }

    /// `before`, the copy of `region` from `src` (TRANSFER_SRC usage) to `dst`
    /// (TRANSFER_DST usage), then `after`: the callers' checks keep the region within
    /// both buffers.
    fn copy_between_barriers(
        &mut self,
        before: &[vk::BufferMemoryBarrier2<'_>],
        src: &Buffer,
        dst: &Buffer,
        region: vk::BufferCopy,
        after: &[vk::BufferMemoryBarrier2<'_>],
    ) {
        // SAFETY: recording; usages and the region are the callers' (see above); the
        // barriers reference live buffers.
        unsafe {
            let d = self.device();
            d.cmd_pipeline_barrier2(
                self.cmd,
                &vk::DependencyInfo::default().buffer_memory_barriers(before),
            );
            d.cmd_copy_buffer(self.cmd, src.raw, dst.raw, &[region]);
            d.cmd_pipeline_barrier2(
                self.cmd,
                &vk::DependencyInfo::default().buffer_memory_barriers(after),
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
        self.copy_between_barriers(&before, src, dst, region, &after);
    }

    /// `push` for `pipeline`, whose push range it must fill exactly.
    pub(super) fn push_constants(&mut self, pipeline: &PipelineCore, push: &[u8]) -> Result<()> {
        let (layout, size, name) = (pipeline.layout, pipeline.push_size, &pipeline.name);
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
