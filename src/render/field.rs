//! The field texture (the sweep's `field` lever, issue 16 item 2): per voxel, the value
//! and ∇η (η = η_tf(value), central differences one voxel apart, texture units), one
//! RGBA32F texel, sampled trilinearly by the plane shaders in place of the thirteen
//! fetches of `sample_field` (seven volume samples, six η lookups), which were 30 % of a
//! plane on lavapipe. Built by `glsl/field.comp` when the volume or the transfer functions
//! change (its GPU time is the scope "field texture", reported like the preintegration
//! table's).
//!
//! Precision: at voxel centres it is what the shader computed; between them, the
//! trilinear interpolation of the voxels' differences of η instead of the difference of η
//! of interpolated values. For the value's gradient the two are the same (interpolation
//! commutes with a shift by whole voxels); for η they differ where η_tf bends within a
//! voxel's range of values (a face of glass), by at most the change of η across a voxel.
//! ∇η drives the thesis' light kick (eq. 4.5, backward transport) and the viewing rays'
//! kick in weak media; faces of glass are turned by Snell steps that read η directly, not
//! through this texture. tests/levers.rs bounds the images' difference; the caustics and
//! image-quality tests run with it.
//!
//! Memory: 16 bytes per voxel. When that would not fit (beside the gradient volume, in
//! half the largest device-local heap), the sweep computes the field on the fly.

use anyhow::Result;

use super::cached::CachedImage;
use crate::shaders;
use crate::vk::{self, Binding, Context, Image, ImageDesc, ImageKind, Recorder, Sampler};

/// The field texture: one dispatch of `glsl/field.comp` over the volume into an RGBA32F
/// 3D image, rebuilt when the renderer says its inputs changed.
pub struct FieldTexture {
    build: CachedImage,
}

impl FieldTexture {
    /// Bytes it takes for a volume of `extent`.
    pub fn bytes(extent: [u32; 3]) -> u64 {
        16 * extent.iter().map(|&e| e as u64).product::<u64>()
    }

    /// Allocate it for `volume` (a sampled 3D texture of the value) and `tf` (the transfer
    /// functions' image, η in layer 1's alpha); [`FieldTexture::record_build`] fills it.
    pub fn new(ctx: &Context, volume: &Image, tf: &Image, sampler: &Sampler) -> Result<Self> {
        let desc = ImageDesc::computed(
            ImageKind::D3,
            vk::Format::R32G32B32A32_SFLOAT,
            volume.extent(),
            1,
        );
        let build = CachedImage::new(
            ctx,
            desc,
            &[
                Binding::Texture(volume, sampler),
                Binding::Texture(tf, sampler),
            ],
            shaders::FIELD_COMP,
            0,
            "field texture",
        )?;
        Ok(Self { build })
    }

    /// Record a rebuild from `volume` and `tf` (the images it was made with). The set's
    /// bindings declare their uses (Recorder::dispatch); the sweep's declared sampled read
    /// transitions the result.
    pub fn record_build(&mut self, rec: &mut Recorder) -> Result<()> {
        self.build.record_always(rec, "field texture", &[])
    }

    /// How many times it has been built (for tests and diagnostics).
    pub fn builds(&self) -> u64 {
        self.build.builds()
    }

    pub fn image(&self) -> &Image {
        self.build.image()
    }
}
