//! Scene files (TOML): the schema and its resolution into a [`Scene`] (relative paths are
//! relative to the file; every section parses into [`Overrides`], applied by
//! [`Scene::apply`] like the command line's).

use super::*;
use crate::light::LightSource;
use crate::render::{declared_options, find_option};

mod resolve;

// ---- the file format -------------------------------------------------------------------

/// Copies the render settings that the command line and a scene file's `[render]` table
/// both hold as plain optional values of the same name into an [`Overrides`] (`None`
/// keeps the scene's value); every other setting is parsed by its front end.
#[macro_export]
macro_rules! copy_plain_render_overrides {
    ($o:expr, $from:expr) => {
        $crate::copy_plain_render_overrides!(@fields $o, $from; width, height,
            sample_distance, roughness, specular, eta_scale, light_rays, light_spacing)
    };
    (@fields $o:expr, $from:expr; $($field:ident),*) => {
        $( $o.$field = $from.$field; )*
    };
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    name: Option<String>,
    volume: VolumeTable,
    transfer: Option<TransferTable>,
    camera: Option<CameraTable>,
    /// `[light]` (the main light) or `[[light]]` tables (the first the main light): read
    /// as a value, then as [`LightTable`]s.
    light: Option<toml::Value>,
    environment: Option<EnvTable>,
    render: Option<RenderSection>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct VolumeTable {
    /// A volume file (relative to the scene file).
    file: Option<String>,
    /// A procedural volume, a thesis stand-in, or a fetched scan, by name.
    builtin: Option<String>,
    /// Voxels per side of a procedural volume.
    size: Option<u32>,
    /// Fraction of a stand-in's resolution.
    scale: Option<f64>,
    /// Raw files: dimensions and type.
    dims: Option<[u32; 3]>,
    #[serde(rename = "type")]
    kind: Option<String>,
    spacing: Option<[f32; 3]>,
    window: Option<[f32; 2]>,
    /// Axes to mirror, e.g. "xy" (a 180° turn about z).
    flip: Option<String>,
    /// Turn the patient upright from the file's stated orientation (default true).
    upright: Option<bool>,
    /// Where the voxel axes point, e.g. "RAS" (replaces the file's; see --orientation).
    orientation: Option<String>,
    /// Quarter turns about the world's axes, e.g. "x90,z180" (see --rotate).
    rotate: Option<String>,
    /// "auto", "on", "off" or a colour table file (see --labels).
    labels: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TransferTable {
    preset: Option<String>,
    file: Option<String>,
    colour: Option<toml::Value>,
    opacity: Option<toml::Value>,
    medium: Option<toml::Value>,
    eta: Option<toml::Value>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraTable {
    azimuth: Option<f32>,
    elevation: Option<f32>,
    distance: Option<f32>,
    fov: Option<f32>,
    eye: Option<[f32; 3]>,
    target: Option<[f32; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightTable {
    towards: Option<Towards>,
    /// A point light's world position (instead of `towards`).
    position: Option<[f32; 3]>,
    colour: Option<[f32; 3]>,
    /// The ambient level, linear RGB irradiance (`--ambient-level`).
    ambient_level: Option<[f32; 3]>,
    softness: Option<f32>,
}

/// `[render] reflections`: on or off, or what the reflected part sees ("volume",
/// "environment").
#[derive(Deserialize)]
#[serde(untagged)]
enum Reflections {
    On(bool),
    Mode(String),
}

/// `[light] towards`: a direction, or "env" (the environment map's brightest region).
#[derive(Deserialize)]
#[serde(untagged)]
enum Towards {
    Direction([f32; 3]),
    Word(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvTable {
    map: Option<String>,
    rotation: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderTable {
    model: Option<String>,
    width: Option<u32>,
    height: Option<u32>,
    sample_distance: Option<f32>,
    preintegrated: Option<bool>,
    background: Option<[f32; 4]>,
    roughness: Option<f32>,
    specular: Option<f32>,
    eta_scale: Option<f32>,
    light_transport: Option<String>,
    light_rays: Option<u32>,
    light_spacing: Option<f32>,
    reflections: Option<Reflections>,
    clip: Option<[f32; 4]>,
    exposure: Option<f32>,
    tonemap: Option<String>,
    /// Deprecated (`[[light]]` tables): lights beside the main one, "dir:X,Y,Z@R,G,B" or
    /// "point:X,Y,Z@R,G,B".
    lights: Option<Vec<String>>,
}

/// The `[render]` table: the settings every scene has ([`RenderTable`]) and the models'
/// declared options' keys (`ao_radius`, `g`...: [`crate::render::ModelOption`]), found
/// by name in the registry rather than listed here.
struct RenderSection {
    table: RenderTable,
    /// (key, value) of each model option given, in the order the models declare them.
    models: Vec<(String, toml::Value)>,
}

impl<'de> Deserialize<'de> for RenderSection {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let mut rest = toml::Table::deserialize(d)?;
        // In the declarations' order (a TOML table does not keep the file's).
        let keys: Vec<String> = declared_options()
            .into_iter()
            .map(|(o, _)| o.key())
            .filter(|k| rest.contains_key(k))
            .collect();
        let models = keys
            .into_iter()
            .filter_map(|k| rest.remove(&k).map(|v| (k, v)))
            .collect();
        let table = RenderTable::deserialize(toml::Value::Table(rest)).map_err(|e| {
            let mut said = e.to_string().trim_end().to_string();
            if said.contains("unknown field") {
                let keys: Vec<String> = declared_options().iter().map(|(o, _)| o.key()).collect();
                said = format!("{said}; or a model's option: {}", keys.join(", "));
            }
            serde::de::Error::custom(said)
        })?;
        Ok(Self { table, models })
    }
}

/// The scene file's `light`: one `[light]` table or `[[light]]` tables, each with the
/// name an error should give it.
fn light_tables(v: toml::Value) -> Result<Vec<(String, LightTable)>> {
    match v {
        toml::Value::Table(_) => {
            let t = v
                .try_into()
                .map_err(|e| anyhow::anyhow!("[light]: {}", e.message()))?;
            Ok(vec![("[light]".to_string(), t)])
        }
        toml::Value::Array(a) => {
            ensure!(!a.is_empty(), "light = []: give [[light]] tables or none");
            a.into_iter()
                .enumerate()
                .map(|(i, t)| {
                    let name = format!("[[light]] {}", i + 1);
                    let t = t
                        .try_into()
                        .map_err(|e| anyhow::anyhow!("{name}: {}", e.message()))?;
                    Ok((name, t))
                })
                .collect()
        }
        other => bail!("light = {other}: expected a [light] table or [[light]] tables"),
    }
}

/// "x", "xy", "xyz", ... (or "none") to the axes to mirror.
pub fn parse_flip(s: &str) -> Result<[bool; 3]> {
    let mut axes = [false; 3];
    if s == "none" {
        return Ok(axes);
    }
    ensure!(
        !s.is_empty(),
        "'' names no axes (use x, y, z, e.g. \"xy\", or \"none\")"
    );
    for c in s.chars() {
        let i = match c {
            'x' => 0,
            'y' => 1,
            'z' => 2,
            _ => bail!("'{s}': '{c}' is not an axis (use x, y, z, e.g. \"xy\", or \"none\")"),
        };
        ensure!(!axes[i], "'{s}' names {c} twice");
        axes[i] = true;
    }
    Ok(axes)
}

pub fn parse_model(s: &str) -> Result<Model> {
    Model::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = Model::ALL.iter().map(|m| m.name()).collect();
        anyhow::anyhow!("model '{s}' is not one of {}", names.join(", "))
    })
}

pub fn parse_tonemap(s: &str) -> Result<ToneOperator> {
    match s {
        "aces" => Ok(ToneOperator::Aces),
        "reinhard" => Ok(ToneOperator::Reinhard),
        "none" => Ok(ToneOperator::None),
        _ => bail!("tone map '{s}' is not one of aces, reinhard, none"),
    }
}

/// Parses "u8|u16|i16|f32" (and the open-scivis spellings uint8, ...).
pub fn parse_scalar_kind(s: &str) -> Result<crate::volume::formats::ScalarKind> {
    crate::volume::formats::ScalarKind::parse(s)
        .with_context(|| format!("voxel type '{s}' is not one of u8, u16, i16, f32"))
}

/// "on" / "off" (also "true" / "false", "yes" / "no"), for switches given as flags.
pub fn parse_on_off(text: &str) -> Result<bool> {
    match text.to_ascii_lowercase().as_str() {
        "on" | "true" | "yes" => Ok(true),
        "off" | "false" | "no" => Ok(false),
        other => bail!("\"{other}\" is neither on nor off"),
    }
}
