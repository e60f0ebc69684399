//! The command line's syntax (clap): every subcommand, flag and its help text.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

use refrakt::render::{Levers, LightTransport, Model};

pub use super::bench_args::*;
pub use super::scene_flags::SceneArgs;

/// `--variant`'s value: the sweep's levers (`Levers::parse`).
pub(super) fn parse_variant(s: &str) -> Result<Levers, String> {
    Levers::parse(s).map_err(|e| format!("{e:#}"))
}

/// `--threads`' value: a worker count from 1 to [`refrakt::workers::MAX_THREADS`]
/// (leaving the flag out means every core).
pub(super) fn parse_threads(s: &str) -> Result<usize, String> {
    let max = refrakt::workers::MAX_THREADS;
    match s.trim().parse::<usize>() {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        _ => Err(format!(
            "expected a whole number of threads from 1 to {max} (leave --threads out for \
             every core)"
        )),
    }
}

pub(super) fn parse_transport(s: &str) -> Result<LightTransport, String> {
    LightTransport::parse(s).map_err(|e| format!("{e:#}"))
}

/// `--variant`'s help, with the syntax `Levers` accepts.
pub(super) fn variant_help(what: &str) -> String {
    format!(
        "{what} SPEC is `default` ({}: the levers that keep the image, what renders \
         otherwise), `reference` (every lever off: the plain implementation), or \
         comma-separated key=value pairs applied to the default, or to the reference after a \
         leading `reference,` (e.g. `region=full,arrays=off`, `reference,arrays=on`); keys: \
         {}. See docs/BENCH.md (\"A/B a change\").",
        Levers::default(),
        Levers::SYNTAX
    )
}

#[derive(Parser)]
#[command(
    name = "refrakt",
    version,
    about = "Vulkan volume renderer with refraction, caustics, soft shadows and tinted media",
    long_about = "refrakt renders volumes after Magnus & Bruckner, 'Interactive Dynamic Volume \
Illumination with Refraction and Caustics'. It runs headless on any Vulkan 1.3 device, \
including Mesa's lavapipe (CPU) when there is no GPU.\n\nSet RUST_LOG=debug for detail; \
REFRAKT_VALIDATE=1 is the same as --validate."
)]
pub struct Cli {
    #[command(flatten)]
    pub gpu: GpuArgs,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Args)]
pub struct GpuArgs {
    /// Vulkan device to use: an index from `refrakt info` or part of its name
    /// (e.g. "llvmpipe"). Default: discrete > integrated > virtual > CPU.
    #[arg(
        help_heading = "Device",
        long,
        global = true,
        value_name = "NAME|INDEX"
    )]
    pub device: Option<String>,
    /// Enable the Khronos validation layer with synchronization validation; the command
    /// exits with status 3 if the layer reports any warning or error.
    #[arg(help_heading = "Device", long, global = true)]
    pub validate: bool,
}

#[derive(Subcommand)]
pub enum Command {
    /// Show the Vulkan loader, the devices and the limits that matter to refrakt.
    Info,
    /// Render a scene to an image (.png = 8-bit sRGB, .exr = linear float) and print the
    /// GPU time of each pass.
    Render(Box<RenderArgs>),
    /// Open a window and render the scene every frame: left-drag orbits, the wheel zooms,
    /// right-drag or the arrow keys move the light, H prints every key. Takes the same
    /// scene options as `render`.
    View(Box<ViewArgs>),
    /// Reference CPU photon tracer: the light (fluence, or with --plane-flux the flux per
    /// unit plane area) on one plane of the sweep (--plane K, as `render --dump
    /// light-colour@K`) or at a view depth,
    /// written as linear EXR; the oracle for the sweep's caustics, shadows and power.
    Photons(Box<PhotonsArgs>),
    /// Reference CPU renderer: a camera image of the refractive model without the sweep's
    /// approximations (light as photons binned in the volume, viewing rays by the ray
    /// equation, Fresnel reflections traced through the volume); slow, for comparisons.
    Reference(Box<ReferenceArgs>),
    /// Generate (and cache) thesis stand-ins ahead of time, printing the time each took;
    /// `render` and `bench` generate missing ones themselves.
    Generate(GenerateArgs),
    /// Benchmarks: the thesis' timing tables (6.1, 6.2) on this device, how the sweep's
    /// cost scales with planes and pixels, and the optical models side by side (Table 1 of
    /// Ament et al.). GPU timestamps; see docs/BENCH.md.
    #[command(subcommand)]
    Bench(BenchCommand),
    /// Precompute (and cache) tables the renderer reads; `precompute ambient` builds the
    /// light-transport table of Ament et al.'s ambient volume scattering.
    #[command(subcommand)]
    Precompute(PrecomputeCommand),
}

#[derive(Subcommand)]
pub enum PrecomputeCommand {
    /// The preintegrated light-transport table of Ament et al., "Ambient Volume
    /// Scattering" (sections 3.2 and 4.1), on the CPU by Monte Carlo, written to the
    /// cache (or --out) and reused when it is there.
    ///
    /// For a homogeneous sphere of radius 1 (extinction s per radius, albedo Λ,
    /// Henyey-Greenstein anisotropy g) lit by a collimated beam of unit irradiance along +z,
    /// the table holds (a) 4π × the radiance scattered at the centre toward angle θ to the
    /// beam from light already scattered at least once (the beam's single scattering is
    /// added analytically), over θ × s × g (a 3D texture), and
    /// (b) the irradiance at the far pole per unit incident irradiance, the direct beam
    /// e^-2s included, over s × g (a 2D texture), each with its Monte-Carlo standard
    /// error. Every entry uses the same random walks, so the table's noise is smooth and
    /// the file is bit-identical for any thread count. Prints where the table is, whether
    /// it was built or found, the build time and the largest standard errors.
    Ambient(AmbientArgs),
}

#[derive(Args)]
pub struct AmbientArgs {
    /// Single-scattering albedo Λ of the medium, in [0, 1].
    #[arg(long, default_value_t = 0.9, allow_negative_numbers = true)]
    pub albedo: f32,
    /// Nodes of the scattering angle θ over [0, π].
    #[arg(long, default_value_t = 33)]
    pub theta_bins: u32,
    /// Nodes of the extinction s over [0, --s-max] (quadratic spacing).
    #[arg(long, default_value_t = 48)]
    pub extinction_bins: u32,
    /// Nodes of the anisotropy g over [-0.99, 0.99].
    #[arg(long, default_value_t = 23)]
    pub g_bins: u32,
    /// The largest extinction (per sphere radius); beyond it the table's last column is
    /// used.
    #[arg(long, default_value_t = 64.0, allow_negative_numbers = true)]
    pub s_max: f32,
    /// Random walks per entry.
    #[arg(long, default_value_t = refrakt::render::ambient::table::TableParams::default().paths)]
    pub paths: u32,
    /// Seed of the random walks.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads, 1 to 1024 [default: all cores].
    #[arg(long, value_parser = parse_threads)]
    pub threads: Option<usize>,
    /// Refuse a table of more Monte-Carlo paths than this in all (θ bins × extinction bins
    /// × g bins × --paths), before building; the default is about 40 minutes on 2 cores
    /// (the default table, 3.0·10⁸ paths, about 70 s).
    #[arg(long, value_name = "N", default_value_t = 1e10)]
    pub max_paths: f64,
    /// Cache folder. Default: $REFRAKT_CACHE_DIR, else $XDG_CACHE_HOME/refrakt, else
    /// ~/.cache/refrakt.
    #[arg(long, value_name = "DIR")]
    pub cache_dir: Option<PathBuf>,
    /// Write the table to FILE instead of the cache (and reuse FILE if it already holds
    /// this table).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Rebuild the table even if it is cached, and let --out replace an existing file
    /// that is not an ambient table (without --force such a file is refused before the
    /// build; a table file of other parameters is replaced either way).
    #[arg(long)]
    pub force: bool,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum ToneArg {
    Aces,
    Reinhard,
    None,
}

/// `--model`'s value: a model of the registry (`Model::ALL`), its help from the model's
/// own declaration.
#[derive(Clone, Copy)]
pub struct ModelArg(pub Model);

/// The registry's models as `--model` values.
const MODEL_ARGS: [ModelArg; Model::ALL.len()] = {
    let mut v = [ModelArg(Model::ALL[0]); Model::ALL.len()];
    let mut i = 0;
    while i < v.len() {
        v[i] = ModelArg(Model::ALL[i]);
        i += 1;
    }
    v
};

impl ValueEnum for ModelArg {
    fn value_variants<'a>() -> &'a [Self] {
        &MODEL_ARGS
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.0.name()).help(self.0.summary()))
    }
}

#[derive(Args)]
pub struct RenderArgs {
    /// Output image; the extension picks the format: .png (8-bit sRGB) or .exr (linear).
    #[arg(help_heading = "Image", short, long, default_value = "refrakt.png")]
    pub output: PathBuf,
    // The scene's options come right after -o: `--help` shows its headings (input,
    // look, camera, light, ...) before the diagnostics below.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Write state buffers after given planes as EXR: "BUFFER@PLANE[,...]" with BUFFER one
    /// of light-colour, light-direction, view-position, view-direction, colour-opacity,
    /// medium, light-rays, light-ray-directions (refract). With the forward light transport
    /// light-colour is the plane's fluence (the light rays' flux per unit area across
    /// each ray, normalised so that the light as launched reads its colour; what matter
    /// scatters) and light-direction its luminance-weighted
    /// direction sum (weight in alpha); light-rays / light-ray-directions are the rays
    /// themselves (with `--variant rays=needed`, the default on both paths, rows a
    /// plane has not moved yet still hold their launch state, on the launch plane). Files
    /// go to --dump-dir as BUFFER-PLANE.exr; each header (and the log)
    /// gives the plane's view depth and world-space plane n·p = d and the camera.
    #[arg(help_heading = "Diagnostics", long, value_name = "BUFFER@PLANE,...")]
    pub dump: Option<String>,
    /// Folder for --dump files (default: the output image's folder).
    #[arg(help_heading = "Diagnostics", long)]
    pub dump_dir: Option<PathBuf>,
    /// Also render the EA baseline with the same volume, view, image size and sample
    /// distance in the same run, and print its GPU time and the ratio to this model's
    /// (the comparison the thesis' cost discussion needs; compare ratios on lavapipe).
    #[arg(help_heading = "Diagnostics", long)]
    pub with_baseline: bool,
    #[arg(help_heading = "Diagnostics", 
        long,
        value_name = "SPEC",
        value_parser = parse_variant,
        help = variant_help("The sweep's speed levers (refract) [default: default].")
    )]
    pub variant: Option<Levers>,
    /// The forward transport's light planes hold the flux per unit plane area (the
    /// thesis' intensity law) instead of the fluence, the flux per unit area across each
    /// ray (cos θ₀ / cos θ of it, θ its angle to the view axis): with --dump
    /// light-colour@K their sum over a plane is the power through it, to compare with
    /// `refrakt photons --plane-flux`. The image then shows light turned towards the
    /// planes too dark (refract).
    #[arg(help_heading = "Diagnostics", long)]
    pub plane_flux: bool,
    /// Time the forward light transport's three draws of every plane apart (light rays,
    /// splat, viewing rays; summed over the planes) with GPU timestamps around each: a
    /// profile, which the extra timestamps may slow a little (refract).
    #[arg(help_heading = "Diagnostics", long)]
    pub pass_timings: bool,
    /// Also print developer diagnostics: the sweep's shaded fraction and state traffic
    /// per plane, the light-ray grid and whether the ray budget bound it, and how often
    /// the sweep clamped a light direction, a gain or a viewing direction (refract).
    #[arg(help_heading = "Diagnostics", short, long)]
    pub verbose: bool,
}

#[derive(Args)]
pub struct ViewArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Present without waiting for the display's vertical blank (mailbox or immediate
    /// presentation where the surface offers one).
    #[arg(long)]
    pub no_vsync: bool,
    /// Render this many frames, then exit (for tests and scripts).
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub frames: Option<u64>,
    /// With --frames: write the last frame as shown (PNG, read back from the window's
    /// swapchain image) and as linear EXR, to FILE and FILE with the other extension.
    #[arg(long, value_name = "FILE", requires = "frames")]
    pub screenshot: Option<PathBuf>,
    /// Ask for a new window size before frame N, "WxH@N" (for tests and scripts); the
    /// viewer waits for the window to take it.
    #[arg(long, value_name = "WxH@N")]
    pub resize: Option<String>,
    /// Folder for the screenshots the P key writes.
    #[arg(long, default_value = ".", value_name = "DIR")]
    pub screenshot_dir: PathBuf,
    /// Do not reload the scene when its files (scene file, volume, transfer functions,
    /// environment map) change on disk (R still reloads).
    #[arg(long)]
    pub no_watch: bool,
    /// GPU time per frame, in ms, that previews must fit while the view changes: they are
    /// rendered at a reduced size and sample distance (two sizes are timed off screen
    /// before the first frame to choose; each preview's own time then moves the choice),
    /// and a full-quality frame follows once the view has been still for 0.3 s. 0: no
    /// previews, every frame at full quality.
    #[arg(long, value_name = "MS", default_value_t = refrakt::viewer::preview::DEFAULT_BUDGET_MS, allow_negative_numbers = true)]
    pub preview_budget: f64,
    /// Orbit the camera before each of the first N frames as a drag of 10 pixels to the
    /// right would (4 degrees; for tests and scripts, with --frames).
    #[arg(long, value_name = "N")]
    pub drag: Option<u64>,
    /// Orbit the camera once, as one step of --drag does, after N batches of planes of the
    /// first full-quality frame (for tests and scripts: a change of view while a frame
    /// refines, which abandons it).
    #[arg(long, value_name = "N")]
    pub interrupt_refinement: Option<u32>,
    /// Start with the on-screen panel hidden (Tab shows it): model, transfer functions,
    /// light, softness, refractive-index scale, sample distance, clipping, environment
    /// rotation and exposure. Screenshots (PNG) show it when it is shown.
    #[arg(long)]
    pub no_panel: bool,
    /// Do not draw the axes marker (the world's x, y, z in red, green, blue in the
    /// bottom-left corner; X toggles it).
    #[arg(long)]
    pub no_axes: bool,
}

#[derive(Args)]
pub struct ReferenceArgs {
    /// Output image (.png: tone mapped 8-bit sRGB; .exr: linear float).
    #[arg(short, long, default_value = "reference.png")]
    pub output: PathBuf,
    /// Photons per voxel side of each light's launch plane (N x N per voxel area).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 8,
        allow_negative_numbers = true
    )]
    pub photons_per_voxel: u32,
    /// Bins of the light volume per voxel side (the light's resolution).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 2,
        allow_negative_numbers = true
    )]
    pub light_bins: u32,
    /// RK4 step of photons and viewing rays, in voxels.
    #[arg(long, default_value_t = 0.1, allow_negative_numbers = true)]
    pub step: f32,
    /// Viewing rays per pixel side (N x N per pixel, averaged).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 1,
        allow_negative_numbers = true
    )]
    pub rays_per_pixel: u32,
    /// Fresnel reflections traced through the volume at most this deep (0: none; the
    /// scene's --reflections off turns them off too).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 3,
        allow_negative_numbers = true
    )]
    pub bounces: u32,
    /// How eta is interpolated between voxels: "cubic" (the cubic B-spline of the values:
    /// smooth surfaces of glass) or "trilinear" (as the GPU samples it, and the photon
    /// tracer; its iso-surfaces are corrugated, which turns rays through a voxelised
    /// ball by about 1° RMS, up to 3°, and the view through glass into speckle). The
    /// matter's colour and opacity are trilinear either way.
    #[arg(long, value_name = "cubic|trilinear", default_value = "cubic",
          value_parser = ["cubic", "trilinear"])]
    pub eta_interpolation: String,
    /// Worker threads, 1 to 1024 [default: all cores].
    #[arg(long, value_parser = parse_threads)]
    pub threads: Option<usize>,
    /// Refuse a phase (the light, the view) of more RK4 steps than this, estimated before
    /// tracing; the default is about 40 minutes on 2 cores.
    #[arg(long, value_name = "N", default_value_t = refrakt::photons::PhotonOptions::DEFAULT_MAX_STEPS)]
    pub max_steps: f64,
    #[command(flatten)]
    pub scene: SceneArgs,
}

#[derive(Args)]
pub struct PhotonsArgs {
    /// Plane of the sweep (0-based, with the scene's --sample-distance), as in
    /// `render --dump light-colour@K`.
    #[arg(
        long,
        value_name = "K",
        required_unless_present = "depth",
        conflicts_with = "depth"
    )]
    pub plane: Option<u32>,
    /// View depth of the plane instead of a plane number.
    #[arg(long, value_name = "Z", allow_negative_numbers = true)]
    pub depth: Option<f32>,
    /// Output image (.exr only: rgb = fluence or, with --plane-flux, flux per unit plane
    /// area; a = 0; the layout of the dumps).
    #[arg(short, long, default_value = "photons.exr")]
    pub output: PathBuf,
    /// Photons per pixel of the plane (round(sqrt(N)) per axis).
    #[arg(long, default_value_t = 64, allow_negative_numbers = true)]
    pub photons_per_pixel: u32,
    /// RK4 step in voxels.
    #[arg(long, default_value_t = 0.1, allow_negative_numbers = true)]
    pub step: f32,
    /// Jitter photons within their launch cells (stratified) instead of a regular grid.
    #[arg(long)]
    pub jitter: bool,
    /// Tally the flux per unit plane area (what crosses the plane: summed over the
    /// plane, the power through it) instead of the fluence (the flux per unit area across
    /// each photon, cos θ₀ / cos θ of it, what `render`'s light planes hold and matter
    /// scatters)
    #[arg(long)]
    pub plane_flux: bool,
    /// Seed of the jitter.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
    /// Worker threads, 1 to 1024 [default: all cores].
    #[arg(long, value_parser = parse_threads)]
    pub threads: Option<usize>,
    /// Refuse a job of more RK4 steps than this, estimated before tracing (photons ×
    /// straight path / step); the default is about 40 minutes on 2 cores.
    #[arg(long, value_name = "N", default_value_t = refrakt::photons::PhotonOptions::DEFAULT_MAX_STEPS)]
    pub max_steps: f64,
    #[command(flatten)]
    pub scene: SceneArgs,
}
