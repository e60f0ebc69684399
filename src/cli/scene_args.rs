//! The scene a command draws, from its arguments: the scene (built-in name, scene file or
//! volume file) with the command line's overrides applied (scene::Overrides), and the
//! parsers of the flags' values.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, ensure, Context as _, Result};

use refrakt::light::LightSource;
use refrakt::output;
use refrakt::render::StateBuffer;
use refrakt::scene::{self, EnvSource, LoadedScene, Scene, TransferSource, VolumeSource};
use refrakt::volume::formats::{DeviceLimits, RawLayout};

use super::args::*;

pub fn parse_floats<const N: usize>(flag: &str, s: &str) -> Result<[f32; N]> {
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

pub fn parse_dumps(s: &str) -> Result<Vec<(StateBuffer, u32)>> {
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

pub fn parse_background(s: &str) -> Result<[f32; 4]> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 && parts.len() != 4 {
        bail!("--background '{s}': expected 3 or 4 comma-separated numbers");
    }
    let mut out = [0.0, 0.0, 0.0, 1.0];
    for (i, p) in parts.iter().enumerate() {
        out[i] = p
            .parse::<f32>()
            .ok()
            .filter(|v| v.is_finite() && *v >= 0.0)
            .with_context(|| {
                format!("--background '{s}': '{p}' is not a finite, non-negative number")
            })?;
    }
    ensure!(
        out[3] <= 1.0,
        "--background '{s}': the alpha {} must be between 0 and 1",
        out[3]
    );
    Ok(out)
}

/// The scene the arguments name, with every given flag applied over it.
pub fn scene_from_args(args: &SceneArgs) -> Result<Scene> {
    scene_with_refract_only(args, &[])
}

/// [`scene_from_args`], with `extra` refractive-model flags a command has beyond the
/// scene's (e.g. `render --variant`) refused for the EA model like the others.
pub fn scene_with_refract_only(args: &SceneArgs, extra: &[&'static str]) -> Result<Scene> {
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
    if let Some(u) = &args.upright {
        // Only files state a patient's orientation (the built-in scenes are upright).
        ensure!(
            matches!(
                s.volume,
                VolumeSource::File { .. } | VolumeSource::Fetched { .. }
            ),
            "--upright applies to volume files; '{name}' is a built-in scene"
        );
        o.upright = Some(scene::parse_on_off(u).context("--upright")?);
    }
    if let Some(l) = &args.labels {
        o.labels = Some(scene::LabelChoice::parse(l));
    }
    if let Some(code) = &args.orientation {
        o.orientation = Some(refrakt::volume::orientation::parse_code(code)?);
    }
    if let Some(spec) = &args.rotate {
        o.rotate = Some(refrakt::volume::orientation::parse_rotation(spec).context("--rotate")?);
    }
    o.transfer = args.tf.clone().map(TransferSource::Named);
    o.model = args.model.map(|m| m.0);
    if args.no_preintegration {
        o.preintegrated = Some(false);
    }
    refrakt::copy_plain_render_overrides!(o, args);
    o.azimuth = args.azimuth;
    o.elevation = args.elevation;
    o.distance = args.distance;
    o.fov = args.fov;
    if let Some(t) = &args.target {
        o.target = Some(glam::Vec3::from(parse_floats::<3>("--target", t)?));
    }
    o.softness = args.softness;
    if let Some(t) = &args.light_transport {
        o.light_transport =
            Some(refrakt::render::LightTransport::parse(t).context("--light-transport")?);
    }
    if let Some(r) = &args.reflections {
        // "volume" and "environment" say what the reflected part sees (the refractive
        // sweep); on/off whether there is one (on: what the scene says, volume by
        // default).
        let (on, volume) = match r.to_ascii_lowercase().as_str() {
            "volume" => (true, Some(true)),
            "environment" => (true, Some(false)),
            _ => (
                refrakt::scene::parse_on_off(r)
                    .context("--reflections (on, off, environment or volume)")?,
                None,
            ),
        };
        o.reflections = Some(on);
        o.reflections_volume = volume;
    }
    o.env_rotation = args.env_rotation;
    if let Some(e) = args.exposure {
        refrakt::tone::ToneMap::check_exposure(e).context("--exposure")?;
        o.exposure = Some(e);
    }
    if let Some(b) = &args.background {
        o.background = Some(parse_background(b)?);
    }
    if let Some(l) = args.light.first() {
        if l.trim().eq_ignore_ascii_case("env") {
            if args.light_colour.is_some() {
                bail!(
                    "--light env takes the light's colour from the environment map too: drop \
                     --light-colour, or give --light X,Y,Z"
                );
            }
            o.light_from_env = Some(true);
        } else {
            let (source, colour) =
                LightSource::parse_with_colour(l).with_context(|| format!("--light {l}"))?;
            o.light_source = Some(source);
            o.light_colour = colour;
        }
    }
    if let Some(c) = &args.light_colour {
        ensure!(
            !args.light.first().is_some_and(|l| l.contains('@')),
            "--light {} gives the main light's colour already: drop --light-colour or the \
             light's @R,G,B",
            args.light[0]
        );
        o.light_colour = Some(parse_floats::<3>("--light-colour", c)?);
    }
    if let Some(a) = &args.ambient_level {
        o.ambient_level = Some(parse_floats::<3>("--ambient-level", a)?);
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
    // --background applies or is an error, never ignored (issue 36): the refractive model
    // shows it only without an environment, so it sets none; with a map or the sky asked
    // for too, one of the two would be ignored.
    if args.background.is_some() {
        match &o.environment {
            None | Some(EnvSource::None) => o.environment = Some(EnvSource::None),
            Some(_) => bail!(
                "--background and --env {}: the environment is what lies behind the volume; \
                 give one of them (--background alone sets --env none)",
                args.env.as_deref().unwrap_or_default()
            ),
        }
    }
    o.tonemap = args.tonemap.map(|t| match t {
        ToneArg::Aces => output::ToneOperator::Aces,
        ToneArg::Reinhard => output::ToneOperator::Reinhard,
        ToneArg::None => output::ToneOperator::None,
    });
    if !args.add_light.is_empty() {
        eprintln!(
            "note: --add-light is deprecated; give --light again (the first is the main light)"
        );
    }
    let more: Vec<&String> = args.light.iter().skip(1).chain(&args.add_light).collect();
    if !more.is_empty() {
        o.extra_lights = Some(
            more.into_iter()
                .map(|l| {
                    ensure!(
                        !l.trim().eq_ignore_ascii_case("env"),
                        "--light env: only the first (main) light can come from the \
                         environment map"
                    );
                    l.parse().with_context(|| format!("--light {l}"))
                })
                .collect::<Result<_>>()?,
        );
    }
    s.apply(o);
    // A flag that belongs to some models (their declarations list it: `Model::takes_flag`),
    // given with a model that does not take it, is an error naming the models that do.
    let given: Vec<scene::Given> = model_flags_given(args)
        .into_iter()
        .chain(extra.iter().copied())
        .map(scene::Given::flag)
        .collect();
    scene::refuse_what_does_not_apply(s.model, s.light_transport, &given)?;
    // The models' options' values, checked once the model is known to take them.
    s.models.merge(&args.model_options.options()?);
    Ok(s)
}

/// The flags given that belong to some models only (which ones: their declarations).
fn model_flags_given(args: &SceneArgs) -> Vec<&'static str> {
    [
        ("--light", !args.light.is_empty()),
        ("--light-colour", args.light_colour.is_some()),
        ("--ambient-level", args.ambient_level.is_some()),
        ("--softness", args.softness.is_some()),
        ("--roughness", args.roughness.is_some()),
        ("--specular", args.specular.is_some()),
        ("--eta-scale", args.eta_scale.is_some()),
        ("--light-transport", args.light_transport.is_some()),
        ("--light-rays", args.light_rays.is_some()),
        ("--light-spacing", args.light_spacing.is_some()),
        ("--reflections", args.reflections.is_some()),
        ("--clip", args.clip.is_some()),
        ("--env", args.env.is_some()),
        ("--env-rotation", args.env_rotation.is_some()),
        ("--ambient-table", args.ambient_table.is_some()),
    ]
    .into_iter()
    .filter_map(|(flag, given)| given.then_some(flag))
    .chain(args.model_options.flags_given())
    .collect()
}

/// The scene the options describe, loaded: the one place `render` and `view` (and the
/// viewer's reload) get a scene from. `limits`: the device's, when it is known before
/// loading (a volume beyond them is refused from its header).
pub fn build_scene(args: &SceneArgs, limits: Option<DeviceLimits>) -> Result<LoadedScene> {
    let scene = scene_from_args(args)?;
    scene.load_all(&data_dir(args), limits)
}

/// Where the arguments say the fetched data and the stand-ins' originals are.
pub fn data_dir(args: &SceneArgs) -> PathBuf {
    args.data_dir.clone().unwrap_or_else(scene::data_dir)
}

/// `--list-scenes` / `--list-presets`: print the list and say to exit.
pub fn list_and_exit(args: &SceneArgs) -> Result<Option<ExitCode>> {
    if args.list_scenes {
        return list_scenes().map(Some);
    }
    if args.list_presets {
        println!("Transfer-function presets (--tf NAME; or --tf FILE.toml, see README):");
        let presets = refrakt::transfer::preset_descriptions();
        let width = presets.iter().map(|(n, _)| n.len()).max().unwrap_or(0);
        for (name, description) in presets {
            println!("  {name:width$}  {description}");
        }
        return Ok(Some(ExitCode::SUCCESS));
    }
    Ok(None)
}

pub fn list_scenes() -> Result<ExitCode> {
    println!("Built-in scenes (refrakt render NAME):");
    for (n, d) in scene::builtin_names() {
        println!("  {n:<16} {d}");
    }
    println!("\nA scene file (.toml) or a volume file works too; see README.md.");
    Ok(ExitCode::SUCCESS)
}

/// "WxH@N" of --resize.
pub fn parse_resize(s: &str) -> Result<([u32; 2], u64)> {
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

/// Refuses the scene flags of `given` ((flag, whether given) pairs) that were given, and
/// any model option, naming them all: a command that does not read them says so rather
/// than ignoring them, as `render` refuses the flags of another model. `who` names the
/// command's renderer and `reads` what it does read.
pub fn refuse_flags_not_read(
    a: &SceneArgs,
    given: &[(&'static str, bool)],
    who: &str,
    reads: &str,
) -> Result<()> {
    let unused: Vec<&str> = given
        .iter()
        .filter_map(|&(flag, given)| given.then_some(flag))
        .chain(a.model_options.flags_given())
        .collect();
    if !unused.is_empty() {
        bail!(
            "{} {} not apply to {who} ({reads})",
            unused.join(", "),
            if unused.len() == 1 { "does" } else { "do" }
        );
    }
    Ok(())
}
