//! Compute work: binding a pipeline with its set and dispatching, with the barriers the
//! set's bindings declare (`Recorder::dispatch`), or without them for a set made
//! `with_explicit_barriers` (the sweep's explicit per-plane barriers).

use super::*;

impl Recorder<'_> {
    /// Bind a pipeline and its descriptor set (set 0) at `point`.
    pub(super) fn bind_with_set(
        &mut self,
        point: vk::PipelineBindPoint,
        pipeline: &PipelineCore,
        set: &DescriptorSet,
    ) {
        let d = self.device();
        // SAFETY: recording; pipeline, layout and set are alive and compatible.
        unsafe {
            d.cmd_bind_pipeline(self.cmd, point, pipeline.raw);
            d.cmd_bind_descriptor_sets(self.cmd, point, pipeline.layout, 0, &[set.raw], &[]);
        }
    }

    /// Bind a compute pipeline and its descriptor set for [`Self::dispatch_bound`]: a
    /// sequence of dispatches (the plane sweep) binds once and then only pushes constants
    /// (on lavapipe each set bind costs ~4 ms and 3 MB, measured).
    pub fn bind_compute(&mut self, pipeline: &ComputePipeline, set: &DescriptorSet) {
        self.bind_with_set(vk::PipelineBindPoint::COMPUTE, &pipeline.core, set);
    }

    /// Switch to compute `pipeline`, keeping the set [`Self::bind_compute`] bound.
    /// `pipeline` must have been made from a set of the same layout and the same push
    /// size as the one bound there (compatible layouts), so that the set stays valid.
    pub fn bind_compute_pipeline(&mut self, pipeline: &ComputePipeline) {
        // SAFETY: recording; the pipeline is alive; its layout is compatible with the
        // bound set's (the caller's contract above), so the set binding persists.
        unsafe {
            self.device().cmd_bind_pipeline(
                self.cmd,
                vk::PipelineBindPoint::COMPUTE,
                pipeline.core.raw,
            )
        };
    }

    /// Push constants for the bound compute `pipeline` and dispatch `groups`, binding
    /// nothing (see [`Self::bind_compute`]).
    pub fn dispatch_bound(
        &mut self,
        pipeline: &ComputePipeline,
        push: &[u8],
        groups: [u32; 3],
    ) -> Result<()> {
        self.push_constants(&pipeline.core, push)?;
        // SAFETY: recording with a compute pipeline and its set bound (the caller's
        // contract of bind_compute).
        unsafe {
            self.device()
                .cmd_dispatch(self.cmd, groups[0], groups[1], groups[2])
        };
        Ok(())
    }

    /// Bind a compute pipeline with its set, push constants, and dispatch `groups`, after
    /// the barriers the set's images and storage buffers need: each bound image (layers)
    /// goes to the use its binding declares (a storage image: read and written; a
    /// texture: sampled), from the state its previous use left; each bound storage buffer
    /// waits for every earlier command's writes and accesses (buffers carry no tracked
    /// state, so the source scope is all commands: a conservative barrier, recorded
    /// once per dispatch and buffer, in one batch with the images'). So a pass of
    /// dispatches declares each resource once, in its bindings, and a dispatch reading
    /// what the one before it wrote is ordered after it. Errors if the set binds an image
    /// or buffer destroyed since the set was made. A set made
    /// [`DescriptorSet::with_explicit_barriers`] takes none: its user records them.
    pub fn dispatch(
        &mut self,
        pipeline: &ComputePipeline,
        set: &DescriptorSet,
        push: &[u8],
        groups: [u32; 3],
    ) -> Result<()> {
        if !set.explicit_barriers {
            self.take_bindings(set)?;
        }
        self.bind_compute(pipeline, set);
        self.dispatch_bound(pipeline, push, groups)
    }

    /// [`Self::dispatch`] with the workgroup counts read on the device from `args` at
    /// byte `offset` (a VkDispatchIndirectCommand: three u32) that an earlier compute
    /// shader wrote: work whose size a shader decided (a list compacted on the GPU)
    /// without a readback. `args` needs INDIRECT_BUFFER usage; the barrier that orders
    /// compute writes to it before the indirect read is recorded here.
    pub fn dispatch_indirect(
        &mut self,
        pipeline: &ComputePipeline,
        set: &DescriptorSet,
        push: &[u8],
        args: &Buffer,
        offset: u64,
    ) -> Result<()> {
        if offset % 4 != 0 || offset + 12 > args.size() {
            bail!(
                "indirect dispatch at byte {offset} of '{}' ({} bytes) is out of range or \
                 unaligned",
                args.name(),
                args.size()
            );
        }
        if !set.explicit_barriers {
            self.take_bindings(set)?;
        }
        let barrier = [raw_buffer_barrier(
            args.raw,
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::AccessFlags2::SHADER_STORAGE_WRITE,
            vk::PipelineStageFlags2::DRAW_INDIRECT,
            vk::AccessFlags2::INDIRECT_COMMAND_READ,
        )];
        // SAFETY: recording; the barrier references a live buffer.
        unsafe {
            self.device().cmd_pipeline_barrier2(
                self.cmd,
                &vk::DependencyInfo::default().buffer_memory_barriers(&barrier),
            )
        };
        self.bind_compute(pipeline, set);
        self.push_constants(&pipeline.core, push)?;
        // SAFETY: recording with the pipeline and its set bound; the command lies within
        // the buffer (checked above), which the caller made with INDIRECT_BUFFER usage.
        unsafe {
            self.device()
                .cmd_dispatch_indirect(self.cmd, args.raw, offset)
        };
        Ok(())
    }

    /// The barriers that take `set`'s bound images and storage buffers to the uses its
    /// bindings declare ([`Self::dispatch`]).
    fn take_bindings(&mut self, set: &DescriptorSet) -> Result<()> {
        let mut barriers = Vec::new();
        for bound in &set.images {
            let Some(state) = bound.image.state.upgrade() else {
                bail!(
                    "descriptor set '{}' binds image '{}', destroyed since the set was made",
                    set.name(),
                    bound.image.name
                );
            };
            tracked_barriers(
                bound.image.raw,
                &state,
                bound.layers.clone(),
                bound.access,
                &mut barriers,
            );
        }
        let mut buffer_barriers = Vec::new();
        for bound in &set.storage_buffers {
            if bound.alive.upgrade().is_none() {
                bail!(
                    "descriptor set '{}' binds buffer '{}', destroyed since the set was made",
                    set.name(),
                    bound.name
                );
            }
            buffer_barriers.push(raw_buffer_barrier(
                bound.raw,
                vk::PipelineStageFlags2::ALL_COMMANDS,
                vk::AccessFlags2::MEMORY_WRITE,
                vk::PipelineStageFlags2::COMPUTE_SHADER,
                vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE,
            ));
        }
        if !barriers.is_empty() || !buffer_barriers.is_empty() {
            let dep = vk::DependencyInfo::default()
                .image_memory_barriers(&barriers)
                .buffer_memory_barriers(&buffer_barriers);
            // SAFETY: recording; the barriers reference images and buffers that are alive.
            unsafe { self.device().cmd_pipeline_barrier2(self.cmd, &dep) };
        }
        Ok(())
    }
}
