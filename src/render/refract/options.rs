//! The refractive model's options beyond the common `RenderOptions`: the light transport,
//! the sweep's optics (specular, Fresnel, films, soft shadows), its limits and levers.

use super::*;

/// How light is carried from plane to plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightTransport {
    /// Light rays advanced forward one by one (each texel of the light state is a ray with
    /// its own position, direction and flux), each ray's flux spread over its cell on every
    /// plane (glsl/light_splat.*). Conserves flux through focal crossings; the default
    /// since issue 12 (docs/NOTES.md, "Light transport for caustics").
    Forward,
    /// The thesis' backward (semi-Lagrangian) step with the intensity law (eqs. 4.4–4.8):
    /// one direction per pixel, gain bounded per plane.
    Backward,
    /// Not propagated with the sweep at all: the light is simulated beforehand by the
    /// eikonal model's light simulator (adaptive wavefronts, seed 001; render/eikonal)
    /// into a light volume, and the viewing rays read their light from it (issue 35
    /// item 5). So the light may come from any direction, also against the sweep, and
    /// moving the camera reruns only the sweep. The planes run as the backward
    /// transport's (one pass each) with the light step replaced by the volume's.
    Eikonal,
}

impl LightTransport {
    pub fn name(self) -> &'static str {
        match self {
            LightTransport::Forward => "forward",
            LightTransport::Backward => "backward",
            LightTransport::Eikonal => "eikonal",
        }
    }

    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "forward" => Ok(LightTransport::Forward),
            "backward" => Ok(LightTransport::Backward),
            "eikonal" => Ok(LightTransport::Eikonal),
            _ => bail!("unknown light transport '{s}'; one of forward, backward, eikonal"),
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

pub use crate::render::limits::MIN_FORWARD;

/// Largest refractive-index scale ([`SweepOptions::eta_scale`]).
pub const MAX_ETA_SCALE: f32 = 3.0;

/// Planes `start..end` of a sweep (see [`SweepOptions::batch`]); an `end` past the
/// frame's last plane means "through the last plane".
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlaneBatch {
    pub start: u32,
    pub end: u32,
}

/// Options of the refractive model beyond the common [`RenderOptions`].
#[derive(Clone, Debug, PartialEq)]
pub struct SweepOptions {
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
    /// Record only these planes of the frame, so that a frame can be submitted in
    /// batches (the viewer's refinement, which a change of view may abandon between two
    /// batches): the setup goes with plane 0, the composite with the last plane, and the
    /// state stays in the pass's images between batches. Batches must follow each other
    /// in plane order with nothing else recorded into the same slot between them. None:
    /// the whole frame.
    pub batch: Option<PlaneBatch>,
    /// Rotation of the environment map about the world's up axis, degrees.
    pub env_rotation: f32,
    /// Average the environment over each pixel's refracted footprint with the summed-area
    /// table (thesis Fig. 4.5); false = one bilinear lookup per pixel (for comparison). The
    /// eikonal model's view reads it too.
    pub env_footprint: bool,
    /// Refractive-index scale k: the sweep uses η' = 1 + k (η_tf − 1), so 0 turns refraction
    /// off and 1 (default) is the transfer function's η.
    pub eta_scale: f32,
    /// An ambient level (linear RGB) every sample receives besides the light, unoccluded
    /// and from no direction: particles return `colour × ambient` (as they return `colour
    /// × irradiance` of the light, the thesis' model). A uniform environment of radiance L
    /// in-scatters L into a white medium, so that is the level it gives. `--light env`
    /// sets it to the environment's mean radiance outside the key light's region
    /// ([`crate::environment::KeyLight::ambient`]); 0 (default) is the thesis' model. The
    /// eikonal model's view takes it too, as `albedo × colour × ambient`.
    pub ambient: [f32; 3],
    /// How light travels between planes.
    pub light_transport: LightTransport,
    /// Forward transport: light rays per screen pixel (1 to `MAX_LIGHT_RAYS`). The rays
    /// cover the light's whole domain at plane 0's pixel pitch as far as this budget
    /// allows; more rays resolve oblique light and crossing rays more finely, at a cost
    /// proportional to their number.
    pub light_rays: u32,
    /// Forward transport: the light rays' spacing on the launch plane, in pixel pitches of
    /// plane 0 (`MIN_LIGHT_SPACING` to `MAX_LIGHT_SPACING`; 1 by default). Below 1 the rays
    /// resolve folds of the light (the arms of a caustic) finer than the pixels, and the
    /// irradiance converges toward a photon tracer's (measured: docs/NOTES.md); above 1
    /// they are fewer and faster, and caustics blur. The cost is proportional to the
    /// rays' number, 1 / spacing². `light_rays` bounds that number: where it binds the
    /// spacing widens evenly, and [`SweepStats::light_spacing`] says so.
    pub light_spacing: f32,
    /// Forward transport: the light planes hold the flux per unit plane area (the
    /// thesis' intensity law: power through a plane is their sum, and a photon tracer's
    /// plane tally measures it, `PhotonOptions::plane_flux`) instead of the fluence
    /// (false, the default: each ray's flux per unit area across the ray, what matter
    /// scatters; glsl/light_splat_ray.glsl). The two differ where light has turned from
    /// its launched direction, by cos θ₀ / cos θ per ray (θ to the sweep axis). For the
    /// tests of power and of the light's transport against the photon tracer's planes;
    /// the images are the fluence's.
    pub plane_flux: bool,
    /// Fresnel reflection of viewing rays at changes of η: the reflected fraction sees the
    /// environment (or background) in the mirrored direction, unoccluded (at the first
    /// face, the volume, with `reflections_volume`); false = the thesis' model (no
    /// reflection, everything transmitted).
    pub reflections: bool,
    /// With `reflections`: the first face a viewing ray meets reflects what its mirrored
    /// ray meets in the volume (traced in the composite, lit by the light the sweep
    /// computed there; glsl/sweep_reflect.glsl), then the environment; false: the
    /// environment only (`--reflections environment`, the mirrored ray unoccluded).
    /// True by default.
    pub reflections_volume: bool,
    /// Benchmark baseline: run every plane with glsl/sweep_floor.frag, which only carries
    /// the state forward (same passes, barriers, attachments and reads). The image is not
    /// a rendering; the time is the floor the sweep's optics add to.
    pub floor: bool,
    /// Benchmark baseline: run every plane with glsl/sweep_skeleton.frag, which makes the
    /// fetches of the thesis' Algorithm 1 (value and ∇η at the light's and the viewing
    /// ray's points as the `field` lever says, the backward step's bilinear light, the
    /// preintegration table) and its plain arithmetic, and none of the optics past it
    /// (soft kernel, intensity law, face steps, films, reflections, specular). Between
    /// the floor and the sweep: what the method costs on this device before those. Not a
    /// rendering. Ignored where `floor` is set.
    pub skeleton: bool,
    /// The speed levers (region drawn per plane, field texture, image-array reads,
    /// specialization constants): each renders the same image as the plain
    /// implementation within stated bounds (tested); `Levers::REFERENCE` is the plain one.
    pub levers: Levers,
    /// Profile: GPU timestamps around the forward transport's three draws of every plane
    /// (scopes "sweep: light rays", "sweep: splat", "sweep: viewing rays", one per plane;
    /// `Timings::get` sums them).
    pub pass_timings: bool,
}

impl Default for SweepOptions {
    fn default() -> Self {
        Self {
            roughness: 0.3,
            specular: 1.0,
            max_gain: 4.0,
            clip: None,
            unlit: false,
            dumps: Vec::new(),
            drop_barrier_before_plane: None,
            batch: None,
            env_rotation: 0.0,
            env_footprint: true,
            eta_scale: 1.0,
            ambient: [0.0; 3],
            light_transport: LightTransport::Forward,
            light_rays: 2,
            light_spacing: 1.0,
            plane_flux: false,
            reflections: true,
            reflections_volume: true,
            floor: false,
            skeleton: false,
            levers: Levers::default(),
            pass_timings: false,
        }
    }
}

impl SweepOptions {
    pub fn validate(&self) -> Result<()> {
        ensure!(
            self.roughness.is_finite() && (0.01..=1.0).contains(&self.roughness),
            "roughness {} must be in [0.01, 1]",
            self.roughness
        );
        ensure!(
            self.specular.is_finite() && self.specular >= 0.0,
            "specular strength {} must be a finite number >= 0",
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
        ensure!(
            self.light_spacing.is_finite()
                && (MIN_LIGHT_SPACING..=MAX_LIGHT_SPACING).contains(&self.light_spacing),
            "light ray spacing {} must be in [{MIN_LIGHT_SPACING}, {MAX_LIGHT_SPACING}] \
             pixel pitches",
            self.light_spacing
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
