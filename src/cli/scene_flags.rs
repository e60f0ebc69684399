//! The flags every command that draws a scene takes (`render`, `view`, `photons`): the
//! scene, its volume, transfer functions, camera, light, environment and the model's
//! options, each overriding what the scene says.

use std::path::PathBuf;

use clap::Args;

use super::args::*;

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
    /// Camera distance from the target, the volume centre unless --target, up to 1000 (the volume's
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
    /// sweep runs front to back, so light cannot come from behind the volume), except
    /// with --light-transport eikonal. The ambient and eikonal models take up to 4,
    /// directional or point. Default: one light from above,
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
    /// The models' own options (`--ao-radius`, `--g`...), from their declarations.
    #[command(flatten)]
    pub model_options: super::model_flags::ModelFlags,
    /// Deprecated: give --light again. Another light after the main one, as --light
    /// takes it.
    #[arg(
        help_heading = "Light",
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
        help_heading = super::model_flags::HEADING,
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
    /// comparison; "eikonal" simulates the light first, as the eikonal model does
    /// (adaptive wavefronts into a light volume; minutes on lavapipe at 64³, again only
    /// when the light or the transfer functions change), and the viewing rays read it
    /// there: light from any direction, also against the sweep, and no --softness
    /// [default: forward].
    #[arg(help_heading = "Light", long, value_name = "forward|backward|eikonal")]
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
    /// Fresnel reflection of viewing rays at changes of η (refract, eikonal). refract:
    /// "volume" (the default, also "on"): the first face's reflected ray is traced
    /// through the volume, lit by the light the sweep computed (glass shows the floor it
    /// stands on), later faces' see the environment; "environment": every reflected
    /// part sees the environment (or background) in the mirrored direction, not
    /// occluded by the volume. eikonal always traces the first face's reflection
    /// through the volume. "off" is the thesis' model, everything transmitted
    /// [default: on].
    #[arg(help_heading = "Look", long, value_name = "on|off|environment|volume")]
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
    /// Exposure in stops applied before tone mapping (PNG output and the window), -64 to 64
    /// [default: 0].
    #[arg(help_heading = "Image", long, allow_negative_numbers = true)]
    pub exposure: Option<f32>,
    /// Tone mapping for PNG output: aces (filmic), reinhard, or none (clamp). EXR output is
    /// always the linear HDR image [default: aces].
    #[arg(help_heading = "Image", long, value_enum)]
    pub tonemap: Option<ToneArg>,
}
