//! The environment map's summed-area table on the GPU (`glsl/sat.comp`, thesis sect. 5.3):
//! built once per map, read by the sweep's composite to average the map over the
//! footprint of a pixel's refracted rays.

use anyhow::Result;
use bytemuck::{Pod, Zeroable};

use crate::environment::{EnvironmentMap, SatReadback};
use crate::shaders;
use crate::vk::{self, Binding, ComputePipeline, Context, DescriptorSet, Image};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SatPush {
    mean: [f32; 4],
    pass_index: u32,
    pad: [u32; 3],
}

/// The summed-area table of a map on the GPU (`glsl/sat.comp`): RGBA32F, the same size as
/// the map, S(x, y) = Σ over [0, x] × [0, y] of (map − mean). Box averages are then
/// (corner combination) / area + mean.
pub struct SummedAreaTable {
    pub table: Image,
    pub mean: [f32; 4],
    pub width: u32,
    pub height: u32,
}

impl SummedAreaTable {
    /// Build from a map already uploaded with [`super::upload::environment_texture`].
    pub fn build(
        ctx: &Context,
        map: &EnvironmentMap,
        map_image: &Image,
    ) -> Result<(Self, vk::Timings)> {
        let usage = vk::usage::SAMPLED | vk::usage::STORAGE | vk::usage::TRANSFER_SRC;
        let table = super::upload::map_sized_image(ctx, map, usage, "environment SAT")?;
        let set = DescriptorSet::new(
            ctx,
            &[
                Binding::StorageImage(map_image),
                Binding::StorageImage(&table),
            ],
            "environment SAT",
        )?;
        let pipeline = ComputePipeline::new(
            ctx,
            shaders::SAT_COMP,
            &set,
            std::mem::size_of::<SatPush>() as u32,
            "environment SAT",
        )?;
        let mean = map.mean();
        let timings = ctx.execute(|rec| {
            // The set's bindings declare the images' uses: each dispatch is ordered after
            // the one before it that wrote the table (Recorder::dispatch).
            rec.pass("environment SAT", &[], |rec| {
                // Rows (one invocation per row), then columns reading what the rows wrote.
                for (pass, lines) in [(0u32, map.height), (1, map.width)] {
                    let push = SatPush {
                        mean,
                        pass_index: pass,
                        pad: [0; 3],
                    };
                    rec.dispatch(
                        &pipeline,
                        &set,
                        bytemuck::bytes_of(&push),
                        [lines.div_ceil(64), 1, 1],
                    )?;
                }
                // The composite's declared sampled read transitions the table.
                Ok(())
            })
        })?;
        Ok((
            Self {
                table,
                mean,
                width: map.width,
                height: map.height,
            },
            timings,
        ))
    }

    /// Read the table back.
    pub fn read(&self, ctx: &Context) -> Result<SatReadback> {
        let bytes = ctx.read_image(&self.table, 0)?;
        Ok(SatReadback {
            table: bytemuck::cast_slice(&bytes).to_vec(),
            width: self.width,
            height: self.height,
            mean: self.mean,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sat_push_matches_the_shaders_block() {
        crate::assert_host_block!(
            shaders::SAT_COMP,
            "Push",
            SatPush {
                mean,
                pass_index,
                pad
            },
            exact_size = false
        );
    }
}
