//! The light of `--light-transport eikonal` (issue 35 item 5), the refractive model's
//! state: the eikonal model's light volume ([`LightVolume`], simulated by the adaptive
//! wavefront light simulator for every light), made on the first frame that asks for this
//! transport and simulated again when the lights, the transfer functions or the η scale
//! change. The planes read it at binding 26 (glsl/sweep_light.glsl, `volume_light`), the
//! composite's reflected rays at binding 16 (glsl/sweep_reflect.glsl); with the other
//! transports a placeholder of two texels fills those bindings (the planes never read it,
//! the composite reads only those two and discards them), so the volume's memory is
//! spent only where it is used.

use anyhow::Result;

use super::LightTransport;
use crate::render::eikonal::LightVolume;
use crate::render::model::{ModelState, Shared};
use crate::render::RenderOptions;
use crate::vk::{self, Buffer, Memory, Timings};

pub(crate) struct SweepLight {
    /// Bound in the light volume's place while there is none.
    placeholder: Buffer,
    volume: Option<LightVolume>,
}

impl SweepLight {
    pub(crate) fn new(shared: &Shared) -> Result<Self> {
        Ok(Self {
            placeholder: Buffer::new(
                shared.ctx,
                32,
                vk::usage::STORAGE_BUFFER,
                Memory::Gpu,
                "sweep light volume placeholder",
            )?,
            volume: None,
        })
    }

    /// What binding 26 names: the light volume, or the placeholder before one is made.
    pub(crate) fn buffer(&self) -> &Buffer {
        self.volume
            .as_ref()
            .map_or(&self.placeholder, |v| v.buffer())
    }
}

impl ModelState for SweepLight {
    /// With the eikonal transport: make the light volume on its first frame (the passes
    /// then bind it: true) and simulate the lights into it where they changed.
    fn prepare(&mut self, shared: &Shared, opts: &RenderOptions) -> Result<bool> {
        if opts.sweep.light_transport != LightTransport::Eikonal {
            return Ok(false);
        }
        let made = self.volume.is_none();
        if made {
            self.volume = Some(LightVolume::new(shared)?);
        }
        self.volume
            .as_mut()
            .expect("made above")
            .update(shared, opts)?;
        Ok(made)
    }

    fn take_timings(&mut self) -> Timings {
        self.volume
            .as_mut()
            .map(|v| v.take_timings())
            .unwrap_or_default()
    }

    fn simulation_stats(&self) -> &[crate::render::light_simulator::SimulationStats] {
        self.volume.as_ref().map_or(&[], |v| v.stats())
    }

    fn bytes(&self) -> u64 {
        self.placeholder.size() + self.volume.as_ref().map_or(0, |v| v.device_bytes())
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}
