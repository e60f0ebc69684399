//! The sweep's GPU resources: state images, render passes, framebuffers, descriptor sets
//! and pipelines, made once per viewport size and ray budget.

use std::collections::HashMap;

use anyhow::Context as _;

use super::pipelines::{
    gather_entries_per_ray, gather_words, ComputePlanes, ForwardPipelines, PlanePipelines,
};
use super::*;

/// An image of two layers (the ping-pong of the plane sweep) with a view of each layer:
/// the state images ([`StateBuffer`]); the forward transport's irradiance (rgb) and light direction
/// (luminance-weighted sum of unit directions, weight in w) of the last two planes, plane
/// i in layer i % 2; and its light rays.
pub(crate) struct StateImage {
    pub(crate) image: Image,
    pub(crate) layers: [LayerView; 2],
}

/// The fewest light rays a grid has: 5 × 5 (two cells of margin on each side of one,
/// `params::light_grid`).
pub(crate) const MIN_LIGHT_RAYS: u64 = 25;

/// The size of the light-ray images: `rays_per_pixel` texels per pixel (at least
/// [`MIN_LIGHT_RAYS`] in all), `width` wide where the height allows; an image too tall for
/// the device (1 × 16384 at 2 rays per pixel) is laid out wider instead, since the rays
/// wrap from texel row to texel row anyway.
pub(crate) fn ray_image_size(
    width: u32,
    height: u32,
    rays_per_pixel: u32,
    max_side: u32,
) -> Result<[u32; 2]> {
    let rays = (width as u64 * height as u64 * rays_per_pixel as u64).max(MIN_LIGHT_RAYS);
    let w = (width as u64).max(rays.div_ceil(max_side as u64));
    let h = rays.div_ceil(w);
    ensure!(
        w <= max_side as u64 && h <= max_side as u64,
        "{rays_per_pixel} light rays per pixel need {rays} texels of ray images, more than \
         {max_side} × {max_side}: use fewer light rays per pixel (--light-rays) or a smaller \
         image"
    );
    Ok([w as u32, h as u32])
}

impl StateImage {
    pub(crate) fn new(ctx: &Context, size: [u32; 2], name: &str) -> Result<Self> {
        let image = Image::new(
            ctx,
            ImageDesc {
                kind: ImageKind::D2Array,
                format: STATE_FORMAT,
                extent: [size[0], size[1], 1],
                layers: 2,
                usage: vk::usage::COLOR_ATTACHMENT
                    | vk::usage::SAMPLED
                    | vk::usage::STORAGE
                    | vk::usage::TRANSFER_SRC,
            },
            name,
        )?;
        let layers = [image.layer_view(0)?, image.layer_view(1)?];
        Ok(Self { image, layers })
    }
}

/// Both layers of each image in one sampled view (the `arrays` lever).
fn array_bindings<'a>(images: &'a [StateImage], sampler: &'a vk::Sampler) -> Vec<Binding<'a>> {
    images
        .iter()
        .map(|s| Binding::ArrayTexture(&s.image, sampler, Access::SampledGeneral))
        .collect()
}

pub(crate) struct SweepPass {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) params: Buffer,
    pub(crate) states: Vec<StateImage>,
    pub(crate) render_pass: RenderPass,
    pub(crate) framebuffers: [Framebuffer; 2],
    pub(crate) sweep_set: DescriptorSet,
    pub(crate) setup_set: DescriptorSet,
    pub(crate) composite_set: DescriptorSet,
    pub(crate) setup: ComputePipeline,
    /// The plane pipelines per feature set (specialization constants); the set with
    /// every feature on is made with the pass, the others on the first frame that
    /// needs them.
    pub(crate) planes: HashMap<Features, PlanePipelines>,
    pub(crate) have_gradient: bool,
    /// Whether the field texture is bound (binding 37; the `field` lever).
    pub(crate) have_field: bool,
    pub(crate) forward: Option<ForwardPipelines>,
    pub(crate) irradiance: [StateImage; 2],
    /// The forward transport's light rays (flux + view x; v + view y): `rays_per_pixel`
    /// texels per screen pixel (the screen's width, that many times its height).
    pub(crate) rays: [StateImage; 2],
    pub(crate) rays_per_pixel: u32,
    pub(crate) splat_pass: RenderPass,
    pub(crate) splat_framebuffers: [Framebuffer; 2],
    /// The compute splat's fixed-point sums (glsl/light_splat_fixed.glsl): seven
    /// channels of two words per pixel, zero between planes.
    pub(crate) splat_sums: Buffer,
    pub(crate) splat_resolve_set: DescriptorSet,
    /// Forward transport: the light rays' pass (the two light buffers) and the viewing
    /// rays' pass (the other four), per written layer.
    pub(crate) light_pass: RenderPass,
    pub(crate) light_framebuffers: [Framebuffer; 2],
    pub(crate) view_pass: RenderPass,
    pub(crate) view_framebuffers: [Framebuffer; 2],
    pub(crate) counters: Buffer,
    /// The compute sweep's set (issue 31): the plane set's bindings, with the state,
    /// irradiance and ray images as storage images (glsl/sweep_buffers.glsl).
    pub(crate) compute_set: DescriptorSet,
    /// The compute sweep's plane pipelines per feature set, made on the first frame that
    /// runs the compute path with those features.
    pub(crate) compute_planes: HashMap<Features, ComputePlanes>,
    /// The compute splat's buffers (glsl/light_gather.glsl): each light ray's deposit (ten
    /// vec4); the tile bins' counts, list offsets and fill cursors; the bins' lists.
    pub(crate) deposits: Buffer,
    /// Whether the deposits buffer holds every ray's deposit as cells (`deposit=cells`);
    /// it always holds them as boxes.
    pub(crate) cells_fit: bool,
    pub(crate) bins: Buffer,
    pub(crate) bin_list: Buffer,
    /// The grouped sprites' buffers (glsl/light_splat_groups.glsl, bindings 23-25).
    pub(crate) sprite_groups: Buffer,
    pub(crate) sprite_fallback: Buffer,
    pub(crate) sprite_draws: Buffer,
    pub(crate) composite: ComputePipeline,
    pub(crate) output: FrameTarget,
    pub(crate) env_params: Buffer,
    /// The light the sweep computed, kept for the reflections that see the volume
    /// (`--reflections volume`, glsl/sweep_reflect.glsl): every `k`-th plane's light
    /// ([`LightRecord::stride`]) scaled onto a layer of this image by a blit.
    pub(crate) light_record: LightRecord,
}

/// The planes' light kept for the composite's reflected rays: at most [`RECORD_LAYERS`]
/// planes, each at most [`RECORD_SIDE`] texels on its longer side (16 MiB at most, half
/// floats). (At 256 texels a 512² demo frame spent 1 s of its 31 s sweep on the blits on
/// lavapipe; what a reflection shows of the light needs less.)
pub(crate) struct LightRecord {
    pub(crate) image: Image,
    /// Whether the blit may filter the state format linearly (optional for 32-bit floats).
    pub(crate) linear: bool,
}

/// Planes the light record holds at most: a frame of more planes keeps every k-th.
pub(crate) const RECORD_LAYERS: u32 = 128;
/// The light record's longer side at most (texels).
pub(crate) const RECORD_SIDE: u32 = 128;

impl LightRecord {
    fn new(ctx: &Context, width: u32, height: u32) -> Result<Self> {
        let shrink = width.max(height).div_ceil(RECORD_SIDE).max(1);
        let image = Image::new(
            ctx,
            ImageDesc {
                kind: ImageKind::D2Array,
                format: vk::Format::R16G16B16A16_SFLOAT,
                extent: [width.div_ceil(shrink), height.div_ceil(shrink), 1],
                layers: RECORD_LAYERS,
                usage: vk::usage::SAMPLED | vk::usage::TRANSFER_DST,
            },
            "sweep light record",
        )?;
        let linear = ctx.format_supports(
            STATE_FORMAT,
            vk::FormatFeatureFlags::BLIT_SRC | vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR,
        );
        Ok(Self { image, linear })
    }

    /// Every how many planes a plane's light is kept, for a frame of `planes` planes.
    pub(crate) fn stride(planes: u32) -> u32 {
        planes.div_ceil(RECORD_LAYERS).max(1)
    }
}

impl SweepPass {
    pub fn new(inputs: &Inputs, width: u32, height: u32, rays_per_pixel: u32) -> Result<Self> {
        let Inputs {
            ctx,
            volume,
            gradient,
            value_ranges,
            field,
            tf,
            preint,
            linear: sampler,
            volume_sampler,
            env,
            ..
        } = inputs;
        let (ctx, volume, tf, preint, sampler) = (*ctx, *volume, *tf, *preint, *sampler);
        let max_image = ctx.info().limits.max_image_dimension2_d;
        let ray_size =
            ray_image_size(width, height, rays_per_pixel, max_image).with_context(|| {
                format!(
                    "the light rays of a {width}x{height} image on '{}'",
                    ctx.info().name
                )
            })?;
        // A deposit takes 3 vec4s as boxes, 10 as cells (light_gather.glsl DEPOSIT_VEC4S).
        // The buffer is bound whole, and a binding may not exceed the device's
        // maxStorageBufferRange (128 MiB on lavapipe: the cells of 2 rays per pixel reach
        // it at 648²): the boxes must fit, the cells may be refused per frame.
        let capacity = ray_size[0] as u64 * ray_size[1] as u64;
        let range = ctx.info().limits.max_storage_buffer_range as u64;
        let [boxes_bytes, cells_bytes] = [capacity * 48, capacity * 160];
        // The compute splat's bin lists (below) are bound whole too.
        let boxes_bytes = boxes_bytes.max(capacity * gather_entries_per_ray() * 4);
        ensure!(
            boxes_bytes <= range,
            "{rays_per_pixel} light rays per pixel at {width}x{height} need {} MiB of light \
             deposits; device '{}' binds at most {} MiB as one storage buffer \
             (maxStorageBufferRange): use fewer light rays per pixel (--light-rays) or a \
             smaller image",
            boxes_bytes.div_ceil(1 << 20),
            ctx.info().name,
            range >> 20
        );
        let cells_fit = cells_bytes <= range;
        let max_attachments = ctx.info().limits.max_color_attachments;
        let backward_attachments = StateBuffer::BACKWARD.len();
        if (max_attachments as usize) < backward_attachments {
            bail!(
                "the plane sweep writes {backward_attachments} colour attachments per plane; \
                 device '{}' allows {}",
                ctx.info().name,
                max_attachments
            );
        }
        let params = Buffer::uniform::<SweepParams>(ctx, "sweep params")?;
        let states = StateBuffer::ALL
            .into_iter()
            .map(|b| StateImage::new(ctx, [width, height], b.name()))
            .collect::<Result<Vec<_>>>()?;
        let render_pass = RenderPass::new(
            ctx,
            &[STATE_FORMAT; StateBuffer::BACKWARD.len()],
            Access::AttachmentGeneral,
            "sweep plane",
        )?;
        let fb = |layer: usize| {
            let views: Vec<&LayerView> = StateBuffer::BACKWARD
                .iter()
                .map(|b| &states[b.index()].layers[layer])
                .collect();
            Framebuffer::new(
                ctx,
                &render_pass,
                &views,
                width,
                height,
                &format!("sweep write layer {layer}"),
            )
        };
        let framebuffers = [fb(0)?, fb(1)?];

        let irradiance = [
            StateImage::new(ctx, [width, height], "irradiance")?,
            StateImage::new(ctx, [width, height], "irradiance direction")?,
        ];
        let rays = [
            StateImage::new(ctx, ray_size, "light rays")?,
            StateImage::new(ctx, ray_size, "light ray directions")?,
        ];
        let splat_pass = RenderPass::cleared(
            ctx,
            &[STATE_FORMAT; 2],
            Access::AttachmentGeneral,
            "light splat",
        )?;
        let splat_fb = |layer: usize| {
            Framebuffer::new(
                ctx,
                &splat_pass,
                &[&irradiance[0].layers[layer], &irradiance[1].layers[layer]],
                width,
                height,
                &format!("light splat layer {layer}"),
            )
        };
        let splat_framebuffers = [splat_fb(0)?, splat_fb(1)?];
        let light_pass = RenderPass::new(
            ctx,
            &[STATE_FORMAT; 2],
            Access::AttachmentGeneral,
            "sweep light rays",
        )?;
        let view_pass = RenderPass::new(
            ctx,
            &[STATE_FORMAT; 4],
            Access::AttachmentGeneral,
            "sweep viewing rays",
        )?;
        let sub_fb =
            |pass: &RenderPass, range: std::ops::Range<usize>, layer: usize, name: &str| {
                let views: Vec<&LayerView> =
                    states[range].iter().map(|s| &s.layers[layer]).collect();
                Framebuffer::new(
                    ctx,
                    pass,
                    &views,
                    width,
                    height,
                    &format!("{name} layer {layer}"),
                )
            };
        let ray_fb = |layer: usize| {
            Framebuffer::new(
                ctx,
                &light_pass,
                &[&rays[0].layers[layer], &rays[1].layers[layer]],
                ray_size[0],
                ray_size[1],
                &format!("sweep light rays layer {layer}"),
            )
        };
        let light_framebuffers = [ray_fb(0)?, ray_fb(1)?];
        let view_framebuffers = [
            sub_fb(&view_pass, 2..6, 0, "sweep viewing rays")?,
            sub_fb(&view_pass, 2..6, 1, "sweep viewing rays")?,
        ];
        // 7 channels x 2 words x 4 bytes per pixel (glsl/light_splat_fixed.glsl).
        let splat_sums = Buffer::new(
            ctx,
            width as u64 * height as u64 * 56,
            vk::usage::STORAGE_BUFFER | vk::usage::BUFFER_TRANSFER_DST,
            vk::Memory::Gpu,
            "light splat sums",
        )?;
        let counters = Buffer::new(
            ctx,
            16,
            vk::usage::STORAGE_BUFFER
                | vk::usage::BUFFER_TRANSFER_DST
                | vk::usage::BUFFER_TRANSFER_SRC,
            vk::Memory::Gpu,
            "sweep clamp counters",
        )?;

        let common = [
            Binding::Uniform(&params),
            Binding::Texture(volume, volume_sampler),
            Binding::Texture(tf, sampler),
            Binding::Texture(preint, sampler),
        ];
        // Bindings 4-9: the six state images, both layers in one view each (the shaders
        // index the read layer; glsl/sweep_buffers.glsl).
        let mut sampled: Vec<Binding> = common.to_vec();
        sampled.extend(array_bindings(&states, sampler));
        let mut plane_bindings = sampled.clone();
        // 10-11: the forward transport's irradiance (glsl/sweep_light.glsl); 12: the clamp
        // counters; 13-14: the light rays (glsl/sweep_rays.glsl).
        plane_bindings.extend(array_bindings(&irradiance, sampler));
        plane_bindings.push(Binding::Storage(&counters));
        plane_bindings.extend(array_bindings(&rays, sampler));
        // 15: the environment for Fresnel reflections (glsl/sweep_light.glsl).
        plane_bindings.push(Binding::Texture(env.map, sampler));
        // 16: the smoothed gradient volume (render::gradient, glsl/sweep_light.glsl);
        // without one the shaders compute normals on the fly (specialization constant 0)
        // and never read the binding, which the volume then fills.
        plane_bindings.push(Binding::Texture(gradient.unwrap_or(volume), sampler));
        let have_gradient = gradient.is_some();
        // 17: the field texture (render::field; the `field` lever, specialization
        // constant 6), or the volume in its place, never read then.
        plane_bindings.push(Binding::Texture(field.unwrap_or(volume), sampler));
        let have_field = field.is_some();
        // 18: the compute splat's sums (the `splat` lever).
        plane_bindings.push(Binding::Storage(&splat_sums));
        // 19: the value ranges per brick (render::value_ranges; the light rays' empty-space
        // test in glsl/sweep_plane.glsl), built with the gradient volume.
        let value_ranges = value_ranges
            .ok_or_else(|| anyhow::anyhow!("the refractive sweep needs the value ranges"))?;
        plane_bindings.push(Binding::Texture(value_ranges, sampler));
        // 20-22: the gather splat's deposits, tile bins and bin lists (glsl/light_gather.glsl),
        // sized for the ray images' capacity C: C deposits; a ray is listed in at most four
        // bins, so 4 C list entries; the bins' words (gather_words).
        use crate::render::limits::SPLAT_GROUP_WORKGROUP;
        let deposits = Buffer::new(
            ctx,
            cells_bytes.min(range),
            vk::usage::STORAGE_BUFFER,
            vk::Memory::Gpu,
            "light deposits",
        )?;
        let bins = Buffer::new(
            ctx,
            gather_words(width, height) * 4,
            vk::usage::STORAGE_BUFFER | vk::usage::BUFFER_TRANSFER_DST,
            vk::Memory::Gpu,
            "light deposit bins",
        )?;
        let bin_list = Buffer::new(
            ctx,
            capacity * gather_entries_per_ray() * 4,
            vk::usage::STORAGE_BUFFER,
            vk::Memory::Gpu,
            "light deposit bin lists",
        )?;
        plane_bindings.push(Binding::Storage(&deposits));
        plane_bindings.push(Binding::Storage(&bins));
        plane_bindings.push(Binding::Storage(&bin_list));
        // 23-25: the grouped sprites (the `splat=groups` lever, glsl/light_splat_groups.glsl;
        // the deposits above): per group of 2 x 2 rays its footprint, per workgroup of
        // SPLAT_GROUP_WORKGROUP groups its listed groups and two indirect draws. A grid of
        // C rays has at most C / 2 + 1 groups (ceil(c / 2) ceil(r / 2) with c r <= C).
        let groups = capacity / 2 + 1;
        let group_workgroups = groups.div_ceil(SPLAT_GROUP_WORKGROUP as u64);
        let sprite_groups = Buffer::new(
            ctx,
            groups * 16,
            vk::usage::STORAGE_BUFFER,
            vk::Memory::Gpu,
            "light splat groups",
        )?;
        let sprite_fallback = Buffer::new(
            ctx,
            group_workgroups * SPLAT_GROUP_WORKGROUP as u64 * 4,
            vk::usage::STORAGE_BUFFER,
            vk::Memory::Gpu,
            "light splat groups' leftover rays",
        )?;
        let sprite_draws = Buffer::new(
            ctx,
            2 * group_workgroups * 16,
            vk::usage::STORAGE_BUFFER | vk::usage::INDIRECT_BUFFER,
            vk::Memory::Gpu,
            "light splat groups' indirect draws",
        )?;
        plane_bindings.push(Binding::Storage(&sprite_groups));
        plane_bindings.push(Binding::Storage(&sprite_fallback));
        plane_bindings.push(Binding::Storage(&sprite_draws));
        // 26: the eikonal transport's light volume (glsl/sweep_light.glsl, specialization
        // constant 10), or a placeholder never read.
        plane_bindings.push(Binding::Storage(
            inputs.state::<super::SweepLight>()?.buffer(),
        ));
        // Every set of the sweep is made `with_explicit_barriers`: the sweep records its
        // per-plane barriers itself (the design's explicit barriers between planes; its
        // sets bind both layers of the ping-pong images, one read and one written per
        // plane, so a binding cannot declare one use).
        // The first set to bind the buffers that grow with the image (the splat's sums,
        // the deposits): where one exceeds the device's binding range, say what to change.
        let sweep_set = DescriptorSet::new(ctx, &plane_bindings, "sweep")
            .with_context(|| {
                format!(
                    "the plane sweep at {width}x{height} with {rays_per_pixel} light rays per \
                     pixel: use a smaller image"
                )
            })?
            .with_explicit_barriers();
        // The compute sweep's set: the same bindings, with every image a plane writes
        // (states 4-9, irradiance 10-11, rays 13-14) a storage image.
        let mut compute_bindings = plane_bindings.clone();
        for (k, s) in states.iter().enumerate() {
            compute_bindings[4 + k] = Binding::StorageImage(&s.image);
        }
        compute_bindings[10] = Binding::StorageImage(&irradiance[0].image);
        compute_bindings[11] = Binding::StorageImage(&irradiance[1].image);
        compute_bindings[13] = Binding::StorageImage(&rays[0].image);
        compute_bindings[14] = Binding::StorageImage(&rays[1].image);
        let compute_set =
            DescriptorSet::new(ctx, &compute_bindings, "sweep (compute)")?.with_explicit_barriers();
        let output = FrameTarget::new(ctx, width, height, "sweep frame")?;
        let env_params = Buffer::uniform::<EnvParams>(ctx, "environment params")?;
        let light_record = LightRecord::new(ctx, width, height)?;
        let mut composite_bindings = sampled.clone();
        composite_bindings.push(Binding::StorageImage(&output.image));
        composite_bindings.push(Binding::Texture(env.map, sampler));
        composite_bindings.push(Binding::Texture(env.sat, sampler));
        composite_bindings.push(Binding::Uniform(&env_params));
        // 14: the planes' light for the reflected rays, 15: the smoothed gradient volume
        // for their faces' normals, or the volume, then never read
        // (glsl/sweep_reflect.glsl).
        composite_bindings.push(Binding::Texture(&light_record.image, sampler));
        composite_bindings.push(Binding::Texture(gradient.unwrap_or(volume), sampler));
        // 16: the eikonal transport's light volume, which lights the reflected rays with
        // that transport (or a placeholder never read).
        composite_bindings.push(Binding::Storage(
            inputs.state::<super::SweepLight>()?.buffer(),
        ));
        let composite_set = DescriptorSet::new(ctx, &composite_bindings, "sweep composite")?
            .with_explicit_barriers();
        let mut setup_bindings: Vec<Binding> = common.to_vec();
        for s in &states {
            setup_bindings.push(Binding::StorageImage(&s.image));
        }
        for irr in &irradiance {
            setup_bindings.push(Binding::StorageImage(&irr.image));
        }
        for r in &rays {
            setup_bindings.push(Binding::StorageImage(&r.image));
        }
        let setup_set =
            DescriptorSet::new(ctx, &setup_bindings, "sweep setup")?.with_explicit_barriers();
        let splat_resolve_set = DescriptorSet::new(
            ctx,
            &[
                Binding::Storage(&splat_sums),
                Binding::StorageImage(&irradiance[0].image),
                Binding::StorageImage(&irradiance[1].image),
            ],
            "light splat resolve",
        )?
        .with_explicit_barriers();

        let setup =
            ComputePipeline::new(ctx, shaders::SWEEP_SETUP_COMP, &setup_set, 0, "sweep setup")?;
        let forward_capable = ctx.info().large_points && ctx.info().fragment_atomics;
        let forward = if forward_capable {
            let largest_point = ctx.info().limits.point_size_range[1];
            Some(ForwardPipelines {
                splat_resolve: ComputePipeline::new(
                    ctx,
                    shaders::LIGHT_SPLAT_RESOLVE_COMP,
                    &splat_resolve_set,
                    16,
                    "light splat resolve",
                )?,
                // Every splat deposits the same, so the point sprites' limit holds for the
                // compute ones too.
                max_half_width: MAX_SPLAT_HALF_WIDTH.min(((largest_point - 2.0) / 2.0).floor()),
            })
        } else {
            None
        };
        let all = PlanePipelines::new(
            ctx,
            [&render_pass, &light_pass, &view_pass, &splat_pass],
            &sweep_set,
            Features::ALL.constants(have_gradient),
            Features::ALL.cells,
            forward_capable,
        )?;
        let planes = HashMap::from([(Features::ALL, all)]);
        let composite = ComputePipeline::new(
            ctx,
            shaders::SWEEP_COMPOSITE_COMP,
            &composite_set,
            std::mem::size_of::<CompositePush>() as u32,
            "sweep composite",
        )?;
        Ok(Self {
            width,
            height,
            params,
            states,
            render_pass,
            framebuffers,
            sweep_set,
            setup_set,
            composite_set,
            setup,
            planes,
            have_gradient,
            have_field,
            forward,
            irradiance,
            rays,
            rays_per_pixel,
            splat_pass,
            splat_framebuffers,
            splat_sums,
            splat_resolve_set,
            light_pass,
            light_framebuffers,
            view_pass,
            view_framebuffers,
            counters,
            compute_set,
            compute_planes: HashMap::new(),
            deposits,
            cells_fit,
            bins,
            bin_list,
            sprite_groups,
            sprite_fallback,
            sprite_draws,
            composite,
            output,
            env_params,
            light_record,
        })
    }

    /// Make the plane pipelines for `features` if this pass has none yet (once per
    /// feature set: a few hundred ms of shader compilation on lavapipe).
    pub(crate) fn ensure_planes(&mut self, ctx: &Context, features: Features) -> Result<()> {
        if !self.planes.contains_key(&features) {
            let planes = PlanePipelines::new(
                ctx,
                [
                    &self.render_pass,
                    &self.light_pass,
                    &self.view_pass,
                    &self.splat_pass,
                ],
                &self.sweep_set,
                features.constants(self.have_gradient),
                features.cells,
                self.forward.is_some(),
            )?;
            self.planes.insert(features, planes);
        }
        Ok(())
    }

    /// Make the compute sweep's plane pipelines for `features` if this pass has none yet.
    pub(crate) fn ensure_compute_planes(
        &mut self,
        ctx: &Context,
        features: Features,
    ) -> Result<()> {
        if !self.compute_planes.contains_key(&features) {
            if let Some(halo) = features.light_tile {
                // Two vec4 per texel (glsl/sweep_plane_io.glsl's tile).
                let side = 8 + 2 * halo;
                let bytes = side * side * 32;
                let limit = ctx.info().limits.max_compute_shared_memory_size;
                if bytes > limit {
                    bail!(
                        "--variant tile={halo}: the light's tile of {side} x {side} texels \
                         needs {bytes} bytes of shared memory; {} offers {limit}. Use a \
                         smaller halo",
                        ctx.info().name
                    );
                }
            }
            let planes = ComputePlanes::new(
                ctx,
                &self.compute_set,
                features.constants(self.have_gradient),
                features.gather,
                features.cells,
            )?;
            self.compute_planes.insert(features, planes);
        }
        Ok(())
    }

    /// The image a dump of `b` copies: with the forward transport (`forward`) what a
    /// plane's light is, is the splatted irradiance, and the rays are in images of their
    /// own.
    pub(crate) fn dump_image(&self, forward: bool, b: StateBuffer) -> &Image {
        match (forward, b) {
            (true, StateBuffer::LightColour) => &self.irradiance[0].image,
            (true, StateBuffer::LightDirection) => &self.irradiance[1].image,
            (true, StateBuffer::LightRays) => &self.rays[0].image,
            (true, StateBuffer::LightRayDirections) => &self.rays[1].image,
            _ => &self.states[b.index()].image,
        }
    }

    /// The images a dump of `b` is made from: the one [`SweepPass::dump_image`] names,
    /// but for the viewing rays' points, which the compact state keeps in parts (x, y
    /// beside other values, the value at the point, the mark that says the depth:
    /// `view_positions` in mod.rs puts them together).
    pub(crate) fn dump_parts(&self, forward: bool, b: StateBuffer) -> Vec<&Image> {
        let image = |b: StateBuffer| &self.states[b.index()].image;
        match (forward, b) {
            (false, StateBuffer::ViewPosition) => vec![
                image(StateBuffer::LightColour),
                image(StateBuffer::LightDirection),
                image(StateBuffer::ViewDirection),
                image(StateBuffer::Medium),
            ],
            (true, StateBuffer::ViewPosition) => vec![
                image(StateBuffer::ViewPosition),
                image(StateBuffer::ViewDirection),
                image(StateBuffer::Medium),
            ],
            _ => vec![self.dump_image(forward, b)],
        }
    }

    /// The backward transport's five state images ([`StateBuffer::BACKWARD`]), in its
    /// render pass's attachment order.
    pub(crate) fn backward_states(&self) -> Vec<&StateImage> {
        StateBuffer::BACKWARD
            .iter()
            .map(|b| &self.states[b.index()])
            .collect()
    }

    /// The same layers of all six state images, bound for the same use.
    pub(crate) fn state_layers(
        &self,
        layers: std::ops::Range<u32>,
        access: Access,
    ) -> Vec<(&Image, std::ops::Range<u32>, Access)> {
        self.states
            .iter()
            .map(|s| (&s.image, layers.clone(), access))
            .collect()
    }

    /// Both layers of every image the setup writes (state, irradiance, rays), for `access`.
    pub(crate) fn every_layer(
        &self,
        access: Access,
    ) -> Vec<(&Image, std::ops::Range<u32>, Access)> {
        self.states
            .iter()
            .chain(&self.irradiance)
            .chain(&self.rays)
            .map(|s| (&s.image, 0..2, access))
            .collect()
    }
}
