//! `refrakt` command line: `info`, `render` and `view`. `render` and `view` share the scene
//! options ([`SceneArgs`]) and build the scene in one function ([`build_scene`]).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context as _, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};

use refrakt::environment::EnvironmentMap;
use refrakt::output;
use refrakt::render::{Camera, Light, Model, RenderOptions, Renderer, StateBuffer, SweepOptions};
use refrakt::scene::Scene;
use refrakt::transfer::TransferFunctions;
use refrakt::viewer::{self, ViewOptions};
use refrakt::vk::{self, Context, ContextDesc};
use refrakt::volume::{procedural, Volume};

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
}

#[derive(Clone, Copy, ValueEnum)]
enum SceneArg {
    /// Noisy spherical shell with a dense core over a ground plane, after the thesis'
    /// supernova (Fig. 6.1).
    Shell,
    /// Solid sphere of value 1, radius 0.35.
    Sphere,
    /// Solid box of value 1.
    Box,
    /// Glass sphere (value 0.5) above an opaque floor (value 1).
    GlassFloor,
    /// A wine glass (value 0.4) holding liquid (value 0.8), after the thesis' Fig. 6.3.
    WineGlass,
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
    /// Procedural scene to render.
    #[arg(long, value_enum, default_value = "shell")]
    scene: SceneArg,
    /// Volume resolution (voxels per side) of the procedural scene.
    #[arg(long, default_value_t = 128)]
    volume_size: u32,
    /// Transfer functions: a preset (ct-bone, glass, wine-glass, supernova, sphere-white,
    /// glass-floor) or a TOML file. Default: supernova for the shell, glass-floor for
    /// glass-floor, wine-glass for wine-glass, sphere-white otherwise.
    #[arg(long, value_name = "PRESET|FILE")]
    tf: Option<String>,
    /// Rendering model.
    #[arg(long, value_enum, default_value = "refract")]
    model: ModelArg,
    /// Sample the transfer function at each step instead of using the preintegration table.
    #[arg(long)]
    no_preintegration: bool,
    /// Image width in pixels (view: the window's initial inner width).
    #[arg(long, default_value_t = 512)]
    width: u32,
    /// Image height in pixels (view: the window's initial inner height).
    #[arg(long, default_value_t = 512)]
    height: u32,
    /// Distance between samples in units of the smallest voxel side (1 = one sample per
    /// voxel, as in the thesis' chapter 6).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    sample_distance: f32,
    /// Camera azimuth in degrees around the vertical axis.
    #[arg(long, default_value_t = 30.0, allow_negative_numbers = true)]
    azimuth: f32,
    /// Camera elevation in degrees.
    #[arg(long, default_value_t = 20.0, allow_negative_numbers = true)]
    elevation: f32,
    /// Camera distance from the volume centre (the volume's longest side is 1).
    #[arg(long, default_value_t = 2.2, allow_negative_numbers = true)]
    distance: f32,
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = 35.0, allow_negative_numbers = true)]
    fov: f32,
    /// Background colour behind the volume, linear "r,g,b" or "r,g,b,a".
    #[arg(long, default_value = "0.08,0.08,0.1,1", allow_hyphen_values = true)]
    background: String,
    /// World-space direction towards the light, "x,y,z" (refract). It must lie in the
    /// viewer's hemisphere: the sweep runs front to back, so light cannot come from behind
    /// the volume. Default: from above, tilted towards the camera.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    light: Option<String>,
    /// Light colour, linear "r,g,b" (refract).
    #[arg(long, default_value = "1,1,1")]
    light_colour: String,
    /// Light softness: radius, in voxels, of the elliptical filter applied to the light at
    /// every plane; 0 = hard shadows and sharp caustics (refract).
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    softness: f32,
    /// GGX roughness of the specular highlights (refract).
    #[arg(long, default_value_t = 0.3, allow_negative_numbers = true)]
    roughness: f32,
    /// Specular strength; 0 turns highlights off (refract).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    specular: f32,
    /// Clipping plane "nx,ny,nz,offset" in world space: opacity is zero where
    /// n·p > offset, the medium and refraction stay (refract, thesis Fig. 6.6).
    #[arg(long, value_name = "NX,NY,NZ,D", allow_hyphen_values = true)]
    clip: Option<String>,
    /// Environment map behind the volume (refract): an equirectangular .exr or .hdr
    /// (linear), .png or .jpg (sRGB), twice as wide as high; "sky" for the built-in sky,
    /// sun and checkered ground; "none" for the flat --background.
    #[arg(long, default_value = "sky", value_name = "FILE|sky|none")]
    env: String,
    /// Rotation of the environment map about the vertical axis, degrees.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    env_rotation: f32,
    /// Exposure in stops applied before tone mapping (PNG output and the window).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
    /// Tone mapping for PNG output and the window: aces (filmic), reinhard, or none
    /// (clamp). EXR output is always the linear HDR image.
    #[arg(long, value_enum, default_value = "aces")]
    tonemap: ToneArg,
    /// Refractive-index scale k: the sweep uses eta' = 1 + k (eta_tf - 1); 0 turns
    /// refraction off, 1 is the transfer function's eta (refract).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    eta_scale: f32,
}

#[derive(Args)]
struct RenderArgs {
    /// Output image; the extension picks the format: .png (8-bit sRGB) or .exr (linear).
    #[arg(short, long, default_value = "refrakt.png")]
    output: PathBuf,
    /// Write state buffers after given planes as EXR: "BUFFER@PLANE[,...]" with BUFFER one
    /// of light-colour, light-direction, view-position, view-direction, colour-opacity,
    /// medium (refract). Files go to --dump-dir as BUFFER-PLANE.exr.
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
    /// Procedural scene to show (the same as --scene).
    #[arg(value_enum, conflicts_with = "scene", value_name = "SCENE")]
    scene_name: Option<SceneArg>,
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
    /// Do not reload the scene when its files (transfer functions, environment map) change
    /// on disk (R still reloads).
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
    frame
        .timings
        .scopes
        .iter()
        .filter(|(name, _)| name != "preintegration" && name != "environment SAT")
        .map(|(_, ms)| ms)
        .sum()
}

fn scene_name(scene: SceneArg) -> &'static str {
    match scene {
        SceneArg::Shell => "shell",
        SceneArg::Sphere => "sphere",
        SceneArg::Box => "box",
        SceneArg::GlassFloor => "glass-floor",
        SceneArg::WineGlass => "wine-glass",
    }
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

/// The scene the options describe: parsed and checked (everything that can be checked
/// without the GPU), with its volume built and its files read. The one place `render` and
/// `view` get a scene from.
fn build_scene(args: &SceneArgs) -> Result<Scene> {
    let opts = RenderOptions {
        width: args.width,
        height: args.height,
        sample_distance: args.sample_distance,
        preintegrated: !args.no_preintegration,
        background: parse_background(&args.background)?,
        ..Default::default()
    };
    let camera = Camera {
        azimuth: args.azimuth,
        elevation: args.elevation,
        distance: args.distance,
        fov_y: args.fov,
    };
    camera.validate()?;
    let (_, forward, right, up) = camera.frame();
    let towards = match &args.light {
        Some(l) => glam::Vec3::from(parse_floats::<3>("--light", l)?),
        // Light from above, tilted towards the camera so the sweep can carry it; when the
        // camera looks up too steeply for that, a key light from the camera's upper left.
        None => {
            let above = (glam::Vec3::Y - 0.5 * forward).normalize();
            if above.dot(-forward) >= 0.3 {
                above
            } else {
                (-forward + 0.6 * up - 0.4 * right).normalize()
            }
        }
    };
    let mut opts = opts;
    opts.sweep = SweepOptions {
        light: Light {
            towards,
            colour: parse_floats::<3>("--light-colour", &args.light_colour)?,
            softness: args.softness,
        },
        roughness: args.roughness,
        specular: args.specular,
        clip: match &args.clip {
            Some(c) => {
                let v = parse_floats::<4>("--clip", c)?;
                Some((glam::Vec3::new(v[0], v[1], v[2]), v[3]))
            }
            None => None,
        },
        env_rotation: args.env_rotation,
        eta_scale: args.eta_scale,
        ..Default::default()
    };
    opts.validate()?;
    if !args.exposure.is_finite() {
        bail!(
            "--exposure {} must be a finite number of stops",
            args.exposure
        );
    }
    let tone = output::ToneMap {
        exposure: args.exposure,
        operator: match args.tonemap {
            ToneArg::Aces => output::ToneOperator::Aces,
            ToneArg::Reinhard => output::ToneOperator::Reinhard,
            ToneArg::None => output::ToneOperator::None,
        },
    };
    let mut files = Vec::new();
    let env = match args.env.as_str() {
        "none" => None,
        "sky" => Some(EnvironmentMap::procedural(1024)?),
        file => {
            files.push(PathBuf::from(file));
            Some(EnvironmentMap::load(std::path::Path::new(file))?)
        }
    };
    let tf_name = args.tf.clone().unwrap_or_else(|| {
        match args.scene {
            SceneArg::Shell => "supernova",
            SceneArg::GlassFloor => "glass-floor",
            SceneArg::WineGlass => "wine-glass",
            _ => "sphere-white",
        }
        .to_string()
    });
    let tf = TransferFunctions::load(&tf_name)?;
    if std::path::Path::new(&tf_name).is_file() {
        files.push(PathBuf::from(&tf_name));
    }
    let n = args.volume_size;
    let volume: Volume = match args.scene {
        SceneArg::Shell => procedural::shell_on_floor(n, 7)?,
        SceneArg::Sphere => procedural::sphere(n, 0.35, 1.0)?,
        SceneArg::Box => procedural::boxed(n, [0.3, 0.25, 0.2], 1.0)?,
        SceneArg::GlassFloor => procedural::sphere_on_floor(n)?,
        SceneArg::WineGlass => procedural::wine_glass(n)?,
    };
    let model = match args.model {
        ModelArg::Ea => Model::Ea,
        ModelArg::Refract => Model::Refract,
    };
    Ok(Scene {
        name: scene_name(args.scene).to_string(),
        volume,
        tf,
        env,
        model,
        camera,
        opts,
        tone,
        files,
    })
}

fn render(desc: &ContextDesc, args: &RenderArgs) -> Result<ExitCode> {
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
    let Scene {
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
    let mut all = env_timings;
    all.extend(std::mem::take(&mut frame.timings));
    frame.timings = all;
    output::write(&frame, &args.output, &tone)?;
    println!(
        "rendered {}x{} of the {} scene ({}x{}x{}, transfer functions {}), model {}{}, sample distance {}, up to {} steps per ray",
        opts.width,
        opts.height,
        scene_name(args.scene.scene),
        volume.dims[0],
        volume.dims[1],
        volume.dims[2],
        tf.name,
        model.name(),
        if opts.preintegrated { " (preintegrated)" } else { "" },
        opts.sample_distance,
        frame.max_steps
    );
    if frame.timings.scopes.is_empty() {
        println!("GPU timings: this device has no timestamp queries");
    } else {
        println!("GPU time per pass:");
        for (name, ms) in &frame.timings.scopes {
            println!("  {name:<16} {ms:9.3} ms");
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
    for d in &frame.dumps {
        let path = dump_dir.join(format!("{}-{}.exr", d.buffer.name(), d.plane));
        output::write_pixels(d.width, d.height, &d.pixels, &path)?;
        println!(
            "dumped {} after plane {} to {}",
            d.buffer.name(),
            d.plane,
            path.display()
        );
    }
    println!("wrote {}", args.output.display());
    drop(renderer);
    finish(ctx)
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
    let mut scene_args = args.scene.clone();
    if let Some(s) = args.scene_name {
        scene_args.scene = s;
    }
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
