//! The refractive plane sweep (thesis ch. 4, ch. 5, Algorithm 1) on Vulkan.
//!
//! Per frame, in ONE command buffer: a compute setup pass initialises six state buffers
//! (light colour, light direction, viewing-ray position, viewing-ray direction, colour +
//! opacity, medium) and, for the forward light transport, the light rays and the
//! irradiance; then the view-aligned planes; then a compute pass composites the
//! background. Each buffer is ONE 2D image with 2 array layers; plane i renders layer
//! i % 2 through a framebuffer of per-layer views and samples layer 1 - i % 2 through
//! per-layer sampled views. The read layer arrives as a push constant: nothing is rebound
//! or updated between planes.
//!
//! Per plane, the thesis' backward transport is one full-screen draw that moves light
//! (semi-Lagrangian) and viewing rays together. The forward transport (the default) is
//! three draws: the light rays advance (over the ray images, whose size follows the ray
//! budget, not the screen), they splat their flux into the plane's irradiance (additive
//! point sprites), and the viewing rays cross the segment that ends on the plane. All
//! plane pipelines are made from one descriptor set, so switching pipelines leaves it
//! bound (a set bind per plane costs ~4 ms and 3 MB on lavapipe, a pipeline switch ~0).
//!
//! Synchronization: the images live in GENERAL layout, so the only barriers between
//! planes are memory dependencies on exactly the layers that change role (the layer just
//! written becomes sampled, the layer just sampled becomes an attachment), batched into
//! one vkCmdPipelineBarrier2 per role change. GENERAL is what lets one descriptor set name
//! both layers: the validation layer checks the layout of every statically used
//! descriptor at every draw (see docs/NOTES.md).

use anyhow::{bail, ensure, Result};
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

use super::{Camera, FrameTarget, RenderOptions, VolumeInfo};
use crate::shaders;
use crate::vk::{
    self, Access, Binding, Buffer, ComputePipeline, Context, DescriptorSet, Framebuffer,
    GraphicsPipeline, Image, ImageDesc, ImageKind, LayerView, Primitives, Recorder, RenderPass,
    Sampler,
};

/// The six state buffers, in attachment order, and what else a plane can be dumped as.
///
/// With the forward light transport `LightColour` and `LightDirection` dump the plane's
/// light as the viewing rays see it (the splatted irradiance, and the luminance-weighted
/// sum of light directions with the weight in w), and `LightRays` / `LightRayDirections`
/// the light rays themselves (flux rgb + view x on the plane; v = η dx/ds + view y; ray
/// r of the grid in [`SweepStats::light_grid`] / [`SweepStats::light_rays`] at texel r).
/// With the backward transport the latter two are the same images as the former.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StateBuffer {
    LightColour,
    LightDirection,
    ViewPosition,
    ViewDirection,
    ColourOpacity,
    Medium,
    LightRays,
    LightRayDirections,
}

impl StateBuffer {
    pub const ALL: [StateBuffer; 6] = [
        StateBuffer::LightColour,
        StateBuffer::LightDirection,
        StateBuffer::ViewPosition,
        StateBuffer::ViewDirection,
        StateBuffer::ColourOpacity,
        StateBuffer::Medium,
    ];

    /// Everything `--dump` accepts.
    pub const DUMPABLE: [StateBuffer; 8] = [
        StateBuffer::LightColour,
        StateBuffer::LightDirection,
        StateBuffer::ViewPosition,
        StateBuffer::ViewDirection,
        StateBuffer::ColourOpacity,
        StateBuffer::Medium,
        StateBuffer::LightRays,
        StateBuffer::LightRayDirections,
    ];

    pub fn name(self) -> &'static str {
        match self {
            StateBuffer::LightColour => "light-colour",
            StateBuffer::LightDirection => "light-direction",
            StateBuffer::ViewPosition => "view-position",
            StateBuffer::ViewDirection => "view-direction",
            StateBuffer::ColourOpacity => "colour-opacity",
            StateBuffer::Medium => "medium",
            StateBuffer::LightRays => "light-rays",
            StateBuffer::LightRayDirections => "light-ray-directions",
        }
    }

    pub fn parse(s: &str) -> Result<Self> {
        Self::DUMPABLE
            .into_iter()
            .find(|b| b.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = Self::DUMPABLE.iter().map(|b| b.name()).collect();
                anyhow::anyhow!("unknown state buffer '{s}'; one of {}", names.join(", "))
            })
    }

    /// The state image this buffer lives in.
    fn index(self) -> usize {
        match self {
            StateBuffer::LightRays => 0,
            StateBuffer::LightRayDirections => 1,
            b => b as usize,
        }
    }
}

/// Every state buffer is RGBA32F: 16 bytes per pixel per layer. 32-bit floats because
/// light and medium are products over hundreds of planes, and the equality with the EA
/// baseline (1/255) and the Beer–Lambert test (1 %) must survive that many roundings.
pub const STATE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
pub const STATE_BYTES_PER_PIXEL: u64 = 16;

pub use crate::light::Light;

/// How light is carried from plane to plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightTransport {
    /// Light rays advanced forward one by one (each texel of the light state is a ray with
    /// its own position, direction and flux), each ray's flux spread over its cell on every
    /// plane (glsl/light_splat.*). Conserves flux through focal crossings; the default
    /// since issue 12 (docs/NOTES.md, "Light transport for caustics").
    Forward,
    /// The thesis' backward (semi-Lagrangian) step with the intensity law (eqs. 4.4–4.8):
    /// one direction per pixel, gain bounded per plane. The default.
    Backward,
}

impl LightTransport {
    pub fn name(self) -> &'static str {
        match self {
            LightTransport::Forward => "forward",
            LightTransport::Backward => "backward",
        }
    }

    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "forward" => Ok(LightTransport::Forward),
            "backward" => Ok(LightTransport::Backward),
            _ => bail!("unknown light transport '{s}'; one of forward, backward"),
        }
    }
}

/// Largest half-width, in pixels, of one light ray's splat (its cell on the plane): a ray
/// whose neighbours have spread further deposits its flux over this many pixels at most
/// (still all of it: the box is normalised). Large enough for the coarsest regular grid:
/// light 80° from the sweep axis drifts ~6 pixels per plane, the grid must reach far
/// aside and its pitch grows past 8 pixels; at 4 (8 pixels across) the boxes no longer
/// tiled the plane and a lit floor showed dark columns (column means −63 % / +22 %,
/// measured), at 16 it is uniform (0.000 %).
pub const MAX_SPLAT_HALF_WIDTH: f32 = 16.0;

pub use super::limits::MIN_FORWARD;

/// Largest refractive-index scale ([`SweepOptions::eta_scale`]).
pub const MAX_ETA_SCALE: f32 = 3.0;

/// Options of the refractive model beyond the common [`RenderOptions`].
#[derive(Clone, Debug)]
pub struct SweepOptions {
    pub light: Light,
    /// GGX roughness of the Cook–Torrance specular term.
    pub roughness: f32,
    /// Scale of the specular term (0 = no specular).
    pub specular: f32,
    /// Bound on the intensity gain I = S_{i-1}/S_i per plane (chapter 7's bright spots).
    /// Focusing by a strong lens stays well below it except right at a focus.
    pub max_gain: f32,
    /// Clipping plane in world space: opacity (not the medium or η) is zero where
    /// dot(normal, p) > offset (thesis Fig. 6.6).
    pub clip: Option<(Vec3, f32)>,
    /// Diagnostic: diffuse light 1 and no specular, so with η ≡ 1 the sweep must equal the
    /// EA baseline.
    pub unlit: bool,
    /// Copy these buffers after these planes (0-based) for inspection.
    pub dumps: Vec<(StateBuffer, u32)>,
    /// Test-only: skip the inter-plane barrier before this plane, to prove synchronization
    /// validation notices.
    pub drop_barrier_before_plane: Option<u32>,
    /// Rotation of the environment map about the world's up axis, degrees.
    pub env_rotation: f32,
    /// Average the environment over each pixel's refracted footprint with the summed-area
    /// table (thesis Fig. 4.5); false = one bilinear lookup per pixel (for comparison).
    pub env_footprint: bool,
    /// Refractive-index scale k: the sweep uses η' = 1 + k (η_tf − 1), so 0 turns refraction
    /// off and 1 (default) is the transfer function's η.
    pub eta_scale: f32,
    /// How light travels between planes.
    pub light_transport: LightTransport,
    /// Forward transport: light rays per screen pixel (1 to `MAX_LIGHT_RAYS`). The rays
    /// cover the light's whole domain at plane 0's pixel pitch as far as this budget
    /// allows; more rays resolve oblique light and crossing rays more finely, at a cost
    /// proportional to their number.
    pub light_rays: u32,
    /// Fresnel reflection of viewing rays at changes of η: the reflected fraction sees the
    /// environment (or background) in the mirrored direction, unoccluded; false = the
    /// thesis' model (no reflection, everything transmitted).
    pub reflections: bool,
    /// Benchmark baseline: run every plane with glsl/sweep_floor.frag, which only carries
    /// the state forward (same passes, barriers, attachments and reads). The image is not
    /// a rendering; the time is the floor the sweep's optics add to.
    pub floor: bool,
}

impl Default for SweepOptions {
    fn default() -> Self {
        Self {
            light: Light::default(),
            roughness: 0.3,
            specular: 1.0,
            max_gain: 4.0,
            clip: None,
            unlit: false,
            dumps: Vec::new(),
            drop_barrier_before_plane: None,
            env_rotation: 0.0,
            env_footprint: true,
            eta_scale: 1.0,
            light_transport: LightTransport::Forward,
            light_rays: 2,
            reflections: true,
            floor: false,
        }
    }
}

impl SweepOptions {
    pub fn validate(&self) -> Result<()> {
        let l = &self.light;
        ensure!(
            l.towards.is_finite() && l.towards.length() > 1e-6,
            "light direction {:?} must be a finite non-zero vector",
            l.towards.to_array()
        );
        ensure!(
            l.colour.iter().all(|c| c.is_finite() && *c >= 0.0),
            "light colour {:?} must be finite and non-negative",
            l.colour
        );
        ensure!(
            l.softness.is_finite() && (0.0..=8.0).contains(&l.softness),
            "light softness {} must be in [0, 8] (filter radius in voxels)",
            l.softness
        );
        ensure!(
            self.roughness.is_finite() && (0.01..=1.0).contains(&self.roughness),
            "roughness {} must be in [0.01, 1]",
            self.roughness
        );
        ensure!(
            self.specular.is_finite() && self.specular >= 0.0,
            "specular strength {} must be >= 0",
            self.specular
        );
        ensure!(
            self.max_gain.is_finite() && self.max_gain >= 1.0,
            "intensity gain bound {} must be >= 1",
            self.max_gain
        );
        ensure!(
            self.env_rotation.is_finite(),
            "environment rotation {} must be a finite number of degrees",
            self.env_rotation
        );
        ensure!(
            self.eta_scale.is_finite() && (0.0..=MAX_ETA_SCALE).contains(&self.eta_scale),
            "refractive-index scale {} must be in [0, {MAX_ETA_SCALE}]",
            self.eta_scale
        );
        ensure!(
            (1..=MAX_LIGHT_RAYS).contains(&self.light_rays),
            "light rays per pixel {} must be in 1..={MAX_LIGHT_RAYS}",
            self.light_rays
        );
        if let Some((n, o)) = self.clip {
            ensure!(
                n.is_finite() && n.length() > 1e-6 && o.is_finite(),
                "clipping plane needs a finite non-zero normal and a finite offset"
            );
        }
        Ok(())
    }
}

/// std140 mirror of `SweepParams` in glsl/sweep_common.glsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SweepParams {
    view_to_tex: [f32; 16],
    view_to_world: [f32; 16],
    camera: [f32; 4],
    planes: [f32; 4],
    light_dir: [f32; 4],
    light_colour: [f32; 4],
    volume_dims: [f32; 4],
    specular: [f32; 4],
    clip: [f32; 4],
    background: [f32; 4],
    refraction: [f32; 4],
    light_grid: [f32; 4],
    transport: [f32; 4],
    light_rays: [f32; 4],
    max_gain: f32,
    termination_alpha: f32,
    unlit: u32,
    pad0: u32,
}

/// std140 mirror of `EnvParams` in glsl/sweep_composite.comp.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct EnvParams {
    info: [f32; 4],
    mean: [f32; 4],
}

/// The environment as the composite sees it: the map, its summed-area table and whether
/// to use them at all (otherwise the constant background).
pub(crate) struct EnvInputs<'a> {
    pub map: &'a Image,
    pub sat: &'a Image,
    pub mean: [f32; 4],
    pub enabled: bool,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PlanePush {
    plane: u32,
    read_layer: u32,
    depth: f32,
    pad: u32,
}

/// The view-aligned planes of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Planes {
    pub first_depth: f32,
    pub spacing: f32,
    pub count: u32,
}

impl Planes {
    /// Planes from the box's nearest to its farthest depth, `spacing` apart (thesis ch. 6:
    /// sample distance × the smallest voxel side).
    pub fn for_box(camera: &Camera, half_extent: Vec3, spacing: f32) -> Result<Self> {
        let (eye, forward, _, _) = camera.frame();
        let mut near = f32::INFINITY;
        let mut far = f32::NEG_INFINITY;
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            ) * half_extent;
            let d = (corner - eye).dot(forward);
            near = near.min(d);
            far = far.max(d);
        }
        if near <= spacing {
            bail!(
                "the plane sweep needs the camera outside the volume box (nearest box depth \
                 {near:.3}); increase the camera distance"
            );
        }
        let count = ((far - near) / spacing).floor() as u32 + 2;
        Ok(Self {
            first_depth: near,
            spacing,
            count,
        })
    }

    pub fn depth(&self, i: u32) -> f32 {
        self.first_depth + i as f32 * self.spacing
    }
}

/// The planes of a frame, after the checks that depend on the camera and the light: the
/// light must come from the viewer's side, the camera must be outside the volume box, and
/// dumps must name planes the frame has.
pub(super) fn check(
    info: VolumeInfo,
    camera: &Camera,
    opts: &RenderOptions,
    sweep: &SweepOptions,
) -> Result<Planes> {
    let (_, forward, _, _) = camera.frame();
    let travel = -sweep.light.towards.normalize();
    let forwardness = travel.dot(forward);
    if forwardness < MIN_FORWARD {
        bail!(
            "the light must come from the viewer's side: the sweep runs front to back, so \
             light travelling against it cannot be propagated (light direction makes {:.1}° \
             with the view direction; at most {:.1}° is supported)",
            forwardness.clamp(-1.0, 1.0).acos().to_degrees(),
            MIN_FORWARD.acos().to_degrees()
        );
    }
    let planes = Planes::for_box(
        camera,
        info.half_extent,
        opts.sample_distance * info.ref_step,
    )?;
    for (b, plane) in &sweep.dumps {
        ensure!(
            *plane < planes.count,
            "--dump {}@{plane}: this frame has planes 0..{}",
            b.name(),
            planes.count - 1
        );
    }
    Ok(planes)
}

/// What recording a sweep leaves for after the submission: the plane stats and the
/// buffers the requested dumps are copied into (alive until the submission completes).
pub(super) struct SweepRecording {
    pub stats: SweepStats,
    pub dumps: Vec<(StateBuffer, u32, Buffer)>,
    /// Where the clamp counters are copied to; `None` for frames that are not read back
    /// (the viewer's): the copy would outlive this recording's buffer.
    clamp_readback: Option<Buffer>,
}

impl SweepRecording {
    /// The clamp counters, once the submission has completed.
    pub fn read_clamps(&mut self) -> Result<()> {
        let Some(buf) = &self.clamp_readback else {
            return Ok(());
        };
        let c: Vec<u32> = buf.read_values(4)?;
        self.stats.clamps = Clamps {
            light_direction: c[0] as u64,
            light_dropped: c[1] as u64,
            view_direction: c[2] as u64,
            gain: c[3] as u64,
        };
        Ok(())
    }

    /// The dumps, once the submission has completed.
    pub fn read_dumps(&self, width: u32, height: u32) -> Result<Vec<Dump>> {
        self.dumps
            .iter()
            .map(|(b, plane, buf)| {
                // The forward transport's rays live in images of their own size.
                let (width, height) = match (self.stats.light_transport, b) {
                    (
                        LightTransport::Forward,
                        StateBuffer::LightRays | StateBuffer::LightRayDirections,
                    ) => (self.stats.light_rays[2], self.stats.light_rays[3]),
                    _ => (width, height),
                };
                Ok(Dump {
                    buffer: *b,
                    plane: *plane,
                    depth: self.stats.planes.depth(*plane),
                    width,
                    height,
                    pixels: buf.read_values(width as usize * height as usize)?,
                })
            })
            .collect()
    }
}

/// A state buffer copied out after a plane.
#[derive(Clone, Debug)]
pub struct Dump {
    pub buffer: StateBuffer,
    pub plane: u32,
    /// Depth of `plane`. The pass for plane k advances the viewing rays to plane k+1, so
    /// the view position buffer holds points one spacing deeper than this.
    pub depth: f32,
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

/// Diagnostics of one sweep, for performance engineers.
#[derive(Clone, Debug)]
pub struct SweepStats {
    pub planes: Planes,
    /// State-buffer bytes read and written per plane (render-pass loads, sampled reads
    /// including filter taps, attachment writes), over the whole viewport.
    pub bytes_per_plane: u64,
    /// How light travelled.
    pub light_transport: LightTransport,
    /// Forward transport: the light rays' grid on the launch plane (one spacing before
    /// plane 0): view x, y of ray (0, 0)'s cell corner, cell width and height; ray (i, j)
    /// starts at the centre of its cell.
    pub light_grid: [f32; 4],
    /// Forward transport: the grid's columns and rows, and the ray images' width and
    /// height. Ray r = j * columns + i is texel (r % width, r / width) of the
    /// `light-rays` / `light-ray-directions` dumps.
    pub light_rays: [u32; 4],
    /// How often physics was bent, summed over pixels and planes (read back after the
    /// frame; zero for recorded frames that were not read back): see [`Clamps`].
    pub clamps: Clamps,
}

/// Pixel-planes at which the sweep had to depart from its model (glsl/sweep_light.glsl).
/// None of them creates light: clamped directions keep their flux, dropped rays lose it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Clamps {
    /// Light directions bent back to 84° from the sweep direction.
    pub light_direction: u64,
    /// Light rays turned back against the sweep (total internal reflection): dropped.
    pub light_dropped: u64,
    /// Viewing-ray directions bent back to 84°.
    pub view_direction: u64,
    /// Backward transport: intensity gains bounded per plane.
    pub gain: u64,
}

impl Clamps {
    pub fn total(&self) -> u64 {
        self.light_direction + self.light_dropped + self.view_direction + self.gain
    }
}

/// An image of two layers (the ping-pong of the plane sweep) with a view of each layer:
/// the six state buffers; the forward transport's irradiance (rgb) and light direction
/// (luminance-weighted sum of unit directions, weight in w) of the last two planes, plane
/// i in layer i % 2; and its light rays.
struct StateImage {
    image: Image,
    layers: [LayerView; 2],
}

impl StateImage {
    fn new(ctx: &Context, size: [u32; 2], name: &str) -> Result<Self> {
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

pub(super) struct SweepPass {
    width: u32,
    height: u32,
    params: Buffer,
    states: Vec<StateImage>,
    render_pass: RenderPass,
    framebuffers: [Framebuffer; 2],
    sweep_set: DescriptorSet,
    setup_set: DescriptorSet,
    composite_set: DescriptorSet,
    setup: ComputePipeline,
    sweep: GraphicsPipeline,
    floor: GraphicsPipeline,
    forward: Option<ForwardPipelines>,
    irradiance: [StateImage; 2],
    /// The forward transport's light rays (flux + view x; v + view y): `rays_per_pixel`
    /// texels per screen pixel (the screen's width, that many times its height).
    rays: [StateImage; 2],
    rays_per_pixel: u32,
    splat_pass: RenderPass,
    splat_framebuffers: [Framebuffer; 2],
    /// Forward transport: the light rays' pass (the two light buffers) and the viewing
    /// rays' pass (the other four), per written layer.
    light_pass: RenderPass,
    light_framebuffers: [Framebuffer; 2],
    view_pass: RenderPass,
    view_framebuffers: [Framebuffer; 2],
    counters: Buffer,
    composite: ComputePipeline,
    output: FrameTarget,
    env_params: Buffer,
}

/// The forward transport's pipelines, all on the plane set's layout so that switching
/// between them leaves the descriptor set bound.
struct ForwardPipelines {
    light: GraphicsPipeline,
    light_soft: GraphicsPipeline,
    splat: GraphicsPipeline,
    view: GraphicsPipeline,
    /// Largest splat half-width the device's point sizes allow.
    max_half_width: f32,
}

impl SweepPass {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: &Context,
        volume: &Image,
        gradient: Option<&Image>,
        tf: &Image,
        preint: &Image,
        sampler: &Sampler,
        env: &EnvInputs,
        width: u32,
        height: u32,
        rays_per_pixel: u32,
    ) -> Result<Self> {
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
            Binding::Texture(volume, sampler),
            Binding::Texture(tf, sampler),
            Binding::Texture(preint, sampler),
        ];
        let mut sampled: Vec<Binding> = common.to_vec();
        for s in &states {
            for view in &s.layers {
                sampled.push(Binding::LayerTexture(view, sampler, Access::SampledGeneral));
            }
        }
        let mut plane_bindings = sampled.clone();
        for irr in &irradiance {
            for view in &irr.layers {
                plane_bindings.push(Binding::LayerTexture(view, sampler, Access::SampledGeneral));
            }
        }
        plane_bindings.push(Binding::Storage(&counters));
        for r in &rays {
            for view in &r.layers {
                plane_bindings.push(Binding::LayerTexture(view, sampler, Access::SampledGeneral));
            }
        }
        // Binding 25: the environment for Fresnel reflections (glsl/sweep_light.glsl).
        plane_bindings.push(Binding::Texture(env.map, sampler));
        // Binding 26: the smoothed gradient volume (render::gradient, glsl/sweep_light.glsl);
        // without one the shaders compute normals on the fly (specialization constant 0)
        // and never read the binding, which the volume then fills.
        plane_bindings.push(Binding::Texture(gradient.unwrap_or(volume), sampler));
        let constants = [gradient.is_some() as u32];
        let sweep_set = DescriptorSet::new(ctx, &plane_bindings, "sweep")?;
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

        let setup =
            ComputePipeline::new(ctx, shaders::SWEEP_SETUP_COMP, &setup_set, 0, "sweep setup")?;
        let sweep = GraphicsPipeline::specialized(
            ctx,
            shaders::FULLSCREEN_VERT,
            shaders::SWEEP_FRAG,
            &render_pass,
            &sweep_set,
            std::mem::size_of::<PlanePush>() as u32,
            Primitives::Triangles,
            &constants,
            "sweep plane",
        )?;
        let floor = GraphicsPipeline::fullscreen(
            ctx,
            shaders::FULLSCREEN_VERT,
            shaders::SWEEP_FLOOR_FRAG,
            &render_pass,
            &sweep_set,
            std::mem::size_of::<PlanePush>() as u32,
            "sweep floor plane",
        )?;
        let forward = if ctx.info().large_points && ctx.info().fragment_atomics {
            let plane = |fs: &[u8], pass: &RenderPass, name: &str| {
                GraphicsPipeline::specialized(
                    ctx,
                    shaders::FULLSCREEN_VERT,
                    fs,
                    pass,
                    &sweep_set,
                    std::mem::size_of::<PlanePush>() as u32,
                    Primitives::Triangles,
                    &constants,
                    name,
                )
            };
            let largest_point = ctx.info().limits.point_size_range[1];
            Some(ForwardPipelines {
                light: plane(
                    shaders::SWEEP_LIGHT_FORWARD_FRAG,
                    &light_pass,
                    "sweep light rays",
                )?,
                light_soft: plane(
                    shaders::SWEEP_LIGHT_FORWARD_SOFT_FRAG,
                    &light_pass,
                    "sweep light rays (soft)",
                )?,
                view: plane(
                    shaders::SWEEP_VIEW_FORWARD_FRAG,
                    &view_pass,
                    "sweep viewing rays",
                )?,
                splat: GraphicsPipeline::new(
                    ctx,
                    shaders::LIGHT_SPLAT_VERT,
                    shaders::LIGHT_SPLAT_FRAG,
                    &splat_pass,
                    &sweep_set,
                    std::mem::size_of::<PlanePush>() as u32,
                    Primitives::AdditivePoints,
                    "light splat",
                )?,
                max_half_width: MAX_SPLAT_HALF_WIDTH.min(((largest_point - 2.0) / 2.0).floor()),
            })
        } else {
            None
        };
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
            sweep,
            floor,
            forward,
            irradiance,
            rays,
            rays_per_pixel,
            splat_pass,
            splat_framebuffers,
            light_pass,
            light_framebuffers,
            view_pass,
            view_framebuffers,
            counters,
            composite,
            output,
            env_params,
        })
    }

    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Light rays per screen pixel the ray images were made for.
    pub fn rays_per_pixel(&self) -> u32 {
        self.rays_per_pixel
    }

    /// The same layers of all six state images, bound for the same use.
    fn state_layers(
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
    fn every_layer(&self, access: Access) -> Vec<(&Image, std::ops::Range<u32>, Access)> {
        self.states
            .iter()
            .chain(&self.irradiance)
            .chain(&self.rays)
            .map(|s| (&s.image, 0..2, access))
            .collect()
    }

    /// State-buffer traffic of one plane (see [`SweepStats::bytes_per_plane`]).
    pub fn bytes_per_plane(&self, soft: bool, specular: bool) -> u64 {
        let pixels = self.width as u64 * self.height as u64;
        // Attachment loads (6) and writes (6); sampled: light direction here (1), light
        // colour + direction at the back-projected point (2 per tap), viewing-ray state
        // (4), light colour at the ray (1), light direction at the ray for specular (1).
        let taps = if soft { 3 } else { 1 };
        let reads = 6 + 1 + 2 * taps + 4 + 1 + u64::from(specular);
        pixels * (reads + 6) * STATE_BYTES_PER_PIXEL
    }

    /// The finished frame (linear RGBA32F) once a recording has run.
    pub fn output(&self) -> &FrameTarget {
        &self.output
    }

    /// Record one frame into `rec`: setup, every plane, and the composite into
    /// [`SweepPass::output`]. Parameters travel in the command stream, so earlier frames
    /// may still be in flight.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        rec: &mut Recorder,
        ctx: &Context,
        info: VolumeInfo,
        volume_dims: [u32; 3],
        camera: &Camera,
        opts: &RenderOptions,
        sweep: &SweepOptions,
        inputs: [&Image; 4],
        env: &EnvInputs,
        read_back: bool,
    ) -> Result<SweepRecording> {
        let (eye, forward, right, up) = camera.frame();
        let travel = -sweep.light.towards.normalize();
        let planes = check(info, camera, opts, sweep)?;
        let view_to_world = Mat4::from_cols(
            right.extend(0.0),
            up.extend(0.0),
            forward.extend(0.0),
            eye.extend(1.0),
        );
        let view_to_tex = Mat4::from_translation(Vec3::splat(0.5))
            * Mat4::from_scale(0.5 / info.half_extent)
            * view_to_world;
        let light_view = Vec3::new(travel.dot(right), travel.dot(up), travel.dot(forward));
        let (clip_n, clip_o) = sweep
            .clip
            .map(|(n, o)| (n.normalize(), o))
            .unwrap_or((Vec3::ZERO, 0.0));
        let forward = match (sweep.light_transport, &self.forward) {
            (LightTransport::Backward, _) => None,
            (LightTransport::Forward, Some(f)) => Some(f),
            (LightTransport::Forward, None) => bail!(
                "the forward light transport needs point sizes above 1 and fragment-shader \
                 atomics (largePoints, fragmentStoresAndAtomics), which device '{}' lacks; \
                 use --light-transport backward",
                ctx.info().name
            ),
        };
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
            ray_image[0] as u64 * ray_image[1] as u64,
        );
        let soft = sweep.light.softness > 0.0;
        let (diffusion_w, diffusion_stride) = diffusion(
            sweep.light.softness * info.ref_step,
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
                sweep.light.softness,
            ],
            light_colour: [
                sweep.light.colour[0],
                sweep.light.colour[1],
                sweep.light.colour[2],
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
                if forward.is_some() { 1.0 } else { 0.0 },
                diffusion_w,
                diffusion_stride as f32,
                forward.map_or(MAX_SPLAT_HALF_WIDTH, |f| f.max_half_width),
            ],
            max_gain: sweep.max_gain,
            termination_alpha: opts.termination_alpha,
            unlit: sweep.unlit as u32,
            pad0: 0,
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
                let image = match (forward.is_some(), b) {
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
        for img in inputs.into_iter().chain([env.map, env.sat]) {
            rec.transition_all(img, Access::Sampled);
        }
        rec.begin_scope("sweep setup");
        rec.clear_storage(&self.counters);
        rec.transition_many(&self.every_layer(Access::ComputeStorage));
        // The setup covers the screen and the ray images (rays_per_pixel times taller).
        let setup_groups = [ray_image[0].div_ceil(8), ray_image[1].div_ceil(8), 1];
        rec.dispatch(&self.setup, &self.setup_set, &[], setup_groups)?;
        // Both layers become sampled: every draw's set names both (see module docs).
        rec.transition_many(&self.every_layer(Access::SampledGeneral));
        rec.end_scope();

        rec.begin_scope("sweep");
        // Bound once: between planes only push constants change, and the forward
        // transport switches pipelines (same layout, so the set stays bound).
        let forward = forward.filter(|_| !sweep.floor);
        let plane_pipeline = match (sweep.floor, forward) {
            (true, _) => &self.floor,
            (false, Some(f)) if soft => &f.light_soft,
            (false, Some(f)) => &f.light,
            (false, None) => &self.sweep,
        };
        rec.bind_graphics(plane_pipeline, &self.sweep_set, self.width, self.height);
        let light_images = [&self.rays[0].image, &self.rays[1].image];
        for i in 0..planes.count {
            let write = i % 2;
            let read = 1 - write;
            let push = PlanePush {
                plane: i,
                read_layer: read,
                depth: planes.depth(i),
                pad: 0,
            };
            // The layer the previous plane wrote becomes sampled (one batched barrier
            // over the six images); begin_render_pass then makes the layer the previous
            // plane sampled an attachment (a second one). Nothing else is synchronised.
            if sweep.drop_barrier_before_plane == Some(i) {
                for s in &self.states {
                    rec.assume_without_barrier(&s.image, read..read + 1, Access::SampledGeneral);
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
                    rec.begin_render_pass(
                        &self.render_pass,
                        &self.framebuffers[write as usize],
                        &attachments,
                    )?;
                    rec.draw_fullscreen(plane_pipeline, bytemuck::bytes_of(&push))?;
                    rec.end_render_pass();
                }
                Some(f) => {
                    // 1. The light rays advance to plane i (over the ray images).
                    rec.begin_render_pass(
                        &self.light_pass,
                        &self.light_framebuffers[write as usize],
                        &[(light_images[0], write), (light_images[1], write)],
                    )?;
                    // Only the rows that hold rays.
                    let rows = (grid_dims[0] * grid_dims[1]).div_ceil(ray_image[0]);
                    rec.set_viewport(ray_image[0], rows.clamp(1, ray_image[1]));
                    rec.draw_fullscreen(plane_pipeline, bytemuck::bytes_of(&push))?;
                    rec.end_render_pass();
                    rec.set_viewport(self.width, self.height);
                    // 2. They deposit their flux on plane i: irradiance layer `write`
                    // (plane i - 2's, read by no draw any more) becomes an attachment.
                    rec.transition_many(&[
                        (light_images[0], write..write + 1, Access::SampledGeneral),
                        (light_images[1], write..write + 1, Access::SampledGeneral),
                    ]);
                    rec.begin_render_pass(
                        &self.splat_pass,
                        &self.splat_framebuffers[write as usize],
                        &[
                            (&self.irradiance[0].image, write),
                            (&self.irradiance[1].image, write),
                        ],
                    )?;
                    rec.bind_pipeline(&f.splat);
                    let splat_push = PlanePush {
                        read_layer: write,
                        ..push
                    };
                    rec.draw(
                        &f.splat,
                        bytemuck::bytes_of(&splat_push),
                        grid_dims[0] * grid_dims[1],
                    )?;
                    rec.end_render_pass();
                    // 3. The viewing rays cross the segment from plane i - 1 to plane i,
                    // lit by the irradiance of both (layers `read` and `write`).
                    rec.transition_many(&[
                        (
                            &self.irradiance[0].image,
                            write..write + 1,
                            Access::SampledGeneral,
                        ),
                        (
                            &self.irradiance[1].image,
                            write..write + 1,
                            Access::SampledGeneral,
                        ),
                    ]);
                    let views: Vec<(&Image, u32)> =
                        self.states[2..].iter().map(|s| (&s.image, write)).collect();
                    rec.begin_render_pass(
                        &self.view_pass,
                        &self.view_framebuffers[write as usize],
                        &views,
                    )?;
                    rec.bind_pipeline(&f.view);
                    rec.draw_fullscreen(&f.view, bytemuck::bytes_of(&push))?;
                    rec.end_render_pass();
                    rec.bind_pipeline(plane_pipeline);
                }
            }
            let splat = forward;
            for (b, plane, buf) in &dump_buffers {
                if *plane != i {
                    continue;
                }
                // With the forward transport what a plane's light is, is the splatted
                // irradiance; the rays are in images of their own.
                let image = match (splat.is_some(), b) {
                    (true, StateBuffer::LightColour) => &self.irradiance[0].image,
                    (true, StateBuffer::LightDirection) => &self.irradiance[1].image,
                    (true, StateBuffer::LightRays) => &self.rays[0].image,
                    (true, StateBuffer::LightRayDirections) => &self.rays[1].image,
                    _ => &self.states[b.index()].image,
                };
                rec.copy_image_to_buffer(image, write, buf);
            }
        }
        rec.end_scope();

        rec.begin_scope("composite");
        let last = (planes.count - 1) % 2;
        rec.transition_many(&self.state_layers(0..2, Access::SampledGeneral));
        rec.transition_all(&self.output.image, Access::ComputeStorage);
        rec.dispatch(
            &self.composite,
            &self.composite_set,
            &last.to_le_bytes(),
            groups,
        )?;
        rec.end_scope();
        if let Some(buf) = &clamp_readback {
            rec.copy_storage_to_host(&self.counters, buf);
        }
        Ok(SweepRecording {
            stats: SweepStats {
                planes,
                bytes_per_plane: self.bytes_per_plane(soft, sweep.specular > 0.0),
                light_transport: sweep.light_transport,
                light_grid: grid,
                light_rays: [grid_dims[0], grid_dims[1], ray_image[0], ray_image[1]],
                clamps: Clamps::default(),
            },
            dumps: dump_buffers,
            clamp_readback,
        })
    }
}

/// Most light rays per screen pixel (`SweepOptions::light_rays`).
pub const MAX_LIGHT_RAYS: u32 = 8;

/// The forward transport's grid of light rays on the launch plane (one spacing before
/// plane 0): (x, y of the grid's corner, cell width, cell height) in view units, and its
/// columns and rows. Every point of every plane's view rectangle traced back along the
/// (unrefracted) light lands inside it, so no plane has a region no ray could reach; two
/// cells of margin on each side keep the splats at the border whole. The cells are the
/// pixel pitch of plane 0 (where pixels are smallest), so the irradiance is resolved at
/// least as finely as the screen, unless that takes more than `budget` rays: oblique
/// light seen through a narrow view needs rays over several screen heights (the light
/// reaching the deepest plane comes from far aside), and then the pitch grows evenly.
fn light_grid(
    planes: &Planes,
    light: Vec3,
    tan_half: f32,
    aspect: f32,
    size: [u32; 2],
    budget: u64,
) -> ([f32; 4], [u32; 2]) {
    let launch = planes.first_depth - planes.spacing;
    let last = planes.depth(planes.count.saturating_sub(1));
    let (mut lo, mut hi) = (
        glam::Vec2::splat(f32::INFINITY),
        glam::Vec2::splat(f32::NEG_INFINITY),
    );
    let slope = glam::Vec2::new(light.x, light.y) / light.z;
    for z in [launch, last] {
        for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
            let corner = glam::Vec2::new(sx * z * tan_half * aspect, sy * z * tan_half);
            let back = corner - slope * (z - launch);
            lo = lo.min(back);
            hi = hi.max(back);
        }
    }
    let pitch = 2.0 * planes.first_depth * tan_half / size[1] as f32;
    let extent = hi - lo;
    let mut n = (extent / pitch).ceil() + 4.0;
    let count = n.x as f64 * n.y as f64;
    if count > budget as f64 {
        n = (n * (budget as f64 / count).sqrt() as f32).floor();
    }
    let n = n.max(glam::Vec2::splat(5.0));
    let cell = extent / (n - 4.0);
    let corner = lo - 2.0 * cell;
    (
        [corner.x, corner.y, cell.x, cell.y],
        [n.x as u32, n.y as u32],
    )
}

/// Softness as diffusion between neighbouring light rays: the weight each ray hands to each
/// of its 4 neighbours `stride` rays away, so that every plane adds the per-axis variance
/// of the thesis' soft-shadow kernel (3 taps on a circle of radius `radius` world units:
/// radius²/2) for rays `cell` world units apart. The weight stays at most 0.2 (a larger
/// variance takes a longer stride), keeping every ray's own share positive.
fn diffusion(radius: f32, cell: f32) -> (f32, u32) {
    if !(radius > 0.0 && cell > 0.0) {
        return (0.0, 1);
    }
    // Per axis, the 5-point exchange adds 2 w stride² cells² of variance.
    let cells2 = 0.5 * radius * radius / (cell * cell);
    let w_stride2 = 0.5 * cells2;
    let stride = (w_stride2 / 0.2).sqrt().ceil().max(1.0);
    (w_stride2 / (stride * stride), stride as u32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vk::spirv::check_block;

    fn sweep_params_layout() -> Vec<(&'static str, usize, usize)> {
        crate::host_layout!(SweepParams {
            view_to_tex,
            view_to_world,
            camera,
            planes,
            light_dir,
            light_colour,
            volume_dims,
            specular,
            clip,
            background,
            refraction,
            light_grid,
            transport,
            light_rays,
            max_gain,
            termination_alpha,
            unlit,
            pad0,
        })
    }

    /// The std140 and push-constant mirrors against the blocks glslang laid out.
    #[test]
    fn host_structs_match_the_shaders_blocks() {
        let params = sweep_params_layout();
        let size = std::mem::size_of::<SweepParams>();
        for spirv in [
            shaders::SWEEP_FRAG,
            shaders::SWEEP_SETUP_COMP,
            shaders::SWEEP_COMPOSITE_COMP,
            shaders::SWEEP_VIEW_FORWARD_FRAG,
        ] {
            check_block(spirv, "SweepParams", &params, size, true).unwrap();
        }
        let env = crate::host_layout!(EnvParams { info, mean });
        let size = std::mem::size_of::<EnvParams>();
        check_block(shaders::SWEEP_COMPOSITE_COMP, "EnvParams", &env, size, true).unwrap();
        let push = crate::host_layout!(PlanePush {
            plane,
            read_layer,
            depth,
            pad
        });
        let size = std::mem::size_of::<PlanePush>();
        for spirv in [
            shaders::SWEEP_FRAG,
            shaders::SWEEP_LIGHT_FORWARD_FRAG,
            shaders::SWEEP_VIEW_FORWARD_FRAG,
            shaders::LIGHT_SPLAT_VERT,
        ] {
            check_block(spirv, "Push", &push, size, false).unwrap();
        }
    }

    /// The check fails when a host field is missing or moved (it can fail).
    #[test]
    fn a_moved_field_fails_the_block_check() {
        let mut params = sweep_params_layout();
        let size = std::mem::size_of::<SweepParams>();
        params.swap(2, 3);
        params[2].0 = "camera";
        params[3].0 = "planes";
        params[2].1 += 16;
        let e = check_block(shaders::SWEEP_FRAG, "SweepParams", &params, size, true);
        assert!(e.unwrap_err().to_string().contains("'camera'"));
        params.retain(|(name, _, _)| *name != "light_rays");
        let e = check_block(shaders::SWEEP_FRAG, "SweepParams", &params, size, true);
        assert!(e.unwrap_err().to_string().contains("light_rays"));
    }
}
