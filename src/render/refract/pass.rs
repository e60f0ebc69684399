//! The sweep's GPU resources: state images, render passes, framebuffers, descriptor sets
//! and pipelines, made once per viewport size and ray budget.

use std::collections::HashMap;

use super::*;

/// An image of two layers (the ping-pong of the plane sweep) with a view of each layer:
/// the six state buffers; the forward transport's irradiance (rgb) and light direction
/// (luminance-weighted sum of unit directions, weight in w) of the last two planes, plane
/// i in layer i % 2; and its light rays.
pub(crate) struct StateImage {
    pub(crate) image: Image,
    pub(crate) layers: [LayerView; 2],
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
    pub(crate) bins: Buffer,
    pub(crate) bin_list: Buffer,
    /// The grouped sprites' buffers (glsl/light_splat_groups.glsl, bindings 23-25).
    pub(crate) sprite_groups: Buffer,
    pub(crate) sprite_fallback: Buffer,
    pub(crate) sprite_draws: Buffer,
    pub(crate) composite: ComputePipeline,
    pub(crate) output: FrameTarget,
    pub(crate) env_params: Buffer,
}

/// The features a frame uses that the plane shaders can leave out, and the shader levers:
/// specialization constants 1-9 (glsl/sweep_common.glsl, sweep_buffers.glsl,
/// light_splat_ray.glsl). The first
/// four are on exactly when their runtime condition can hold, so switching one off changes
/// no image (tested) and costs nothing; `arrays` and `field` choose how the shaders read
/// the state and the field (`Levers`). `films` is on when the η function has an interior
/// extremum (`TransferFunctions::eta_has_films`): without one no value ramp passes through
/// a band of η past both its ends, so the film tests (sweep_plane.glsl) can only be set off
/// by the 1D transfer-function texture's blur of a step, which is no film either.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct Features {
    pub(crate) specular: bool,
    pub(crate) clip: bool,
    pub(crate) reflections: bool,
    pub(crate) soft_light: bool,
    pub(crate) arrays: bool,
    pub(crate) field: bool,
    pub(crate) films: bool,
    /// The `clear` lever: one light sub-step through clear space (render::value_ranges).
    pub(crate) clear: bool,
    /// The `deposit` lever: the forward light rays deposit cells, not boxes.
    pub(crate) cells: bool,
    /// The `gather` lever: the compute sweep's splat sums by (ray, pixel) pairs
    /// (glsl/sweep_gather.comp), not by pixels (sweep_gather_pixels.comp). Not a
    /// constant: it chooses the gather's shader.
    pub(crate) gather_pairs: bool,
}

impl Features {
    pub(crate) const ALL: Features = Features {
        specular: true,
        clip: true,
        reflections: true,
        soft_light: true,
        arrays: true,
        field: true,
        films: true,
        clear: true,
        cells: true,
        gather_pairs: true,
    };

    /// `have_field`: whether the field texture exists (it may not fit in memory);
    /// `eta_films`: whether the transfer functions' η can make films.
    pub(crate) fn of(opts: &RenderOptions, have_field: bool, eta_films: bool) -> Self {
        let sweep = &opts.sweep;
        let levers = sweep.levers;
        let shader = Self {
            arrays: levers.arrays,
            field: levers.field && have_field,
            clear: levers.clear,
            cells: levers.deposit == super::Deposit::Cells,
            gather_pairs: levers.gather == super::Gather::Pairs,
            ..Self::ALL
        };
        if !levers.specialize {
            return shader;
        }
        Self {
            specular: sweep.specular > 0.0,
            clip: sweep.clip.is_some(),
            reflections: sweep.reflections,
            soft_light: opts.light().softness > 0.0,
            films: eta_films,
            ..shader
        }
    }

    /// Constant 0 (the gradient volume is bound), then 1-9.
    fn constants(self, have_gradient: bool) -> [u32; 10] {
        [
            have_gradient as u32,
            self.specular as u32,
            self.clip as u32,
            self.reflections as u32,
            self.soft_light as u32,
            self.arrays as u32,
            self.field as u32,
            self.films as u32,
            self.clear as u32,
            self.cells as u32,
        ]
    }
}

/// The plane pipelines that read the specialization constants: the backward sweep's
/// and the forward transport's light-ray, splat and viewing-ray passes.
pub(crate) struct PlanePipelines {
    pub(crate) sweep: GraphicsPipeline,
    /// The benchmark floor (`SweepOptions::floor`), reading the state as `sweep` does.
    pub(crate) floor: GraphicsPipeline,
    /// The benchmark skeleton (`SweepOptions::skeleton`): Algorithm 1's fetches and plain
    /// arithmetic, none of the optics past it.
    pub(crate) skeleton: GraphicsPipeline,
    pub(crate) forward: Option<ForwardPlanes>,
}

impl PlanePipelines {
    /// `passes`: the backward sweep's, the light rays', the viewing rays', the splat's;
    /// `cells`: the `deposit` lever (the point sprites' shaders are built per deposit, the
    /// boxes' with fewer varyings: glsl/light_splat_sprite.glsl).
    fn new(
        ctx: &Context,
        passes: [&RenderPass; 4],
        set: &DescriptorSet,
        constants: [u32; 10],
        cells: bool,
        forward: bool,
    ) -> Result<Self> {
        let plane = |fragment, pass, name: &str| {
            let desc = GraphicsDesc {
                constants: &constants,
                ..GraphicsDesc::fullscreen(
                    shaders::FULLSCREEN_VERT,
                    fragment,
                    pass,
                    set,
                    std::mem::size_of::<PlanePush>() as u32,
                )
            };
            GraphicsPipeline::new(ctx, &desc, name)
        };
        let [sweep_pass, light_pass, view_pass, splat_pass] = passes;
        // The splat's point sprites (vertex and fragment shader) and its compute passes
        // over the rays, on the plane set with the plane's push constants.
        let sprites = |[vertex, fragment]: [&[u8]; 2], name: &str| {
            let desc = GraphicsDesc {
                primitives: Primitives::AdditivePoints,
                constants: &constants,
                ..GraphicsDesc::fullscreen(
                    vertex,
                    fragment,
                    splat_pass,
                    set,
                    std::mem::size_of::<PlanePush>() as u32,
                )
            };
            GraphicsPipeline::new(ctx, &desc, name)
        };
        let per_ray = |shader, name: &str| {
            ComputePipeline::with_constants(
                ctx,
                shader,
                set,
                std::mem::size_of::<PlanePush>() as u32,
                &constants,
                name,
            )
        };
        Ok(Self {
            sweep: plane(shaders::SWEEP_FRAG, sweep_pass, "sweep plane")?,
            floor: plane(shaders::SWEEP_FLOOR_FRAG, sweep_pass, "sweep floor plane")?,
            skeleton: plane(
                shaders::SWEEP_SKELETON_FRAG,
                sweep_pass,
                "sweep skeleton plane",
            )?,
            forward: if forward {
                Some(ForwardPlanes {
                    light: plane(
                        shaders::SWEEP_LIGHT_FORWARD_FRAG,
                        light_pass,
                        "sweep light rays",
                    )?,
                    light_soft: plane(
                        shaders::SWEEP_LIGHT_FORWARD_SOFT_FRAG,
                        light_pass,
                        "sweep light rays (soft)",
                    )?,
                    view: plane(
                        shaders::SWEEP_VIEW_FORWARD_FRAG,
                        view_pass,
                        "sweep viewing rays",
                    )?,
                    splat: sprites(
                        if cells {
                            [shaders::LIGHT_SPLAT_VERT, shaders::LIGHT_SPLAT_FRAG]
                        } else {
                            [
                                shaders::LIGHT_SPLAT_BOXES_VERT,
                                shaders::LIGHT_SPLAT_BOXES_FRAG,
                            ]
                        },
                        "light splat",
                    )?,
                    splat_compute: per_ray(shaders::LIGHT_SPLAT_COMP, "light splat (compute)")?,
                    group_deposits: per_ray(
                        shaders::LIGHT_SPLAT_GROUPS_COMP,
                        "light splat groups (deposits)",
                    )?,
                    splat_groups: sprites(
                        if cells {
                            [
                                shaders::LIGHT_SPLAT_GROUPS_VERT,
                                shaders::LIGHT_SPLAT_GROUPS_FRAG,
                            ]
                        } else {
                            [
                                shaders::LIGHT_SPLAT_GROUPS_BOXES_VERT,
                                shaders::LIGHT_SPLAT_GROUPS_BOXES_FRAG,
                            ]
                        },
                        "light splat groups",
                    )?,
                })
            } else {
                None
            },
        })
    }
}

/// The compute sweep's plane pipelines for one feature set (the same shaders as
/// [`PlanePipelines`], glsl/*.comp), all on [`SweepPass::compute_set`] with
/// [`ComputePush`].
/// The gather splat's bins for a `width` × `height` screen (glsl/light_gather.glsl): one
/// per tile of GATHER_TILE pixels, one per coarse tile of GATHER_COARSE_TILE pixels, and
/// the one for deposits wider than 2 × 2 coarse tiles.
pub(crate) fn gather_bins(width: u32, height: u32) -> u64 {
    use crate::render::limits::GATHER_COARSE_TILE;
    let tiles = |side: u32| width.div_ceil(side) as u64 * height.div_ceil(side) as u64;
    gather_tiles(width, height) + tiles(GATHER_COARSE_TILE) + 1
}

/// The most bins one ray is listed in (glsl/light_gather.glsl, footprint_bins): the fine
/// tiles of a GATHER_FINE_SPAN-square, or 2 × 2 coarse tiles.
pub(crate) fn gather_entries_per_ray() -> u64 {
    use crate::render::limits::GATHER_FINE_SPAN;
    (GATHER_FINE_SPAN.max(2) as u64).pow(2)
}

/// The fine tiles (GATHER_TILE pixels a side) of a `width` × `height` screen.
pub(crate) fn gather_tiles(width: u32, height: u32) -> u64 {
    use crate::render::limits::GATHER_TILE;
    width.div_ceil(GATHER_TILE) as u64 * height.div_ceil(GATHER_TILE) as u64
}

/// Words of the `bins` buffer (glsl/light_gather.glsl): three per bin (count, offset,
/// cursor), the pair gather's first chunk per fine tile and their total, and the sums of
/// the tiles of more than one chunk (64 pixels × 7 channels × 2 words per fine tile).
pub(crate) fn gather_words(width: u32, height: u32) -> u64 {
    let fine = gather_tiles(width, height);
    3 * gather_bins(width, height) + fine + 1 + fine * 64 * 7 * 2
}

pub(crate) struct ComputePlanes {
    pub(crate) sweep: ComputePipeline,
    pub(crate) floor: ComputePipeline,
    pub(crate) skeleton: ComputePipeline,
    pub(crate) light: ComputePipeline,
    pub(crate) light_soft: ComputePipeline,
    pub(crate) view: ComputePipeline,
    /// The splat, a tile-binned gather (glsl/light_gather.glsl): each ray's deposit and
    /// its count in the tile bins, the bins' offsets, the bins' lists, each pixel's sum.
    pub(crate) deposit: ComputePipeline,
    pub(crate) bin_scan: ComputePipeline,
    pub(crate) bin_fill: ComputePipeline,
    pub(crate) gather: ComputePipeline,
    /// Whether `gather` is the pair gather (the `gather` lever): one workgroup per chunk
    /// of a tile's candidates, then `gather_resolve` for the tiles of several chunks.
    pub(crate) gather_pairs: bool,
    pub(crate) gather_resolve: ComputePipeline,
}

impl ComputePlanes {
    fn new(
        ctx: &Context,
        set: &DescriptorSet,
        constants: [u32; 10],
        gather_pairs: bool,
    ) -> Result<Self> {
        let push = std::mem::size_of::<ComputePush>() as u32;
        let make = |spirv, name: &str| {
            ComputePipeline::with_constants(ctx, spirv, set, push, &constants, name)
        };
        Ok(Self {
            sweep: make(shaders::SWEEP_COMP, "sweep plane (compute)")?,
            floor: make(shaders::SWEEP_FLOOR_COMP, "sweep floor plane (compute)")?,
            skeleton: make(
                shaders::SWEEP_SKELETON_COMP,
                "sweep skeleton plane (compute)",
            )?,
            light: make(
                shaders::SWEEP_LIGHT_FORWARD_COMP,
                "sweep light rays (compute)",
            )?,
            light_soft: make(
                shaders::SWEEP_LIGHT_FORWARD_SOFT_COMP,
                "sweep light rays, soft (compute)",
            )?,
            view: make(
                shaders::SWEEP_VIEW_FORWARD_COMP,
                "sweep viewing rays (compute)",
            )?,
            deposit: make(
                shaders::SWEEP_DEPOSIT_COMP,
                "light deposits (compute sweep)",
            )?,
            bin_scan: make(
                shaders::SWEEP_BIN_SCAN_COMP,
                "light bin offsets (compute sweep)",
            )?,
            bin_fill: make(
                shaders::SWEEP_BIN_FILL_COMP,
                "light bin lists (compute sweep)",
            )?,
            gather: match gather_pairs {
                true => make(shaders::SWEEP_GATHER_COMP, "light gather (compute sweep)")?,
                false => make(
                    shaders::SWEEP_GATHER_PIXELS_COMP,
                    "light gather by pixels (compute sweep)",
                )?,
            },
            gather_pairs,
            gather_resolve: make(
                shaders::SWEEP_GATHER_RESOLVE_COMP,
                "light gather, tiles of several chunks (compute sweep)",
            )?,
        })
    }
}

pub(crate) struct ForwardPlanes {
    pub(crate) light: GraphicsPipeline,
    pub(crate) light_soft: GraphicsPipeline,
    pub(crate) view: GraphicsPipeline,
    /// The point sprites, one per ray (`splat=raster`).
    pub(crate) splat: GraphicsPipeline,
    /// The `splat=compute` lever: deposits into [`SweepPass::splat_sums`], resolved by
    /// [`ForwardPipelines::splat_resolve`] (glsl/light_splat.comp, _resolve.comp).
    pub(crate) splat_compute: ComputePipeline,
    /// The `splat=groups` lever: each plane's deposits, groups and indirect draws
    /// (glsl/light_splat_groups.comp), then the grouped sprites (light_splat_groups.*).
    pub(crate) group_deposits: ComputePipeline,
    pub(crate) splat_groups: GraphicsPipeline,
}

/// The forward transport's pipelines that do not depend on the features, on the plane
/// set's layout so that switching between them leaves the descriptor set bound.
pub(crate) struct ForwardPipelines {
    /// The `splat=compute` lever's resolve of the sums into the irradiance images.
    pub(crate) splat_resolve: ComputePipeline,
    /// Largest splat half-width the device's point sizes allow.
    pub(crate) max_half_width: f32,
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
        ensure!(
            (height as u64) * (rays_per_pixel as u64) <= max_image as u64,
            "{rays_per_pixel} light rays per pixel need ray images {width}x{} texels; device \
             '{}' allows {max_image} per side",
            height as u64 * rays_per_pixel as u64,
            ctx.info().name
        );
        let max_attachments = ctx.info().limits.max_color_attachments;
        if max_attachments < 6 {
            bail!(
                "the plane sweep writes 6 colour attachments per plane; device '{}' allows {}",
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
            &[STATE_FORMAT; 6],
            Access::AttachmentGeneral,
            "sweep plane",
        )?;
        let fb = |layer: usize| {
            let views: Vec<&LayerView> = states.iter().map(|s| &s.layers[layer]).collect();
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
        let ray_size = [width, height * rays_per_pixel];
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
                width,
                height * rays_per_pixel,
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
        let capacity = ray_size[0] as u64 * ray_size[1] as u64;
        let deposits = Buffer::new(
            ctx,
            capacity * 160,
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
        // SPLAT_GROUP_WORKGROUP groups its listed groups and one indirect draw. A grid of
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
            group_workgroups * 16,
            vk::usage::STORAGE_BUFFER | vk::usage::INDIRECT_BUFFER,
            vk::Memory::Gpu,
            "light splat groups' indirect draws",
        )?;
        plane_bindings.push(Binding::Storage(&sprite_groups));
        plane_bindings.push(Binding::Storage(&sprite_fallback));
        plane_bindings.push(Binding::Storage(&sprite_draws));
        let sweep_set = DescriptorSet::new(ctx, &plane_bindings, "sweep")?;
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
        let compute_set = DescriptorSet::new(ctx, &compute_bindings, "sweep (compute)")?;
        let output = FrameTarget::new(ctx, width, height, "sweep frame")?;
        let env_params = Buffer::uniform::<EnvParams>(ctx, "environment params")?;
        let mut composite_bindings = sampled.clone();
        composite_bindings.push(Binding::StorageImage(&output.image));
        composite_bindings.push(Binding::Texture(env.map, sampler));
        composite_bindings.push(Binding::Texture(env.sat, sampler));
        composite_bindings.push(Binding::Uniform(&env_params));
        let composite_set = DescriptorSet::new(ctx, &composite_bindings, "sweep composite")?;
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
        let setup_set = DescriptorSet::new(ctx, &setup_bindings, "sweep setup")?;
        let splat_resolve_set = DescriptorSet::new(
            ctx,
            &[
                Binding::Storage(&splat_sums),
                Binding::StorageImage(&irradiance[0].image),
                Binding::StorageImage(&irradiance[1].image),
            ],
            "light splat resolve",
        )?;

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
            4,
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
            bins,
            bin_list,
            sprite_groups,
            sprite_fallback,
            sprite_draws,
            composite,
            output,
            env_params,
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
            let planes = ComputePlanes::new(
                ctx,
                &self.compute_set,
                features.constants(self.have_gradient),
                features.gather_pairs,
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

    /// State-buffer traffic of one plane (see [`SweepStats::bytes_per_plane`]): every
    /// texel the plane shaders fetch or write, as glsl/sweep_plane.glsl does per shaded
    /// pixel (and, forward, per light ray), for the frame's features and levers.
    pub fn bytes_per_plane(&self, f: TrafficInputs) -> u64 {
        // A choice between two layers fetches both on llvmpipe (the `arrays` lever off).
        let fetch = if f.features.arrays { 1 } else { 2 };
        let pixel = 1;
        let bilinear = 4;
        // Highlights read the light at the face (two bilinear reads), counted for every
        // shaded pixel: an upper bound, what a SIMD driver running the branch fetches.
        let specular = if f.features.specular { 2 * bilinear } else { 0 };
        // The viewing rays: their four buffers, the light and its direction at the
        // segment (bilinear), the highlight's.
        let view_reads = 4 * pixel + 2 * bilinear + specular;
        let texels_per_pixel = if f.forward {
            // Render-pass load and store of the four viewing-ray attachments.
            8 + fetch * view_reads
        } else {
            // Load and store of the six attachments; the light direction here; per
            // soft-kernel tap the four texels of light colour and of direction.
            let taps = if f.features.soft_light { 3 } else { 1 };
            12 + fetch * (pixel + taps * 2 * bilinear + view_reads)
        };
        let mut texels = f.shaded_pixels * texels_per_pixel;
        if f.forward {
            // Per light ray: its two texels and, with softness, four neighbours' flux;
            // load and store of the two ray attachments; the splat reads the ray and its
            // four neighbours' positions (two texels each).
            let ray_reads = 2 + if f.soft { 4 } else { 0 } + 2 + 4 * 2;
            texels += f.light_rays * (4 + fetch * ray_reads);
            if f.compute_splat {
                // The resolve, over the viewport: the sums' 14 words read and zeroed
                // (7 texels' worth) and two texels written. (Neither splat's deposits
                // are counted: how many pixels a ray's box covers is known on the GPU
                // only.)
                texels += f.viewport_pixels * 9;
            }
        }
        texels * STATE_BYTES_PER_PIXEL
    }

    /// The compulsory part of a plane's state traffic (see
    /// [`SweepStats::compulsory_bytes_per_plane`]): each state texel the plane needs, read
    /// once and written once, in the state's present layout (RGBA32F texels). Backward:
    /// the six state images per shaded pixel. Forward: the four viewing-ray images and
    /// the irradiance's two per shaded pixel (read), the irradiance written over the
    /// viewport by the splat, and each light ray's two texels.
    pub fn compulsory_bytes_per_plane(&self, f: TrafficInputs) -> u64 {
        let texels = if f.forward {
            f.shaded_pixels * (4 * 2 + 2) + f.viewport_pixels * 2 + f.light_rays * 2 * 2
        } else {
            f.shaded_pixels * 6 * 2
        };
        texels * STATE_BYTES_PER_PIXEL
    }
}

/// What [`SweepPass::bytes_per_plane`] counts for.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TrafficInputs {
    pub(crate) features: Features,
    pub(crate) forward: bool,
    pub(crate) soft: bool,
    /// Mean pixels a plane shades.
    pub(crate) shaded_pixels: u64,
    /// Light rays a plane advances (forward).
    pub(crate) light_rays: u64,
    /// The `splat=compute` lever (forward), and the viewport its resolve covers.
    pub(crate) compute_splat: bool,
    pub(crate) viewport_pixels: u64,
}
