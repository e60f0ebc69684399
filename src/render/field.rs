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

use crate::shaders;
use crate::vk::{
    self, Binding, ComputePipeline, Context, DescriptorSet, Image, ImageDesc, ImageKind, Recorder,
    Sampler,
};

pub struct FieldTexture {
    image: Image,
    pipeline: ComputePipeline,
    set: DescriptorSet,
    builds: u64,
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
        let image = Image::new(ctx, desc, "field texture")?;
        let set = DescriptorSet::new(
            ctx,
            &[
                Binding::Texture(volume, sampler),
                Binding::Texture(tf, sampler),
                Binding::StorageImage(&image),
            ],
            "field texture",
        )?;
        let pipeline = ComputePipeline::new(ctx, shaders::FIELD_COMP, &set, 0, "field texture")?;
        Ok(Self {
            image,
            pipeline,
            set,
            builds: 0,
        })
    }

    /// Record a rebuild from `volume` and `tf` (the images it was made with).
    pub fn record_build(&mut self, rec: &mut Recorder) -> Result<()> {
        let [w, h, d] = self.image.extent();
        let (pipeline, set, _image) = (&self.pipeline, &self.set, &self.image);
        // The set binds volume, tf and the field: its bindings declare their uses
        // (Recorder::dispatch); the sweep's declared sampled read transitions the result.
        rec.pass("field texture", &[], |rec| {
            rec.dispatch(pipeline, set, &[], [w.div_ceil(8), h.div_ceil(8), d])
        })?;
        self.builds += 1;
        Ok(())
    }

    /// How many times it has been built (for tests and diagnostics).
    pub fn builds(&self) -> u64 {
        self.builds
    }

    pub fn image(&self) -> &Image {
        &self.image
    }
}
