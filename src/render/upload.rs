//! Uploads of the host-side data (volume, transfer functions, environment map) into the
//! textures the passes sample, with the device checks they need. The data modules
//! (`volume`, `transfer`, `environment`) know nothing of the GPU.

use anyhow::{bail, Context as _, Result};

use crate::environment::EnvironmentMap;
use crate::transfer::{TransferFunctions, TF_SAMPLES};
use crate::vk::{self, Context, Image, ImageDesc, ImageKind};
use crate::volume::{formats, Volume, Voxels};

fn volume_format(volume: &Volume) -> vk::Format {
    match volume.voxels {
        Voxels::U8(_) => vk::Format::R8_UNORM,
        Voxels::U16(_) => vk::Format::R16_UNORM,
        Voxels::F32(_) => vk::Format::R32_SFLOAT,
    }
}

/// Fails, naming the limit, when the device cannot hold `volume` as one 3D texture: a
/// side beyond maxImageDimension3D, or more texel bytes than its largest device-local
/// memory heap (the texture also needs a staging copy of the same size).
pub fn check_volume_fits(ctx: &Context, volume: &Volume) -> Result<()> {
    let l = device_limits(ctx);
    formats::check_volume_limits(volume, l.max_3d_extent, l.bytes_available)
        .with_context(|| format!("device '{}'", ctx.info().name))
}

/// The limits a volume must fit on this device, for the loaders' header checks
/// ([`formats::LoadOptions::limits`]).
pub fn device_limits(ctx: &Context) -> formats::DeviceLimits {
    let info = ctx.info();
    formats::DeviceLimits {
        max_3d_extent: info.limits.max_image_dimension3_d,
        bytes_available: info
            .memory_heaps
            .iter()
            .filter(|(_, local)| *local)
            .map(|(size, _)| *size)
            .max(),
    }
}

/// The volume as a 3D texture ready for trilinear sampling.
pub fn volume_texture(ctx: &Context, volume: &Volume) -> Result<Image> {
    volume.validate()?;
    check_volume_fits(ctx, volume)?;
    let format = volume_format(volume);
    if !ctx.format_supports(
        format,
        vk::FormatFeatureFlags::SAMPLED_IMAGE | vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR,
    ) {
        bail!(
            "device '{}' cannot filter {format:?} textures linearly, needed for {} volumes",
            ctx.info().name,
            volume.voxels.type_name()
        );
    }
    let image = Image::new(
        ctx,
        ImageDesc {
            kind: ImageKind::D3,
            format,
            extent: volume.dims,
            layers: 1,
            usage: vk::usage::SAMPLED | vk::usage::TRANSFER_DST | vk::usage::TRANSFER_SRC,
        },
        "volume",
    )?;
    ctx.upload_image(&image, 0, &volume.texel_bytes())?;
    Ok(image)
}

/// The transfer functions as a 1D-array image (2 layers of RGBA32F, `TF_SAMPLES` wide).
pub fn transfer_texture(ctx: &Context, tf: &TransferFunctions) -> Result<Image> {
    let image = Image::new(
        ctx,
        ImageDesc {
            kind: ImageKind::D1Array,
            format: vk::Format::R32G32B32A32_SFLOAT,
            extent: [TF_SAMPLES, 1, 1],
            layers: 2,
            usage: vk::usage::SAMPLED | vk::usage::TRANSFER_DST | vk::usage::TRANSFER_SRC,
        },
        "transfer functions",
    )?;
    write_transfer_texture(ctx, tf, &image)?;
    Ok(image)
}

/// Overwrite a transfer-function image made by [`transfer_texture`].
pub fn write_transfer_texture(ctx: &Context, tf: &TransferFunctions, image: &Image) -> Result<()> {
    let (l0, l1) = tf.texels();
    ctx.upload_image(image, 0, bytemuck::cast_slice(&l0))?;
    ctx.upload_image(image, 1, bytemuck::cast_slice(&l1))?;
    Ok(())
}

/// An RGBA32F 2D image the size of `map` (the map itself, its summed-area table).
pub(super) fn map_sized_image(
    ctx: &Context,
    map: &EnvironmentMap,
    usage: vk::ImageUsageFlags,
    name: &str,
) -> Result<Image> {
    Image::new(
        ctx,
        ImageDesc {
            kind: ImageKind::D2,
            format: vk::Format::R32G32B32A32_SFLOAT,
            extent: [map.width, map.height, 1],
            layers: 1,
            usage,
        },
        name,
    )
}

/// The map as an RGBA32F 2D image (for sampling and for building the SAT).
pub fn environment_texture(ctx: &Context, map: &EnvironmentMap) -> Result<Image> {
    let usage = vk::usage::SAMPLED | vk::usage::STORAGE | vk::usage::TRANSFER_DST;
    let image = map_sized_image(ctx, map, usage, "environment map")?;
    ctx.upload_image(&image, 0, bytemuck::cast_slice(&map.pixels))?;
    Ok(image)
}
