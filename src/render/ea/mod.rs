//! The baseline emission–absorption ray marcher (`glsl/ea.comp`), the reference every
//! refractive image is compared against.

use anyhow::Result;

use super::march::{delegate_to_march, MarchParams, RayMarchPass};
use super::model::{no_state_buffers, Inputs, ModelPass, OpticalModel, Recorded};
use super::LightSupport;
use crate::shaders;
use crate::vk::Recorder;

pub(super) struct EaPass {
    march: RayMarchPass,
}

impl EaPass {
    pub fn new(inputs: &Inputs, width: u32, height: u32) -> Result<Self> {
        Ok(Self {
            march: RayMarchPass::new::<MarchParams>(
                inputs,
                width,
                height,
                shaders::EA_COMP,
                "ea",
                &[],
            )?,
        })
    }
}

/// The emission–absorption model's declaration (listed in render/registry.rs).
pub(crate) static EA: OpticalModel = OpticalModel {
    name: "ea",
    summary: "Emission-absorption ray marcher (the baseline).",
    // Unlit: emission only.
    lights: LightSupport::NONE,
    phase_function: false,
    gradient: false,
    extinction: None,
    check: no_state_buffers,
    make_pass: |inputs| {
        let o = inputs.opts;
        Ok(Box::new(EaPass::new(inputs, o.width, o.height)?))
    },
    flags: &[],
    rebuild_scopes: &[],
    state: None,
};

impl ModelPass for EaPass {
    delegate_to_march!();

    fn record(&mut self, rec: &mut Recorder, inputs: &Inputs) -> Result<Recorded> {
        let (width, height) = self.march.size();
        let p = MarchParams::new(inputs, width, height);
        self.march.record(rec, inputs, bytemuck::bytes_of(&p))
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
