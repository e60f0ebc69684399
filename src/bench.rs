//! Benchmark mode: the protocol of the thesis' Tables 6.1 and 6.2 on the local device
//! (`refrakt bench thesis`), and how the sweep's cost scales with planes and pixels
//! (`refrakt bench scaling`). Every time is a GPU timestamp difference; a frame's time is
//! the `render` scope of `Renderer::record` (all passes and barriers of the frame).
//! docs/BENCH.md documents the protocol and the CSV/JSON schema.

use std::path::{Path, PathBuf};
use std::time::SystemTime;

use anyhow::{bail, ensure, Context as _, Result};
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};

use crate::render::{Camera, Frame, Model, RenderOptions, Renderer};
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

#[derive(Clone, Debug)]
pub struct ThesisSettings {
    pub scale: f64,
    pub frames: u32,
    pub warmup: u32,
    pub rows: Vec<String>,
    pub baselines: bool,
    pub data_dir: PathBuf,
    pub progress: bool,
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
    /// bytes_per_plane_pixel × plane_pixels_per_s.
    pub effective_gb_per_s: f64,
    pub ea: Option<Variant>,
    pub floor: Option<Variant>,
    pub sweep_over_ea: Option<f64>,
    pub sweep_over_floor: Option<f64>,
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

/// Renders warm-up and measured frames of one variant, orbiting the camera.
#[allow(clippy::too_many_arguments)]
fn run_variant(
    renderer: &mut Renderer,
    name: &str,
    model: Model,
    camera: &Camera,
    opts: &RenderOptions,
    warmup: u32,
    frames: u32,
    pb: &ProgressBar,
) -> Result<(Variant, Option<u32>, Option<u64>)> {
    let mut warm = Vec::new();
    let mut times = Vec::new();
    let mut sweep = Vec::new();
    let mut passes = Passes::default();
    let mut planes = None;
    let mut bytes = None;
    for k in 0..warmup + frames {
        let cam = Camera {
            azimuth: camera.azimuth + ORBIT_DEG_PER_FRAME * k as f32,
            ..*camera
        };
        let f = renderer.render(model, &cam, opts)?;
        let ms = frame_ms(&f)?;
        pb.inc(1);
        if k < warmup {
            warm.push(ms);
            continue;
        }
        times.push(ms);
        let get = |n: &str| f.timings.get(n).unwrap_or(0.0);
        passes.setup_ms += get("sweep setup");
        passes.sweep_ms += get("sweep");
        passes.composite_ms += get("composite");
        passes.raymarch_ms += get("ea raymarch");
        if let Some(s) = &f.sweep {
            sweep.push(get("sweep"));
            planes = Some(s.planes.count);
            bytes = Some(s.bytes_per_plane);
        }
    }
    let n = frames.max(1) as f64;
    passes.setup_ms /= n;
    passes.sweep_ms /= n;
    passes.composite_ms /= n;
    passes.raymarch_ms /= n;
    let stats = Stats::of(&times)?;
    Ok((
        Variant {
            variant: name.to_string(),
            warmup_ms: warm,
            frames_ms: times,
            fps: 1000.0 / stats.mean,
            stats,
            passes,
            sweep_ms: sweep,
        },
        planes,
        bytes,
    ))
}

/// Runs the thesis protocol on every selected row.
pub fn thesis(ctx: &Context, s: &ThesisSettings) -> Result<Report> {
    ensure!(s.frames >= 1, "--frames must be at least 1");
    let rows = select_rows(&s.rows)?;
    let variants = if s.baselines { 3 } else { 1 };
    let total = rows.len() as u64 * (s.warmup + s.frames) as u64 * variants;
    let pb = progress_bar(total, s.progress);
    let side = ((THESIS_VIEWPORT as f64 * s.scale).round() as u32).max(8);
    let mut out = Vec::new();
    for d in rows {
        let mut scene = Scene::builtin(d.name)?.context("stand-in scene")?;
        if let VolumeSource::Standin { scale, .. } = &mut scene.volume {
            *scale = s.scale;
        }
        scene.width = side;
        scene.height = side;
        scene.sample_distance = THESIS_SAMPLE_DISTANCE;
        pb.set_message(format!("{}: preparing the volume", d.name));
        let original = crate::scene::original_in(&s.data_dir, d.name);
        let volume = scene.load_volume(&s.data_dir)?;
        let tf = scene.transfer_functions()?;
        let mut renderer = Renderer::new(ctx, &volume, &tf)?;
        renderer.set_environment(scene.environment_map()?.as_ref())?;
        let preintegration_ms = renderer
            .update_preintegration()?
            .get("preintegration")
            .unwrap_or(0.0);
        let opts = scene.render_options()?;
        pb.set_message(d.name.to_string());
        let (refract, planes, bytes) = run_variant(
            &mut renderer,
            "refract",
            Model::Refract,
            &scene.camera,
            &opts,
            s.warmup,
            s.frames,
            &pb,
        )?;
        let planes = planes.context("the sweep reported no planes")?;
        let bytes = bytes.unwrap_or(0);
        let (ea, floor) = if s.baselines {
            pb.set_message(format!("{}: EA baseline", d.name));
            let ea = run_variant(
                &mut renderer,
                "ea",
                Model::Ea,
                &scene.camera,
                &opts,
                s.warmup,
                s.frames,
                &pb,
            )?
            .0;
            pb.set_message(format!("{}: floor baseline", d.name));
            let mut fo = opts.clone();
            fo.sweep.floor = true;
            let floor = run_variant(
                &mut renderer,
                "floor",
                Model::Refract,
                &scene.camera,
                &fo,
                s.warmup,
                s.frames,
                &pb,
            )?
            .0;
            (Some(ea), Some(floor))
        } else {
            (None, None)
        };
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
            resolution: volume.dims,
            viewport: [side, side],
            planes,
            preintegration_ms,
            ms_per_plane: refract.passes.sweep_ms / planes as f64,
            plane_pixels_per_s,
            bytes_per_plane_pixel,
            effective_gb_per_s: bytes_per_plane_pixel * plane_pixels_per_s / 1e9,
            sweep_over_ea: ea.as_ref().map(|e| refract.stats.mean / e.stats.mean),
            sweep_over_floor: floor.as_ref().map(|f| refract.stats.mean / f.stats.mean),
            refract,
            ea,
            floor,
        });
    }
    pb.finish_and_clear();
    Ok(Report {
        schema: SCHEMA.into(),
        meta: meta(ctx),
        settings: SettingsRecord {
            scale: s.scale,
            frames: s.frames,
            warmup: s.warmup,
            baselines: s.baselines,
            sample_distance: THESIS_SAMPLE_DISTANCE,
            orbit_deg_per_frame: ORBIT_DEG_PER_FRAME,
            rows: out.iter().map(|r| r.dataset.clone()).collect(),
        },
        rows: out,
    })
}

fn dims(d: [u32; 3]) -> String {
    format!("{}×{}×{}", d[0], d[1], d[2])
}

/// The report as Markdown: the thesis table beside ours, the per-pass breakdown, and the
/// baselines when measured.
pub fn markdown(r: &Report) -> String {
    let m = &r.meta;
    let mut s = format!(
        "Device: {} ({}, {} {}, Vulkan {}); refrakt {} ({}); {}\n\
         Protocol: viewport {}² × scale {} , sample distance {}, {} frames after {} warm-up, camera orbiting {}°/frame; GPU timestamps of the whole frame.\n\n",
        m.device,
        m.device_type,
        m.driver,
        m.driver_info,
        m.vulkan,
        m.refrakt_version,
        m.git_commit,
        m.date,
        THESIS_VIEWPORT,
        r.settings.scale,
        r.settings.sample_distance,
        r.settings.frames,
        r.settings.warmup,
        r.settings.orbit_deg_per_frame
    );
    s += "| Dataset | Thesis resolution | Ours | Viewport | Planes | Thesis ms | Thesis FPS | Thesis GPU | Mean ms | FPS | Median | Min | Max | Std-dev |\n";
    s += "|---|---|---|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|\n";
    for row in &r.rows {
        let st = &row.refract.stats;
        s += &format!(
            "| {} | {} | {}{} | {}² | {} | {:.2} | {:.2} | {} | {:.2} | {:.3} | {:.2} | {:.2} | {:.2} | {:.2} |\n",
            row.title,
            dims(row.thesis.resolution),
            dims(row.resolution),
            if row.source == "stand-in" { " (stand-in)" } else { " (original)" },
            row.viewport[0],
            row.planes,
            row.thesis.ms,
            row.thesis.fps,
            row.thesis.gpu.replace("NVIDIA GeForce ", ""),
            st.mean,
            row.refract.fps,
            st.median,
            st.min,
            st.max,
            st.std_dev
        );
    }
    s += "\nPer pass (mean GPU ms) and state-buffer traffic:\n\n";
    s += "| Dataset | Preintegration | Setup | Sweep | Composite | ms/plane | Plane-pixels/s | B/plane-pixel | Effective GB/s |\n";
    s += "|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for row in &r.rows {
        let p = &row.refract.passes;
        s += &format!(
            "| {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.3} | {:.3e} | {:.0} | {:.2} |\n",
            row.title,
            row.preintegration_ms,
            p.setup_ms,
            p.sweep_ms,
            p.composite_ms,
            row.ms_per_plane,
            row.plane_pixels_per_s,
            row.bytes_per_plane_pixel,
            row.effective_gb_per_s
        );
    }
    if r.settings.baselines {
        s += "\nBaselines in the same run (mean GPU ms per frame):\n\n";
        s += "| Dataset | Refract | EA ray marcher | Sweep floor | Refract / EA | Refract / floor |\n";
        s += "|---|---:|---:|---:|---:|---:|\n";
        for row in &r.rows {
            let f = |v: &Option<Variant>| {
                v.as_ref()
                    .map(|v| format!("{:.2}", v.stats.mean))
                    .unwrap_or_default()
            };
            let g = |x: Option<f64>| x.map(|x| format!("{x:.2}")).unwrap_or_default();
            s += &format!(
                "| {} | {:.2} | {} | {} | {} | {} |\n",
                row.title,
                row.refract.stats.mean,
                f(&row.ea),
                f(&row.floor),
                g(row.sweep_over_ea),
                g(row.sweep_over_floor)
            );
        }
    }
    s
}

/// One CSV record per measured or warm-up frame of every variant, each carrying the whole
/// context (device, commit, settings), so a file is self-describing and files concatenate.
pub fn write_csv(r: &Report, path: &Path) -> Result<()> {
    let mut w = csv::Writer::from_path(path)
        .with_context(|| format!("{}: cannot create the CSV file", path.display()))?;
    w.write_record([
        "schema",
        "dataset",
        "variant",
        "frame",
        "warmup",
        "frame_ms",
        "res_x",
        "res_y",
        "res_z",
        "viewport",
        "planes",
        "scale",
        "sample_distance",
        "thesis_ms",
        "thesis_gpu",
        "device",
        "driver",
        "vulkan",
        "refrakt_version",
        "git_commit",
        "date",
    ])?;
    for row in &r.rows {
        let variants = [Some(&row.refract), row.ea.as_ref(), row.floor.as_ref()];
        for v in variants.into_iter().flatten() {
            let all = v
                .warmup_ms
                .iter()
                .map(|t| (true, t))
                .chain(v.frames_ms.iter().map(|t| (false, t)));
            for (k, (warm, t)) in all.enumerate() {
                w.write_record([
                    SCHEMA.to_string(),
                    row.dataset.clone(),
                    v.variant.clone(),
                    k.to_string(),
                    warm.to_string(),
                    format!("{t:.6}"),
                    row.resolution[0].to_string(),
                    row.resolution[1].to_string(),
                    row.resolution[2].to_string(),
                    row.viewport[0].to_string(),
                    row.planes.to_string(),
                    r.settings.scale.to_string(),
                    r.settings.sample_distance.to_string(),
                    row.thesis.ms.to_string(),
                    row.thesis.gpu.clone(),
                    r.meta.device.clone(),
                    r.meta.driver.clone(),
                    r.meta.vulkan.clone(),
                    r.meta.refrakt_version.clone(),
                    r.meta.git_commit.clone(),
                    r.meta.date.clone(),
                ])?;
            }
        }
    }
    w.flush()
        .with_context(|| format!("{}: writing the CSV file", path.display()))?;
    Ok(())
}

pub fn write_json(r: &Report, path: &Path) -> Result<()> {
    let text = serde_json::to_string_pretty(r)?;
    std::fs::write(path, text + "\n")
        .with_context(|| format!("{}: cannot write the JSON file", path.display()))
}

/// Checks an output path before hours of benchmarking, not after.
pub fn check_output(path: &Path, ext: &str) -> Result<()> {
    let e = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if !e.eq_ignore_ascii_case(ext) {
        bail!("{}: expected a .{ext} file", path.display());
    }
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(p) = parent {
        ensure!(p.is_dir(), "{}: the folder does not exist", p.display());
    }
    ensure!(!path.is_dir(), "{}: is a folder", path.display());
    Ok(())
}

// ---- scaling ------------------------------------------------------------------------------

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Point {
    pub planes: u32,
    pub pixels: u64,
    pub sweep_ms: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Fit {
    /// sweep_ms ≈ intercept + slope · x
    pub slope: f64,
    pub intercept: f64,
    pub r2: f64,
}

/// Least-squares line through (x, y).
pub fn fit(x: &[f64], y: &[f64]) -> Result<Fit> {
    ensure!(x.len() == y.len() && x.len() >= 2, "a fit needs two points");
    let n = x.len() as f64;
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    ensure!(sxx > 0.0, "a fit needs two different x values");
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let ss_tot: f64 = y.iter().map(|b| (b - my).powi(2)).sum();
    let ss_res: f64 = x
        .iter()
        .zip(y)
        .map(|(a, b)| (b - intercept - slope * a).powi(2))
        .sum();
    let r2 = if ss_tot > 0.0 {
        1.0 - ss_res / ss_tot
    } else {
        1.0
    };
    Ok(Fit {
        slope,
        intercept,
        r2,
    })
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ScalingReport {
    pub meta: Meta,
    pub scene: String,
    pub frames: u32,
    /// Varying the sample distance at a fixed viewport.
    pub by_planes: Vec<Point>,
    pub planes_fit: Fit,
    /// Varying the viewport at a fixed sample distance.
    pub by_pixels: Vec<Point>,
    pub pixels_fit: Fit,
}

/// Sweep time against plane count (sample distances `distances` at `side`²) and against
/// pixel count (viewports `sides` at the scene's sample distance), each point the mean of
/// `frames` frames after one warm-up.
pub fn scaling(
    ctx: &Context,
    scene: &Scene,
    data_dir: &Path,
    distances: &[f32],
    sides: &[u32],
    frames: u32,
    progress: bool,
) -> Result<ScalingReport> {
    ensure!(frames >= 1, "--frames must be at least 1");
    let volume = scene.load_volume(data_dir)?;
    let tf = scene.transfer_functions()?;
    let mut renderer = Renderer::new(ctx, &volume, &tf)?;
    renderer.set_environment(scene.environment_map()?.as_ref())?;
    let pb = progress_bar(
        ((distances.len() + sides.len()) as u64) * (frames as u64 + 1),
        progress,
    );
    let mut measure = |opts: &RenderOptions| -> Result<Point> {
        let mut sum = 0.0;
        let mut planes = 0;
        for k in 0..=frames {
            let f = renderer.render(Model::Refract, &scene.camera, opts)?;
            pb.inc(1);
            if k > 0 {
                sum += f.timings.get("sweep").context("no timestamps")?;
            }
            planes = f.sweep.as_ref().map(|s| s.planes.count).unwrap_or(0);
        }
        Ok(Point {
            planes,
            pixels: opts.width as u64 * opts.height as u64,
            sweep_ms: sum / frames as f64,
        })
    };
    let base = scene.render_options()?;
    let mut by_planes = Vec::new();
    for &d in distances {
        let mut o = base.clone();
        o.sample_distance = d;
        o.validate()?;
        by_planes.push(measure(&o)?);
    }
    let mut by_pixels = Vec::new();
    for &side in sides {
        let mut o = base.clone();
        o.width = side;
        o.height = side;
        o.validate()?;
        by_pixels.push(measure(&o)?);
    }
    pb.finish_and_clear();
    let planes_fit = fit(
        &by_planes
            .iter()
            .map(|p| p.planes as f64)
            .collect::<Vec<_>>(),
        &by_planes.iter().map(|p| p.sweep_ms).collect::<Vec<_>>(),
    )?;
    let pixels_fit = fit(
        &by_pixels
            .iter()
            .map(|p| p.pixels as f64)
            .collect::<Vec<_>>(),
        &by_pixels.iter().map(|p| p.sweep_ms).collect::<Vec<_>>(),
    )?;
    Ok(ScalingReport {
        meta: meta(ctx),
        scene: scene.name.clone(),
        frames,
        by_planes,
        planes_fit,
        by_pixels,
        pixels_fit,
    })
}

pub fn scaling_markdown(r: &ScalingReport) -> String {
    let mut s = format!(
        "Device: {} ({}); scene {}; mean sweep GPU ms of {} frames per point\n\n",
        r.meta.device, r.meta.driver_info, r.scene, r.frames
    );
    s += "| Planes | Pixels | Sweep ms | ms per plane | ns per plane-pixel |\n|---:|---:|---:|---:|---:|\n";
    for p in r.by_planes.iter().chain(&r.by_pixels) {
        s += &format!(
            "| {} | {} | {:.2} | {:.3} | {:.2} |\n",
            p.planes,
            p.pixels,
            p.sweep_ms,
            p.sweep_ms / p.planes as f64,
            p.sweep_ms * 1e6 / (p.planes as f64 * p.pixels as f64)
        );
    }
    s += &format!(
        "\nAgainst planes (fixed pixels): {:.4} ms per plane + {:.2} ms, R² = {:.4}\n",
        r.planes_fit.slope, r.planes_fit.intercept, r.planes_fit.r2
    );
    s += &format!(
        "Against pixels (fixed sample distance): {:.4} ms per 1000 pixels + {:.2} ms, R² = {:.4}\n",
        r.pixels_fit.slope * 1000.0,
        r.pixels_fit.intercept,
        r.pixels_fit.r2
    );
    s
}

/// Bar chart of the thesis' mean frame time beside ours per row (log scale: on lavapipe
/// the two differ by orders of magnitude), as SVG.
pub fn plot_svg(r: &Report, path: &Path) -> Result<()> {
    use plotters::prelude::*;
    let err = |e: &dyn std::fmt::Display| anyhow::anyhow!("{}: plotting: {e}", path.display());
    let n = r.rows.len();
    ensure!(n > 0, "no rows to plot");
    let all: Vec<f64> = r
        .rows
        .iter()
        .flat_map(|row| [row.thesis.ms, row.refract.stats.mean])
        .collect();
    let lo = all.iter().cloned().fold(f64::INFINITY, f64::min) / 2.0;
    let hi = all.iter().cloned().fold(0.0, f64::max) * 2.0;
    let root = SVGBackend::new(path, (120 * n as u32 + 160, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let caption = format!(
        "Mean frame time, thesis GPU vs {} (scale {})",
        r.meta.device, r.settings.scale
    );
    let mut chart = ChartBuilder::on(&root)
        .caption(caption, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(0f64..n as f64, (lo..hi).log_scale())
        .map_err(|e| err(&e))?;
    let names: Vec<String> = r.rows.iter().map(|row| row.title.clone()).collect();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(n)
        .x_label_formatter(&|x| {
            let i = x.floor() as usize;
            names.get(i).cloned().unwrap_or_default()
        })
        .y_desc("ms per frame (log)")
        .draw()
        .map_err(|e| err(&e))?;
    let thesis = RGBColor(120, 120, 120);
    let ours = RGBColor(200, 80, 40);
    chart
        .draw_series(r.rows.iter().enumerate().map(|(i, row)| {
            let x = i as f64;
            Rectangle::new([(x + 0.15, lo), (x + 0.48, row.thesis.ms)], thesis.filled())
        }))
        .map_err(|e| err(&e))?
        .label("thesis (GTX 1070 / 980)")
        .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], thesis.filled()));
    chart
        .draw_series(r.rows.iter().enumerate().map(|(i, row)| {
            let x = i as f64;
            Rectangle::new(
                [(x + 0.52, lo), (x + 0.85, row.refract.stats.mean)],
                ours.filled(),
            )
        }))
        .map_err(|e| err(&e))?
        .label("ours")
        .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], ours.filled()));
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

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
