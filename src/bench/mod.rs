//! Benchmark mode: the protocol of the thesis' Tables 6.1 and 6.2 on the local device
//! (`refrakt bench thesis`), how the sweep's cost scales with planes and pixels
//! (`refrakt bench scaling`), the sweep's levers A/B'd in one process (`refrakt bench
//! variants`), the optical models side by side after the protocol of Ament et al.'s Table 1
//! (`refrakt bench models`), and two reports compared with a noise-aware verdict (`refrakt bench
//! compare`). Every time is a GPU timestamp difference; a frame's time is
//! the `render` scope of `Renderer::record` (all passes and barriers of the frame).
//! docs/BENCH.md documents the protocol and the CSV/JSON schema.

use std::path::{Path, PathBuf};
use std::time::SystemTime;

use anyhow::{bail, ensure, Context as _, Result};
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};

use crate::render::{
    upload, Camera, Frame, Levers, LightTransport, Model, RenderOptions, Renderer,
};
use crate::scene::{Scene, VolumeSource};
use crate::vk::{self, Context};
use crate::volume::standins::{self, Dataset, DATASETS};

/// Version of the JSON layout; bump when a field changes meaning or goes away.
pub const SCHEMA: &str = "refrakt-bench-thesis/1";

/// Degrees the camera orbits per frame (warm-up included), so that every frame renders a
/// new view and nothing can be reused between frames.
pub const ORBIT_DEG_PER_FRAME: f32 = 0.5;

/// The thesis' viewport side and sample distance (Tables 6.1 and 6.2).
pub const THESIS_VIEWPORT: u32 = 768;
pub const THESIS_SAMPLE_DISTANCE: f32 = 1.0;

/// What every timing mode over the thesis' rows is given: the scale of viewport and
/// volumes, measured and warm-up frames per row (and variant or model), the rows (empty:
/// all), the folder of the originals and fetched scans, and whether to show progress.
#[derive(Clone, Debug)]
pub struct Timing {
    pub scale: f64,
    pub frames: u32,
    pub warmup: u32,
    pub rows: Vec<String>,
    pub data_dir: PathBuf,
    pub progress: bool,
}

impl Timing {
    /// The progress bar's message for frame `k` of a row (warm-up frames first).
    pub fn frame_message(&self, row: &str, k: u32) -> String {
        if k < self.warmup {
            format!("{row}: warm-up {}/{}", k + 1, self.warmup)
        } else {
            format!("{row}: frame {}/{}", k - self.warmup + 1, self.frames)
        }
    }
}

#[derive(Clone, Debug)]
pub struct ThesisSettings {
    pub timing: Timing,
    pub baselines: bool,
    /// The sweep's levers every row uses (the floor baseline too).
    pub levers: Levers,
    /// The sweep's light transport for every row, replacing the scenes' own (`forward`,
    /// the photon-faithful one); `backward` is the thesis' Algorithm 1, the method its
    /// Tables 6.1 and 6.2 time.
    pub light_transport: Option<LightTransport>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Stats {
    pub mean: f64,
    pub median: f64,
    pub min: f64,
    pub max: f64,
    /// Sample standard deviation (n − 1); 0 for one frame.
    pub std_dev: f64,
}

impl Stats {
    pub fn of(v: &[f64]) -> Result<Stats> {
        ensure!(!v.is_empty(), "no frames to summarise");
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let mut s = v.to_vec();
        s.sort_by(|a, b| a.total_cmp(b));
        let median = if s.len() % 2 == 1 {
            s[s.len() / 2]
        } else {
            0.5 * (s[s.len() / 2 - 1] + s[s.len() / 2])
        };
        let var = if v.len() > 1 {
            v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)
        } else {
            0.0
        };
        Ok(Stats {
            mean,
            median,
            min: s[0],
            max: s[s.len() - 1],
            std_dev: var.sqrt(),
        })
    }
}

/// Mean GPU ms per pass over the measured frames.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Passes {
    pub setup_ms: f64,
    pub sweep_ms: f64,
    pub composite_ms: f64,
    /// EA only: the ray marcher.
    pub raymarch_ms: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    /// "refract", "ea" or "floor".
    pub variant: String,
    pub warmup_ms: Vec<f64>,
    pub frames_ms: Vec<f64>,
    pub stats: Stats,
    pub fps: f64,
    pub passes: Passes,
    /// Per-frame sweep pass ms (refract and floor), for the per-plane figures.
    pub sweep_ms: Vec<f64>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Thesis {
    pub table: String,
    pub gpu: String,
    pub resolution: [u32; 3],
    pub ms: f64,
    pub fps: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Row {
    pub dataset: String,
    pub title: String,
    pub thesis: Thesis,
    /// "stand-in" or the original's path from --data-dir.
    pub source: String,
    pub resolution: [u32; 3],
    pub viewport: [u32; 2],
    pub planes: u32,
    /// One table build at this row's transfer functions (not part of the frame time: the
    /// table is rebuilt only when the transfer functions change).
    pub preintegration_ms: f64,
    pub refract: Variant,
    pub ms_per_plane: f64,
    /// planes × pixels / sweep seconds.
    pub plane_pixels_per_s: f64,
    /// State-buffer bytes read and written per plane pixel (attachment loads and stores,
    /// sampled reads including the filter taps).
    pub bytes_per_plane_pixel: f64,
    /// The compulsory part: each state texel a plane needs read once and written once
    /// (`SweepStats::compulsory_bytes_per_plane`).
    #[serde(default)]
    pub compulsory_bytes_per_plane_pixel: f64,
    /// bytes_per_plane_pixel × plane_pixels_per_s.
    pub effective_gb_per_s: f64,
    pub ea: Option<Variant>,
    pub floor: Option<Variant>,
    /// Algorithm 1's fetches and plain arithmetic (`SweepOptions::skeleton`); absent from
    /// reports written before it existed.
    #[serde(default)]
    pub skeleton: Option<Variant>,
    pub sweep_over_ea: Option<f64>,
    pub sweep_over_floor: Option<f64>,
    #[serde(default)]
    pub sweep_over_skeleton: Option<f64>,
}

impl Row {
    /// The sweep and whichever baselines ran, in the order they render each frame.
    pub fn variants(&self) -> impl Iterator<Item = &Variant> {
        [
            Some(&self.refract),
            self.ea.as_ref(),
            self.floor.as_ref(),
            self.skeleton.as_ref(),
        ]
        .into_iter()
        .flatten()
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Meta {
    pub device: String,
    pub device_type: String,
    pub driver: String,
    pub driver_info: String,
    pub vulkan: String,
    pub refrakt_version: String,
    pub git_commit: String,
    /// UTC, RFC 3339.
    pub date: String,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SettingsRecord {
    pub scale: f64,
    pub frames: u32,
    pub warmup: u32,
    pub baselines: bool,
    pub sample_distance: f32,
    pub orbit_deg_per_frame: f32,
    pub rows: Vec<String>,
    /// The sweep's levers (`--variant`, in `Levers`' text form); absent in reports from
    /// before `--variant` existed (they rendered that version's default).
    #[serde(default)]
    pub variant: Option<String>,
    /// The light transport every row's sweep ran (`forward` | `backward`); absent in
    /// reports from before `--light-transport` existed (they ran the scenes' own,
    /// `forward`).
    #[serde(default)]
    pub light_transport: Option<String>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Report {
    pub schema: String,
    pub meta: Meta,
    pub settings: SettingsRecord,
    pub rows: Vec<Row>,
}

pub fn meta(ctx: &Context) -> Meta {
    let i = ctx.info();
    Meta {
        device: i.name.clone(),
        device_type: vk::device_type_name(i.device_type).to_string(),
        driver: i.driver_name.clone(),
        driver_info: i.driver_info.clone(),
        vulkan: vk::version_string(i.api_version),
        refrakt_version: env!("CARGO_PKG_VERSION").to_string(),
        git_commit: env!("REFRAKT_GIT_COMMIT").to_string(),
        date: humantime::format_rfc3339_seconds(SystemTime::now()).to_string(),
    }
}

/// The rows `--rows` names (all eight when empty), in table order.
pub fn select_rows(names: &[String]) -> Result<Vec<&'static Dataset>> {
    if names.is_empty() {
        return Ok(DATASETS.iter().collect());
    }
    for n in names {
        standins::dataset(n)?;
    }
    Ok(DATASETS
        .iter()
        .filter(|d| names.iter().any(|n| n == d.name))
        .collect())
}

fn frame_ms(f: &Frame) -> Result<f64> {
    f.timings
        .get("render")
        .context("the device reports no timestamps; the benchmark needs them")
}

fn progress_bar(total: u64, show: bool) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(total);
    pb.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{bar:30}] {pos}/{len} frames, ETA {eta} {msg}",
        )
        .expect("static template")
        .progress_chars("=> "),
    );
    pb
}

/// The camera of frame `k` (warm-up frames counted): `camera` orbited
/// [`ORBIT_DEG_PER_FRAME`] per frame about the vertical axis.
fn orbit(camera: &Camera, k: u32) -> Camera {
    Camera {
        azimuth: camera.azimuth + ORBIT_DEG_PER_FRAME * k as f32,
        ..*camera
    }
}

/// A timed variant with the sweep's plane count and bytes per plane, fetched and
/// compulsory (of its last frame; None for a model without a sweep).
type Timed = (Variant, Option<u32>, Option<(u64, u64)>);

/// One variant's frames as they come (warm-up apart), summarised by [`Collector::finish`].
#[derive(Default)]
struct Collector {
    warm: Vec<f64>,
    times: Vec<f64>,
    sweep: Vec<f64>,
    passes: Passes,
    planes: Option<u32>,
    bytes: Option<(u64, u64)>,
}

impl Collector {
    fn add(&mut self, f: &Frame, warmup: bool) -> Result<()> {
        let ms = frame_ms(f)?;
        if warmup {
            self.warm.push(ms);
            return Ok(());
        }
        self.times.push(ms);
        let get = |n: &str| f.timings.get(n).unwrap_or(0.0);
        self.passes.setup_ms += get("sweep setup");
        self.passes.sweep_ms += get("sweep");
        self.passes.composite_ms += get("composite");
        self.passes.raymarch_ms += get("ea raymarch");
        if let Some(s) = &f.sweep {
            self.sweep.push(get("sweep"));
            self.planes = Some(s.planes.count);
            self.bytes = Some((s.bytes_per_plane, s.compulsory_bytes_per_plane));
        }
        Ok(())
    }

    /// The variant, with the sweep's plane count and bytes per plane (of the last frame).
    fn finish(self, name: &str) -> Result<Timed> {
        let mut passes = self.passes;
        let n = self.times.len().max(1) as f64;
        passes.setup_ms /= n;
        passes.sweep_ms /= n;
        passes.composite_ms /= n;
        passes.raymarch_ms /= n;
        let stats = Stats::of(&self.times)?;
        Ok((
            Variant {
                variant: name.to_string(),
                warmup_ms: self.warm,
                frames_ms: self.times,
                fps: 1000.0 / stats.mean,
                stats,
                passes,
                sweep_ms: self.sweep,
            },
            self.planes,
            self.bytes,
        ))
    }
}

/// Renders warm-up and measured frames of the variants `(name, model, options)`,
/// interleaved (frame k of every variant before frame k + 1 of any, all at the same
/// orbited camera), so that a swing in machine load hits them alike and their ratios
/// stay fair: on lavapipe a short EA frame has read 4–5× its time while something else
/// ran, for a whole sequential run of it. Returns each variant with the sweep's plane
/// count and bytes per plane (of its last frame), in the given order.
fn run_interleaved(
    renderer: &mut Renderer,
    variants: &[(&str, Model, &RenderOptions)],
    camera: &Camera,
    warmup: u32,
    frames: u32,
    pb: &ProgressBar,
) -> Result<Vec<Timed>> {
    let mut collectors: Vec<Collector> = variants.iter().map(|_| Collector::default()).collect();
    for k in 0..warmup + frames {
        let cam = orbit(camera, k);
        for ((_, model, opts), c) in variants.iter().zip(&mut collectors) {
            let f = renderer.render(*model, &cam, opts)?;
            pb.inc(1);
            c.add(&f, k < warmup)?;
        }
    }
    collectors
        .into_iter()
        .zip(variants)
        .map(|(c, (name, _, _))| c.finish(name))
        .collect()
}

/// A thesis stand-in row's scene at `scale` (volume and viewport) and the thesis' sample
/// distance, its volume loaded (an original from `data_dir` if there is one), and a
/// renderer with its transfer functions, environment and preintegration table (timed)
/// set up: what `thesis` and `variants` time.
pub(crate) struct PreparedRow {
    pub scene: Scene,
    pub original: Option<PathBuf>,
    pub resolution: [u32; 3],
    pub side: u32,
    pub preintegration_ms: f64,
    pub opts: RenderOptions,
}

/// The viewport side at `scale` (at least 8 pixels).
fn scaled_side(scale: f64) -> u32 {
    ((THESIS_VIEWPORT as f64 * scale).round() as u32).max(8)
}

fn prepare_row(
    ctx: &Context,
    d: &Dataset,
    scale: f64,
    data_dir: &Path,
) -> Result<(PreparedRow, Renderer)> {
    prepare_builtin(ctx, d.name, scale, scaled_side(scale), data_dir)
}

/// [`prepare_row`] for any built-in scene (a stand-in, its volume shrunk by `scale`, or a
/// fetched scan, read as it is) at a `side`² viewport. `original` is the file read: the
/// stand-in's original from `data_dir`, or the scan.
pub(crate) fn prepare_builtin(
    ctx: &Context,
    name: &str,
    scale: f64,
    side: u32,
    data_dir: &Path,
) -> Result<(PreparedRow, Renderer)> {
    let mut scene = Scene::builtin(name)?.with_context(|| format!("{name}: no such scene"))?;
    if let VolumeSource::Standin { scale: s, .. } = &mut scene.volume {
        *s = scale;
    }
    scene.width = side;
    scene.height = side;
    scene.sample_distance = THESIS_SAMPLE_DISTANCE;
    let original = match &scene.volume {
        VolumeSource::Fetched { file, .. } => Some(data_dir.join(file)),
        _ => crate::scene::original_in(data_dir, name),
    };
    let volume = scene.load_volume(data_dir, Some(upload::device_limits(ctx)))?;
    let tf = scene.transfer_functions()?;
    let mut renderer = Renderer::new(ctx, &volume, &tf)?;
    renderer.set_environment(scene.environment_map()?.as_ref())?;
    let preintegration_ms = renderer
        .update_preintegration()?
        .get("preintegration")
        .unwrap_or(0.0);
    let opts = scene.render_options()?;
    Ok((
        PreparedRow {
            scene,
            original,
            resolution: volume.dims,
            side,
            preintegration_ms,
            opts,
        },
        renderer,
    ))
}

/// What a report records as the rows' light transport: its name when every row ran the
/// same, else "per scene".
fn transport_record(t: &[LightTransport]) -> String {
    match t.first() {
        Some(f) if t.iter().all(|x| x == f) => f.name().to_string(),
        Some(_) => "per scene".into(),
        None => "none".into(),
    }
}

/// Runs the thesis protocol on every selected row.
pub fn thesis(ctx: &Context, s: &ThesisSettings) -> Result<Report> {
    ensure!(s.timing.frames >= 1, "--frames must be at least 1");
    let rows = select_rows(&s.timing.rows)?;
    let variants = if s.baselines { 4 } else { 1 };
    let total = rows.len() as u64 * (s.timing.warmup + s.timing.frames) as u64 * variants;
    let pb = progress_bar(total, s.timing.progress);
    let side = scaled_side(s.timing.scale);
    let mut out = Vec::new();
    let mut transports = Vec::new();
    for d in rows {
        pb.set_message(format!("{}: preparing the volume", d.name));
        let (row, mut renderer) = prepare_row(ctx, d, s.timing.scale, &s.timing.data_dir)?;
        let PreparedRow {
            scene,
            original,
            resolution,
            preintegration_ms,
            mut opts,
            ..
        } = row;
        opts.sweep.levers = s.levers;
        if let Some(t) = s.light_transport {
            opts.sweep.light_transport = t;
        }
        transports.push(opts.sweep.light_transport);
        pb.set_message(d.name.to_string());
        let mut floor_opts = opts.clone();
        floor_opts.sweep.floor = true;
        let mut skeleton_opts = opts.clone();
        skeleton_opts.sweep.skeleton = true;
        let mut variants = vec![("refract", Model::Refract, &opts)];
        if s.baselines {
            variants.push(("ea", Model::Ea, &opts));
            variants.push(("floor", Model::Refract, &floor_opts));
            variants.push(("skeleton", Model::Refract, &skeleton_opts));
        }
        let mut runs = run_interleaved(
            &mut renderer,
            &variants,
            &scene.camera,
            s.timing.warmup,
            s.timing.frames,
            &pb,
        )?
        .into_iter();
        let (refract, planes, bytes) = runs.next().context("the sweep was not timed")?;
        let planes = planes.context("the sweep reported no planes")?;
        let (bytes, compulsory) = bytes.unwrap_or((0, 0));
        let ea = runs.next().map(|r| r.0);
        let floor = runs.next().map(|r| r.0);
        let skeleton = runs.next().map(|r| r.0);
        let pixels = side as f64 * side as f64;
        let sweep_s = refract.passes.sweep_ms / 1000.0;
        let plane_pixels_per_s = if sweep_s > 0.0 {
            planes as f64 * pixels / sweep_s
        } else {
            0.0
        };
        let bytes_per_plane_pixel = bytes as f64 / pixels;
        out.push(Row {
            dataset: d.name.to_string(),
            title: d.title.to_string(),
            thesis: Thesis {
                table: d.table.to_string(),
                gpu: d.thesis_gpu.to_string(),
                resolution: d.dims,
                ms: d.thesis_ms,
                fps: d.thesis_fps,
            },
            source: original
                .map(|p| p.display().to_string())
                .unwrap_or_else(|| "stand-in".into()),
            resolution,
            viewport: [side, side],
            planes,
            preintegration_ms,
            ms_per_plane: refract.passes.sweep_ms / planes as f64,
            plane_pixels_per_s,
            bytes_per_plane_pixel,
            compulsory_bytes_per_plane_pixel: compulsory as f64 / pixels,
            effective_gb_per_s: bytes_per_plane_pixel * plane_pixels_per_s / 1e9,
            sweep_over_ea: ea.as_ref().map(|e| refract.stats.mean / e.stats.mean),
            sweep_over_floor: floor.as_ref().map(|f| refract.stats.mean / f.stats.mean),
            sweep_over_skeleton: skeleton.as_ref().map(|k| refract.stats.mean / k.stats.mean),
            refract,
            ea,
            floor,
            skeleton,
        });
    }
    pb.finish_and_clear();
    Ok(Report {
        schema: SCHEMA.into(),
        meta: meta(ctx),
        settings: SettingsRecord {
            scale: s.timing.scale,
            frames: s.timing.frames,
            warmup: s.timing.warmup,
            baselines: s.baselines,
            sample_distance: THESIS_SAMPLE_DISTANCE,
            orbit_deg_per_frame: ORBIT_DEG_PER_FRAME,
            rows: out.iter().map(|r| r.dataset.clone()).collect(),
            variant: Some(s.levers.to_string()),
            light_transport: Some(transport_record(&transports)),
        },
        rows: out,
    })
}

mod compare;
mod models;
mod models_report;
mod scaling;
mod variants;
mod writers;

pub use compare::*;
pub use models::*;
pub use models_report::*;
pub use scaling::*;
pub use variants::*;
pub use writers::*;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stats_of_known_samples() {
        let s = Stats::of(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]).unwrap();
        assert_eq!(s.mean, 5.0);
        assert_eq!(s.median, 4.5);
        assert_eq!((s.min, s.max), (2.0, 9.0));
        // Sample variance 32/7.
        assert!((s.std_dev - (32.0f64 / 7.0).sqrt()).abs() < 1e-12);
        assert!(Stats::of(&[]).is_err());
    }

    #[test]
    fn fit_recovers_a_line() {
        let x = [10.0, 20.0, 40.0, 80.0];
        let y: Vec<f64> = x.iter().map(|v| 3.0 + 0.5 * v).collect();
        let f = fit(&x, &y).unwrap();
        assert!((f.slope - 0.5).abs() < 1e-12 && (f.intercept - 3.0).abs() < 1e-9);
        assert!((f.r2 - 1.0).abs() < 1e-12);
        assert!(fit(&[1.0, 1.0], &[2.0, 3.0]).is_err());
    }

    #[test]
    fn rows_select_in_table_order_and_unknown_is_an_error() {
        let r = select_rows(&["kiwi".into(), "supernova".into()]).unwrap();
        assert_eq!(
            r.iter().map(|d| d.name).collect::<Vec<_>>(),
            ["supernova", "kiwi"]
        );
        assert_eq!(select_rows(&[]).unwrap().len(), 8);
        let e = select_rows(&["teapot".into()]).unwrap_err().to_string();
        assert!(e.contains("teapot") && e.contains("supernova"), "{e}");
    }
}
