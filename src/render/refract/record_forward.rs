//! The fragment path's forward transport, one plane (issue 31's three passes as draws):
//! the light rays advance, deposit their flux, and the viewing rays cross the segment.
//! Called per plane by [`SweepPass::record_sweep`] (record.rs), which records the
//! barrier before it and the dumps after it.

use super::pass::StateImage;
use super::pipelines::{ForwardPipelines, ForwardPlanes};
use super::ray_rows::{light_pass_rows, ray_texel_rows, PlaneRays};
use super::region::REGION_VERTICES;
use super::*;
use crate::render::limits::SPLAT_GROUP_WORKGROUP;
use crate::vk::{Area, BufferUse, Framebuffer, GraphicsPipeline, RenderPass};

/// What every plane's forward draws share within a frame.
pub(crate) struct ForwardDraws<'a> {
    /// The pass-level pipelines (the compute splat's resolve).
    pub(crate) resolve: &'a ForwardPipelines,
    /// The plane pipelines of the frame's feature set.
    pub(crate) planes: &'a ForwardPlanes,
    /// The light rays' pipeline (with or without softness), bound between planes.
    pub(crate) plane_pipeline: &'a GraphicsPipeline,
    /// The rows each plane moves and the workgroups it deposits (`rays=needed`).
    pub(crate) plane_rays: Option<&'a [PlaneRays]>,
    pub(crate) grid_dims: [u32; 2],
    pub(crate) ray_image: [u32; 2],
    pub(crate) groups_on: bool,
    /// The compute splat's fixed-point unit, and its resolve's workgroups.
    pub(crate) unit: f32,
    pub(crate) resolve_groups: [u32; 3],
    /// The pixels each plane shades (render area of the viewing rays' pass).
    pub(crate) regions: &'a [Area],
    pub(crate) splat: Splat,
    pub(crate) timed: bool,
}

impl SweepPass {
    /// A plane's draw over its region (render area and scissor: the rectangle; the
    /// polygon in `push`, glsl/sweep_region.vert) into the write layer of `images`, with
    /// `pipeline` bound.
    pub(crate) fn draw_plane_region(
        &self,
        rec: &mut Recorder,
        (pass, framebuffer): (&RenderPass, &Framebuffer),
        images: &[&StateImage],
        area: Area,
        pipeline: &GraphicsPipeline,
        push: &PlanePush,
    ) -> Result<()> {
        let write = push.plane % 2;
        let attachments: Vec<(&Image, u32)> = images.iter().map(|s| (&s.image, write)).collect();
        rec.begin_render_pass_in(pass, framebuffer, &attachments, area)?;
        rec.set_scissor(area);
        rec.draw(pipeline, bytemuck::bytes_of(push), REGION_VERTICES)?;
        rec.end_render_pass();
        Ok(())
    }

    /// Plane `push.plane`'s forward draws: 1. the light rays to the plane, 2. their
    /// deposits on it, 3. the viewing rays over the segment before it.
    pub(crate) fn record_forward_plane_draws(
        &self,
        rec: &mut Recorder,
        draws: &ForwardDraws,
        push: PlanePush,
    ) -> Result<()> {
        let ForwardDraws {
            resolve: f,
            planes: fp,
            plane_pipeline,
            plane_rays,
            grid_dims,
            ray_image,
            groups_on,
            unit,
            resolve_groups: groups,
            regions,
            splat,
            timed,
        } = *draws;
        let (i, write) = (push.plane, push.plane % 2);
        let light_images = [&self.rays[0].image, &self.rays[1].image];
        if timed {
            rec.begin_scope("sweep: light rays");
        }
        // 1. The light rays advance to plane i (over the ray images):
        // the texel rows that hold rays, or those of the grid rows this
        // plane moves (ray_rows.rs); `pad` gives the previous plane's, the
        // rows still in their launch state outside them.
        let rows = ray_texel_rows(grid_dims, ray_image);
        let (moved, before) = light_pass_rows(plane_rays, i, grid_dims, ray_image);
        let light_push = PlanePush {
            pad: before.0 | before.1 << 16,
            ..push
        };
        if moved.1 > moved.0 {
            let area = Area {
                x: 0,
                y: moved.0,
                width: ray_image[0],
                height: moved.1 - moved.0,
            };
            rec.begin_render_pass_in(
                &self.light_pass,
                &self.light_framebuffers[write as usize],
                &[(light_images[0], write), (light_images[1], write)],
                area,
            )?;
            rec.set_viewport(ray_image[0], rows);
            rec.set_scissor(area);
            rec.draw_fullscreen(plane_pipeline, bytemuck::bytes_of(&light_push))?;
            rec.end_render_pass();
            rec.set_viewport(self.width, self.height);
        }
        if timed {
            rec.end_scope();
            rec.begin_scope("sweep: splat");
        }
        // 2. They deposit their flux on plane i: irradiance layer `write`
        // (plane i - 2's, read by no draw any more) is overwritten.
        rec.transition_many(&[
            (light_images[0], write..write + 1, Access::SampledGeneral),
            (light_images[1], write..write + 1, Access::SampledGeneral),
        ]);
        match splat {
            Splat::Raster | Splat::Groups => {
                let splat_push = PlanePush {
                    read_layer: write,
                    ..push
                };
                // splat=groups: the deposits and groups first, in a compute
                // pass (glsl/light_splat_groups.glsl), after the previous
                // plane's sprites read them.
                let groups = grid_dims[0].div_ceil(2) * grid_dims[1].div_ceil(2);
                let workgroups = groups.div_ceil(SPLAT_GROUP_WORKGROUP);
                // The workgroups this plane deposits (ray_rows.rs): `pad`
                // gives the first.
                let (first_wg, end_wg) = match plane_rays {
                    Some(p) => {
                        let w = p[i as usize].workgroups;
                        (w.lo, w.end.max(w.lo))
                    }
                    None => (0, workgroups),
                };
                let group_buffers = [
                    &self.deposits,
                    &self.sprite_groups,
                    &self.sprite_fallback,
                    &self.sprite_draws,
                ];
                if groups_on && end_wg > first_wg {
                    if timed {
                        rec.begin_scope("sweep: splat: deposits");
                    }
                    rec.buffer_handover(&group_buffers, BufferUse::Draws, BufferUse::Compute);
                    let deposits_push = PlanePush {
                        pad: first_wg,
                        ..splat_push
                    };
                    rec.dispatch(
                        &fp.group_deposits,
                        &self.sweep_set,
                        bytemuck::bytes_of(&deposits_push),
                        [end_wg - first_wg, 1, 1],
                    )?;
                    rec.buffer_handover(&group_buffers, BufferUse::Compute, BufferUse::Draws);
                    if timed {
                        rec.end_scope();
                    }
                }
                rec.begin_render_pass(
                    &self.splat_pass,
                    &self.splat_framebuffers[write as usize],
                    &[
                        (&self.irradiance[0].image, write),
                        (&self.irradiance[1].image, write),
                    ],
                )?;
                if groups_on {
                    // The indirect draws of one point per group, then of
                    // one point per ray (push constant `pad` 0 and 1):
                    // each workgroup's two lists, in order.
                    rec.bind_pipeline(&fp.splat_groups);
                    rec.draw_indirect(
                        &fp.splat_groups,
                        bytemuck::bytes_of(&splat_push),
                        &self.sprite_draws,
                        workgroups + first_wg..workgroups + end_wg,
                    )?;
                    let leftover_push = PlanePush {
                        pad: 1,
                        ..splat_push
                    };
                    let leftover = fp.splat_group_rays.as_ref().unwrap_or(&fp.splat_groups);
                    rec.bind_pipeline(leftover);
                    rec.draw_indirect(
                        leftover,
                        bytemuck::bytes_of(&leftover_push),
                        &self.sprite_draws,
                        first_wg..end_wg,
                    )?;
                } else {
                    rec.bind_pipeline(&fp.splat);
                    rec.draw(
                        &fp.splat,
                        bytemuck::bytes_of(&splat_push),
                        grid_dims[0] * grid_dims[1],
                    )?;
                }
                rec.end_render_pass();
            }
            Splat::Compute => {
                // The previous plane's resolve zeroed the sums.
                rec.compute_storage_barrier(&self.splat_sums);
                let rays = grid_dims[0] * grid_dims[1];
                // glsl/light_splat.comp reads the fourth word as the
                // sums' unit; the layout's push range is PlanePush's.
                let splat_push = PlanePush {
                    read_layer: write,
                    pad: unit.to_bits(),
                    ..push
                };
                rec.dispatch(
                    &fp.splat_compute,
                    &self.sweep_set,
                    bytemuck::bytes_of(&splat_push),
                    [rays.div_ceil(64), 1, 1],
                )?;
                rec.compute_storage_barrier(&self.splat_sums);
                // The resolve's storage views name both layers, so both
                // are ordered after their last reads (only `write` is
                // written).
                rec.transition_many(&[
                    (&self.irradiance[0].image, 0..2, Access::ComputeStorage),
                    (&self.irradiance[1].image, 0..2, Access::ComputeStorage),
                ]);
                let resolve_push = [write, self.width, self.height, unit.to_bits()];
                rec.dispatch(
                    &f.splat_resolve,
                    &self.splat_resolve_set,
                    bytemuck::bytes_of(&resolve_push),
                    groups,
                )?;
            }
        }
        if timed {
            rec.end_scope();
            rec.begin_scope("sweep: viewing rays");
        }
        // 3. The viewing rays cross the segment from plane i - 1 to plane i,
        // lit by the irradiance of both (layers `read` and `write`).
        rec.transition_many(&[
            (&self.irradiance[0].image, 0..2, Access::SampledGeneral),
            (&self.irradiance[1].image, 0..2, Access::SampledGeneral),
        ]);
        rec.bind_pipeline(&fp.view);
        self.draw_plane_region(
            rec,
            (&self.view_pass, &self.view_framebuffers[write as usize]),
            &self.states[2..].iter().collect::<Vec<_>>(),
            regions[i as usize],
            &fp.view,
            &push,
        )?;
        if timed {
            rec.end_scope();
        }
        rec.bind_pipeline(plane_pipeline);
        Ok(())
    }
}
