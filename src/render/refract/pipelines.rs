//! The sweep's per-plane pipelines: the features that specialise them (`Features`),
//! the draws' and the compute path's pipelines made per feature set, and the gather
//! splat's buffer sizes.

use super::*;

/// The features a frame uses that the plane shaders can leave out, and the shader levers:
/// specialization constants 1-13 (glsl/sweep_common.glsl, sweep_buffers.glsl,
/// light_splat_ray.glsl, sweep_plane_io.glsl). The first
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
    /// The `gather` lever: how the compute sweep's splat sums the deposits. Not a
    /// constant: it chooses the splat's shaders.
    pub(crate) gather: super::Gather,
    /// The eikonal light transport: the plane's light read from the light volume instead
    /// of the backward step (constant 10, glsl/sweep_light.glsl). Not a lever: it
    /// chooses what the light is, so it is always specialised.
    pub(crate) light_volume: bool,
    /// What the forward transport's light planes hold (constant 11,
    /// glsl/light_splat_ray.glsl): the fluence (true) or the flux per unit plane area
    /// (`SweepOptions::plane_flux`). Not a lever: it chooses what the light is.
    pub(crate) fluence: bool,
    /// The `tile` lever (constants 12 and 13, glsl/sweep_plane_io.glsl): the compute
    /// backward plane's light reads from a workgroup tile with this halo in pixels.
    pub(crate) light_tile: Option<u32>,
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
        gather: super::Gather::Pairs,
        light_volume: false,
        fluence: true,
        light_tile: None,
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
            gather: levers.gather,
            light_volume: sweep.light_transport == super::LightTransport::Eikonal,
            fluence: !sweep.plane_flux,
            light_tile: levers.tile,
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

    /// Constant 0 (the gradient volume is bound), then 1-13 (13: the tile's halo, 0
    /// without a tile, so that its shared memory is the smallest).
    pub(super) fn constants(self, have_gradient: bool) -> [u32; 14] {
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
            self.light_volume as u32,
            self.fluence as u32,
            self.light_tile.is_some() as u32,
            self.light_tile.unwrap_or(0),
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
    pub(super) fn new(
        ctx: &Context,
        passes: [&RenderPass; 4],
        set: &DescriptorSet,
        constants: [u32; 14],
        cells: bool,
        forward: bool,
    ) -> Result<Self> {
        let [sweep_pass, light_pass, view_pass, splat_pass] = passes;
        // The planes over the screen draw their polygon (the `region` lever,
        // glsl/sweep_region.vert); the light rays' pass covers its ray images.
        let drawn = |vertex, fragment, pass, name: &str| {
            let desc = GraphicsDesc {
                constants: &constants,
                ..GraphicsDesc::fullscreen(
                    vertex,
                    fragment,
                    pass,
                    set,
                    std::mem::size_of::<PlanePush>() as u32,
                )
            };
            GraphicsPipeline::new(ctx, &desc, name)
        };
        let plane =
            |fragment, pass, name: &str| drawn(shaders::SWEEP_REGION_VERT, fragment, pass, name);
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
                    light: drawn(
                        shaders::FULLSCREEN_VERT,
                        shaders::SWEEP_LIGHT_FORWARD_FRAG,
                        light_pass,
                        "sweep light rays",
                    )?,
                    light_soft: drawn(
                        shaders::FULLSCREEN_VERT,
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
                    // The boxes' rays of groups too wide for one sprite: three varyings
                    // instead of the group sprite's twelve (the cells keep the group
                    // shaders, which read the deposits in the fragments).
                    splat_group_rays: if cells {
                        None
                    } else {
                        Some(sprites(
                            [
                                shaders::LIGHT_SPLAT_GROUP_RAYS_VERT,
                                shaders::LIGHT_SPLAT_BOXES_FRAG,
                            ],
                            "light splat groups' rays",
                        )?)
                    },
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
    /// The forward transport's splat (the `gather` lever).
    pub(crate) splat: ComputeSplat,
}

/// The compute sweep's splat, by the `gather` lever: only the chosen way's pipelines are
/// made (each is compiled when it is created; on lavapipe that is most of a frame's
/// setup).
pub(crate) enum ComputeSplat {
    /// A tile-binned gather (glsl/light_gather.glsl): each ray's deposit and its count in
    /// the tile bins, the bins' offsets, the bins' lists, each pixel's sum; with `pairs`
    /// (glsl/sweep_gather.comp) one workgroup per chunk of a tile's candidates, then
    /// `resolve` for the tiles of several chunks, else one per tile
    /// (sweep_gather_pixels.comp).
    Binned {
        deposit: ComputePipeline,
        bin_scan: ComputePipeline,
        bin_fill: ComputePipeline,
        gather: ComputePipeline,
        pairs: bool,
        resolve: ComputePipeline,
    },
    /// Blocks of rays scattered into shared tiles and the tiles into the plane's sums
    /// (glsl/sweep_scatter.comp), then the sums into the irradiance layer
    /// (sweep_scatter_resolve.comp).
    Blocks {
        scatter: ComputePipeline,
        resolve: ComputePipeline,
    },
}

impl ComputePlanes {
    pub(super) fn new(
        ctx: &Context,
        set: &DescriptorSet,
        constants: [u32; 14],
        gather: super::Gather,
        cells: bool,
    ) -> Result<Self> {
        let push = std::mem::size_of::<ComputePush>() as u32;
        let make = |spirv, name: &str| {
            ComputePipeline::with_constants(ctx, spirv, set, push, &constants, name)
        };
        let splat = match gather {
            super::Gather::Blocks => ComputeSplat::Blocks {
                // 64-bit atomics where the device has them (on an H100 the scatter took
                // 123 ms a frame with them and 335 with two words, the default scene at
                // 768²), the boxes deposit's own build where it applies.
                scatter: make(
                    match (ctx.info().int64_atomics, cells) {
                        (true, false) => shaders::SWEEP_SCATTER_INT64_BOXES_COMP,
                        (true, true) => shaders::SWEEP_SCATTER_INT64_COMP,
                        (false, _) => shaders::SWEEP_SCATTER_COMP,
                    },
                    "light scatter of ray blocks (compute sweep)",
                )?,
                resolve: make(
                    shaders::SWEEP_SCATTER_RESOLVE_COMP,
                    "light scatter's sums (compute sweep)",
                )?,
            },
            super::Gather::Pairs | super::Gather::Pixels => {
                let pairs = gather == super::Gather::Pairs;
                ComputeSplat::Binned {
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
                    gather: match pairs {
                        true => make(shaders::SWEEP_GATHER_COMP, "light gather (compute sweep)")?,
                        false => make(
                            shaders::SWEEP_GATHER_PIXELS_COMP,
                            "light gather by pixels (compute sweep)",
                        )?,
                    },
                    pairs,
                    resolve: make(
                        shaders::SWEEP_GATHER_RESOLVE_COMP,
                        "light gather, tiles of several chunks (compute sweep)",
                    )?,
                }
            }
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
            splat,
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
    /// The boxes deposit's rays of the groups too wide for one sprite (None: the group
    /// shaders draw them, `pad` 1).
    pub(crate) splat_group_rays: Option<GraphicsPipeline>,
}

/// The forward transport's pipelines that do not depend on the features, on the plane
/// set's layout so that switching between them leaves the descriptor set bound.
pub(crate) struct ForwardPipelines {
    /// The `splat=compute` lever's resolve of the sums into the irradiance images.
    pub(crate) splat_resolve: ComputePipeline,
    /// Largest splat half-width the device's point sizes allow.
    pub(crate) max_half_width: f32,
}
