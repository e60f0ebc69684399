//! Scenes: everything a render needs (volume, spacing, transfer functions, camera, light,
//! environment, viewport, sample distance, clipping, exposure) in one TOML file, or one of
//! the built-in scenes (procedural test scenes, the thesis stand-ins, the fetched real
//! scans), or a bare volume file rendered with a default preset and camera.
//!
//! The command line overrides any field after the scene is resolved; relative paths in a
//! scene file are relative to the file. See README.md ("Scene files") for the format.

use std::path::{Path, PathBuf};

use anyhow::{bail, ensure, Context as _, Result};
use glam::Vec3;
use serde::Deserialize;

use crate::environment::EnvironmentMap;
use crate::output::{ToneMap, ToneOperator};
use crate::render::{
    Camera, Light, LightTransport, Model, ModelOptions, RenderOptions, SweepOptions,
};
use crate::transfer::TransferFunctions;
use crate::volume::formats::DeviceLimits;
use crate::volume::{procedural, standins, Volume};

mod applies;
mod catalogue;
mod data;
mod file;
mod load;

pub use applies::{refuse_what_does_not_apply, Given};
pub use catalogue::*;
use file::SceneFile;
pub use file::{parse_flip, parse_model, parse_on_off, parse_scalar_kind, parse_tonemap};

/// Where the volume comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum VolumeSource {
    /// A procedural test volume of `size`³ voxels.
    Procedural { kind: String, size: u32 },
    /// A thesis stand-in (or the original from `--data-dir`) at `scale` of its resolution.
    Standin { name: String, scale: f64 },
    /// A volume file in any supported format (src/volume/formats).
    File {
        path: PathBuf,
        raw: Option<crate::volume::formats::RawLayout>,
        window: Option<(f32, f32)>,
    },
    /// A file fetched by `scripts/fetch-data`, looked up in the data directory.
    Fetched {
        file: String,
        window: Option<(f32, f32)>,
    },
}

/// Environment behind the volume.
#[derive(Clone, Debug, PartialEq)]
pub enum EnvSource {
    Sky,
    None,
    File(PathBuf),
}

/// `--labels`: is the volume a label map (segmentation), and where do its colours come
/// from (`crate::labels`).
#[derive(Clone, Debug, PartialEq)]
pub enum LabelChoice {
    /// A volume file whose transfer functions are derived from the data and whose
    /// values are at most [`crate::labels::MAX_AUTO_LABELS`] distinct integers.
    Auto,
    /// A label map, coloured from the built-in palette.
    On,
    /// A label map, coloured from this colour table.
    Table(PathBuf),
    Off,
}

impl LabelChoice {
    pub fn parse(s: &str) -> Self {
        match s.trim() {
            "auto" => Self::Auto,
            "on" => Self::On,
            "off" => Self::Off,
            file => Self::Table(PathBuf::from(file)),
        }
    }
}

/// A fully resolved scene. Build the GPU inputs with the methods below.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Name shown in the output (built-in name or file name).
    pub name: String,
    pub volume: VolumeSource,
    /// Voxel spacing override (x, y, z); `None` keeps the volume's own.
    pub spacing: Option<[f32; 3]>,
    /// Turn the volume upright when its file states the patient's orientation
    /// ([`Volume::turn_upright`]): on for volume files, off for the built-in scenes (each
    /// composed with its own view).
    pub upright: bool,
    /// Where the voxel axes point in the patient (LPS unit vectors, as
    /// [`Volume::axes`]), stated by the user (`--orientation RAS`): replaces what the
    /// file says, for volume files only.
    pub orientation: Option<[[f32; 3]; 3]>,
    /// Whether the volume is a label map (`--labels`): detected, forced with the built-in
    /// palette or a colour table, or off.
    pub labels: LabelChoice,
    /// Quarter turns about the world's axes after loading and turning upright
    /// (`--rotate`), before `flip`.
    pub rotate: Option<crate::volume::orientation::QuarterTurns>,
    /// Axes (x, y, z) to mirror the data along after loading and turning upright (two = a
    /// 180° rotation).
    pub flip: [bool; 3],
    /// A preset name or a TF file path (resolved), or inline functions.
    pub transfer: TransferSource,
    pub camera: Camera,
    /// Where the main light is; `None`: the default key light for the camera (see
    /// [`default_light`]).
    pub light_source: Option<crate::light::LightSource>,
    /// `--light env`: the key light's direction and colour come from the environment
    /// map's brightest region ([`EnvironmentMap::key_light`]) when the scene is loaded.
    pub light_from_env: bool,
    pub light_colour: [f32; 3],
    /// The ambient level (`SweepOptions::ambient`); None: 0, or with `light_from_env` the
    /// environment map's ([`crate::environment::KeyLight::ambient`]).
    pub ambient_level: Option<[f32; 3]>,
    pub softness: f32,
    pub environment: EnvSource,
    pub env_rotation: f32,
    pub model: Model,
    pub width: u32,
    pub height: u32,
    pub sample_distance: f32,
    pub preintegrated: bool,
    pub background: [f32; 4],
    pub roughness: f32,
    pub specular: f32,
    /// Refractive-index scale k: η' = 1 + k (η_tf − 1); 0 turns refraction off.
    pub eta_scale: f32,
    /// How light travels between the sweep's planes.
    pub light_transport: LightTransport,
    /// Forward transport: light rays per screen pixel.
    pub light_rays: u32,
    /// Forward transport: light ray spacing on the launch plane, pixel pitches of plane 0.
    pub light_spacing: f32,
    /// Fresnel reflection of viewing rays (false: the thesis' model).
    pub reflections: bool,
    /// With `reflections`, the refractive sweep's first reflection sees the volume
    /// (`--reflections volume`, the default); false: the environment only
    /// (`--reflections environment`).
    pub reflections_volume: bool,
    pub clip: Option<(Vec3, f32)>,
    pub exposure: f32,
    pub tonemap: ToneOperator,
    /// The models' declared options' values (`--ao-radius`, `--g`...).
    pub models: ModelOptions,
    /// The lights after the main one (the ambient-scattering model takes several).
    pub extra_lights: Vec<Light>,
    /// The scene file this came from, if any (the viewer reloads when it changes).
    pub file: Option<PathBuf>,
}

/// Values that replace a scene's, from a scene file's sections or from the command line:
/// each front end parses its own syntax (with its own error context) into this, and
/// [`Scene::apply`] is the one place they are applied (`None` keeps the scene's value).
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    pub transfer: Option<TransferSource>,
    pub model: Option<Model>,
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub sample_distance: Option<f32>,
    pub preintegrated: Option<bool>,
    pub background: Option<[f32; 4]>,
    pub roughness: Option<f32>,
    pub specular: Option<f32>,
    pub eta_scale: Option<f32>,
    pub light_rays: Option<u32>,
    pub light_spacing: Option<f32>,
    pub light_transport: Option<LightTransport>,
    pub reflections: Option<bool>,
    pub reflections_volume: Option<bool>,
    /// `Some(None)` removes the scene's clipping plane.
    pub clip: Option<Option<(Vec3, f32)>>,
    pub exposure: Option<f32>,
    pub tonemap: Option<ToneOperator>,
    pub extra_lights: Option<Vec<Light>>,
    pub azimuth: Option<f32>,
    pub elevation: Option<f32>,
    pub distance: Option<f32>,
    pub fov: Option<f32>,
    pub target: Option<Vec3>,
    pub light_source: Option<crate::light::LightSource>,
    pub light_from_env: Option<bool>,
    pub light_colour: Option<[f32; 3]>,
    pub ambient_level: Option<[f32; 3]>,
    pub softness: Option<f32>,
    pub environment: Option<EnvSource>,
    pub env_rotation: Option<f32>,
    pub flip: Option<[bool; 3]>,
    pub rotate: Option<crate::volume::orientation::QuarterTurns>,
    pub upright: Option<bool>,
    pub orientation: Option<[[f32; 3]; 3]>,
    pub labels: Option<LabelChoice>,
}

impl Scene {
    /// Replace this scene's values by those `o` gives.
    pub fn apply(&mut self, o: Overrides) {
        fn set<T>(field: &mut T, value: Option<T>) {
            if let Some(v) = value {
                *field = v;
            }
        }
        set(&mut self.transfer, o.transfer);
        set(&mut self.model, o.model);
        set(&mut self.width, o.width);
        set(&mut self.height, o.height);
        set(&mut self.sample_distance, o.sample_distance);
        set(&mut self.preintegrated, o.preintegrated);
        set(&mut self.background, o.background);
        set(&mut self.roughness, o.roughness);
        set(&mut self.specular, o.specular);
        set(&mut self.eta_scale, o.eta_scale);
        set(&mut self.light_rays, o.light_rays);
        set(&mut self.light_spacing, o.light_spacing);
        set(&mut self.light_transport, o.light_transport);
        set(&mut self.reflections, o.reflections);
        set(&mut self.reflections_volume, o.reflections_volume);
        set(&mut self.clip, o.clip);
        set(&mut self.exposure, o.exposure);
        set(&mut self.tonemap, o.tonemap);
        set(&mut self.extra_lights, o.extra_lights);
        set(&mut self.camera.azimuth, o.azimuth);
        set(&mut self.camera.elevation, o.elevation);
        set(&mut self.camera.distance, o.distance);
        set(&mut self.camera.fov_y, o.fov);
        set(&mut self.camera.target, o.target);
        if o.light_source.is_some() {
            self.light_source = o.light_source;
            self.light_from_env = false;
        }
        if o.light_from_env == Some(true) {
            self.light_from_env = true;
            self.light_source = None;
        }
        set(&mut self.light_colour, o.light_colour);
        if o.ambient_level.is_some() {
            self.ambient_level = o.ambient_level;
        }
        set(&mut self.softness, o.softness);
        set(&mut self.environment, o.environment);
        set(&mut self.env_rotation, o.env_rotation);
        set(&mut self.flip, o.flip);
        if o.rotate.is_some() {
            self.rotate = o.rotate;
        }
        set(&mut self.upright, o.upright);
        if o.orientation.is_some() {
            self.orientation = o.orientation;
        }
        set(&mut self.labels, o.labels);
    }
}

/// A scene with its inputs loaded: what `render` and `view` draw. Built only by
/// [`Scene::load_all`], the one place both commands get a scene from.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// Short name for messages and the window title.
    pub name: String,
    pub volume: Volume,
    pub tf: TransferFunctions,
    /// Environment behind the volume (refractive model); None = the flat background.
    pub env: Option<EnvironmentMap>,
    /// What `env` is, for people: "sky", "none" or the map's file name.
    pub env_name: String,
    pub model: Model,
    pub camera: Camera,
    /// Image size, sampling, light, specular, clipping (the viewer replaces the size with
    /// the window's).
    pub opts: RenderOptions,
    /// How linear colour becomes 8-bit output (PNG, the window).
    pub tone: ToneMap,
    /// Files the scene was read from (scene file, volume, transfer functions, environment
    /// map): the viewer reloads the scene when one of them changes.
    pub files: Vec<PathBuf>,
    /// What loading decided that the user should see (a volume file's spacing, value
    /// range and window, transfer functions derived from its histogram).
    pub notes: Vec<String>,
}

#[derive(Clone, Debug)]
pub enum TransferSource {
    Named(String),
    Inline(Box<TransferFunctions>),
    /// Derived from the volume's histogram when it is loaded
    /// ([`TransferFunctions::for_histogram`]): what a bare volume file gets.
    FromData,
}

impl Default for Scene {
    fn default() -> Self {
        Self {
            name: "sphere-on-floor".into(),
            volume: VolumeSource::Procedural {
                kind: "sphere-on-floor".into(),
                size: 128,
            },
            spacing: None,
            flip: [false; 3],
            rotate: None,
            upright: false,
            orientation: None,
            labels: LabelChoice::Auto,
            transfer: TransferSource::Named("glass-floor".into()),
            camera: Camera::default(),
            light_source: None,
            light_from_env: false,
            light_colour: Light::DEFAULT_COLOUR,
            softness: Light::DEFAULT_SOFTNESS,
            ambient_level: None,
            environment: EnvSource::Sky,
            env_rotation: 0.0,
            model: Model::Refract,
            width: 512,
            height: 512,
            sample_distance: 1.0,
            preintegrated: true,
            background: [0.08, 0.08, 0.1, 1.0],
            roughness: 0.3,
            specular: 1.0,
            eta_scale: 1.0,
            light_transport: LightTransport::Forward,
            light_rays: 2,
            light_spacing: 1.0,
            reflections: true,
            reflections_volume: true,
            clip: None,
            exposure: 0.0,
            tonemap: ToneOperator::Aces,
            models: ModelOptions::default(),
            extra_lights: Vec::new(),
            file: None,
        }
    }
}

impl Scene {
    /// A built-in scene by name, a scene file (.toml), or a volume file.
    pub fn resolve(arg: &str) -> Result<Scene> {
        if let Some(s) = Self::builtin(arg)? {
            return Ok(s);
        }
        let path = Path::new(arg);
        if path.extension().is_some_and(|e| e == "toml") {
            return Self::load(path);
        }
        if path.exists() {
            return Ok(Self::for_volume_file(path));
        }
        let why =
            crate::volume::formats::why_not_a_file(path).unwrap_or_else(|| "cannot be read".into());
        if std::fs::symlink_metadata(path).is_ok() {
            // Something is there (a symlink loop, a dangling link): its reason is the one.
            bail!("scene '{arg}': {why}");
        }
        let names: Vec<String> = builtin_names().into_iter().map(|(n, _)| n).collect();
        bail!(
            "scene '{arg}': {why}, and not a built-in scene ({})",
            names.join(", ")
        )
    }

    /// A bare volume file: transfer functions derived from its histogram (refractive
    /// material, opaque dense structure), the default camera and light, the flat
    /// background behind it.
    pub fn for_volume_file(path: &Path) -> Scene {
        Scene {
            name: path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            volume: VolumeSource::File {
                path: path.to_path_buf(),
                raw: None,
                window: None,
            },
            transfer: TransferSource::FromData,
            upright: true,
            orientation: None,
            labels: LabelChoice::Auto,
            // A neutral backdrop: the sky's checkerboard seen from above became giant
            // tiles that washed out translucent tissue (issue 36).
            environment: EnvSource::None,
            ..Default::default()
        }
    }

    /// Reads a scene file; unknown keys, wrong types and missing referenced files are
    /// errors naming the file.
    pub fn load(path: &Path) -> Result<Scene> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("scene {}: cannot read it", path.display()))?;
        Self::parse(&text, path)
    }

    pub fn parse(text: &str, path: &Path) -> Result<Scene> {
        let f: SceneFile = toml::from_str(text)
            .map_err(|e| anyhow::anyhow!("scene {}: {}", path.display(), one_line(&e, text)))?;
        f.resolve(path)
            .with_context(|| format!("scene {}", path.display()))
    }

    pub fn transfer_functions(&self) -> Result<TransferFunctions> {
        match &self.transfer {
            TransferSource::Named(n) => TransferFunctions::load(n),
            TransferSource::Inline(tf) => Ok((**tf).clone()),
            TransferSource::FromData => {
                bail!(
                    "the transfer functions are derived from the volume's data, which is not \
                     loaded here: give --tf"
                )
            }
        }
    }

    pub fn environment_map(&self) -> Result<Option<EnvironmentMap>> {
        Ok(match &self.environment {
            EnvSource::None => None,
            EnvSource::Sky => Some(EnvironmentMap::procedural(EnvironmentMap::SKY_WIDTH)?),
            EnvSource::File(p) => Some(EnvironmentMap::load(p)?),
        })
    }

    /// The main light.
    pub fn light(&self) -> Light {
        Light {
            source: self
                .light_source
                .unwrap_or_else(|| crate::light::LightSource::Directional {
                    towards: default_light(&self.camera),
                }),
            colour: self.light_colour,
            softness: self.softness,
        }
    }

    /// Render options for this scene (validated).
    pub fn render_options(&self) -> Result<RenderOptions> {
        self.camera.validate()?;
        ensure!(
            self.env_rotation == 0.0 || self.environment != EnvSource::None,
            "an environment rotation ({}°) turns an environment map, and this scene has none \
             (--env none or a background): drop the rotation or give a map",
            self.env_rotation
        );
        let opts = RenderOptions {
            width: self.width,
            height: self.height,
            sample_distance: self.sample_distance,
            preintegrated: self.preintegrated,
            background: self.background,
            sweep: SweepOptions {
                roughness: self.roughness,
                specular: self.specular,
                eta_scale: self.eta_scale,
                light_transport: self.light_transport,
                light_rays: self.light_rays,
                light_spacing: self.light_spacing,
                reflections: self.reflections,
                reflections_volume: self.reflections_volume,
                clip: self.clip,
                env_rotation: self.env_rotation,
                ambient: self.ambient_level.unwrap_or([0.0; 3]),
                ..Default::default()
            },
            models: self.models.clone(),
            lights: std::iter::once(self.light())
                .chain(self.extra_lights.iter().copied())
                .collect(),
            ..Default::default()
        };
        opts.validate()?;
        Ok(opts)
    }

    pub fn tone_map(&self) -> Result<ToneMap> {
        ToneMap::check_exposure(self.exposure)?;
        Ok(ToneMap {
            exposure: self.exposure,
            operator: self.tonemap,
        })
    }
}

/// The parser's message with the line it points at, on one line.
fn one_line(e: &toml::de::Error, text: &str) -> String {
    let msg = e.message().trim().replace('\n', " ");
    match e.span() {
        Some(span) => {
            let line = text[..span.start.min(text.len())].matches('\n').count() + 1;
            let src = text.lines().nth(line - 1).unwrap_or("").trim();
            format!("line {line} `{src}`: {msg}")
        }
        None => msg,
    }
}
