//! A volume computed from other images by one compute dispatch and rebuilt only when the
//! key of what it was built from changes (the "volume in, volume out" caches of the
//! models: AO's occlusion, single scattering's transmittance, ambient scattering's
//! extinction and radiance). Shared machinery, so it lives here (issue 34).

use anyhow::Result;

use crate::vk::{Binding, ComputePipeline, Context, DescriptorSet, Image, ImageDesc, Recorder};

/// A compute step that writes one image from its inputs, remembering what it was last
/// built from so it is rebuilt only when that changes.
pub(crate) struct CachedImage {
    image: Image,
    set: DescriptorSet,
    pipeline: ComputePipeline,
    built_for: Option<Vec<u32>>,
    /// How many times it has been built (for tests and diagnostics).
    builds: u64,
}

impl CachedImage {
    pub(crate) fn new(
        ctx: &Context,
        desc: ImageDesc,
        inputs: &[Binding<'_>],
        spirv: &[u8],
        push_size: usize,
        name: &str,
    ) -> Result<Self> {
        let image = Image::new(ctx, desc, name)?;
        let mut bindings = inputs.to_vec();
        bindings.push(Binding::StorageImage(&image));
        let set = DescriptorSet::new(ctx, &bindings, name)?;
        let pipeline = ComputePipeline::new(ctx, spirv, &set, push_size as u32, name)?;
        Ok(Self {
            image,
            set,
            pipeline,
            built_for: None,
            builds: 0,
        })
    }

    /// Record the build under `scope` if `key` differs from the last build's.
    pub(crate) fn record(
        &mut self,
        rec: &mut Recorder,
        scope: &str,
        key: Vec<u32>,
        push: &[u8],
    ) -> Result<bool> {
        if self.built_for.as_ref() == Some(&key) {
            return Ok(false);
        }
        // The set binds what the build reads and the image it writes: its bindings
        // declare their uses (Recorder::dispatch).
        let [w, h, d] = self.image.extent();
        rec.pass(scope, &[], |rec| {
            rec.dispatch(
                &self.pipeline,
                &self.set,
                push,
                [w.div_ceil(8), h.div_ceil(8), d],
            )
        })?;
        self.built_for = Some(key);
        self.builds += 1;
        Ok(true)
    }

    /// Record a build under `scope` whatever it was built from (its owner tracks what
    /// changed: the field texture, rebuilt with the volume or the transfer functions).
    pub(crate) fn record_always(
        &mut self,
        rec: &mut Recorder,
        scope: &str,
        push: &[u8],
    ) -> Result<()> {
        self.built_for = None;
        self.record(rec, scope, Vec::new(), push).map(|_| ())
    }

    /// How many times it has been built.
    pub(crate) fn builds(&self) -> u64 {
        self.builds
    }

    /// The image (R32F or as `desc` said), once built.
    pub(crate) fn image(&self) -> &Image {
        &self.image
    }
}
