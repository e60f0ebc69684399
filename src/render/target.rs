//! What every frame renders into and with: the frame's target image and its readback,
//! and the environment map on the GPU.

use super::*;

/// The environment map on the GPU with its summed-area table. A 2 × 1 black map stands in
/// when there is none, so the composite's descriptor set is always complete.
/// The environment as a model's passes see it: the map, its summed-area table, its mean
/// and whether to use them at all (otherwise the constant background). Any model may
/// read it; today the sweep's composite does.
pub(crate) struct EnvInputs<'a> {
    pub map: &'a Image,
    pub sat: &'a Image,
    pub mean: [f32; 4],
    pub enabled: bool,
}

pub(super) struct Environment {
    pub(super) map: EnvironmentMap,
    pub(super) image: Image,
    pub(super) sat: SummedAreaTable,
    pub(super) enabled: bool,
}

impl Environment {
    pub(super) fn new(ctx: &Context, map: Option<&EnvironmentMap>) -> Result<(Self, Timings)> {
        let enabled = map.is_some();
        let map = match map {
            Some(m) => m.clone(),
            None => EnvironmentMap::constant(2, [0.0; 3])?,
        };
        let image = upload::environment_texture(ctx, &map)?;
        let (sat, timings) = SummedAreaTable::build(ctx, &map, &image)?;
        Ok((
            Self {
                map,
                image,
                sat,
                enabled,
            },
            timings,
        ))
    }
}

/// The RGBA32F image a pass writes its frame into, and the host buffer it is copied to.
pub(crate) struct FrameTarget {
    pub image: Image,
    readback: Buffer,
    pixels: usize,
}

impl FrameTarget {
    pub fn new(ctx: &Context, width: u32, height: u32, name: &str) -> Result<Self> {
        let format = vk::Format::R32G32B32A32_SFLOAT;
        let desc = ImageDesc::computed(ImageKind::D2, format, [width, height, 1], 1);
        let image = Image::new(ctx, desc, name)?;
        let readback = Buffer::readback(ctx, image.layer_bytes()?, &format!("{name} readback"))?;
        Ok(Self {
            image,
            readback,
            pixels: width as usize * height as usize,
        })
    }

    /// Record the copy of the finished frame to the host.
    pub fn record_copy(&self, rec: &mut Recorder) {
        rec.copy_image_to_buffer(&self.image, 0, &self.readback);
    }

    /// The frame, once the submission that recorded the copy has completed.
    pub fn pixels(&self) -> Result<Vec<[f32; 4]>> {
        self.readback.read_values(self.pixels)
    }
}
