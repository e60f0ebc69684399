//! The value ranges: for each brick of [`VALUE_BRICK`]³ voxels, the smallest and largest
//! value a sample can read within one brick of it (x = min, y = max; RGBA32F, one texel
//! per brick). Built by `glsl/value_range.comp` (each brick with a one-voxel apron, the
//! support of a trilinear fetch and of the 8-corner gradient) and
//! `glsl/value_range_dilate.comp` (the 3 × 3 × 3 bricks around), once per volume: it
//! depends on the volume only, so editing the transfer functions rebuilds nothing.
//!
//! Why: the forward transport advances each light ray to the next plane in
//! `LIGHT_SUBSTEPS` Snell sub-steps (glsl/sweep_plane.glsl), which only matter where η
//! or the medium changes along the step. Where every value the step can meet is the same,
//! or the transfer functions make all of them clear (no opacity, a white medium) with
//! one η, one sub-step gives the same ray: nothing turns it and the attenuation
//! composes exactly (eq. 4.4 over the whole step). Most light rays cross air most of
//! the time, and on llvmpipe a loop's trip count is where lanes that agree save work
//! (a branch costs both sides): on lavapipe the light rays' pass took <see
//! docs/NOTES.md "Empty space for the light rays"> less.
//!
//! Memory: 16 bytes per brick, twice (the undilated ranges are kept for tests and dumps).

use anyhow::Result;

use super::limits::VALUE_BRICK;
use crate::shaders;
use crate::vk::{
    self, Binding, ComputePipeline, Context, DescriptorSet, Image, ImageDesc, ImageKind, Sampler,
    Timings,
};

pub struct ValueRanges {
    /// Each brick's own range (with its apron).
    bricks: Image,
    /// The range over each brick's 3 × 3 × 3 neighbourhood: what the sweep reads.
    dilated: Image,
}

impl ValueRanges {
    /// Bricks per axis for a volume of `extent` voxels.
    pub fn grid(extent: [u32; 3]) -> [u32; 3] {
        extent.map(|e| e.div_ceil(VALUE_BRICK))
    }

    /// Build the ranges of `volume` (a sampled 3D texture of the scalar value) now;
    /// returns them with the build's GPU time (scope "value ranges").
    pub fn build(ctx: &Context, volume: &Image, sampler: &Sampler) -> Result<(Self, Timings)> {
        let grid = Self::grid(volume.extent());
        let desc = ImageDesc::computed(ImageKind::D3, vk::Format::R32G32B32A32_SFLOAT, grid, 1);
        let bricks = Image::new(ctx, desc.clone(), "value ranges (bricks)")?;
        let dilated = Image::new(ctx, desc, "value ranges")?;
        let brick_set = DescriptorSet::new(
            ctx,
            &[
                Binding::Texture(volume, sampler),
                Binding::StorageImage(&bricks),
            ],
            "value ranges (bricks)",
        )?;
        let dilate_set = DescriptorSet::new(
            ctx,
            &[
                Binding::StorageImage(&bricks),
                Binding::StorageImage(&dilated),
            ],
            "value ranges",
        )?;
        let brick_pipeline = ComputePipeline::new(
            ctx,
            shaders::VALUE_RANGE_COMP,
            &brick_set,
            0,
            "value ranges",
        )?;
        let dilate_pipeline = ComputePipeline::new(
            ctx,
            shaders::VALUE_RANGE_DILATE_COMP,
            &dilate_set,
            0,
            "value ranges (dilate)",
        )?;
        let groups = grid.map(|g| g.div_ceil(4));
        let timings = ctx.execute(|rec| {
            // The sets' bindings declare every image's use: the dilation is ordered after
            // the bricks' writes (Recorder::dispatch).
            rec.pass("value ranges", &[], |rec| {
                rec.dispatch(&brick_pipeline, &brick_set, &[], groups)?;
                rec.dispatch(&dilate_pipeline, &dilate_set, &[], groups)?;
                // The sweep's declared sampled read transitions the result.
                Ok(())
            })
        })?;
        Ok((Self { bricks, dilated }, timings))
    }

    /// The dilated ranges, as the sweep reads them.
    pub fn image(&self) -> &Image {
        &self.dilated
    }

    /// Each brick's own range (tests).
    pub fn bricks(&self) -> &Image {
        &self.bricks
    }
}
