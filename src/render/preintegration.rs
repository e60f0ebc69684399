//! The preintegration table (thesis sect. 3.9, 4.3 "Compositing", 5.1).
//!
//! A 256 × 256 2D image with 3 array layers of RGBA32F, indexed by (front value, back value):
//! layer 0 = premultiplied particle colour and opacity of a segment one reference sample
//! distance long (eqs. 3.17, 4.16), layer 1 = its medium colour, the multiplicative
//! integral of m_tf (eqs. 4.14–4.15). Renderers correct both for their actual step length
//! (eq. 3.19 and the power rule). Layer 2 = the extremes of η over the values between the
//! two (largest η, the value where it peaks, smallest η, the value of that dip): the
//! sweep finds with it the films of glass a value ramp crosses between two samples (a
//! floor whose edge passes through the glass's η band). Built by `glsl/preintegrate.comp`,
//! only when the transfer functions change.

use anyhow::Result;

use crate::shaders;
use crate::transfer::{TransferFunctions, MAX_POINTS_PER_FUNCTION};
use crate::vk::{
    self, Binding, Buffer, ComputePipeline, Context, DescriptorSet, Image, ImageDesc, ImageKind,
    Memory, Recorder,
};

/// Entries per axis: `PREINT_SIZE`, defined once for Rust and the shaders.
pub const TABLE_SIZE: u32 = crate::render::limits::PREINT_SIZE;

/// Both table layers read back: (colour + opacity, medium), index = back * 256 + front.
pub type TableLayers = (Vec<[f32; 4]>, Vec<[f32; 4]>);

pub struct PreintegrationTable {
    pub(crate) image: Image,
    control_points: Buffer,
    pipeline: ComputePipeline,
    set: DescriptorSet,
    builds: u64,
}

impl PreintegrationTable {
    /// `labels`: the table of a label volume (nearest-voxel classification: each segment
    /// half its front label, half its back label; glsl/preintegrate.comp).
    pub fn new(ctx: &Context, labels: bool) -> Result<Self> {
        // Header (2 x uvec4) plus every control point of the four functions: at most
        // MAX_POINTS_PER_FUNCTION each from a file, or a label volume's categorical
        // functions (two points per label in colour, opacity and η, one in medium).
        let points = if labels {
            6 * crate::labels::MAX_LABELS + 1
        } else {
            4 * MAX_POINTS_PER_FUNCTION
        };
        let control_points = Buffer::new(
            ctx,
            ((2 + points) * 16) as u64,
            vk::usage::STORAGE_BUFFER,
            Memory::Upload,
            "tf control points",
        )?;
        let image = Image::new(
            ctx,
            ImageDesc::computed(
                ImageKind::D2Array,
                vk::Format::R32G32B32A32_SFLOAT,
                [TABLE_SIZE, TABLE_SIZE, 1],
                3,
            ),
            "preintegration table",
        )?;
        let set = DescriptorSet::new(
            ctx,
            &[
                Binding::Storage(&control_points),
                Binding::StorageImage(&image),
            ],
            "preintegration",
        )?;
        let pipeline = ComputePipeline::with_constants(
            ctx,
            shaders::PREINTEGRATE_COMP,
            &set,
            0,
            &[labels as u32],
            "preintegrate",
        )?;
        Ok(Self {
            image,
            control_points,
            pipeline,
            set,
            builds: 0,
        })
    }

    /// Record a rebuild of the table from `tf`; leaves it ready for sampling. The control
    /// points are written to a host-visible buffer now, so the recording must be submitted
    /// before the next call.
    pub fn record_build(&mut self, rec: &mut Recorder, tf: &TransferFunctions) -> Result<()> {
        let points = tf.control_points();
        anyhow::ensure!(
            (points.len() * 16) as u64 <= self.control_points.size(),
            "the transfer functions '{}' have {} control points, more than the {} the \
             preintegration takes",
            tf.name,
            points.len() - 2,
            self.control_points.size() / 16 - 2
        );
        self.control_points
            .write(0, bytemuck::cast_slice(&points))?;
        let (pipeline, set, _image) = (&self.pipeline, &self.set, &self.image);
        rec.pass(
            "preintegration",
            &[], // the set's storage binding declares the table's write
            |rec| {
                let groups = TABLE_SIZE.div_ceil(16);
                // Its consumers declare their sampled reads (vk::Use), which transition it.
                rec.dispatch(pipeline, set, &[], [groups, groups, 1])
            },
        )?;
        self.builds += 1;
        Ok(())
    }

    /// How many times the table has been built (for tests and diagnostics).
    pub fn builds(&self) -> u64 {
        self.builds
    }

    pub fn image(&self) -> &Image {
        &self.image
    }

    /// Read both layers back: (colour + opacity, medium), row-major with the back value
    /// along rows (index = back * 256 + front).
    pub fn read(&self, ctx: &Context) -> Result<TableLayers> {
        let l0 = ctx.read_image(&self.image, 0)?;
        let l1 = ctx.read_image(&self.image, 1)?;
        Ok((
            bytemuck::cast_slice(&l0).to_vec(),
            bytemuck::cast_slice(&l1).to_vec(),
        ))
    }

    /// Read layer 2 back: the extremes of η between the two values (largest, its value,
    /// smallest, its value), indexed as `read`.
    pub fn read_eta_extremes(&self, ctx: &Context) -> Result<Vec<[f32; 4]>> {
        Ok(bytemuck::cast_slice(&ctx.read_image(&self.image, 2)?).to_vec())
    }
}
