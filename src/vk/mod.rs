//! The Vulkan backend: raw `ash` behind safe wrappers. It knows nothing about volumes or
//! rendering; `crate::render` builds passes out of these pieces.
//!
//! Safety model: every object holds a [`Context`] (an `Arc` of the device), so the device
//! outlives its objects; every submission is waited for before [`Context::execute`]
//! returns, so dropping a resource after use never races the GPU. The one exception is
//! [`Swapchain::frame`], which returns with the frame in flight: its caller keeps what the
//! frame uses alive and calls [`Swapchain::wait_idle`] before freeing any of it.

mod barriers;
mod commands;
mod context;
mod graphics;
mod overlay;
mod pipeline;
mod resources;
pub mod spirv;
mod swapchain;

pub use ash::vk::{Format, ImageUsageFlags, PhysicalDeviceType};
pub use barriers::Access;
pub use commands::{Area, BufferUse, Recorder, Timings, Use};
pub use context::{
    device_type_name, version_string, Context, ContextDesc, DeviceInfo, ValidationLog, WindowSource,
};
pub use graphics::{Framebuffer, GraphicsDesc, GraphicsPipeline, Primitives, RenderPass};
pub use overlay::Overlay;
pub use pipeline::{Binding, ComputePipeline, DescriptorSet};
pub use resources::{
    format_size, Buffer, Filter, Image, ImageDesc, ImageKind, LayerView, Memory, Sampler,
};
pub use swapchain::{FrameStatus, Swapchain, SwapchainDesc, FRAMES_IN_FLIGHT};

/// Usage flags re-exported so callers need not import ash.
pub mod usage {
    use ash::vk::{BufferUsageFlags as B, ImageUsageFlags as I};
    pub const SAMPLED: I = I::SAMPLED;
    pub const STORAGE: I = I::STORAGE;
    pub const TRANSFER_DST: I = I::TRANSFER_DST;
    pub const TRANSFER_SRC: I = I::TRANSFER_SRC;
    pub const COLOR_ATTACHMENT: I = I::COLOR_ATTACHMENT;
    pub const UNIFORM_BUFFER: B = B::UNIFORM_BUFFER;
    pub const STORAGE_BUFFER: B = B::STORAGE_BUFFER;
    pub const BUFFER_TRANSFER_DST: B = B::TRANSFER_DST;
    pub const BUFFER_TRANSFER_SRC: B = B::TRANSFER_SRC;
    pub const INDIRECT_BUFFER: B = B::INDIRECT_BUFFER;
}

/// Format features re-exported for capability checks.
pub use ash::vk::FormatFeatureFlags;
