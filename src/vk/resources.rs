//! Buffers, images, views and samplers, with memory from gpu-allocator.
//!
//! Images remember the state (layout, last stage, last access) of each array layer, so a
//! barrier is derived in one place ([`crate::vk::Recorder::transition`]) from what the next
//! use declares, rather than written by hand at every call site.

use std::sync::{Arc, Mutex, Weak};

use anyhow::{bail, Context as _, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::{Access, Context};

static NEXT_IMAGE_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

fn next_image_id() -> u64 {
    NEXT_IMAGE_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

/// Where a buffer lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Memory {
    /// Device-local, not mapped.
    Gpu,
    /// Host-visible, mapped, for uploads and uniforms written every frame.
    Upload,
    /// Host-visible, mapped, cached, for readback.
    Readback,
}

pub struct Buffer {
    ctx: Context,
    pub(crate) raw: vk::Buffer,
    allocation: Option<Allocation>,
    size: u64,
    name: String,
    /// Held while the buffer lives: the descriptor sets that bind it keep a weak handle,
    /// so a dispatch can refuse a set whose buffer was destroyed.
    pub(crate) alive: Arc<()>,
}

/// What a descriptor set keeps of a storage buffer it binds, to derive its barrier at a
/// dispatch (see [`TrackedImage`]).
#[derive(Clone)]
pub(crate) struct TrackedBuffer {
    pub(crate) raw: vk::Buffer,
    pub(crate) name: String,
    pub(crate) alive: Weak<()>,
}

/// Memory for one resource from the context's allocator (its own block when the
/// allocator decides so). `linear`: buffers and linear images.
fn allocate(
    ctx: &Context,
    name: &str,
    requirements: vk::MemoryRequirements,
    location: MemoryLocation,
    linear: bool,
) -> gpu_allocator::Result<Allocation> {
    ctx.shared
        .allocator
        .lock()
        .unwrap()
        .allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        })
}

impl Buffer {
    pub fn new(
        ctx: &Context,
        size: u64,
        usage: vk::BufferUsageFlags,
        memory: Memory,
        name: &str,
    ) -> Result<Self> {
        let size = size.max(4);
        let device = ctx.device();
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid device and create info.
        let raw = unsafe { device.create_buffer(&info, None) }?;
        let requirements = unsafe { device.get_buffer_memory_requirements(raw) };
        let location = match memory {
            Memory::Gpu => MemoryLocation::GpuOnly,
            Memory::Upload => MemoryLocation::CpuToGpu,
            Memory::Readback => MemoryLocation::GpuToCpu,
        };
        let allocation = match allocate(ctx, name, requirements, location, true) {
            Ok(a) => a,
            Err(e) => {
                unsafe { device.destroy_buffer(raw, None) };
                return Err(e)
                    .with_context(|| format!("allocating {size} bytes for buffer '{name}'"));
            }
        };
        // SAFETY: memory comes from the allocator for exactly these requirements.
        unsafe { device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) }?;
        ctx.set_name(raw, name);
        Ok(Self {
            ctx: ctx.clone(),
            raw,
            allocation: Some(allocation),
            size,
            name: name.to_owned(),
            alive: Arc::new(()),
        })
    }

    pub(crate) fn tracked(&self) -> TrackedBuffer {
        TrackedBuffer {
            raw: self.raw,
            name: self.name.clone(),
            alive: Arc::downgrade(&self.alive),
        }
    }

    /// A device-local uniform buffer for one `T` (std140 layout is the caller's business),
    /// written in the command stream with [`crate::vk::Recorder::update_uniform`].
    pub fn uniform<T>(ctx: &Context, name: &str) -> Result<Self> {
        Self::new(
            ctx,
            std::mem::size_of::<T>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            Memory::Gpu,
            name,
        )
    }

    /// A host-visible buffer that copies land in.
    pub fn readback(ctx: &Context, size: u64, name: &str) -> Result<Self> {
        Self::new(
            ctx,
            size,
            vk::BufferUsageFlags::TRANSFER_DST,
            Memory::Readback,
            name,
        )
    }

    /// The first `count` values of a host-visible buffer, after the GPU work that wrote
    /// them has been waited for.
    pub fn read_values<T: bytemuck::Pod>(&self, count: usize) -> Result<Vec<T>> {
        let bytes = count * std::mem::size_of::<T>();
        let mapped = self.mapped()?;
        if bytes > mapped.len() {
            bail!("reading {bytes} bytes from a {}-byte buffer", mapped.len());
        }
        Ok(bytemuck::pod_collect_to_vec(&mapped[..bytes]))
    }

    pub fn size(&self) -> u64 {
        self.size
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// Copy bytes into a mapped buffer at `offset`.
    pub fn write(&mut self, offset: usize, bytes: &[u8]) -> Result<()> {
        let slice = self
            .allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .context("buffer is not host-visible")?;
        if offset + bytes.len() > slice.len() {
            bail!(
                "write of {} bytes at {offset} overruns a {}-byte buffer",
                bytes.len(),
                slice.len()
            );
        }
        slice[offset..offset + bytes.len()].copy_from_slice(bytes);
        Ok(())
    }

    /// The mapped contents (host-visible buffers only). Read after the GPU work that wrote
    /// them has been waited for.
    pub fn mapped(&self) -> Result<&[u8]> {
        self.allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .context("buffer is not host-visible")
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        // SAFETY: users wait for the GPU work that uses a buffer before dropping it (every
        // submission in this crate is waited for).
        unsafe { self.ctx.device().destroy_buffer(self.raw, None) };
        if let Some(a) = self.allocation.take() {
            let _ = self.ctx.shared.allocator.lock().unwrap().free(a);
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageKind {
    D1Array,
    D2,
    D2Array,
    D3,
}

/// Description of an image to create.
#[derive(Clone, Debug)]
pub struct ImageDesc {
    pub kind: ImageKind,
    pub format: vk::Format,
    pub extent: [u32; 3],
    pub layers: u32,
    pub usage: vk::ImageUsageFlags,
}

impl ImageDesc {
    /// An image a compute pass writes and later passes sample or copy out (storage,
    /// sampled and transfer-source usage).
    pub fn computed(kind: ImageKind, format: vk::Format, extent: [u32; 3], layers: u32) -> Self {
        Self {
            kind,
            format,
            extent,
            layers,
            usage: vk::ImageUsageFlags::STORAGE
                | vk::ImageUsageFlags::SAMPLED
                | vk::ImageUsageFlags::TRANSFER_SRC,
        }
    }
}

pub struct Image {
    ctx: Context,
    pub(crate) raw: vk::Image,
    pub(crate) view: vk::ImageView,
    allocation: Option<Allocation>,
    pub(crate) desc: ImageDesc,
    /// Each layer's last declared use. Shared (weakly) with the descriptor sets that bind
    /// the image, so a dispatch can derive its barriers from the set's bindings.
    pub(crate) layer_state: Arc<Mutex<Vec<Access>>>,
    name: String,
    /// Unique for the process, never reused (unlike Vulkan handles).
    id: u64,
    /// False for swapchain images: the swapchain owns them, only the view is ours.
    owned: bool,
}

/// Bytes per texel of the formats refrakt uses.
pub fn format_size(format: vk::Format) -> Result<u32> {
    Ok(match format {
        vk::Format::R8_UNORM => 1,
        vk::Format::R16_UNORM | vk::Format::R16_SFLOAT => 2,
        vk::Format::R32_SFLOAT
        | vk::Format::R8G8B8A8_UNORM
        | vk::Format::R8G8B8A8_SRGB
        | vk::Format::B8G8R8A8_UNORM
        | vk::Format::B8G8R8A8_SRGB
        | vk::Format::A8B8G8R8_UNORM_PACK32
        | vk::Format::A8B8G8R8_SRGB_PACK32 => 4,
        vk::Format::R16G16B16A16_SFLOAT | vk::Format::R32G32_SFLOAT | vk::Format::R32G32_UINT => 8,
        vk::Format::R32G32B32A32_SFLOAT => 16,
        other => bail!("format {other:?} has no known texel size"),
    })
}

impl Image {
    pub fn new(ctx: &Context, desc: ImageDesc, name: &str) -> Result<Self> {
        let device = ctx.device();
        let (image_type, view_type) = match desc.kind {
            ImageKind::D1Array => (vk::ImageType::TYPE_1D, vk::ImageViewType::TYPE_1D_ARRAY),
            ImageKind::D2 => (vk::ImageType::TYPE_2D, vk::ImageViewType::TYPE_2D),
            ImageKind::D2Array => (vk::ImageType::TYPE_2D, vk::ImageViewType::TYPE_2D_ARRAY),
            ImageKind::D3 => (vk::ImageType::TYPE_3D, vk::ImageViewType::TYPE_3D),
        };
        let limits = &ctx.info().limits;
        let max = match desc.kind {
            ImageKind::D1Array => limits.max_image_dimension1_d,
            ImageKind::D2 | ImageKind::D2Array => limits.max_image_dimension2_d,
            ImageKind::D3 => limits.max_image_dimension3_d,
        };
        if desc.extent.iter().any(|&e| e == 0 || e > max) {
            bail!(
                "image '{name}' extent {:?} is outside this device's limit of 1..={max} per axis",
                desc.extent
            );
        }
        if desc.layers == 0 || desc.layers > limits.max_image_array_layers {
            bail!(
                "image '{name}' wants {} layers; device allows {}",
                desc.layers,
                limits.max_image_array_layers
            );
        }
        let info = vk::ImageCreateInfo::default()
            .image_type(image_type)
            .format(desc.format)
            .extent(vk::Extent3D {
                width: desc.extent[0],
                height: desc.extent[1],
                depth: desc.extent[2],
            })
            .mip_levels(1)
            .array_layers(desc.layers)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid device and create info.
        let raw = unsafe { device.create_image(&info, None) }
            .with_context(|| format!("creating image '{name}' ({:?})", desc.format))?;
        let requirements = unsafe { device.get_image_memory_requirements(raw) };
        let allocation = match allocate(ctx, name, requirements, MemoryLocation::GpuOnly, false) {
            Ok(a) => a,
            Err(e) => {
                unsafe { device.destroy_image(raw, None) };
                return Err(e).with_context(|| format!("allocating memory for image '{name}'"));
            }
        };
        // SAFETY: memory from the allocator for this image's requirements.
        unsafe { device.bind_image_memory(raw, allocation.memory(), allocation.offset()) }?;
        let view = create_view(ctx, raw, view_type, desc.format, 0, desc.layers)?;
        ctx.set_name(raw, name);
        ctx.set_name(view, name);
        let layers = desc.layers as usize;
        Ok(Self {
            ctx: ctx.clone(),
            raw,
            view,
            allocation: Some(allocation),
            desc,
            layer_state: Arc::new(Mutex::new(vec![Access::Undefined; layers])),
            name: name.to_owned(),
            id: next_image_id(),
            owned: true,
        })
    }

    /// Wrap an image the swapchain owns: a view is created (and destroyed with the
    /// wrapper), the image and its memory are left to the swapchain.
    pub(crate) fn from_swapchain(
        ctx: &Context,
        raw: vk::Image,
        format: vk::Format,
        extent: [u32; 2],
        usage: vk::ImageUsageFlags,
        name: &str,
    ) -> Result<Self> {
        let view = create_view(ctx, raw, vk::ImageViewType::TYPE_2D, format, 0, 1)?;
        ctx.set_name(raw, name);
        ctx.set_name(view, name);
        Ok(Self {
            ctx: ctx.clone(),
            raw,
            view,
            allocation: None,
            desc: ImageDesc {
                kind: ImageKind::D2,
                format,
                extent: [extent[0], extent[1], 1],
                layers: 1,
                usage,
            },
            layer_state: Arc::new(Mutex::new(vec![Access::Undefined])),
            name: name.to_owned(),
            id: next_image_id(),
            owned: false,
        })
    }

    pub(crate) fn tracked(&self) -> TrackedImage {
        TrackedImage {
            raw: self.raw,
            name: self.name.clone(),
            state: Arc::downgrade(&self.layer_state),
        }
    }

    /// An identity that is never reused in this process, for caches keyed by image (a
    /// Vulkan handle can come back for a new image after the old one is destroyed).
    pub fn id(&self) -> u64 {
        self.id
    }

    /// Record that every layer is now in `access` without a barrier: for images whose
    /// state changed outside any recording (a swapchain image when it is acquired).
    pub(crate) fn reset_state(&self, access: Access) {
        for s in self.layer_state.lock().unwrap().iter_mut() {
            *s = access;
        }
    }

    pub fn desc(&self) -> &ImageDesc {
        &self.desc
    }
    pub fn name(&self) -> &str {
        &self.name
    }
    pub fn extent(&self) -> [u32; 3] {
        self.desc.extent
    }
    /// Bytes in one array layer.
    pub fn layer_bytes(&self) -> Result<u64> {
        let [w, h, d] = self.desc.extent;
        Ok(w as u64 * h as u64 * d as u64 * format_size(self.desc.format)? as u64)
    }

    /// A view of a single layer, as a non-array 2D view (colour attachments, per-layer
    /// sampling in the plane sweep).
    pub fn layer_view(&self, layer: u32) -> Result<LayerView> {
        let view_type = match self.desc.kind {
            ImageKind::D2 | ImageKind::D2Array => vk::ImageViewType::TYPE_2D,
            ImageKind::D1Array => vk::ImageViewType::TYPE_1D,
            ImageKind::D3 => bail!("3D images have no layers"),
        };
        if layer >= self.desc.layers {
            bail!("image '{}' has no layer {layer}", self.name);
        }
        let view = create_view(&self.ctx, self.raw, view_type, self.desc.format, layer, 1)?;
        self.ctx.set_name(view, &format!("{}[{layer}]", self.name));
        Ok(LayerView {
            ctx: self.ctx.clone(),
            raw: view,
            layer,
            image: self.tracked(),
        })
    }
}

fn create_view(
    ctx: &Context,
    image: vk::Image,
    view_type: vk::ImageViewType,
    format: vk::Format,
    base_layer: u32,
    layers: u32,
) -> Result<vk::ImageView> {
    let info = vk::ImageViewCreateInfo::default()
        .image(image)
        .view_type(view_type)
        .format(format)
        .subresource_range(color_range(base_layer, layers));
    // SAFETY: valid image of this device.
    Ok(unsafe { ctx.device().create_image_view(&info, None) }?)
}

pub(crate) fn color_range(base_layer: u32, layers: u32) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: base_layer,
        layer_count: layers,
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: GPU work using the image has been waited for (all submissions are).
        unsafe {
            self.ctx.device().destroy_image_view(self.view, None);
            if self.owned {
                self.ctx.device().destroy_image(self.raw, None);
            }
        }
        if let Some(a) = self.allocation.take() {
            let _ = self.ctx.shared.allocator.lock().unwrap().free(a);
        }
    }
}

/// A single-layer view of an image array.
pub struct LayerView {
    ctx: Context,
    pub(crate) raw: vk::ImageView,
    pub layer: u32,
    /// The image the view shows, for the barriers of a set that binds the view.
    pub(crate) image: TrackedImage,
}

/// What a descriptor set keeps of an image it binds, to derive the image's barriers at a
/// dispatch: its handle, name and (weakly) its layers' state. The set does not keep the
/// image alive; a dispatch whose set binds an image destroyed since is refused.
#[derive(Clone)]
pub(crate) struct TrackedImage {
    pub(crate) raw: vk::Image,
    pub(crate) name: String,
    pub(crate) state: Weak<Mutex<Vec<Access>>>,
}

impl Drop for LayerView {
    fn drop(&mut self) {
        // SAFETY: not in use by pending GPU work.
        unsafe { self.ctx.device().destroy_image_view(self.raw, None) };
    }
}

/// Texture filtering and addressing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    Nearest,
    Linear,
}

pub struct Sampler {
    ctx: Context,
    pub(crate) raw: vk::Sampler,
}

impl Sampler {
    /// Clamp-to-edge sampler with normalised coordinates.
    pub fn new(ctx: &Context, filter: Filter, name: &str) -> Result<Self> {
        let f = match filter {
            Filter::Nearest => vk::Filter::NEAREST,
            Filter::Linear => vk::Filter::LINEAR,
        };
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(f)
            .min_filter(f)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(0.0);
        // SAFETY: valid device.
        let raw = unsafe { ctx.device().create_sampler(&info, None) }?;
        ctx.set_name(raw, name);
        Ok(Self {
            ctx: ctx.clone(),
            raw,
        })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        // SAFETY: not in use by pending GPU work.
        unsafe { self.ctx.device().destroy_sampler(self.raw, None) };
    }
}
