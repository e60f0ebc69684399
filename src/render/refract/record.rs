//! Recording one frame of the sweep: the setup pass, the planes with their barriers, the
//! composite, dumps and timestamps.
//!
//! The per-plane transitions here are written by hand, not declared as `vk::Use`: a pass
//! declares one state per image for its start, while the sweep moves single layers of
//! the ping-pong images between sampled, attachment and storage use plane by plane inside
//! one pass (and `drop_barrier_before_plane` must be able to leave one out).

use super::record_forward::ForwardDraws;
use super::region::RegionPolygon;
use super::*;
use crate::render::limits::SPLAT_GROUP_WORKGROUP;
use crate::vk::{Area, Use};

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
            (LightTransport::Backward | LightTransport::Eikonal, _) => None,
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
        let dump_buffers: Vec<DumpCopy> = sweep
            .dumps
            .iter()
            .map(|&(b, plane)| {
                let parts = self
                    .dump_parts(forward_on, b)
                    .into_iter()
                    .enumerate()
                    .map(|(k, image)| {
                        Buffer::readback(
                            ctx,
                            image.layer_bytes()?,
                            &format!("dump {}@{plane} part {k}", b.name()),
                        )
                    })
                    .collect::<Result<_>>()?;
                Ok(DumpCopy {
                    buffer: b,
                    plane,
                    parts,
                })
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
                rec.dispatch(&self.setup, &self.setup_set, &[], setup_groups)?;
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
                    let polygons = r
                        .rects
                        .iter()
                        .map(|&a| RegionPolygon::new(a, None))
                        .collect();
                    (r.rects, polygons, r.rect_fraction)
                }
            }
        };

        // The light rays each plane moves and deposits (ray_rows.rs, the `rays` lever): on
        // the fragment path with grouped sprites and on the compute path; with the other
        // sprites every ray, every plane.
        let rows_known = groups_on || (compute && forward_on);
        let plane_rays =
            (rows_known && sweep.levers.needed_rays && ray_image[1] < 1 << 16).then(|| {
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
        // The planes' light kept for the reflections that see the volume (every
        // `stride`-th plane; with the eikonal light transport the reflected rays read
        // the light volume, and nothing is kept).
        let volume_reflections = sweep.reflections && sweep.reflections_volume && !baseline;
        let record_stride = (volume_reflections
            && sweep.light_transport != LightTransport::Eikonal)
            .then(|| LightRecord::stride(planes.count));
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
                    record_stride,
                    batch: batch.clone(),
                    plane_rays: plane_rays.as_deref(),
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
                    None => self.draw_plane_region(
                        rec,
                        (&self.render_pass, &self.framebuffers[write as usize]),
                        &self.backward_states(),
                        regions[i as usize],
                        plane_pipeline,
                        &push,
                    )?,
                    Some(f) => self.record_forward_plane_draws(
                        rec,
                        &ForwardDraws {
                            resolve: f,
                            planes: forward_planes.expect("made with the forward transport"),
                            plane_pipeline,
                            plane_rays: plane_rays.as_deref(),
                            grid_dims,
                            ray_image,
                            groups_on,
                            unit,
                            resolve_groups: groups,
                            regions: &regions,
                            splat: sweep.levers.splat,
                            timed: sweep.pass_timings,
                        },
                        push,
                    )?,
                }
                let splat = forward;
                for d in dump_buffers.iter().filter(|d| d.plane == i) {
                    for (image, buf) in self
                        .dump_parts(splat.is_some(), d.buffer)
                        .iter()
                        .zip(&d.parts)
                    {
                        rec.copy_image_to_buffer(image, write, buf);
                    }
                }
                if let Some(stride) = record_stride {
                    self.record_light(rec, splat.is_some(), i, stride);
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
        uses.push(Use::all(&self.light_record.image, Access::Sampled));
        if last_batch {
            let push = CompositePush {
                layer: last,
                volume_reflections: volume_reflections as u32,
                record_stride: record_stride.unwrap_or(1),
                have_gradient: self.have_gradient as u32,
                light_from_volume: (sweep.light_transport == LightTransport::Eikonal) as u32,
            };
            rec.pass("composite", &uses, |rec| {
                rec.dispatch(
                    &self.composite,
                    &self.composite_set,
                    bytemuck::bytes_of(&push),
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
            // The rays a plane moves: every ray of the grid, or with `rays=needed` the
            // mean over the planes of the moved rows' (the deposits are of a subset).
            light_rays: match &plane_rays {
                Some(p) if !p.is_empty() => {
                    let rows: u64 = p
                        .iter()
                        .map(|r| r.moved.end.saturating_sub(r.moved.lo) as u64)
                        .sum();
                    grid_dims[0] as u64 * rows / p.len() as u64
                }
                _ => grid_dims[0] as u64 * grid_dims[1] as u64,
            },
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
