//! The command line's syntax (clap): every subcommand, flag and its help text.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

use refrakt::render::{Levers, LightTransport, Model};

pub use super::bench_args::*;

/// `--variant`'s value: the sweep's levers (`Levers::parse`).
pub(super) fn parse_variant(s: &str) -> Result<Levers, String> {
    Levers::parse(s).map_err(|e| format!("{e:#}"))
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
    /// Reference CPU photon tracer: the irradiance of the scene's light on one plane of
    /// the sweep (--plane K, as `render --dump light-colour@K`) or at a view depth,
    /// written as linear EXR; the oracle for the sweep's caustics, shadows and power.
    Photons(Box<PhotonsArgs>),
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
    /// Worker threads [default: all cores].
    #[arg(long)]
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

/// Scene options shared by `render` and `view`.
#[derive(Args, Clone)]
pub struct SceneArgs {
    /// What to render: a built-in scene name (see --list-scenes; default
    /// sphere-on-floor), a scene file (.toml, see README "Scene files"), or a volume file
    /// (.raw, .nrrd, .nhdr, .nii, .nii.gz, .mhd, .mha, .vti, or a DICOM directory).
    /// Flags below override the scene's fields.
    #[arg(value_name = "SCENE")]
    pub scene: Option<String>,
    /// List the built-in scenes and exit.
    #[arg(help_heading = "Input", long)]
    pub list_scenes: bool,
    /// List the transfer-function presets (--tf NAME) and exit.
    #[arg(help_heading = "Input", long)]
    pub list_presets: bool,
    /// Same as the SCENE argument (kept for scripts).
    #[arg(
        help_heading = "Input",
        long = "scene",
        value_name = "SCENE",
        conflicts_with = "scene"
    )]
    pub scene_flag: Option<String>,
    /// Folder of fetched data (scripts/fetch-data) and of thesis originals that replace the
    /// stand-ins (<name>.<ext>, e.g. supernova.nrrd). Default: $REFRAKT_DATA_DIR or
    /// ~/.cache/refrakt/data.
    #[arg(help_heading = "Input", long, value_name = "DIR")]
    pub data_dir: Option<PathBuf>,
    /// Voxels per side of a procedural scene [scene default: 128].
    #[arg(help_heading = "Input", long, allow_negative_numbers = true)]
    pub volume_size: Option<u32>,
    /// Fraction of a thesis stand-in's resolution (e.g. 0.25) [scene default: 1].
    #[arg(help_heading = "Input", long, allow_negative_numbers = true)]
    pub scale: Option<f64>,
    /// Raw volume files: dimensions "X,Y,Z" (with --type). Files named
    /// <name>_<X>x<Y>x<Z>_<type>.raw need neither.
    #[arg(help_heading = "Input", long, value_name = "X,Y,Z")]
    pub dims: Option<String>,
    /// Raw volume files: voxel type u8, u16, i16 or f32 (little endian).
    #[arg(help_heading = "Input", long = "type", value_name = "TYPE")]
    pub voxel_type: Option<String>,
    /// Voxel spacing "X,Y,Z" (overrides the file's).
    #[arg(help_heading = "Input", long, value_name = "X,Y,Z")]
    pub spacing: Option<String>,
    /// Mirror the volume along these axes after loading, e.g. "xy" (two axes = a 180°
    /// turn, keeping handedness), or "none" to undo a scene's flip.
    #[arg(help_heading = "Input", long, value_name = "AXES")]
    pub flip: Option<String>,
    /// "on" (the default for volume files): turn the patient upright, head up and facing
    /// the camera, when the file states its orientation (NIfTI sform/qform, NRRD space
    /// directions, DICOM ImageOrientationPatient); "off": keep the file's voxel axes.
    #[arg(help_heading = "Input", long, value_name = "on|off")]
    pub upright: Option<String>,
    /// Where the voxel axes point in the patient, as three letters naming the side each
    /// of x, y, z points towards (the DICOM/NIfTI convention): RAS, LPS, LAS, PIR, ...
    /// Replaces what the file states (or supplies what a raw file cannot); the volume is
    /// then turned upright, head up and facing the camera. For volume files.
    #[arg(help_heading = "Input", long, value_name = "CODE")]
    pub orientation: Option<String>,
    /// Turn the volume about the world's axes (x right, y up, z towards the camera) after
    /// loading and turning it upright, before --flip: quarter turns in the order given,
    /// right-handed (x90 turns up to towards the camera), e.g. "x90" or "y-90,z180".
    #[arg(
        help_heading = "Input",
        long,
        value_name = "TURNS",
        allow_hyphen_values = true
    )]
    pub rotate: Option<String>,
    /// Value window "LO,HI" mapped to [0,1] for signed or float data (e.g. CT Hounsfield
    /// units -1000,2000); default: the data's minimum and maximum. See docs/FORMATS.md.
    #[arg(
        help_heading = "Input",
        long,
        value_name = "LO,HI",
        allow_hyphen_values = true
    )]
    pub window: Option<String>,
    /// Transfer functions: a preset (see README) or a TOML file [scene default].
    #[arg(help_heading = "Look", long, value_name = "PRESET|FILE")]
    pub tf: Option<String>,
    /// Label volumes (segmentations): "auto" (default) takes a volume file of at most 64
    /// distinct integer values, with no --tf, as a label map; "on" forces it with the
    /// built-in palette; FILE colours the labels from a colour table (3D Slicer
    /// `index name R G B A`, or ITK-SNAP's label description); "off" treats the values as
    /// a scan. Each label gets its own colour and opacity (label 0 none), and each sample
    /// is classified by its nearest voxel (a segment between two labels is half each).
    #[arg(help_heading = "Look", long, value_name = "auto|on|off|FILE")]
    pub labels: Option<String>,
    /// Rendering model [default: refract].
    #[arg(help_heading = "Look", long, value_enum)]
    pub model: Option<ModelArg>,
    /// Sample the transfer function at each step instead of using the preintegration table.
    #[arg(help_heading = "Look", long)]
    pub no_preintegration: bool,
    /// Image width in pixels [default: 512; thesis stand-ins 768].
    #[arg(help_heading = "Image", long, allow_negative_numbers = true)]
    pub width: Option<u32>,
    /// Image height in pixels [default: 512; thesis stand-ins 768].
    #[arg(help_heading = "Image", long, allow_negative_numbers = true)]
    pub height: Option<u32>,
    /// Distance between samples in units of the smallest voxel side (1 = one sample per
    /// voxel, as in the thesis' chapter 6) [default: 1].
    #[arg(help_heading = "Look", long, allow_negative_numbers = true)]
    pub sample_distance: Option<f32>,
    /// Camera azimuth in degrees around the vertical axis [scene default].
    #[arg(help_heading = "Camera", long, allow_negative_numbers = true)]
    pub azimuth: Option<f32>,
    /// Camera elevation in degrees, -90 (looking straight up) to 90 (straight down)
    /// [scene default].
    #[arg(help_heading = "Camera", long, allow_negative_numbers = true)]
    pub elevation: Option<f32>,
    /// Camera distance from the target, the volume centre unless --target (the volume's
    /// longest side is 1) [scene default].
    #[arg(help_heading = "Camera", long, allow_negative_numbers = true)]
    pub distance: Option<f32>,
    /// Vertical field of view in degrees [default: 35].
    #[arg(help_heading = "Camera", long, allow_negative_numbers = true)]
    pub fov: Option<f32>,
    /// World-space point "x,y,z" the camera orbits and looks at; --azimuth, --elevation
    /// and --distance are taken around it [scene default: 0,0,0, the volume centre].
    #[arg(
        help_heading = "Camera",
        long,
        value_name = "X,Y,Z",
        allow_hyphen_values = true
    )]
    pub target: Option<String>,
    /// Background colour behind the volume, linear "r,g,b" or "r,g,b,a"; it replaces the
    /// environment (sets --env none; with --env MAP it is an error) [default:
    /// 0.08,0.08,0.1,1].
    #[arg(help_heading = "Environment", long, allow_hyphen_values = true)]
    pub background: Option<String>,
    /// A light, repeatable; the first is the main light. "X,Y,Z" or "dir:X,Y,Z": a
    /// directional light, the world-space direction towards it; "point:X,Y,Z": a point
    /// light at that world position (the volume's box is centred at 0 with its longest
    /// half side 1); either optionally followed by "@R,G,B" (linear colour; a point
    /// light's is the irradiance at distance 1). The refract, ao and single models take
    /// one directional light; for the sweep it must lie in the viewer's hemisphere (the
    /// sweep runs front to back, so light cannot come from behind the volume). The
    /// ambient model takes up to 4, directional or point. Default: one light from above,
    /// tilted towards the camera. "env" (first only): direction and colour from the
    /// environment map's brightest region (its irradiance, in the map's units: a night
    /// map gives a night scene).
    #[arg(
        help_heading = "Light",
        long,
        value_name = "X,Y,Z|dir:X,Y,Z|point:X,Y,Z[@R,G,B]|env",
        allow_hyphen_values = true
    )]
    pub light: Vec<String>,
    /// The main light's colour, linear "r,g,b" [default: 1,1,1].
    #[arg(help_heading = "Light", long)]
    pub light_colour: Option<String>,
    /// Ambient level, linear "r,g,b": every sample of the refract model is lit by it
    /// besides the light, unoccluded (particles return colour × ambient, as they return
    /// colour × the light's colour; a uniform environment of radiance L gives L)
    /// [default: 0,0,0; with --light env the environment map's mean radiance outside the
    /// light's region].
    #[arg(help_heading = "Light", long, value_name = "R,G,B")]
    pub ambient_level: Option<String>,
    /// Ambient occlusion (--model ao): half-size, in voxels, of the largest cube around a
    /// sample whose extinction occludes it; a power of two (the cubes double from 1)
    /// [default: 16].
    #[arg(
        help_heading = "Scattering models (ao, single, ambient)",
        long,
        value_name = "VOXELS"
    )]
    pub ao_radius: Option<u32>,
    /// Ambient occlusion (--model ao): weight of the light's Lambert term (gradient
    /// normal, unshadowed) against the ambient term, 0-1 [default: 0.5].
    #[arg(
        help_heading = "Scattering models (ao, single, ambient)",
        long,
        value_name = "W",
        allow_negative_numbers = true
    )]
    pub ao_diffuse: Option<f32>,
    /// Scattering models (--model single, ambient): Henyey-Greenstein anisotropy of the phase
    /// function, -0.99 to 0.99; 0 isotropic, positive forward scattering [default: 0].
    #[arg(
        help_heading = "Scattering models (ao, single, ambient)",
        long,
        value_name = "G",
        allow_negative_numbers = true
    )]
    pub g: Option<f32>,
    /// Scattering models (--model single, ambient): albedo, the fraction of the extinguished light
    /// that is scattered, 0-1 [default: 0.9].
    #[arg(
        help_heading = "Scattering models (ao, single, ambient)",
        long,
        allow_negative_numbers = true
    )]
    pub albedo: Option<f32>,
    /// Ambient scattering (--model ambient): radius r of the sphere around each sample in
    /// which light scatters, in voxels, 0.5-64: the size of the soft shadows and of the
    /// translucency [default: 6].
    #[arg(
        help_heading = "Scattering models (ao, single, ambient)",
        long,
        value_name = "VOXELS",
        allow_negative_numbers = true
    )]
    pub ambient_radius: Option<f32>,
    /// Deprecated: give --light again. Another light after the main one, as --light
    /// takes it.
    #[arg(
        help_heading = "Scattering models (ao, single, ambient)",
        hide = true,
        long,
        value_name = "LIGHT",
        allow_hyphen_values = true
    )]
    pub add_light: Vec<String>,
    /// Ambient scattering (--model ambient): the preintegrated table to use, a file written
    /// by `refrakt precompute ambient --out` (its albedo must be the scene's). Default: the
    /// cached table for --albedo, built on first use (about a minute on 2 cores).
    #[arg(
        help_heading = "Scattering models (ao, single, ambient)",
        long,
        value_name = "FILE"
    )]
    pub ambient_table: Option<PathBuf>,
    /// Light softness: radius, in voxels, of the elliptical filter applied to the light at
    /// every plane; 0 = hard shadows and sharp caustics (refract) [default: 0.5].
    #[arg(help_heading = "Light", long, allow_negative_numbers = true)]
    pub softness: Option<f32>,
    /// GGX roughness of the specular highlights (refract) [default: 0.3].
    #[arg(help_heading = "Look", long, allow_negative_numbers = true)]
    pub roughness: Option<f32>,
    /// Specular strength; 0 turns highlights off (refract) [default: 1].
    #[arg(help_heading = "Look", long, allow_negative_numbers = true)]
    pub specular: Option<f32>,
    /// Refractive-index scale k: the sweep uses eta' = 1 + k (eta_tf - 1); 0 turns
    /// refraction off, 1 is the transfer function's eta (refract) [default: 1].
    #[arg(help_heading = "Look", long, allow_negative_numbers = true)]
    pub eta_scale: Option<f32>,
    /// How light travels from plane to plane (refract): "forward" advances every light
    /// ray on its own and splats its flux onto each plane, so light is conserved through
    /// foci and caustics land where geometric optics puts them; "backward" is the thesis'
    /// semi-Lagrangian step (one direction per pixel, gain bounded per plane), kept for
    /// comparison [default: forward].
    #[arg(help_heading = "Light", long, value_name = "forward|backward")]
    pub light_transport: Option<String>,
    /// Forward light transport: light rays per screen pixel, 1 to 8 (refract). The rays
    /// cover the light's whole domain at the nearest plane's pixel pitch as far as this
    /// budget allows; more resolve oblique light and caustics more finely, at a cost
    /// proportional to their number [default: 2].
    #[arg(
        help_heading = "Light",
        long,
        value_name = "N",
        allow_negative_numbers = true
    )]
    pub light_rays: Option<u32>,
    /// Forward light transport: the light rays' spacing in pixels of the nearest plane,
    /// 0.25 to 4 (refract). Below 1 the rays resolve caustics finer than the pixels (0.5:
    /// four times the rays, closer to a photon tracer's irradiance); above 1 they are
    /// fewer and faster, and caustics blur. The time of the light transport grows with
    /// 1 / spacing²; --light-rays bounds the rays' number, and `render` says when that
    /// bound widened the spacing [default: 1].
    #[arg(help_heading = "Light", long, value_name = "PIXELS")]
    pub light_spacing: Option<f32>,
    /// Fresnel reflection of viewing rays at changes of η (refract): the reflected part
    /// sees the environment (or background) in the mirrored direction, not occluded by
    /// the volume; "off" is the thesis' model, everything transmitted [default: on].
    #[arg(help_heading = "Look", long, value_name = "on|off")]
    pub reflections: Option<String>,
    /// Clipping plane "nx,ny,nz,offset" in world space: opacity is zero where
    /// n·p > offset, the medium and refraction stay (refract, thesis Fig. 6.6); "none"
    /// removes a scene's plane.
    #[arg(
        help_heading = "Look",
        long,
        value_name = "NX,NY,NZ,D|none",
        allow_hyphen_values = true
    )]
    pub clip: Option<String>,
    /// Environment map behind the volume (refract): an equirectangular .exr or .hdr
    /// (linear), .png or .jpg (sRGB), twice as wide as high; "sky" for the built-in sky,
    /// sun and checkered ground; "none" for the flat --background [default: sky for the
    /// built-in scenes and scene files, none for a bare volume file].
    #[arg(help_heading = "Environment", long, value_name = "FILE|sky|none")]
    pub env: Option<String>,
    /// Rotation of the environment map about the vertical axis, degrees [default: 0].
    #[arg(help_heading = "Environment", long, allow_negative_numbers = true)]
    pub env_rotation: Option<f32>,
    /// Exposure in stops applied before tone mapping (PNG output and the window)
    /// [default: 0].
    #[arg(help_heading = "Image", long, allow_negative_numbers = true)]
    pub exposure: Option<f32>,
    /// Tone mapping for PNG output: aces (filmic), reinhard, or none (clamp). EXR output is
    /// always the linear HDR image [default: aces].
    #[arg(help_heading = "Image", long, value_enum)]
    pub tonemap: Option<ToneArg>,
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
    /// light-colour is the plane's irradiance and light-direction its luminance-weighted
    /// direction sum (weight in alpha); light-rays / light-ray-directions are the rays
    /// themselves. Files go to --dump-dir as BUFFER-PLANE.exr; each header (and the log)
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
    /// Output image (.exr only: rgb = irradiance, a = 0, the layout of the dumps).
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
    /// Seed of the jitter.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
    /// Worker threads [default: all cores].
    #[arg(long)]
    pub threads: Option<usize>,
    /// Refuse a job of more RK4 steps than this, estimated before tracing (photons ×
    /// straight path / step); the default is about 40 minutes on 2 cores.
    #[arg(long, value_name = "N", default_value_t = refrakt::photons::PhotonOptions::DEFAULT_MAX_STEPS)]
    pub max_steps: f64,
    #[command(flatten)]
    pub scene: SceneArgs,
}
