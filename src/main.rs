//! `refrakt` command line: `info` (devices), `render` (one frame to an image, with GPU
//! timings), `view` (the interactive viewer), `photons` (the CPU photon tracer's reference),
//! `generate` (write a stand-in volume) and `bench` (the timing tables).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, ensure, Context as _, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};

use refrakt::output;
use refrakt::render::{Camera, Model, Renderer, StateBuffer};
use refrakt::scene::{self, EnvSource, LoadedScene, Scene, TransferSource, VolumeSource};
use refrakt::viewer::{self, ViewOptions};
use refrakt::vk::{self, Context, ContextDesc};
use refrakt::volume::formats::RawLayout;
use refrakt::volume::standins;

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
struct Cli {
    #[command(flatten)]
    gpu: GpuArgs,
    #[command(subcommand)]
    command: Command,
}

#[derive(Args)]
struct GpuArgs {
    /// Vulkan device to use: an index from `refrakt info` or part of its name
    /// (e.g. "llvmpipe"). Default: discrete > integrated > virtual > CPU.
    #[arg(long, global = true, value_name = "NAME|INDEX")]
    device: Option<String>,
    /// Enable the Khronos validation layer with synchronization validation; the command
    /// exits with status 3 if the layer reports any warning or error.
    #[arg(long, global = true)]
    validate: bool,
}

#[derive(Subcommand)]
enum Command {
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
    /// Benchmarks: the thesis' timing tables (6.1, 6.2) on this device, and how the
    /// sweep's cost scales with planes and pixels. GPU timestamps; see docs/BENCH.md.
    #[command(subcommand)]
    Bench(BenchCommand),
}

#[derive(Subcommand)]
enum BenchCommand {
    /// One row per data set of Tables 6.1 and 6.2 (stand-ins at the thesis' resolutions
    /// unless --data-dir holds the originals): 768² viewport, sample distance 1, 100
    /// frames, the camera orbiting 0.5° per frame; the thesis' figures beside ours.
    Thesis(ThesisArgs),
    /// Sweep time against plane count (several sample distances) and against pixel count
    /// (several viewports), with least-squares fits.
    Scaling(ScalingArgs),
}

#[derive(Args)]
struct GenerateArgs {
    /// Stand-ins to generate (supernova, piggy-bank, glass, hand, head, water, ship,
    /// kiwi); default: all.
    #[arg(value_delimiter = ',')]
    names: Vec<String>,
    /// Fraction of the thesis resolution.
    #[arg(long, default_value_t = 1.0)]
    scale: f64,
}

#[derive(Args)]
struct ThesisArgs {
    /// Shrinks viewport and volume together (e.g. 0.25 on lavapipe, where a full-size
    /// frame takes tens of seconds). Printed in the table.
    #[arg(long, default_value_t = 1.0)]
    scale: f64,
    /// Measured frames per row (the thesis: 100).
    #[arg(long, default_value_t = 100)]
    frames: u32,
    /// Warm-up frames per row and variant, excluded from the statistics (reported).
    #[arg(long, default_value_t = 3)]
    warmup: u32,
    /// Rows to run, comma-separated (supernova, piggy-bank, glass, hand, head, water, ship,
    /// kiwi). Default: all.
    #[arg(long, value_delimiter = ',')]
    rows: Vec<String>,
    /// Also time the EA ray marcher and the sweep's floor variant (same buffers, trivial
    /// shader) per row, and print the ratios.
    #[arg(long)]
    baselines: bool,
    /// Folder with the thesis originals (<name>.<ext>, e.g. supernova.nrrd) that replace
    /// the stand-ins. Default: $REFRAKT_DATA_DIR or ~/.cache/refrakt/data.
    #[arg(long, value_name = "DIR")]
    data_dir: Option<PathBuf>,
    /// Write every frame time with the full context as CSV.
    #[arg(long, value_name = "FILE.csv")]
    csv: Option<PathBuf>,
    /// Write the whole report as JSON (schema in docs/BENCH.md).
    #[arg(long, value_name = "FILE.json")]
    json: Option<PathBuf>,
    /// Draw the thesis' mean frame times beside ours as an SVG bar chart.
    #[arg(long, value_name = "FILE.svg")]
    plot: Option<PathBuf>,
    /// No progress bar on stderr.
    #[arg(long)]
    quiet: bool,
}

#[derive(Args)]
struct ScalingArgs {
    /// Scene to time (any `refrakt render` scene).
    #[arg(long, default_value = "sphere-on-floor")]
    scene: String,
    /// Voxels per side for a procedural scene.
    #[arg(long, default_value_t = 64)]
    volume_size: u32,
    /// Sample distances for the plane-count series.
    #[arg(long, value_delimiter = ',', default_value = "0.5,1,2,4")]
    sample_distances: Vec<f32>,
    /// Viewport sides for the pixel-count series.
    #[arg(long, value_delimiter = ',', default_value = "64,96,128,192")]
    sides: Vec<u32>,
    /// Viewport side for the plane-count series.
    #[arg(long, default_value_t = 128)]
    side: u32,
    /// Measured frames per point (after one warm-up).
    #[arg(long, default_value_t = 3)]
    frames: u32,
    /// Write the report as JSON.
    #[arg(long, value_name = "FILE.json")]
    json: Option<PathBuf>,
    /// Folder of fetched data (see `render --data-dir`).
    #[arg(long, value_name = "DIR")]
    data_dir: Option<PathBuf>,
    /// No progress bar on stderr.
    #[arg(long)]
    quiet: bool,
}

#[derive(Clone, Copy, ValueEnum)]
enum ToneArg {
    Aces,
    Reinhard,
    None,
}

#[derive(Clone, Copy, ValueEnum)]
enum ModelArg {
    /// The refractive plane sweep: refraction, caustics, soft shadows, tinted media.
    Refract,
    /// Emission-absorption ray marcher (the baseline).
    Ea,
}

/// Scene options shared by `render` and `view`.
#[derive(Args, Clone)]
struct SceneArgs {
    /// What to render: a built-in scene name (see --list-scenes; default
    /// sphere-on-floor), a scene file (.toml, see README "Scene files"), or a volume file
    /// (.raw, .nrrd, .nhdr, .nii, .nii.gz, .mhd, .mha, .vti, or a DICOM directory).
    /// Flags below override the scene's fields.
    #[arg(value_name = "SCENE")]
    scene: Option<String>,
    /// Same as the SCENE argument (kept for scripts).
    #[arg(long = "scene", value_name = "SCENE", conflicts_with = "scene")]
    scene_flag: Option<String>,
    /// Folder of fetched data (scripts/fetch-data) and of thesis originals that replace the
    /// stand-ins (<name>.<ext>, e.g. supernova.nrrd). Default: $REFRAKT_DATA_DIR or
    /// ~/.cache/refrakt/data.
    #[arg(long, value_name = "DIR")]
    data_dir: Option<PathBuf>,
    /// Voxels per side of a procedural scene [scene default: 128].
    #[arg(long)]
    volume_size: Option<u32>,
    /// Fraction of a thesis stand-in's resolution (e.g. 0.25) [scene default: 1].
    #[arg(long)]
    scale: Option<f64>,
    /// Raw volume files: dimensions "X,Y,Z" (with --type). Files named
    /// <name>_<X>x<Y>x<Z>_<type>.raw need neither.
    #[arg(long, value_name = "X,Y,Z")]
    dims: Option<String>,
    /// Raw volume files: voxel type u8, u16, i16 or f32 (little endian).
    #[arg(long = "type", value_name = "TYPE")]
    voxel_type: Option<String>,
    /// Voxel spacing "X,Y,Z" (overrides the file's).
    #[arg(long, value_name = "X,Y,Z")]
    spacing: Option<String>,
    /// Mirror the volume along these axes after loading, e.g. "xy" (two axes = a 180°
    /// turn, keeping handedness), or "none" to undo a scene's flip.
    #[arg(long, value_name = "AXES")]
    flip: Option<String>,
    /// Value window "LO,HI" mapped to [0,1] for signed or float data (e.g. CT Hounsfield
    /// units -1000,2000); default: the data's minimum and maximum. See docs/FORMATS.md.
    #[arg(long, value_name = "LO,HI", allow_hyphen_values = true)]
    window: Option<String>,
    /// Transfer functions: a preset (see README) or a TOML file [scene default].
    #[arg(long, value_name = "PRESET|FILE")]
    tf: Option<String>,
    /// Rendering model [default: refract].
    #[arg(long, value_enum)]
    model: Option<ModelArg>,
    /// Sample the transfer function at each step instead of using the preintegration table.
    #[arg(long)]
    no_preintegration: bool,
    /// Image width in pixels [default: 512; thesis stand-ins 768].
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels [default: 512; thesis stand-ins 768].
    #[arg(long)]
    height: Option<u32>,
    /// Distance between samples in units of the smallest voxel side (1 = one sample per
    /// voxel, as in the thesis' chapter 6) [default: 1].
    #[arg(long, allow_negative_numbers = true)]
    sample_distance: Option<f32>,
    /// Camera azimuth in degrees around the vertical axis [scene default].
    #[arg(long, allow_negative_numbers = true)]
    azimuth: Option<f32>,
    /// Camera elevation in degrees, -90 (looking straight up) to 90 (straight down)
    /// [scene default].
    #[arg(long, allow_negative_numbers = true)]
    elevation: Option<f32>,
    /// Camera distance from the target, the volume centre unless --target (the volume's
    /// longest side is 1) [scene default].
    #[arg(long, allow_negative_numbers = true)]
    distance: Option<f32>,
    /// Vertical field of view in degrees [default: 35].
    #[arg(long, allow_negative_numbers = true)]
    fov: Option<f32>,
    /// World-space point "x,y,z" the camera orbits and looks at; --azimuth, --elevation
    /// and --distance are taken around it [scene default: 0,0,0, the volume centre].
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    target: Option<String>,
    /// Background colour behind the volume, linear "r,g,b" or "r,g,b,a" (seen with
    /// --env none) [default: 0.08,0.08,0.1,1].
    #[arg(long, allow_hyphen_values = true)]
    background: Option<String>,
    /// World-space direction towards the light, "x,y,z" (refract). It must lie in the
    /// viewer's hemisphere: the sweep runs front to back, so light cannot come from behind
    /// the volume. Default: from above, tilted towards the camera.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    light: Option<String>,
    /// Light colour, linear "r,g,b" (refract) [default: 1,1,1].
    #[arg(long)]
    light_colour: Option<String>,
    /// Light softness: radius, in voxels, of the elliptical filter applied to the light at
    /// every plane; 0 = hard shadows and sharp caustics (refract) [default: 0.5].
    #[arg(long, allow_negative_numbers = true)]
    softness: Option<f32>,
    /// GGX roughness of the specular highlights (refract) [default: 0.3].
    #[arg(long, allow_negative_numbers = true)]
    roughness: Option<f32>,
    /// Specular strength; 0 turns highlights off (refract) [default: 1].
    #[arg(long, allow_negative_numbers = true)]
    specular: Option<f32>,
    /// Refractive-index scale k: the sweep uses eta' = 1 + k (eta_tf - 1); 0 turns
    /// refraction off, 1 is the transfer function's eta (refract) [default: 1].
    #[arg(long, allow_negative_numbers = true)]
    eta_scale: Option<f32>,
    /// How light travels from plane to plane (refract): "forward" advances every light
    /// ray on its own and splats its flux onto each plane, so light is conserved through
    /// foci and caustics land where geometric optics puts them; "backward" is the thesis'
    /// semi-Lagrangian step (one direction per pixel, gain bounded per plane), kept for
    /// comparison [default: forward].
    #[arg(long, value_name = "forward|backward")]
    light_transport: Option<String>,
    /// Forward light transport: light rays per screen pixel, 1 to 8 (refract). The rays
    /// cover the light's whole domain at the nearest plane's pixel pitch as far as this
    /// budget allows; more resolve oblique light and caustics more finely, at a cost
    /// proportional to their number [default: 2].
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    light_rays: Option<u32>,
    /// Fresnel reflection of viewing rays at changes of η (refract): the reflected part
    /// sees the environment (or background) in the mirrored direction, not occluded by
    /// the volume; "off" is the thesis' model, everything transmitted [default: on].
    #[arg(long, value_name = "on|off")]
    reflections: Option<String>,
    /// Clipping plane "nx,ny,nz,offset" in world space: opacity is zero where
    /// n·p > offset, the medium and refraction stay (refract, thesis Fig. 6.6); "none"
    /// removes a scene's plane.
    #[arg(long, value_name = "NX,NY,NZ,D|none", allow_hyphen_values = true)]
    clip: Option<String>,
    /// Environment map behind the volume (refract): an equirectangular .exr or .hdr
    /// (linear), .png or .jpg (sRGB), twice as wide as high; "sky" for the built-in sky,
    /// sun and checkered ground; "none" for the flat --background [default: sky].
    #[arg(long, value_name = "FILE|sky|none")]
    env: Option<String>,
    /// Rotation of the environment map about the vertical axis, degrees [default: 0].
    #[arg(long, allow_negative_numbers = true)]
    env_rotation: Option<f32>,
    /// Exposure in stops applied before tone mapping (PNG output and the window)
    /// [default: 0].
    #[arg(long, allow_negative_numbers = true)]
    exposure: Option<f32>,
    /// Tone mapping for PNG output: aces (filmic), reinhard, or none (clamp). EXR output is
    /// always the linear HDR image [default: aces].
    #[arg(long, value_enum)]
    tonemap: Option<ToneArg>,
}

#[derive(Args)]
struct RenderArgs {
    /// List the built-in scenes and exit.
    #[arg(long)]
    list_scenes: bool,
    /// Output image; the extension picks the format: .png (8-bit sRGB) or .exr (linear).
    #[arg(short, long, default_value = "refrakt.png")]
    output: PathBuf,
    /// Write state buffers after given planes as EXR: "BUFFER@PLANE[,...]" with BUFFER one
    /// of light-colour, light-direction, view-position, view-direction, colour-opacity,
    /// medium, light-rays, light-ray-directions (refract). With the forward light transport
    /// light-colour is the plane's irradiance and light-direction its luminance-weighted
    /// direction sum (weight in alpha); light-rays / light-ray-directions are the rays
    /// themselves. Files go to --dump-dir as BUFFER-PLANE.exr; each header (and the log)
    /// gives the plane's view depth and world-space plane n·p = d and the camera.
    #[arg(long, value_name = "BUFFER@PLANE,...")]
    dump: Option<String>,
    /// Folder for --dump files (default: the output image's folder).
    #[arg(long)]
    dump_dir: Option<PathBuf>,
    /// Also render the EA baseline with the same volume, view, image size and sample
    /// distance in the same run, and print its GPU time and the ratio to this model's
    /// (the comparison the thesis' cost discussion needs; compare ratios on lavapipe).
    #[arg(long)]
    with_baseline: bool,
    #[command(flatten)]
    scene: SceneArgs,
}

#[derive(Args)]
struct ViewArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Present without waiting for the display's vertical blank (mailbox or immediate
    /// presentation where the surface offers one).
    #[arg(long)]
    no_vsync: bool,
    /// Render this many frames, then exit (for tests and scripts).
    #[arg(long, value_name = "N")]
    frames: Option<u64>,
    /// With --frames: write the last frame as shown (PNG, read back from the window's
    /// swapchain image) and as linear EXR, to FILE and FILE with the other extension.
    #[arg(long, value_name = "FILE", requires = "frames")]
    screenshot: Option<PathBuf>,
    /// Ask for a new window size before frame N, "WxH@N" (for tests and scripts); the
    /// viewer waits for the window to take it.
    #[arg(long, value_name = "WxH@N")]
    resize: Option<String>,
    /// Folder for the screenshots the P key writes.
    #[arg(long, default_value = ".", value_name = "DIR")]
    screenshot_dir: PathBuf,
    /// Do not reload the scene when its files (scene file, volume, transfer functions,
    /// environment map) change on disk (R still reloads).
    #[arg(long)]
    no_watch: bool,
}

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn"))
        .format_timestamp(None)
        .init();
    let cli = Cli::parse();
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<ExitCode> {
    let desc = ContextDesc::from_env(cli.gpu.validate, cli.gpu.device.clone());
    match cli.command {
        Command::Info => info(&desc),
        Command::Render(args) => render(&desc, &args),
        Command::View(args) => view(&desc, *args),
        Command::Photons(args) => photons(&args),
        Command::Generate(args) => generate(&args),
        Command::Bench(BenchCommand::Thesis(args)) => bench_thesis(&desc, &args),
        Command::Bench(BenchCommand::Scaling(args)) => bench_scaling(&desc, &args),
    }
}

fn finish(ctx: Context) -> Result<ExitCode> {
    let log = ctx.validation_log();
    drop(ctx);
    let n = log.count();
    if n > 0 {
        eprintln!("validation: {n} message(s) reported (see above)");
        return Ok(ExitCode::from(3));
    }
    Ok(ExitCode::SUCCESS)
}

fn info(desc: &ContextDesc) -> Result<ExitCode> {
    let devices = Context::list_devices()?;
    let ctx = Context::new(desc)?;
    println!(
        "Vulkan loader: {}",
        vk::version_string(ctx.loader_version())
    );
    println!("Devices:");
    for d in &devices {
        let mark = if d.index == ctx.info().index {
            "*"
        } else {
            " "
        };
        println!(
            " {mark}[{}] {} ({}), Vulkan {}",
            d.index,
            d.name,
            vk::device_type_name(d.device_type),
            vk::version_string(d.api_version)
        );
    }
    let i = ctx.info();
    let l = &i.limits;
    println!("\nSelected: [{}] {}", i.index, i.name);
    println!(
        "  type:                   {}",
        vk::device_type_name(i.device_type)
    );
    println!(
        "  Vulkan version:         {}",
        vk::version_string(i.api_version)
    );
    println!(
        "  driver:                 {} ({})",
        i.driver_name, i.driver_info
    );
    println!("  max 3D image size:      {}", l.max_image_dimension3_d);
    println!("  max 2D image size:      {}", l.max_image_dimension2_d);
    println!("  max array layers:       {}", l.max_image_array_layers);
    println!(
        "  max push constants:     {} bytes",
        l.max_push_constants_size
    );
    println!("  max colour attachments: {}", l.max_color_attachments);
    println!(
        "  timestamps:             {} (period {} ns)",
        if i.timestamps { "yes" } else { "no" },
        l.timestamp_period
    );
    println!("  memory heaps:");
    for (n, (size, device_local)) in i.memory_heaps.iter().enumerate() {
        let local = if *device_local {
            "device-local"
        } else {
            "host"
        };
        println!(
            "    [{n}] {:.1} GiB {local}",
            *size as f64 / (1u64 << 30) as f64
        );
    }
    finish(ctx)
}

/// GPU time of a frame's rendering passes, without the one-off builds (preintegration
/// table, environment SAT) that happen only when their inputs change.
fn main_pass_ms(frame: &refrakt::render::Frame) -> f64 {
    frame.timings.get("render").unwrap_or(0.0)
}

fn parse_floats<const N: usize>(flag: &str, s: &str) -> Result<[f32; N]> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != N {
        bail!("{flag} '{s}': expected {N} comma-separated numbers");
    }
    let mut out = [0.0; N];
    for (i, p) in parts.iter().enumerate() {
        out[i] = p
            .parse::<f32>()
            .ok()
            .filter(|v| v.is_finite())
            .with_context(|| format!("{flag} '{s}': '{p}' is not a finite number"))?;
    }
    Ok(out)
}

fn parse_dumps(s: &str) -> Result<Vec<(StateBuffer, u32)>> {
    s.split(',')
        .map(|item| {
            let (b, p) = item.trim().split_once('@').with_context(|| {
                format!("--dump '{item}': expected BUFFER@PLANE, e.g. light-colour@10")
            })?;
            let plane = p
                .parse::<u32>()
                .with_context(|| format!("--dump '{item}': '{p}' is not a plane number"))?;
            Ok((
                StateBuffer::parse(b).with_context(|| format!("--dump '{item}'"))?,
                plane,
            ))
        })
        .collect()
}

fn parse_background(s: &str) -> Result<[f32; 4]> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 && parts.len() != 4 {
        bail!("--background '{s}': expected 3 or 4 comma-separated numbers");
    }
    let mut out = [0.0, 0.0, 0.0, 1.0];
    for (i, p) in parts.iter().enumerate() {
        out[i] = p
            .parse::<f32>()
            .with_context(|| format!("--background '{s}': '{p}' is not a number"))?;
    }
    Ok(out)
}

/// The scene the arguments name, with every given flag applied over it.
fn scene_from_args(args: &SceneArgs) -> Result<Scene> {
    let name = args
        .scene
        .as_deref()
        .or(args.scene_flag.as_deref())
        .unwrap_or("sphere-on-floor");
    let mut s = Scene::resolve(name)?;
    if let Some(n) = args.volume_size {
        match &mut s.volume {
            VolumeSource::Procedural { size, .. } => *size = n,
            _ => bail!("--volume-size applies to procedural scenes; '{name}' is not one"),
        }
    }
    if let Some(f) = args.scale {
        match &mut s.volume {
            VolumeSource::Standin { scale, .. } => *scale = f,
            _ => bail!("--scale applies to the thesis stand-ins; '{name}' is not one"),
        }
    }
    let window = match &args.window {
        Some(w) => {
            let [lo, hi] = parse_floats::<2>("--window", w)?;
            ensure!(lo < hi, "--window '{w}': low must be below high");
            Some((lo, hi))
        }
        None => None,
    };
    let raw = match (&args.dims, &args.voxel_type) {
        (Some(d), Some(t)) => {
            let d = parse_floats::<3>("--dims", d)?;
            ensure!(
                d.iter()
                    .all(|&x| x >= 1.0 && x.fract() == 0.0 && x <= u32::MAX as f32),
                "--dims: expected three positive whole numbers"
            );
            Some(RawLayout {
                dims: d.map(|x| x as u32),
                kind: scene::parse_scalar_kind(t).context("--type")?,
                spacing: None,
            })
        }
        (None, None) => None,
        _ => bail!("--dims and --type go together (raw files)"),
    };
    if raw.is_some() || window.is_some() {
        match &mut s.volume {
            VolumeSource::File {
                raw: r, window: w, ..
            } => {
                if raw.is_some() {
                    *r = raw;
                }
                if window.is_some() {
                    *w = window;
                }
            }
            VolumeSource::Fetched { window: w, .. } if raw.is_none() => *w = window,
            _ => bail!("--dims/--type/--window apply to volume files; '{name}' is not one"),
        }
    }
    if let Some(sp) = &args.spacing {
        s.spacing = Some(parse_floats::<3>("--spacing", sp)?);
    }
    let mut o = scene::Overrides::default();
    if let Some(f) = &args.flip {
        o.flip = Some(scene::parse_flip(f).context("--flip")?);
    }
    o.transfer = args.tf.clone().map(TransferSource::Named);
    o.model = args.model.map(|m| match m {
        ModelArg::Ea => Model::Ea,
        ModelArg::Refract => Model::Refract,
    });
    if args.no_preintegration {
        o.preintegrated = Some(false);
    }
    o.width = args.width;
    o.height = args.height;
    o.sample_distance = args.sample_distance;
    o.azimuth = args.azimuth;
    o.elevation = args.elevation;
    o.distance = args.distance;
    o.fov = args.fov;
    if let Some(t) = &args.target {
        o.target = Some(glam::Vec3::from(parse_floats::<3>("--target", t)?));
    }
    o.softness = args.softness;
    o.roughness = args.roughness;
    o.specular = args.specular;
    o.eta_scale = args.eta_scale;
    o.light_rays = args.light_rays;
    if let Some(t) = &args.light_transport {
        o.light_transport =
            Some(refrakt::render::LightTransport::parse(t).context("--light-transport")?);
    }
    if let Some(r) = &args.reflections {
        o.reflections = Some(refrakt::scene::parse_on_off(r).context("--reflections")?);
    }
    o.env_rotation = args.env_rotation;
    if let Some(e) = args.exposure {
        ensure!(
            e.is_finite(),
            "--exposure {e} must be a finite number of stops"
        );
        o.exposure = Some(e);
    }
    if let Some(b) = &args.background {
        o.background = Some(parse_background(b)?);
    }
    if let Some(l) = &args.light {
        o.light_towards = Some(glam::Vec3::from(parse_floats::<3>("--light", l)?));
    }
    if let Some(c) = &args.light_colour {
        o.light_colour = Some(parse_floats::<3>("--light-colour", c)?);
    }
    if let Some(c) = &args.clip {
        o.clip = Some(if c == "none" {
            None
        } else {
            let v = parse_floats::<4>("--clip", c)?;
            Some((glam::Vec3::new(v[0], v[1], v[2]), v[3]))
        });
    }
    if let Some(e) = &args.env {
        o.environment = Some(match e.as_str() {
            "sky" => EnvSource::Sky,
            "none" => EnvSource::None,
            f => EnvSource::File(PathBuf::from(f)),
        });
    }
    o.tonemap = args.tonemap.map(|t| match t {
        ToneArg::Aces => output::ToneOperator::Aces,
        ToneArg::Reinhard => output::ToneOperator::Reinhard,
        ToneArg::None => output::ToneOperator::None,
    });
    s.apply(o);
    Ok(s)
}

fn generate(args: &GenerateArgs) -> Result<ExitCode> {
    let rows = refrakt::bench::select_rows(&args.names)?;
    let dir = standins::cache_dir();
    for d in rows {
        let dims = standins::scaled_dims(d.dims, args.scale).context("--scale")?;
        let file = standins::cache_file(&dir, d.name, dims);
        let t = std::time::Instant::now();
        let (_, cached) = standins::load_or_generate(d.name, dims, &dir)?;
        println!(
            "{:<11} {}x{}x{} {} in {:.2} s: {}",
            d.name,
            dims[0],
            dims[1],
            dims[2],
            if cached {
                "read from cache"
            } else {
                "generated"
            },
            t.elapsed().as_secs_f64(),
            file.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn bench_thesis(desc: &ContextDesc, args: &ThesisArgs) -> Result<ExitCode> {
    standins::scaled_dims([1, 1, 1], args.scale).context("--scale")?;
    ensure!(args.frames >= 1, "--frames must be at least 1");
    refrakt::bench::select_rows(&args.rows).context("--rows")?;
    if let Some(p) = &args.csv {
        refrakt::bench::check_output(p, "csv").context("--csv")?;
    }
    if let Some(p) = &args.json {
        refrakt::bench::check_output(p, "json").context("--json")?;
    }
    if let Some(p) = &args.plot {
        refrakt::bench::check_output(p, "svg").context("--plot")?;
    }
    let ctx = Context::new(desc)?;
    let settings = refrakt::bench::ThesisSettings {
        scale: args.scale,
        frames: args.frames,
        warmup: args.warmup,
        rows: args.rows.clone(),
        baselines: args.baselines,
        data_dir: args.data_dir.clone().unwrap_or_else(scene::data_dir),
        progress: !args.quiet,
    };
    let report = refrakt::bench::thesis(&ctx, &settings)?;
    print!("{}", refrakt::bench::markdown(&report));
    if let Some(p) = &args.csv {
        refrakt::bench::write_csv(&report, p)?;
        println!("\nwrote {}", p.display());
    }
    if let Some(p) = &args.json {
        refrakt::bench::write_json(&report, p)?;
        println!("wrote {}", p.display());
    }
    if let Some(p) = &args.plot {
        refrakt::bench::plot_svg(&report, p)?;
        println!("wrote {}", p.display());
    }
    finish(ctx)
}

fn bench_scaling(desc: &ContextDesc, args: &ScalingArgs) -> Result<ExitCode> {
    let mut s = Scene::resolve(&args.scene)?;
    if let VolumeSource::Procedural { size, .. } = &mut s.volume {
        *size = args.volume_size;
    }
    s.width = args.side;
    s.height = args.side;
    s.render_options()?;
    if let Some(p) = &args.json {
        refrakt::bench::check_output(p, "json").context("--json")?;
    }
    let ctx = Context::new(desc)?;
    let data_dir = args.data_dir.clone().unwrap_or_else(scene::data_dir);
    let r = refrakt::bench::scaling(
        &ctx,
        &s,
        &data_dir,
        &args.sample_distances,
        &args.sides,
        args.frames,
        !args.quiet,
    )?;
    print!("{}", refrakt::bench::scaling_markdown(&r));
    if let Some(p) = &args.json {
        std::fs::write(p, serde_json::to_string_pretty(&r)? + "\n")
            .with_context(|| format!("{}: cannot write", p.display()))?;
        println!("wrote {}", p.display());
    }
    finish(ctx)
}

/// The scene the options describe, loaded: the one place `render` and `view` (and the
/// viewer's reload) get a scene from.
fn build_scene(args: &SceneArgs) -> Result<LoadedScene> {
    let scene = scene_from_args(args)?;
    let data_dir = args.data_dir.clone().unwrap_or_else(scene::data_dir);
    scene.load_all(&data_dir)
}

fn list_scenes() -> Result<ExitCode> {
    println!("Built-in scenes (refrakt render NAME):");
    for (n, d) in scene::builtin_names() {
        println!("  {n:<16} {d}");
    }
    println!("\nA scene file (.toml) or a volume file works too; see README.md.");
    Ok(ExitCode::SUCCESS)
}

fn render(desc: &ContextDesc, args: &RenderArgs) -> Result<ExitCode> {
    if args.list_scenes {
        return list_scenes();
    }
    // Everything that can be checked without the GPU is checked first, so bad input fails
    // at once with a clear message.
    output::format_for(&args.output)?;
    let dumps = match &args.dump {
        Some(d) => parse_dumps(d)?,
        None => Vec::new(),
    };
    let dump_dir = match &args.dump_dir {
        Some(d) => d.clone(),
        None => args
            .output
            .parent()
            .map(|p| p.to_path_buf())
            .unwrap_or_default(),
    };
    if !dumps.is_empty() && !dump_dir.as_os_str().is_empty() && !dump_dir.is_dir() {
        bail!(
            "--dump-dir {}: the folder does not exist",
            dump_dir.display()
        );
    }
    let LoadedScene {
        name,
        volume,
        tf,
        env,
        model,
        camera,
        mut opts,
        tone,
        ..
    } = build_scene(&args.scene)?;
    opts.sweep.dumps = dumps;

    let ctx = Context::new(desc)?;
    println!(
        "device: {} ({})",
        ctx.info().name,
        vk::device_type_name(ctx.info().device_type)
    );
    let mut renderer = Renderer::new(&ctx, &volume, &tf)?;
    let env_timings = if model == Model::Refract {
        renderer.set_environment(env.as_ref())?
    } else {
        Default::default()
    };
    let mut frame = renderer.render(model, &camera, &opts)?;
    // One-off builds first (the gradient volume once per volume, the environment's SAT
    // once per map), then the frame's own passes.
    let mut all = renderer.gradient_timings().clone();
    all.extend(env_timings);
    all.extend(std::mem::take(&mut frame.timings));
    frame.timings = all;
    output::write(&frame, &args.output, &tone)?;
    println!(
        "rendered {}x{} of the {} scene ({}x{}x{}, transfer functions {}), model {}{}, sample distance {}, up to {} steps per ray",
        opts.width,
        opts.height,
        name,
        volume.dims[0],
        volume.dims[1],
        volume.dims[2],
        tf.name,
        model.name(),
        if opts.preintegrated { " (preintegrated)" } else { "" },
        opts.sample_distance,
        frame.max_steps
    );
    if let refrakt::render::gradient::GradientStatus::TooLarge { needed, budget } =
        renderer.gradient_status()
    {
        println!(
            "note: the gradient volume would need {} MiB (budget {} MiB, half the device's \
             largest heap): surface normals computed on the fly instead (3D Sobel, ~1.5° \
             less accurate at faces of glass; docs/NOTES.md)",
            needed >> 20,
            budget >> 20
        );
    }
    if frame.timings.scopes.is_empty() {
        println!("GPU timings: this device has no timestamp queries");
    } else {
        println!("GPU time per pass:");
        for (name, ms) in frame.timings.scopes.iter().filter(|(n, _)| n != "render") {
            println!("  {name:<16} {ms:9.3} ms");
        }
        if let Some(ms) = frame.timings.get("render") {
            println!(
                "  {:<16} {ms:9.3} ms (the whole frame: passes and barriers)",
                "frame"
            );
        }
    }
    if let Some(stats) = &frame.sweep {
        let planes = stats.planes.count;
        println!(
            "sweep: {planes} planes, spacing {:.5}, {:.1} MiB of state-buffer traffic per plane",
            stats.planes.spacing,
            stats.bytes_per_plane as f64 / (1 << 20) as f64
        );
        if let Some(ms) = frame.timings.get("sweep") {
            println!("  {:.3} ms per plane", ms / planes as f64);
        }
        let c = stats.clamps;
        println!(
            "light transport: {}; clamps (pixel-planes): light direction {}, light rays \
             turned back and dropped {}, viewing direction {}, gain {}",
            stats.light_transport.name(),
            c.light_direction,
            c.light_dropped,
            c.view_direction,
            c.gain
        );
    }
    if args.with_baseline {
        let main_ms = main_pass_ms(&frame);
        let ea = renderer.render(Model::Ea, &camera, &opts)?;
        let ea_ms = main_pass_ms(&ea);
        println!("baseline: ea raymarch {ea_ms:.3} ms");
        if ea_ms > 0.0 {
            println!(
                "ratio {} / ea: {:.2} (same volume, view, image and sample distance)",
                model.name(),
                main_ms / ea_ms
            );
        }
    }
    write_dumps(&frame, &camera, &dump_dir)?;
    println!("wrote {}", args.output.display());
    drop(renderer);
    finish(ctx)
}

/// Writes the --dump state buffers as EXR. Each file's header says where the buffer lives:
/// the plane's index and view depth, the world-space plane `n·p = d` (n the camera's
/// forward, d = n·eye + depth) and the camera; the log line says the same.
fn write_dumps(frame: &refrakt::render::Frame, camera: &Camera, dir: &Path) -> Result<()> {
    use output::HeaderValue::{Text, Vec3 as V3, F32, I32};
    if frame.dumps.is_empty() {
        return Ok(());
    }
    let (eye, forward, _, _) = camera.frame();
    let t = camera.target;
    // (+ 0.0 turns -0 into 0 for the log.)
    let v = |v: glam::Vec3| format!("({:.4},{:.4},{:.4})", v.x + 0.0, v.y + 0.0, v.z + 0.0);
    println!(
        "dump camera: eye {} target {} vertical fov {}°",
        v(eye),
        v(t),
        camera.fov_y
    );
    let spacing = frame.sweep.as_ref().map(|s| s.planes.spacing);
    for d in &frame.dumps {
        let path = dir.join(format!("{}-{}.exr", d.buffer.name(), d.plane));
        let offset = forward.dot(eye) + d.depth;
        let mut attrs = vec![
            ("refrakt.buffer", Text(d.buffer.name().into())),
            ("refrakt.plane", I32(d.plane as i32)),
            ("refrakt.viewDepth", F32(d.depth)),
            ("refrakt.planeNormal", V3(forward.to_array())),
            ("refrakt.planeOffset", F32(offset)),
            ("refrakt.cameraEye", V3(eye.to_array())),
            ("refrakt.cameraTarget", V3(t.to_array())),
            ("refrakt.cameraFovY", F32(camera.fov_y)),
        ];
        // The pass for plane k leaves the viewing rays on plane k+1 (see Dump::depth).
        let mut next = String::new();
        if let (StateBuffer::ViewPosition, Some(s)) = (d.buffer, spacing) {
            let depth = d.depth + s;
            attrs.push(("refrakt.positionsViewDepth", F32(depth)));
            attrs.push(("refrakt.positionsPlaneOffset", F32(offset + s)));
            next = format!(
                "; positions on the next plane: view depth {depth:.4}, d={:.4}",
                offset + s
            );
        }
        output::write_pixels_with_attributes(d.width, d.height, &d.pixels, &path, &attrs)?;
        println!(
            "dumped {} after plane {} (view depth {:.4}, world plane n={} d={offset:.4}{next}) to {}",
            d.buffer.name(),
            d.plane,
            d.depth,
            v(forward),
            path.display()
        );
    }
    Ok(())
}

/// "WxH@N" of --resize.
fn parse_resize(s: &str) -> Result<([u32; 2], u64)> {
    let bad = || format!("--resize '{s}': expected WIDTHxHEIGHT@FRAME, e.g. 320x200@2");
    let (size, frame) = s.split_once('@').with_context(bad)?;
    let (w, h) = size.split_once(['x', 'X']).with_context(bad)?;
    let w: u32 = w.trim().parse().ok().with_context(bad)?;
    let h: u32 = h.trim().parse().ok().with_context(bad)?;
    let frame: u64 = frame.trim().parse().ok().with_context(bad)?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        bail!("--resize '{s}': the size must be between 1 and 16384 per side");
    }
    Ok(([w, h], frame))
}

fn view(desc: &ContextDesc, args: ViewArgs) -> Result<ExitCode> {
    if let Some(path) = &args.screenshot {
        output::format_for(path)?;
    }
    if args.frames == Some(0) {
        bail!("--frames must be at least 1");
    }
    let resize = args.resize.as_deref().map(parse_resize).transpose()?;
    if !args.screenshot_dir.is_dir() {
        bail!(
            "--screenshot-dir {}: the folder does not exist",
            args.screenshot_dir.display()
        );
    }
    let scene_args = args.scene.clone();
    let scene = build_scene(&scene_args)?;
    let options = ViewOptions {
        vsync: !args.no_vsync,
        frames: args.frames,
        screenshot: args.screenshot.clone(),
        resize,
        screenshot_dir: args.screenshot_dir.clone(),
        watch: !args.no_watch,
    };
    let report = viewer::run(
        desc.clone(),
        scene,
        Box::new(move || build_scene(&scene_args)),
        options,
    )?;
    if report.validation_messages > 0 {
        eprintln!(
            "validation: {} message(s) reported (see above)",
            report.validation_messages
        );
        return Ok(ExitCode::from(3));
    }
    Ok(ExitCode::SUCCESS)
}

#[derive(Args)]
struct PhotonsArgs {
    /// Plane of the sweep (0-based, with the scene's --sample-distance), as in
    /// `render --dump light-colour@K`.
    #[arg(
        long,
        value_name = "K",
        required_unless_present = "depth",
        conflicts_with = "depth"
    )]
    plane: Option<u32>,
    /// View depth of the plane instead of a plane number.
    #[arg(long, value_name = "Z")]
    depth: Option<f32>,
    /// Output image (.exr only: rgb = irradiance, a = 0, the layout of the dumps).
    #[arg(short, long, default_value = "photons.exr")]
    output: PathBuf,
    /// Photons per pixel of the plane (round(sqrt(N)) per axis).
    #[arg(long, default_value_t = 64)]
    photons_per_pixel: u32,
    /// RK4 step in voxels.
    #[arg(long, default_value_t = 0.1)]
    step: f32,
    /// Jitter photons within their launch cells (stratified) instead of a regular grid.
    #[arg(long)]
    jitter: bool,
    /// Seed of the jitter.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Worker threads [default: all cores].
    #[arg(long)]
    threads: Option<usize>,
    #[command(flatten)]
    scene: SceneArgs,
}

fn photons(args: &PhotonsArgs) -> Result<ExitCode> {
    use refrakt::photons::{self, PhotonOptions};
    let ext = args.output.extension().and_then(|e| e.to_str());
    if !ext.is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
        bail!(
            "{}: the photon tracer writes linear EXR only; use a .exr file name",
            args.output.display()
        );
    }
    output::format_for(&args.output)?;
    let popts = PhotonOptions {
        photons_per_pixel: args.photons_per_pixel,
        step: args.step,
        seed: args.seed,
        jitter: args.jitter,
        threads: args.threads.unwrap_or(0),
    };
    popts.validate()?;
    let LoadedScene {
        name,
        volume,
        tf,
        camera,
        opts,
        ..
    } = build_scene(&args.scene)?;
    let planes = photons::planes(&volume, &camera, &opts)?;
    let depth = match (args.plane, args.depth) {
        (Some(k), _) => photons::plane_depth(&volume, &camera, &opts, k)?,
        (None, Some(z)) => z,
        (None, None) => bail!("give --plane K or --depth Z"),
    };
    let img = photons::trace_irradiance(&volume, &tf, &camera, &opts, depth, &popts)?;
    output::write_pixels(img.width, img.height, &img.pixels, &args.output)?;
    println!(
        "irradiance of the {} scene ({}x{}x{}, transfer functions {}) on the plane at view \
         depth {depth:.5}{}, {}x{}",
        name,
        volume.dims[0],
        volume.dims[1],
        volume.dims[2],
        tf.name,
        match args.plane {
            Some(k) => format!(" (plane {k} of 0..{})", planes.count - 1),
            None => String::new(),
        },
        img.width,
        img.height
    );
    println!("{}", img.summary());
    println!("wrote {}", args.output.display());
    Ok(ExitCode::SUCCESS)
}
