//! Recording one frame of the sweep: the setup pass, the planes with their barriers, the
//! composite, dumps and timestamps.
//!
//! The per-plane transitions here are written by hand, not declared as `vk::Use`: a pass
//! declares one state per image for its start, while the sweep moves single layers of
//! the ping-pong images between sampled, attachment and storage use plane by plane inside
//! one pass (and `drop_barrier_before_plane` must be able to leave one out).

use super::region::RegionPolygon;
use super::*;
use crate::render::limits::SPLAT_GROUP_WORKGROUP;
use crate::vk::{Area, BufferUse, Use};

/// The vertices of a plane's draw over its region: a fan of six triangles over the
/// polygon's eight vertices (glsl/sweep_region.vert).
const REGION_VERTICES: u32 = 18;

impl SweepPass {
    /// Record one frame into `rec`: setup, every plane, and the composite into
    /// [`SweepPass::output`]. Parameters travel in the command stream, so earlier frames
    /// may still be in flight.
    pub(crate) fn record_sweep(
        &mut self,
        rec: &mut Recorder,
        inputs: &Inputs,
    ) -> Result<SweepRecording> {
        let (camera, opts, read_back) = (inputs.camera, inputs.opts, inputs.read_back);
        let (ctx, info, env, sweep) = (inputs.ctx, inputs.info, &inputs.env, &opts.sweep);
        // The plane pipelines with what this frame does not use compiled out.
        let features = Features::of(opts, self.have_field, inputs.eta_films);
        if features.cells && !self.cells_fit {
            bail!(
                "deposit=cells needs 160 bytes of light deposits per light ray, more at \
                 {}x{} with this ray budget than device '{}' binds as one storage buffer \
                 (maxStorageBufferRange); use deposit=boxes, fewer light rays per pixel \
                 (--light-rays) or a smaller image",
                self.width,
                self.height,
                ctx.info().name
            );
        }
        // Draws or dispatches per plane (issue 31): `auto` is what measured fastest on
        // this class of device.
        let compute = sweep.levers.sweep.for_device(
            ctx.info().device_type,
            sweep.light_transport == LightTransport::Forward,
        ) == SweepPath::Compute;
        if compute {
            self.ensure_compute_planes(ctx, features)?;
        } else {
            self.ensure_planes(ctx, features)?;
        }
        let volume_dims = info.dims;
        let (_, forward, right, up) = camera.frame();
        let travel = opts.light().travel();
        let planes = check(info, camera, opts, sweep)?;
        let batch = match sweep.batch {
            None => 0..planes.count,
            Some(b) => {
                ensure!(
                    b.start < b.end && b.start < planes.count,
                    "planes {}..{} of a sweep of {} planes",
                    b.start,
                    b.end,
                    planes.count
                );
                b.start..b.end.min(planes.count)
            }
        };
        let (first_batch, last_batch) = (batch.start == 0, batch.end == planes.count);
        let (view_to_world, view_to_tex) = super::region::view_matrices(camera, info.half_extent);
        let light_view = Vec3::new(travel.dot(right), travel.dot(up), travel.dot(forward));
        let (clip_n, clip_o) = sweep
            .clip
            .map(|(n, o)| (n.normalize(), o))
            .unwrap_or((Vec3::ZERO, 0.0));
        // The transport; the fragment path's forward pipelines where it runs. The compute
        // path needs neither point sprites nor fragment-shader atomics.
        let forward_on = sweep.light_transport == LightTransport::Forward;
        let forward = match (sweep.light_transport, &self.forward) {
            (LightTransport::Backward, _) => None,
            (LightTransport::Forward, Some(f)) => Some(f),
            (LightTransport::Forward, None) if compute => None,
            (LightTransport::Forward, None) => bail!(
                "the forward light transport needs point sizes above 1 and fragment-shader \
                 atomics (largePoints, fragmentStoresAndAtomics), which device '{}' lacks; \
                 use --light-transport backward",
                ctx.info().name
            ),
        };
        let groups_on = forward.is_some() && !compute && sweep.levers.splat == Splat::Groups;
        let tan_half = (camera.fov_y.to_radians() * 0.5).tan();
        let aspect = self.width as f32 / self.height as f32;
        let ray_image = [
            self.rays[0].image.extent()[0],
            self.rays[0].image.extent()[1],
        ];
        let (grid, grid_dims) = light_grid(
            &planes,
            light_view,
            tan_half,
            aspect,
            [self.width, self.height],
            sweep.light_spacing,
            ray_image[0] as u64 * ray_image[1] as u64,
        );
        let soft = opts.light().softness > 0.0;
        let (diffusion_w, diffusion_stride) = diffusion(
            opts.light().softness * info.ref_step,
            (grid[2] * grid[3]).sqrt(),
        );
        let p = SweepParams {
            view_to_tex: view_to_tex.to_cols_array(),
            view_to_world: view_to_world.to_cols_array(),
            camera: [
                (camera.fov_y.to_radians() * 0.5).tan(),
                self.width as f32 / self.height as f32,
                self.width as f32,
                self.height as f32,
            ],
            planes: [
                planes.first_depth,
                planes.spacing,
                planes.count as f32,
                info.ref_step,
            ],
            light_dir: [
                light_view.x,
                light_view.y,
                light_view.z,
                opts.light().softness,
            ],
            light_colour: [
                opts.light().colour[0],
                opts.light().colour[1],
                opts.light().colour[2],
                0.0,
            ],
            volume_dims: [
                volume_dims[0] as f32,
                volume_dims[1] as f32,
                volume_dims[2] as f32,
                0.0,
            ],
            specular: [sweep.roughness, sweep.specular, 0.0, 0.0],
            clip: [clip_n.x, clip_n.y, clip_n.z, clip_o],
            background: opts.background,
            refraction: [
                sweep.eta_scale,
                if sweep.reflections { 1.0 } else { 0.0 },
                if env.enabled { 1.0 } else { 0.0 },
                sweep.env_rotation.to_radians(),
            ],
            light_grid: grid,
            light_rays: [
                grid_dims[0] as f32,
                grid_dims[1] as f32,
                ray_image[0] as f32,
                ray_image[1] as f32,
            ],
            transport: [
                if forward_on { 1.0 } else { 0.0 },
                diffusion_w,
                diffusion_stride as f32,
                // The point sprites' size limit binds the fragment path only.
                match (compute, forward) {
                    (false, Some(f)) => f.max_half_width,
                    _ => MAX_SPLAT_HALF_WIDTH,
                },
            ],
            max_gain: sweep.max_gain,
            termination_alpha: opts.termination_alpha,
            unlit: sweep.unlit as u32,
            pad0: 0,
            // The diagnostic's light is 1 everywhere: nothing besides it.
            ambient: match sweep.unlit {
                true => [0.0; 4],
                false => [sweep.ambient[0], sweep.ambient[1], sweep.ambient[2], 0.0],
            },
        };
        let e = EnvParams {
            info: [
                if env.enabled { 1.0 } else { 0.0 },
                sweep.env_rotation.to_radians(),
                if sweep.env_footprint { 1.0 } else { 0.0 },
                0.0,
            ],
            mean: env.mean,
        };

        // Only frames read back by the caller (dumps are the same case) copy the counters
        // out: a recorded frame's buffers die with the recording, before the GPU runs it.
        let clamp_readback = if read_back {
            Some(Buffer::readback(ctx, 16, "sweep clamp counters readback")?)
        } else {
            None
        };
        let dump_buffers: Vec<(StateBuffer, u32, Buffer)> = sweep
            .dumps
            .iter()
            .map(|&(b, plane)| {
                let image = match (forward_on, b) {
                    (true, StateBuffer::LightRays) => &self.rays[0].image,
                    (true, StateBuffer::LightRayDirections) => &self.rays[1].image,
                    _ => &self.states[b.index()].image,
                };
                let buf = Buffer::readback(
                    ctx,
                    image.layer_bytes()?,
                    &format!("dump {}@{plane}", b.name()),
                )?;
                Ok((b, plane, buf))
            })
            .collect::<Result<_>>()?;

        let groups = [self.width.div_ceil(8), self.height.div_ceil(8), 1];
        rec.update_uniform(&self.params, bytemuck::bytes_of(&p))?;
        rec.update_uniform(&self.env_params, bytemuck::bytes_of(&e))?;
        // The setup reads the volume's inputs and writes every state layer.
        let mut uses: Vec<Use> = [
            inputs.volume,
            inputs.gradient.unwrap_or(inputs.volume),
            inputs.value_ranges.unwrap_or(inputs.volume),
            inputs.field.unwrap_or(inputs.volume),
            inputs.tf,
            inputs.preint,
            env.map,
            env.sat,
        ]
        .into_iter()
        .map(|img| Use::all(img, Access::Sampled))
        .collect();
        uses.extend(self.every_layer(Access::ComputeStorage).into_iter().map(
            |(image, layers, access)| Use {
                image,
                layers,
                access,
            },
        ));
        // The compute splat's unit (glsl/light_splat_fixed.glsl): the brightest channel.
        let unit = opts.light().colour.into_iter().fold(0.0f32, f32::max);
        let unit = if unit > 0.0 { unit } else { 1.0 };
        let compute_splat = forward_on && (compute || sweep.levers.splat == Splat::Compute);
        // A later batch goes on from the state the earlier ones left in the images.
        if first_batch {
            rec.pass("sweep setup", &uses, |rec| {
                rec.clear_storage(&self.counters);
                if compute_splat {
                    rec.clear_storage(&self.splat_sums);
                }
                if compute && forward_on {
                    // The gather's bin counts start each frame at zero (each plane's bin
                    // scan zeroes them for the next).
                    rec.clear_storage(&self.bins);
                }
                // The setup covers the screen and the ray images (rays_per_pixel times taller).
                let setup_groups = [ray_image[0].div_ceil(8), ray_image[1].div_ceil(8), 1];
                rec.dispatch_explicit(&self.setup, &self.setup_set, &[], setup_groups)?;
                // Both layers become sampled: every draw's set names both (see module docs).
                // (The compute planes declare their storage uses themselves.)
                if !compute {
                    rec.transition_many(&self.every_layer(Access::SampledGeneral));
                }
                Ok(())
            })?;
        }

        // The pixels each plane shades (the `region` lever; region.rs).
        // The rectangles are the render areas and the compute dispatches; the fragment
        // path draws the polygons inside them (`region=octagon` cuts the rectangles'
        // empty corners, the others draw the rectangles).
        let size = [self.width, self.height];
        let (regions, polygons, shaded_fraction) = match sweep.levers.region {
            Region::Full => {
                let full = Area::full(self.width, self.height);
                let n = planes.count as usize;
                (vec![full; n], vec![RegionPolygon::new(full, None); n], 1.0)
            }
            region => {
                let r = super::region::plane_regions(
                    view_to_tex,
                    &planes,
                    info.ref_step,
                    tan_half,
                    aspect,
                    size,
                );
                if region == Region::Octagon && !compute {
                    (r.rects, r.polygons, r.polygon_fraction)
                } else {
                    let polygons = r.rects.iter().map(|&a| RegionPolygon::new(a, None));
                    (r.rects.clone(), polygons.collect(), r.rect_fraction)
                }
            }
        };

        // The light rays each plane moves and deposits (ray_rows.rs, the `rays` lever): on
        // the fragment path with grouped sprites; elsewhere every ray, every plane.
        let plane_rays =
            (groups_on && sweep.levers.needed_rays && ray_image[1] < 1 << 16).then(|| {
                super::ray_rows::light_ray_rows(
                    &super::ray_rows::View {
                        view_to_tex,
                        planes: &planes,
                        ref_step: info.ref_step,
                        tan_half,
                        size: [self.width, self.height],
                    },
                    &super::ray_rows::RayGrid {
                        grid,
                        dims: grid_dims,
                        light: light_view,
                    },
                    // A box is at most 2 transport.w wide, centred on its ray.
                    p.transport[3] + 1.0,
                    (diffusion_w, diffusion_stride),
                    SPLAT_GROUP_WORKGROUP,
                )
            });

        rec.begin_scope("sweep");
        let baseline = sweep.floor || sweep.skeleton;
        if compute {
            self.record_compute_planes(
                rec,
                &ComputeFrame {
                    features,
                    planes: &planes,
                    regions: &regions,
                    forward: forward_on && !baseline,
                    soft,
                    grid: grid_dims,
                    ray_image,
                    unit,
                    dumps: &dump_buffers,
                    batch: batch.clone(),
                },
                sweep,
            )?;
        } else {
            // Bound once: between planes only push constants change, and the forward
            // transport switches pipelines (same layout, so the set stays bound).
            // The baselines run the backward sweep's one pass per plane.
            let forward = forward.filter(|_| !baseline);
            let pipelines = &self.planes[&features];
            let forward_planes = pipelines.forward.as_ref();
            let plane_pipeline = match (sweep.floor, forward_planes.filter(|_| forward.is_some())) {
                (true, _) => &pipelines.floor,
                (false, _) if sweep.skeleton => &pipelines.skeleton,
                (false, Some(f)) if soft => &f.light_soft,
                (false, Some(f)) => &f.light,
                (false, None) => &pipelines.sweep,
            };
            rec.bind_graphics(plane_pipeline, &self.sweep_set, self.width, self.height);
            let light_images = [&self.rays[0].image, &self.rays[1].image];
            for i in batch.clone() {
                rec.progress(i, planes.count);
                let write = i % 2;
                let read = 1 - write;
                let push = PlanePush {
                    plane: i,
                    read_layer: read,
                    depth: planes.depth(i),
                    pad: 0,
                    region: polygons[i as usize].ndc(size),
                };
                // The layer the previous plane wrote becomes sampled (one batched barrier
                // over the six images); begin_render_pass then makes the layer the previous
                // plane sampled an attachment (a second one). Nothing else is synchronised.
                if sweep.drop_barrier_before_plane == Some(i) {
                    for s in &self.states {
                        rec.assume_without_barrier(
                            &s.image,
                            read..read + 1,
                            Access::SampledGeneral,
                        );
                    }
                } else {
                    // With the forward transport the previous plane's irradiance, which this
                    // plane's viewing rays read, is in the same batch (a dump may have copied
                    // it out).
                    let mut items = self.state_layers(read..read + 1, Access::SampledGeneral);
                    if forward.is_some() {
                        for img in self.irradiance.iter().map(|i| &i.image).chain(light_images) {
                            items.push((img, read..read + 1, Access::SampledGeneral));
                        }
                    }
                    rec.transition_many(&items);
                }
                match forward {
                    None => {
                        let attachments: Vec<(&Image, u32)> =
                            self.states.iter().map(|s| (&s.image, write)).collect();
                        let area = regions[i as usize];
                        rec.begin_render_pass_in(
                            &self.render_pass,
                            &self.framebuffers[write as usize],
                            &attachments,
                            area,
                        )?;
                        rec.set_scissor(area);
                        rec.draw(plane_pipeline, bytemuck::bytes_of(&push), REGION_VERTICES)?;
                        rec.end_render_pass();
                    }
                    Some(f) => {
                        let fp = forward_planes.expect("made with the forward transport");
                        let timed = sweep.pass_timings;
                        if timed {
                            rec.begin_scope("sweep: light rays");
                        }
                        // 1. The light rays advance to plane i (over the ray images):
                        // the texel rows that hold rays, or those of the grid rows this
                        // plane moves (ray_rows.rs); `pad` gives the previous plane's, the
                        // rows still in their launch state outside them.
                        let rows = (grid_dims[0] * grid_dims[1]).div_ceil(ray_image[0]);
                        let rows = rows.clamp(1, ray_image[1]);
                        let texel_rows = |r: super::ray_rows::Rows| {
                            let lo = r.lo * grid_dims[0] / ray_image[0];
                            (
                                lo,
                                (r.end * grid_dims[0])
                                    .div_ceil(ray_image[0])
                                    .clamp(lo, rows),
                            )
                        };
                        let (moved, before) = match &plane_rays {
                            Some(p) => (
                                texel_rows(p[i as usize].moved),
                                match i {
                                    0 => (0, 0),
                                    _ => texel_rows(p[i as usize - 1].moved),
                                },
                            ),
                            None => ((0, rows), (0, rows)),
                        };
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
                        match sweep.levers.splat {
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
                                let (first_wg, end_wg) = match &plane_rays {
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
                                    rec.buffer_handover(
                                        &group_buffers,
                                        BufferUse::Draws,
                                        BufferUse::Compute,
                                    );
                                    let deposits_push = PlanePush {
                                        pad: first_wg,
                                        ..splat_push
                                    };
                                    rec.dispatch_explicit(
                                        &fp.group_deposits,
                                        &self.sweep_set,
                                        bytemuck::bytes_of(&deposits_push),
                                        [end_wg - first_wg, 1, 1],
                                    )?;
                                    rec.buffer_handover(
                                        &group_buffers,
                                        BufferUse::Compute,
                                        BufferUse::Draws,
                                    );
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
                                    let leftover =
                                        fp.splat_group_rays.as_ref().unwrap_or(&fp.splat_groups);
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
                                rec.dispatch_explicit(
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
                                rec.dispatch_explicit(
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
                        let views: Vec<(&Image, u32)> =
                            self.states[2..].iter().map(|s| (&s.image, write)).collect();
                        let area = regions[i as usize];
                        rec.begin_render_pass_in(
                            &self.view_pass,
                            &self.view_framebuffers[write as usize],
                            &views,
                            area,
                        )?;
                        rec.set_scissor(area);
                        let view = &forward_planes
                            .expect("made with the forward transport")
                            .view;
                        rec.bind_pipeline(view);
                        rec.draw(view, bytemuck::bytes_of(&push), REGION_VERTICES)?;
                        rec.end_render_pass();
                        if timed {
                            rec.end_scope();
                        }
                        rec.bind_pipeline(plane_pipeline);
                    }
                }
                let splat = forward;
                for (b, plane, buf) in &dump_buffers {
                    if *plane != i {
                        continue;
                    }
                    rec.copy_image_to_buffer(self.dump_image(splat.is_some(), *b), write, buf);
                }
            }
        }
        rec.progress(batch.end, planes.count);
        rec.end_scope();

        let last = (planes.count - 1) % 2;
        let mut uses: Vec<Use> = self
            .state_layers(0..2, Access::SampledGeneral)
            .into_iter()
            .map(|(image, layers, access)| Use {
                image,
                layers,
                access,
            })
            .collect();
        uses.push(Use::all(&self.output.image, Access::ComputeStorage));
        if last_batch {
            rec.pass("composite", &uses, |rec| {
                rec.dispatch_explicit(
                    &self.composite,
                    &self.composite_set,
                    &last.to_le_bytes(),
                    groups,
                )
            })?;
        }
        if let Some(buf) = &clamp_readback {
            rec.copy_storage_to_host(&self.counters, buf);
        }
        let traffic = TrafficInputs {
            features,
            forward: forward_on && !baseline,
            soft,
            shaded_pixels: (shaded_fraction * self.width as f64 * self.height as f64).round()
                as u64,
            light_rays: grid_dims[0] as u64 * grid_dims[1] as u64,
            compute_splat,
            viewport_pixels: self.width as u64 * self.height as u64,
        };
        Ok(SweepRecording {
            stats: SweepStats {
                planes,
                bytes_per_plane: self.bytes_per_plane(traffic),
                compulsory_bytes_per_plane: self.compulsory_bytes_per_plane(traffic),
                shaded_fraction,
                light_transport: sweep.light_transport,
                path: if compute {
                    SweepPath::Compute
                } else {
                    SweepPath::Fragment
                },
                light_grid: grid,
                light_rays: [grid_dims[0], grid_dims[1], ray_image[0], ray_image[1]],
                light_spacing: [
                    sweep.light_spacing,
                    grid[2].max(grid[3])
                        / plane0_pixel_pitch(&planes, tan_half, [self.width, self.height]),
                ],
                clamps: Clamps::default(),
            },
            dumps: dump_buffers,
            clamp_readback,
        })
    }
}
