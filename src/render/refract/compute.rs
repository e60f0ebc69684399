//! The compute sweep (issue 31): every per-plane pass of both transports as a compute
//! dispatch on storage images, in the same one command buffer, with the same shaders as
//! the fragment path (glsl/sweep_plane_io.glsl says what differs).
//!
//! Why: on Hopper GPUs (H100, H200) only two TPCs, 4 of 132 SMs, run vertex and fragment
//! shaders, so a sweep of draws runs on about 3 % of the chip; dispatches use all of it.
//!
//! Synchronisation: every image a plane pass writes is bound as a storage image over
//! both layers (one set for the whole frame, bound once: a set bind per plane costs
//! ~4 ms and 3 MB on lavapipe), so each dispatch declares its images' both layers as
//! `Access::ComputeStorage` and the recorder puts a barrier wherever a dispatch follows
//! a write of an image it uses. A pipeline barrier waits for all earlier dispatches, so
//! the passes are ordered to let independent work share the interval between two
//! barriers. Forward transport, per plane i (six barriers a plane):
//!
//! ```text
//!   barrier | viewing rays of plane i-1   (state, irradiance of planes i-2 and i-1;
//!                                          the last plane's after the loop)
//!           | light rays of plane i       (rays only: independent of the view)
//!   barrier | deposits of plane i         (rays -> each ray's deposit, counted into
//!                                          the bins of the screen tiles it overlaps,
//!                                          one atomic per bin and workgroup)
//!   barrier | bin offsets                 (one workgroup: a prefix sum of the counts,
//!                                          and each fine tile's first chunk)
//!   barrier | bin lists                   (each ray listed in its bins)
//!   barrier | gather of plane i           (deposits -> irradiance layer i % 2, which
//!                                          the viewing rays of plane i-1 have read)
//!   barrier | resolve                     (`gather=pairs`: the tiles of more than one
//!                                          chunk, from their sums)
//! ```
//!
//! With `rays=needed` (the default; render/refract/ray_rows.rs) the light rays' dispatch
//! covers the texel rows of the grid rows needed by then (a row that joins steps from its
//! launch state first), and the per-ray dispatches of the splat (deposits, bin lists, the
//! scatter of blocks) the needed grid rows: on the demo most rays lie outside the view and
//! have not met the box yet.
//!
//! The splat is a tile-binned gather (glsl/light_gather.glsl): the rays are sorted by
//! counting into bins of 8 × 8-pixel tiles (32-pixel tiles, or one bin for all, for wide
//! deposits); each tile's candidate rays are split into chunks of 256, one workgroup
//! each, which deals out the (ray, pixel) pairs where a deposit lands and adds them into
//! the tile's 32.32 fixed-point sums in shared memory (glsl/sweep_gather.comp; a tile of
//! several chunks adds its chunks' sums in memory, resolved by the next dispatch). The
//! same integer sums as the atomic compute splat, so bit for bit its irradiance. On the
//! H100 the splat is bound by the deposits' bytes (docs/BENCH.md, "the splat rebuilt").
//!
//! The backward transport is one dispatch per plane with one barrier before it.

use super::pass::RECORD_LAYERS;
use super::pipelines::{gather_tiles, ComputeSplat};
use super::ray_rows::{light_pass_rows, PlaneRays};
use super::*;
use crate::render::limits::GATHER_CHUNK;
use crate::vk::Area;

/// What one frame's compute planes need from [`SweepPass::record_sweep`].
pub(crate) struct ComputeFrame<'a> {
    pub(crate) features: Features,
    pub(crate) planes: &'a Planes,
    /// The pixels each plane shades (the `region` lever).
    pub(crate) regions: &'a [Area],
    /// The forward transport's passes (not for the baselines).
    pub(crate) forward: bool,
    pub(crate) soft: bool,
    /// The light rays' grid (columns, rows), and the ray images' size.
    pub(crate) grid: [u32; 2],
    pub(crate) ray_image: [u32; 2],
    /// The splat's fixed-point unit.
    pub(crate) unit: f32,
    pub(crate) dumps: &'a [DumpCopy],
    /// Every how many planes the light is kept for the reflections that see the volume
    /// (none without them).
    pub(crate) record_stride: Option<u32>,
    /// The planes to record ([`SweepOptions::batch`]).
    pub(crate) batch: std::ops::Range<u32>,
    /// The light rays each plane moves and deposits (`rays=needed`, ray_rows.rs); None:
    /// every ray, every plane.
    pub(crate) plane_rays: Option<&'a [PlaneRays]>,
}

// The gather's workgroup is one tile of 8 × 8 pixels (glsl/sweep_gather.comp).
const _: () = assert!(crate::render::limits::GATHER_TILE == 8);
const _: () = assert!(crate::render::limits::GATHER_COARSE_TILE % 8 == 0);

/// Workgroups of 8 × 8 covering `area`.
fn groups(area: Area) -> [u32; 3] {
    [area.width.div_ceil(8), area.height.div_ceil(8), 1]
}

impl SweepPass {
    /// Keep plane `plane`'s light (the layer it wrote) in the light record if it is one
    /// of every `stride` planes; returns whether it was.
    pub(crate) fn record_light(
        &self,
        rec: &mut Recorder,
        forward: bool,
        plane: u32,
        stride: u32,
    ) -> bool {
        if !Self::records(plane, stride) {
            return false;
        }
        let light = self.dump_image(forward, StateBuffer::LightColour);
        let r = &self.light_record;
        rec.blit_layer(light, plane % 2, &r.image, plane / stride, r.linear);
        true
    }

    fn push(&self, plane: u32, depth: f32, unit: f32, area: Area) -> ComputePush {
        ComputePush {
            plane,
            read_layer: 1 - plane % 2,
            depth,
            unit,
            origin: [area.x as i32, area.y as i32],
            extent: [area.width as i32, area.height as i32],
            pad: 0,
        }
    }

    /// Both layers of `images` as storage images of the next dispatches.
    fn storage<'a>(
        images: impl IntoIterator<Item = &'a StateImage>,
    ) -> Vec<(&'a Image, std::ops::Range<u32>, Access)> {
        images
            .into_iter()
            .map(|s| (&s.image, 0..2, Access::ComputeStorage))
            .collect()
    }

    /// Copy plane `plane`'s dumps out, and return the dumped images to storage use (a
    /// copied layer is in TRANSFER_SRC, and every dispatch names both layers).
    fn compute_dumps(&self, rec: &mut Recorder, f: &ComputeFrame, plane: u32) {
        let write = plane % 2;
        for d in f.dumps.iter().filter(|d| d.plane == plane) {
            for (image, buf) in self
                .dump_parts(f.forward, d.buffer)
                .into_iter()
                .zip(&d.parts)
            {
                rec.copy_image_to_buffer(image, write, buf);
                rec.transition(image, 0..2, Access::ComputeStorage);
            }
        }
        if let Some(stride) = f.record_stride {
            if self.record_light(rec, f.forward, plane, stride) {
                let image = self.dump_image(f.forward, StateBuffer::LightColour);
                rec.transition(image, 0..2, Access::ComputeStorage);
            }
        }
    }

    /// Whether plane `plane`'s light is kept in the light record (every `stride`-th).
    fn records(plane: u32, stride: u32) -> bool {
        plane % stride == 0 && plane / stride < RECORD_LAYERS
    }

    /// Record every plane of the frame as dispatches (see the module docs).
    pub(crate) fn record_compute_planes(
        &self,
        rec: &mut Recorder,
        f: &ComputeFrame,
        sweep: &SweepOptions,
    ) -> Result<()> {
        let pipelines = &self.compute_planes[&f.features];
        let n = f.planes.count;
        let drop_before = sweep.drop_barrier_before_plane;
        let timed = sweep.pass_timings && f.forward;
        if !f.forward {
            let pipeline = if sweep.floor {
                &pipelines.floor
            } else if sweep.skeleton {
                &pipelines.skeleton
            } else {
                &pipelines.sweep
            };
            rec.bind_compute(pipeline, &self.compute_set);
            for i in f.batch.clone() {
                rec.progress(i, n);
                // The layer the previous plane wrote is read, the one it read is written:
                // one barrier over the six images.
                if drop_before == Some(i) {
                    for s in &self.states {
                        rec.assume_without_barrier(&s.image, 0..2, Access::ComputeStorage);
                    }
                } else {
                    rec.transition_many(&Self::storage(&self.states));
                }
                let area = f.regions[i as usize];
                let push = self.push(i, f.planes.depth(i), f.unit, area);
                rec.dispatch_bound(pipeline, bytemuck::bytes_of(&push), groups(area))?;
                self.compute_dumps(rec, f, i);
            }
            rec.progress(f.batch.end, n);
            return Ok(());
        }

        let light = if f.soft {
            &pipelines.light_soft
        } else {
            &pipelines.light
        };
        let view = &pipelines.view;
        let screen = Area::full(self.width, self.height);
        rec.bind_compute(light, &self.compute_set);
        // Step i records plane i - 1's viewing rays and plane i's light rays: a batch
        // whose last plane is the frame's takes one more step for its viewing rays.
        let steps = f.batch.start..if f.batch.end == n { n + 1 } else { f.batch.end };
        for i in steps {
            rec.progress(i, n);
            // Stage A: the viewing rays of plane i - 1 and the light rays of plane i.
            let view_prev = i.checked_sub(1);
            let light_now = i < n;
            // (Keeping the light for the reflections copies out as a dump does.)
            let dumps_prev = view_prev.is_some_and(|p| {
                f.dumps.iter().any(|d| d.plane == p)
                    || f.record_stride.is_some_and(|k| Self::records(p, k))
            });
            let mut batch = Vec::new();
            if let Some(p) = view_prev {
                if drop_before != Some(p) {
                    batch.extend(Self::storage(&self.states));
                } else {
                    for s in &self.states {
                        rec.assume_without_barrier(&s.image, 0..2, Access::ComputeStorage);
                    }
                }
                batch.extend(Self::storage(&self.irradiance));
            }
            if light_now && !dumps_prev {
                batch.extend(Self::storage(&self.rays));
            }
            rec.transition_many(&batch);
            if let Some(p) = view_prev {
                if timed {
                    rec.begin_scope("sweep: viewing rays");
                }
                let area = f.regions[p as usize];
                let push = self.push(p, f.planes.depth(p), f.unit, area);
                rec.bind_compute_pipeline(view);
                rec.dispatch_bound(view, bytemuck::bytes_of(&push), groups(area))?;
                if timed {
                    rec.end_scope();
                }
                if dumps_prev {
                    self.compute_dumps(rec, f, p);
                    if light_now {
                        rec.transition_many(&Self::storage(&self.rays));
                    }
                }
            }
            if !light_now {
                break;
            }
            let depth = f.planes.depth(i);
            if timed {
                rec.begin_scope("sweep: light rays");
            }
            // The light rays' dispatch covers the texel rows of the ray images that hold
            // the rays this plane moves (all that hold rays with `rays=all`); `pad` names
            // the previous plane's, outside which rows still hold their launch state.
            let (moved, before) = light_pass_rows(f.plane_rays, i, f.grid, f.ray_image);
            let ray_area = Area {
                x: 0,
                y: moved.0,
                width: f.ray_image[0],
                height: moved.1 - moved.0,
            };
            rec.bind_compute_pipeline(light);
            let push = ComputePush {
                pad: before.0 | before.1 << 16,
                ..self.push(i, depth, f.unit, ray_area)
            };
            rec.dispatch_bound(light, bytemuck::bytes_of(&push), groups(ray_area))?;
            if timed {
                rec.end_scope();
                rec.begin_scope("sweep: splat");
            }
            // The splat's dispatches read the write layer: their push names it as the
            // read layer. The per-ray ones cover the grid rows this plane deposits (the
            // needed ones, glsl/sweep_rays.glsl DEPOSITED_RAY; all with `rays=all`).
            let deposited = match f.plane_rays {
                Some(p) => p[i as usize].needed,
                None => super::ray_rows::Rows {
                    lo: 0,
                    end: f.grid[1],
                },
            };
            let deposit_rows = deposited.end.saturating_sub(deposited.lo);
            let push = ComputePush {
                read_layer: i % 2,
                origin: [0, deposited.lo as i32],
                extent: [f.grid[0] as i32, deposit_rows as i32],
                ..self.push(i, depth, f.unit, screen)
            };
            let ray_groups = [f.grid[0].div_ceil(8), deposit_rows.div_ceil(8), 1];
            match &pipelines.splat {
                ComputeSplat::Blocks { scatter, resolve } => {
                    // Stage B: the rays just written scatter their deposits into the sums
                    // (which the previous plane's resolve zeroed).
                    rec.compute_storage_barriers(&Self::storage(&self.rays), &[&self.splat_sums]);
                    if timed {
                        rec.begin_scope("sweep: splat: scatter");
                    }
                    rec.bind_compute_pipeline(scatter);
                    rec.dispatch_bound(scatter, bytemuck::bytes_of(&push), ray_groups)?;
                    if timed {
                        rec.end_scope();
                        rec.begin_scope("sweep: splat: resolve");
                    }
                    // Stage C: the sums into irradiance layer i % 2 (after the viewing rays
                    // of plane i - 1 read it as plane i - 2's).
                    rec.compute_storage_barriers(
                        &Self::storage(&self.irradiance),
                        &[&self.splat_sums],
                    );
                    rec.bind_compute_pipeline(resolve);
                    let rows = [self.width.div_ceil(64), self.height, 1];
                    rec.dispatch_bound(resolve, bytemuck::bytes_of(&push), rows)?;
                }
                ComputeSplat::Binned {
                    deposit,
                    bin_scan,
                    bin_fill,
                    gather,
                    pairs,
                    resolve,
                } => {
                    // Stage B: the rays just written make their deposits and count
                    // themselves into the tile bins (after the previous plane's gather read
                    // the last deposits and lists; the previous scan zeroed the counts).
                    let splat_buffers = [&self.deposits, &self.bins, &self.bin_list];
                    rec.compute_storage_barriers(&Self::storage(&self.rays), &splat_buffers);
                    // Within the splat's scope, one scope per step, so that a GPU's
                    // timings say which of them to work on.
                    if timed {
                        rec.begin_scope("sweep: splat: deposits");
                    }
                    rec.bind_compute_pipeline(deposit);
                    rec.dispatch_bound(deposit, bytemuck::bytes_of(&push), ray_groups)?;
                    if timed {
                        rec.end_scope();
                        rec.begin_scope("sweep: splat: bins");
                    }
                    // The bins' list offsets, then the lists.
                    rec.compute_storage_barriers(&[], &splat_buffers);
                    rec.bind_compute_pipeline(bin_scan);
                    rec.dispatch_bound(bin_scan, bytemuck::bytes_of(&push), [1, 1, 1])?;
                    rec.compute_storage_barriers(&[], &splat_buffers);
                    rec.bind_compute_pipeline(bin_fill);
                    rec.dispatch_bound(bin_fill, bytemuck::bytes_of(&push), ray_groups)?;
                    if timed {
                        rec.end_scope();
                        rec.begin_scope("sweep: splat: gather");
                    }
                    // Stage C: the gather into irradiance layer i % 2 (after the viewing
                    // rays of plane i - 1 read it as plane i - 2's).
                    rec.compute_storage_barriers(&Self::storage(&self.irradiance), &splat_buffers);
                    rec.bind_compute_pipeline(gather);
                    if *pairs {
                        // One workgroup per chunk of a tile's candidates: at least one per
                        // tile, and one more per GATHER_CHUNK rays the ray images hold (a
                        // workgroup takes several chunks in turn where there are more), at
                        // most 65535, the dispatch size every device must take (large
                        // screens: 2048² has 65536 tiles).
                        let workgroups = (gather_tiles(self.width, self.height)
                            + (f.ray_image[0] as u64 * f.ray_image[1] as u64)
                                .div_ceil(GATHER_CHUNK as u64))
                        .min(65535) as u32;
                        rec.dispatch_bound(gather, bytemuck::bytes_of(&push), [workgroups, 1, 1])?;
                        // The tiles of several chunks, from their sums.
                        rec.compute_storage_barriers(
                            &Self::storage(&self.irradiance),
                            &splat_buffers,
                        );
                        rec.bind_compute_pipeline(resolve);
                        rec.dispatch_bound(resolve, bytemuck::bytes_of(&push), groups(screen))?;
                    } else {
                        rec.dispatch_bound(gather, bytemuck::bytes_of(&push), groups(screen))?;
                    }
                }
            }
            if timed {
                rec.end_scope();
                rec.end_scope();
            }
        }
        Ok(())
    }
}
