//! The refractive plane sweep (thesis ch. 4, ch. 5, Algorithm 1) on Vulkan.
//!
//! Per frame, in ONE command buffer: a compute setup pass initialises the state images
//! (the backward transport's five: light colour, light direction, viewing-ray direction,
//! colour + opacity, medium, with the viewing ray's point x, y in the light images' w and
//! its depth its plane's, [`StateBuffer::BACKWARD`]; the forward transport's viewing rays
//! keep x, y in a viewing-ray position image) and, for the forward light transport, the
//! light rays and the irradiance; then the view-aligned planes; then a compute pass composites the
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
use glam::Vec3;

use super::model::{
    FrameReadback, Inputs, ModelPass, ModelStateDecl, MoreLights, OpticalModel, Recorded,
};
use super::LightSupport;
use super::{Camera, FrameTarget, RenderOptions, VolumeInfo};
use crate::shaders;
use crate::vk::{
    self, Access, Binding, Buffer, ComputePipeline, Context, DescriptorSet, Framebuffer,
    GraphicsDesc, GraphicsPipeline, Image, ImageDesc, ImageKind, LayerView, Primitives, Recorder,
    RenderPass,
};

/// The six state images (the backward transport uses five of them: [`StateBuffer::BACKWARD`];
/// a dump of `ViewPosition` is put together from the compact state), and what else a plane
/// can be dumped as.
///
/// With the forward light transport `LightColour` and `LightDirection` dump the plane's
/// light as the viewing rays see it (the splatted irradiance, and the luminance-weighted
/// sum of light directions with the weight in w), and `LightRays` / `LightRayDirections`
/// the light rays themselves (flux rgb + view x on the plane; v = η dx/ds + view y; ray
/// r of the grid in [`SweepStats::light_grid`] / [`SweepStats::light_rays`] at texel r;
/// with `rays=needed` the rows a plane has not moved yet hold their launch state,
/// ray_rows.rs). With the backward transport the latter two are the same images as the former.
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
    /// The six state buffers (the first six of [`StateBuffer::DUMPABLE`]).
    pub const ALL: [StateBuffer; 6] = {
        let d = Self::DUMPABLE;
        [d[0], d[1], d[2], d[3], d[4], d[5]]
    };

    /// The backward transport's compact state, in attachment order (the fragment path's
    /// render pass; glsl/sweep_plane_io.glsl): light colour and direction with the viewing
    /// ray's x and y in their w, its direction with the value at its point in w, colour
    /// and opacity, medium. `ViewPosition` holds the forward transport's x and y only; a
    /// ray's depth is its plane's.
    pub const BACKWARD: [StateBuffer; 5] = [
        StateBuffer::LightColour,
        StateBuffer::LightDirection,
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
        if near <= 0.0 {
            bail!(
                "the plane sweep needs the camera outside the volume box (nearest box depth \
                 {near:.3}); increase the camera distance"
            );
        }
        // The first plane lies one spacing in front of the box (the viewing rays start
        // there), so the spacing must stay below the camera's distance to the box.
        if near <= spacing {
            bail!(
                "the planes would be {spacing:.3} apart (sample distance × smallest voxel \
                 side), more than the camera's distance to the volume box ({near:.3}); use \
                 a smaller sample distance or a larger camera distance"
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
    let travel = opts.light().travel();
    let forwardness = travel.dot(forward);
    // (The eikonal transport's light comes from the light volume, simulated for any
    // direction.)
    if forwardness < MIN_FORWARD && sweep.light_transport != LightTransport::Eikonal {
        bail!(
            "the light must come from the viewer's side: the sweep runs front to back, so \
             light travelling against it cannot be propagated (light direction makes {:.1}° \
             with the view direction; at most {:.1}° is supported; --light-transport eikonal \
             takes light from any direction)",
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
            sweep.light_transport != LightTransport::Eikonal
                || !matches!(
                    b,
                    StateBuffer::LightColour
                        | StateBuffer::LightDirection
                        | StateBuffer::LightRays
                        | StateBuffer::LightRayDirections
                ),
            "--dump {}: with the eikonal light transport the light is in the light volume, \
             not on the planes",
            b.name()
        );
        ensure!(
            *plane < planes.count,
            "--dump {}@{plane}: this frame has planes 0..{}",
            b.name(),
            planes.count - 1
        );
    }
    Ok(planes)
}

/// What the refractive model refuses that every model accepts: transfer functions sampled
/// per step instead of preintegrated, and what [`check`] refuses.
pub(super) fn check_model(info: VolumeInfo, camera: &Camera, opts: &RenderOptions) -> Result<()> {
    // The sweep composites every segment from the preintegration table (thesis sect.
    // 4.3); sampling the transfer functions per step is the EA model's option.
    ensure!(
        opts.preintegrated,
        "sampling the transfer functions per step (no preintegration) is an option of the EA \
         model (--model ea); the refractive sweep always integrates its segments with the \
         preintegration table"
    );
    check(info, camera, opts, &opts.sweep).map(|_| ())
}

/// The refractive sweep's declaration (listed in render/registry.rs).
pub(crate) static REFRACT: OpticalModel = OpticalModel {
    name: "refract",
    summary: "The refractive plane sweep: refraction, caustics, soft shadows, tinted media (the default).",
    // One directional light (thesis sect. 4.2; several lights are future work), propagated
    // with the planes; the eikonal transport's light volume sums up to MAX_LIGHTS,
    // directional or point, simulated apart.
    lights: LightSupport::ONE_DIRECTIONAL,
    more_lights: Some(MoreLights {
        lights: LightSupport {
            max: crate::render::limits::MAX_LIGHTS,
            point: true,
        },
        when: |opts| opts.sweep.light_transport == LightTransport::Eikonal,
        how: "--light-transport eikonal",
    }),
    phase_function: false,
    gradient: true,
    extinction: None,
    check: |_, info, camera, opts| check_model(info, camera, opts),
    make_pass: |inputs| {
        let o = inputs.opts;
        Ok(Box::new(SweepPass::new(inputs, o.width, o.height, o.sweep.light_rays)?))
    },
    options: &[],
    flags: &[
        "--ambient-level",
        "--softness",
        "--roughness",
        "--specular",
        "--eta-scale",
        "--light-transport",
        "--light-rays",
        "--light-spacing",
        "--reflections",
        "--clip",
        "--env",
        "--env-rotation",
        "--variant",
        "--pass-timings",
        "--plane-flux",
    ],
    // (The eikonal transport's light simulation is the eikonal model's scope.)
    rebuild_scopes: &[],
    // The light volume of the eikonal transport, made when a frame asks for it.
    state: Some(ModelStateDecl {
        what: "the light volume (--light-transport eikonal)",
        bytes: |_| 0,
        make: |shared| Ok(Box::new(SweepLight::new(shared)?)),
    }),
    experimental: None,
};

impl ModelPass for SweepPass {
    /// The state images are sized by the viewport, the ray images by the rays per pixel too.
    fn fits(&self, opts: &RenderOptions) -> bool {
        (self.width, self.height) == (opts.width, opts.height)
            && self.rays_per_pixel == opts.sweep.light_rays
    }

    fn record(&mut self, rec: &mut Recorder, inputs: &Inputs) -> Result<Recorded> {
        let recording = self.record_sweep(rec, inputs)?;
        Ok(Recorded {
            max_steps: recording.stats.planes.count,
            readback: Some(Box::new(recording)),
        })
    }

    fn output(&self) -> &FrameTarget {
        &self.output
    }
}

/// One requested dump: the state buffer, the plane after which it is copied, and one
/// readback buffer per image it is made from ([`SweepPass::dump_parts`]).
pub(crate) struct DumpCopy {
    pub buffer: StateBuffer,
    pub plane: u32,
    pub parts: Vec<Buffer>,
}

/// What recording a sweep leaves for after the submission: the plane stats and the
/// buffers the requested dumps are copied into (alive until the submission completes).
pub(crate) struct SweepRecording {
    pub stats: SweepStats,
    pub dumps: Vec<DumpCopy>,
    /// Where the clamp counters are copied to; `None` for frames that are not read back
    /// (the viewer's): the copy would outlive this recording's buffer.
    clamp_readback: Option<Buffer>,
}

impl FrameReadback for SweepRecording {
    fn read(
        mut self: Box<Self>,
        width: u32,
        height: u32,
    ) -> Result<(Option<SweepStats>, Vec<Dump>)> {
        self.read_clamps()?;
        let dumps = self.read_dumps(width, height)?;
        Ok((Some(self.stats), dumps))
    }

    fn unread(self: Box<Self>) -> Option<SweepStats> {
        Some(self.stats)
    }
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
        let forward = self.stats.light_transport == LightTransport::Forward;
        self.dumps
            .iter()
            .map(|d| {
                // The forward transport's rays live in images of their own size.
                let (width, height) = match (forward, d.buffer) {
                    (true, StateBuffer::LightRays | StateBuffer::LightRayDirections) => {
                        (self.stats.light_rays[2], self.stats.light_rays[3])
                    }
                    _ => (width, height),
                };
                let texels = width as usize * height as usize;
                let parts = d
                    .parts
                    .iter()
                    .map(|b| b.read_values::<[f32; 4]>(texels))
                    .collect::<Result<Vec<_>>>()?;
                let pixels = if d.buffer == StateBuffer::ViewPosition {
                    view_positions(&parts, forward, self.stats.planes, d.plane)
                } else {
                    parts.into_iter().next().expect("a dump has an image")
                };
                Ok(Dump {
                    buffer: d.buffer,
                    plane: d.plane,
                    depth: self.stats.planes.depth(d.plane),
                    width,
                    height,
                    pixels,
                })
            })
            .collect()
    }
}

/// The viewing rays' points after plane `plane` (x, y, z, and the value there in w) from
/// the compact state's images as [`SweepPass::dump_parts`] lists them: x and y from the
/// light images' w (backward) or `view_position` (forward), the value from
/// `view_direction`'s w, and the depth from `medium`'s mark (glsl/sweep_plane_io.glsl):
/// a ray the setup left on plane 0 is there, a ray finished at plane k stays on plane
/// k + 1, every other one is on the next plane.
fn view_positions(
    parts: &[Vec<[f32; 4]>],
    forward: bool,
    planes: Planes,
    plane: u32,
) -> Vec<[f32; 4]> {
    let n = parts.len();
    (0..parts[0].len())
        .map(|i| {
            let (x, y) = if forward {
                (parts[0][i][0], parts[0][i][1])
            } else {
                (parts[0][i][3], parts[1][i][3])
            };
            let value = parts[n - 2][i][3];
            let mark = parts[n - 1][i][3];
            let z = if mark == VIEW_RAY_AT_SETUP {
                planes.depth(0)
            } else if mark <= -1.0 {
                planes.depth((-mark) as u32)
            } else {
                planes.depth(plane + 1)
            };
            [x, y, z, value]
        })
        .collect()
}

/// `medium.w` of a viewing ray the setup left on plane 0 (glsl/sweep_common.glsl).
const VIEW_RAY_AT_SETUP: f32 = -0.5;

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
    /// State-buffer bytes read and written per plane: render-pass loads and stores of the
    /// shaded pixels, every texel the plane shaders fetch (four per bilinear read, both
    /// layers where the `arrays` lever is off), and the forward transport's light rays.
    pub bytes_per_plane: u64,
    /// The part of it no sweep over this state can avoid: each state texel the plane
    /// needs, read once and written once (issue 31's bytes model). Algorithm 1 itself
    /// needs 19 scalars per plane-pixel; this counts the present layout's texels.
    pub compulsory_bytes_per_plane: u64,
    /// Mean fraction of the viewport each plane shades (1 with `Region::Full`; the
    /// `region` lever's rectangles otherwise).
    pub shaded_fraction: f64,
    /// How light travelled.
    pub light_transport: LightTransport,
    /// How the planes ran: `Fragment` or `Compute`, what `SweepPath::Auto` resolved to
    /// on this device and transport.
    pub path: SweepPath,
    /// Forward transport: the light rays' grid on the launch plane (one spacing before
    /// plane 0): view x, y of ray (0, 0)'s cell corner, cell width and height; ray (i, j)
    /// starts at the centre of its cell.
    pub light_grid: [f32; 4],
    /// Forward transport: the grid's columns and rows, and the ray images' width and
    /// height. Ray r = j * columns + i is texel (r % width, r / width) of the
    /// `light-rays` / `light-ray-directions` dumps.
    pub light_rays: [u32; 4],
    /// Forward transport: the light rays' spacing asked for (`SweepOptions::light_spacing`)
    /// and the one launched, in pixel pitches of plane 0 (the larger of the grid's two
    /// cell sides). Wider than asked when the grid would need more rays than
    /// `SweepOptions::light_rays` per screen pixel.
    pub light_spacing: [f32; 2],
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

/// Most light rays per screen pixel (`SweepOptions::light_rays`).
pub const MAX_LIGHT_RAYS: u32 = 8;

/// Finest light ray spacing, in pixel pitches of plane 0 (`SweepOptions::light_spacing`):
/// sixteen rays per pixel, which twice `MAX_LIGHT_RAYS` could not hold anyway.
pub const MIN_LIGHT_SPACING: f32 = 0.25;
/// Coarsest light ray spacing: a ray per 4 × 4 pixels of plane 0.
pub const MAX_LIGHT_SPACING: f32 = 4.0;

mod compute;
mod eikonal_light;
mod levers;
mod options;
mod params;
mod pass;
mod pipelines;
mod ray_rows;
mod record;
mod record_forward;
mod region;
mod traffic;

use compute::ComputeFrame;
pub(crate) use eikonal_light::SweepLight;
pub use levers::{Deposit, Gather, Levers, Region, Splat, SweepPath};
pub use options::*;
use params::*;
pub(crate) use pass::{LightRecord, StateImage, SweepPass};
pub(crate) use pipelines::Features;
pub(crate) use traffic::TrafficInputs;
