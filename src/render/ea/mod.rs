//! The baseline emission–absorption ray marcher (`glsl/ea.comp`), the reference every
//! refractive image is compared against.

use anyhow::Result;

use super::march::{delegate_to_march, MarchParams, RayMarchPass, RAY_MARCHER};
use super::model::{Inputs, ModelPass, OpticalModel, Recorded};
use crate::shaders;
use crate::vk::Recorder;

pub(super) struct EaPass {
    march: RayMarchPass,
}

impl EaPass {
    pub fn new(inputs: &Inputs) -> Result<Self> {
        Ok(Self {
            march: RayMarchPass::new::<MarchParams>(inputs, shaders::EA_COMP, "ea", &[])?,
        })
    }
}

/// The emission–absorption model's declaration (listed in render/registry.rs).
pub(crate) static EA: OpticalModel = OpticalModel {
    name: "ea",
    summary: "Emission-absorption ray marcher (the baseline).",
    make_pass: |inputs| Ok(Box::new(EaPass::new(inputs)?)),
    ..RAY_MARCHER
};

impl ModelPass for EaPass {
    delegate_to_march!();

    fn record(&mut self, rec: &mut Recorder, inputs: &Inputs) -> Result<Recorded> {
        self.march.record(rec, inputs, |march: MarchParams| march)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_match_the_shaders_block() {
        // EA's block is the march's alone.
        crate::render::march::check_params_block(
            shaders::EA_COMP,
            Vec::new(),
            std::mem::size_of::<MarchParams>(),
        );
    }
}
