//! The one place where a use of an image becomes synchronization: each [`Access`] maps to
//! a layout, pipeline stages and access mask, and [`plan_transitions`] decides which
//! layers need a barrier from what to what (the recorder turns the plan into
//! synchronization2 barriers).

use std::ops::Range;

use ash::vk;

/// The stage at which a frame waits for its swapchain image to be acquired; the first
/// barrier on an [`Access::Acquired`] image starts from it.
pub(crate) const ACQUIRE_WAIT_STAGE: vk::PipelineStageFlags2 =
    vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT;

/// How an image is used next; each maps to a layout, pipeline stage and access mask.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    Undefined,
    TransferDst,
    TransferSrc,
    /// Sampled (texture()) from a compute, vertex or fragment shader.
    Sampled,
    /// Read and written as a storage image from a compute shader.
    ComputeStorage,
    /// Written as a colour attachment of a render pass.
    ColorAttachment,
    /// Colour attachment in GENERAL layout. With [`Access::SampledGeneral`] this lets one
    /// image array be rendered to and sampled layer by layer (the plane sweep's ping-pong)
    /// with memory barriers only: descriptors of both layers stay valid at every draw.
    AttachmentGeneral,
    /// Sampled from a compute, vertex or fragment shader, in GENERAL layout.
    SampledGeneral,
    /// A swapchain image just acquired: its old contents are discarded (UNDEFINED layout),
    /// and the stage is the one the acquire semaphore is waited at, so the first barrier
    /// chains with that wait.
    Acquired,
    /// Handed to the presentation engine (PRESENT_SRC_KHR); the submission's signal
    /// semaphore, not a pipeline stage, orders what comes after.
    Present,
}

impl Access {
    pub(crate) fn layout(self) -> vk::ImageLayout {
        match self {
            Access::Undefined => vk::ImageLayout::UNDEFINED,
            Access::TransferDst => vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            Access::TransferSrc => vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            Access::Sampled => vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            Access::ComputeStorage => vk::ImageLayout::GENERAL,
            Access::ColorAttachment => vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            Access::AttachmentGeneral | Access::SampledGeneral => vk::ImageLayout::GENERAL,
            Access::Acquired => vk::ImageLayout::UNDEFINED,
            Access::Present => vk::ImageLayout::PRESENT_SRC_KHR,
        }
    }
    pub(crate) fn stage(self) -> vk::PipelineStageFlags2 {
        match self {
            Access::Undefined => vk::PipelineStageFlags2::NONE,
            // Copies and blits (synchronization2 tells them apart).
            Access::TransferDst | Access::TransferSrc => {
                vk::PipelineStageFlags2::COPY | vk::PipelineStageFlags2::BLIT
            }
            Access::Sampled => {
                vk::PipelineStageFlags2::COMPUTE_SHADER
                    | vk::PipelineStageFlags2::FRAGMENT_SHADER
                    | vk::PipelineStageFlags2::VERTEX_SHADER
            }
            Access::ComputeStorage => vk::PipelineStageFlags2::COMPUTE_SHADER,
            Access::ColorAttachment => vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
            Access::AttachmentGeneral => vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
            Access::SampledGeneral => {
                vk::PipelineStageFlags2::COMPUTE_SHADER
                    | vk::PipelineStageFlags2::FRAGMENT_SHADER
                    | vk::PipelineStageFlags2::VERTEX_SHADER
            }
            Access::Acquired => ACQUIRE_WAIT_STAGE,
            Access::Present => vk::PipelineStageFlags2::NONE,
        }
    }
    pub(crate) fn access(self) -> vk::AccessFlags2 {
        match self {
            Access::Undefined => vk::AccessFlags2::NONE,
            Access::TransferDst => vk::AccessFlags2::TRANSFER_WRITE,
            Access::TransferSrc => vk::AccessFlags2::TRANSFER_READ,
            Access::Sampled => vk::AccessFlags2::SHADER_SAMPLED_READ,
            Access::ComputeStorage => {
                vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE
            }
            Access::ColorAttachment => {
                vk::AccessFlags2::COLOR_ATTACHMENT_WRITE | vk::AccessFlags2::COLOR_ATTACHMENT_READ
            }
            Access::AttachmentGeneral => {
                vk::AccessFlags2::COLOR_ATTACHMENT_WRITE | vk::AccessFlags2::COLOR_ATTACHMENT_READ
            }
            Access::SampledGeneral => vk::AccessFlags2::SHADER_SAMPLED_READ,
            Access::Acquired | Access::Present => vk::AccessFlags2::NONE,
        }
    }
    pub(crate) fn writes(self) -> bool {
        !matches!(
            self,
            Access::Sampled
                | Access::TransferSrc
                | Access::Undefined
                | Access::Acquired
                | Access::Present
        )
    }
}

/// The barriers taking `layers` of an image whose layers are in `state` to `to`, as
/// (layer range, previous access) — consecutive layers in the same state share one — and
/// `state` updated. None between two reads in the same state; always one around a write
/// (write after write, read after write, write after read).
pub(crate) fn plan_transitions(
    state: &mut [Access],
    layers: Range<u32>,
    to: Access,
) -> Vec<(Range<u32>, Access)> {
    let mut plan = Vec::new();
    let mut layer = layers.start;
    while layer < layers.end {
        let from = state[layer as usize];
        let mut end = layer + 1;
        while end < layers.end && state[end as usize] == from {
            end += 1;
        }
        if from != to || from.writes() || to.writes() {
            plan.push((layer..end, from));
        }
        for l in layer..end {
            state[l as usize] = to;
        }
        layer = end;
    }
    plan
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_in_the_same_state_need_no_barrier() {
        let mut state = [Access::Sampled; 2];
        assert!(plan_transitions(&mut state, 0..2, Access::Sampled).is_empty());
    }

    #[test]
    fn writes_always_get_a_barrier() {
        // Write after write in the same state (the sweep's planes rendering into one layer).
        let mut state = [Access::AttachmentGeneral; 2];
        let plan = plan_transitions(&mut state, 1..2, Access::AttachmentGeneral);
        assert_eq!(plan, vec![(1..2, Access::AttachmentGeneral)]);
        // Read after write, then write after read.
        let mut state = [Access::ComputeStorage];
        assert_eq!(
            plan_transitions(&mut state, 0..1, Access::Sampled),
            vec![(0..1, Access::ComputeStorage)]
        );
        assert_eq!(
            plan_transitions(&mut state, 0..1, Access::ComputeStorage),
            vec![(0..1, Access::Sampled)]
        );
    }

    #[test]
    fn layers_in_one_state_share_a_barrier_and_the_state_follows() {
        let mut state = [
            Access::Sampled,
            Access::Sampled,
            Access::ComputeStorage,
            Access::Undefined,
        ];
        let plan = plan_transitions(&mut state, 0..3, Access::TransferSrc);
        assert_eq!(
            plan,
            vec![(0..2, Access::Sampled), (2..3, Access::ComputeStorage)]
        );
        // Untouched layers keep their state.
        assert_eq!(
            state,
            [
                Access::TransferSrc,
                Access::TransferSrc,
                Access::TransferSrc,
                Access::Undefined
            ]
        );
    }
}
