//! `bench models`: every optical model of [`Model::benched`] (or those `--models` names)
//! on the same rows, after the protocol of Table 1 of Ament et al., "Ambient Volume
//! Scattering" (512² viewport, early ray termination at α = 0.98): per row and model the
//! rendering time, its ratio to EA's, and what a change of the transfer function (TF),
//! the light source (LS) and the phase function (PF) costs: the GPU time of everything
//! the renderer rebuilds for it ([`rebuild_scopes`]) in the first frame after the change,
//! measured per model on a renderer of its own. The models are rendered interleaved frame
//! by frame (frame k of every model before frame k+1 of any), as `bench variants` does,
//! so a change in machine load hits them alike.

use glam::{Quat, Vec3};

use super::*;
use crate::render::{rebuild_scopes, SCATTER_G};
use crate::scene::FETCHED;
use crate::transfer::TransferFunctions;

/// Version of the models report's JSON layout.
pub const MODELS_SCHEMA: &str = "refrakt-bench-models/1";

/// The paper's viewport side (Table 1: 512² pixels).
pub const MODELS_VIEWPORT: u32 = 512;

/// The paper's early-ray-termination threshold (Table 1: α = 0.98).
pub const MODELS_TERMINATION_ALPHA: f32 = 0.98;

/// Every opacity is scaled by this for the TF change (a slightly different transfer
/// function: everything that depends on it must be rebuilt, the image barely changes).
pub const TF_CHANGE_OPACITY_SCALE: f32 = 0.999;

/// Degrees the light direction turns for the LS change.
pub const LS_CHANGE_DEG: f32 = 1.0;

/// The real scans `bench models` times after the thesis rows when their data is present:
/// name and title (their files and presets are [`FETCHED`]'s).
pub const SCAN_ROWS: [(&str, &str); 2] = [("lung-ct", "Lung CT"), ("mri-head", "MRI head")];

#[derive(Clone, Debug)]
pub struct ModelsSettings {
    /// Rows by name: thesis stand-ins and [`SCAN_ROWS`].
    pub timing: Timing,
    /// The models timed, in the order each frame renders them, EA first
    /// ([`select_models`]).
    pub models: Vec<Model>,
    /// The ambient-scattering model's table (for the default albedo); `None`: each
    /// renderer loads the cached one (built on first use).
    pub ambient_table: Option<crate::render::ambient::table::AmbientTable>,
}

/// A row `bench models` can time: a thesis stand-in or a fetched scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelsRowSpec {
    pub name: &'static str,
    pub title: &'static str,
    /// The fetched file (relative to the data directory) of a scan; None for a stand-in.
    pub scan_file: Option<&'static str>,
}

/// Every row `bench models` knows, in report order: the thesis rows, then the scans.
pub fn models_row_specs() -> Vec<ModelsRowSpec> {
    let mut v: Vec<ModelsRowSpec> = DATASETS
        .iter()
        .map(|d| ModelsRowSpec {
            name: d.name,
            title: d.title,
            scan_file: None,
        })
        .collect();
    for (name, title) in SCAN_ROWS {
        let file = FETCHED
            .iter()
            .find(|f| f.0 == name)
            .map(|f| f.1)
            .expect("every scan row is a fetched scene");
        v.push(ModelsRowSpec {
            name,
            title,
            scan_file: Some(file),
        });
    }
    v
}

/// The rows `--rows` names (all when empty), in report order; an unknown name is an error
/// that lists the known ones.
pub fn select_models_rows(names: &[String]) -> Result<Vec<ModelsRowSpec>> {
    let all = models_row_specs();
    for n in names {
        if !all.iter().any(|r| r.name == n) {
            let known: Vec<&str> = all.iter().map(|r| r.name).collect();
            bail!("unknown row '{n}'; the rows are {}", known.join(", "));
        }
    }
    Ok(all
        .into_iter()
        .filter(|r| names.is_empty() || names.iter().any(|n| n == r.name))
        .collect())
}

/// The models `--models` names, in [`Model::ALL`]'s order, EA among them (the ratios'
/// base: added when not named); none named: [`Model::benched`]. An experimental model
/// ([`Model::experimental`]) is timed only when named. An unknown name is an error that
/// lists the known ones.
pub fn select_models(names: &[String]) -> Result<Vec<Model>> {
    if names.is_empty() {
        return Ok(Model::benched());
    }
    for n in names {
        if Model::from_name(n).is_none() {
            let known: Vec<&str> = Model::ALL.iter().map(|m| m.name()).collect();
            bail!("unknown model '{n}'; the models are {}", known.join(", "));
        }
    }
    Ok(Model::ALL
        .into_iter()
        .filter(|m| *m == Model::Ea || names.iter().any(|n| n == m.name()))
        .collect())
}

/// Eikonal Rendering's own figures (Ihrke et al. 2007, seed 001, sect. 6), printed
/// beside the eikonal model's: not Table 1's rows but its own scenes, so a reference line
/// rather than a column.
pub const PAPER_EIKONAL: &str = "Eikonal Rendering (Ihrke et al., SIGGRAPH 2007, sect. 6), \
its own scenes at 128³ on a GeForce 8800 GTX: rendering about 25 fps (40 ms) at 800 × 600 \
with one object and the light fixed (24.8 fps in its Fig. 1 left, 26.2 fps in Fig. 8 \
middle); a light update (the simulation run again after the light moved) typically 5 to \
10 s. Ours: the eikonal model's median ms is its view, its LS change ms the simulation \
run again for the light turned by 1°.";

/// The paper's figures for one of its optical models on one row (Table 1; "-" there is
/// None here: the change does not apply to that model).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PaperFigures {
    /// The paper's name of the model.
    pub model: String,
    pub tf_change_ms: Option<f64>,
    pub pf_change_ms: Option<f64>,
    pub ls_change_ms: Option<f64>,
    pub fps: f64,
    /// 1000 / fps.
    pub ms: f64,
    /// The paper's rendering-time ratio to its EA, as the paper states it.
    pub ratio: f64,
}

/// The paper's model, our model's name, TF, PF, LS change ms, fps, ratio to EA.
type PaperEntry = (
    &'static str,
    Option<&'static str>,
    Option<f64>,
    Option<f64>,
    Option<f64>,
    f64,
    f64,
);

/// The paper's Supernova row of Table 1 (GTX 560, 432³, 512²), per its model: our model
/// name it corresponds to (None: we would have no such model), TF, PF, LS change ms, fps, and
/// the ratio to EA it states.
const PAPER_SUPERNOVA: [PaperEntry; 3] = [
    (
        "emission-absorption",
        Some("ea"),
        None,
        None,
        None,
        64.0,
        1.0,
    ),
    (
        "ambient occlusion",
        Some("ao"),
        Some(532.0),
        None,
        None,
        27.0,
        2.4,
    ),
    (
        "ambient scattering",
        Some("ambient"),
        Some(490.0),
        Some(34.0),
        Some(34.0),
        20.0,
        3.2,
    ),
];

/// The paper's name of the row whose figures Table 1 gives beside ours.
pub const PAPER_ROW: &str = "supernova";

fn paper_figures(p: &PaperEntry) -> PaperFigures {
    PaperFigures {
        model: p.0.to_string(),
        tf_change_ms: p.2,
        pf_change_ms: p.3,
        ls_change_ms: p.4,
        fps: p.5,
        ms: 1000.0 / p.5,
        ratio: p.6,
    }
}

/// The paper's Supernova figures for our `model`, if the paper has that model.
pub fn paper_supernova(model: Model) -> Option<PaperFigures> {
    PAPER_SUPERNOVA
        .iter()
        .find(|p| p.1 == Some(model.name()))
        .map(paper_figures)
}

/// Table 1 of the paper as it is printed (model order per row as its colour code:
/// emission-absorption, ambient occlusion, single scattering, ambient scattering, for the
/// models each row shows).
pub const PAPER_TABLE_1: &str = "\
| Data set | Volume size | Figures | TF change [ms] | PF change [ms] | LS change [ms] | Rendering [fps] |
|---|---|---|---|---|---|---|
| Supernova | 432 × 432 × 432 | 1a/b/c | -/532/490 | -/-/34 | -/-/34 | 64/27/20 |
| Vis. Human | 202 × 256 × 259 | 6a/b/c/d/e | 1020/126/117/117/158 | -/-/16/16/16 | 1020/-/16/16/16 | 110/105/60/53/50 |
| Manix (Tiss.) | 256 × 256 × 276 | 7a-e | 182 | 11 | 11 | 38 |
| Manix (Skel.) | 256 × 256 × 276 | 8a-b/c/d/e | 1190/231/192/180 | -/36/16/10 | 1190/36/16/10 | 60/35/35/35 |
| Mecanix | 256 × 256 × 302 | 9a/b/c | 1372/206/192 | -/34/20 | 1372/34/20 | 73/48/48 |
| Buoyancy Flow | 181 × 91 × 181 | 10a/b | -/85 | -/5 | -/5 | 180/63 |
| Boundary Layer | 538 × 54 × 261 | 11a/b/c | 128/780/112 | -/-/8 | -/780/8 | 105/87/69 |
";

/// One rebuild scope's GPU time in a change's frame.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ScopeMs {
    pub scope: String,
    pub ms: f64,
}

/// What one change cost: the sum of the [`rebuild_scopes`] in the first frame after it,
/// and those scopes (empty, and `ms` 0, when the change rebuilt nothing).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Change {
    pub ms: f64,
    pub scopes: Vec<ScopeMs>,
    /// That frame's own rendering time (the `render` scope), for reference.
    pub frame_ms: f64,
}

impl Change {
    fn of(f: &Frame) -> Result<Change> {
        let scopes: Vec<ScopeMs> = rebuild_scopes()
            .into_iter()
            .filter_map(|s| {
                f.timings.get(s).map(|ms| ScopeMs {
                    scope: s.to_string(),
                    ms,
                })
            })
            .collect();
        Ok(Change {
            // Not `sum()`: an empty float sum is -0.
            ms: scopes.iter().fold(0.0, |a, s| a + s.ms),
            scopes,
            frame_ms: frame_ms(f)?,
        })
    }
}

/// One model on one row.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ModelRun {
    /// [`Model::name`].
    pub model: String,
    pub warmup_ms: Vec<f64>,
    pub frames_ms: Vec<f64>,
    pub stats: Stats,
    /// 1000 / median.
    pub fps: f64,
    /// Median rendering time over EA's median on the same row.
    pub ratio_to_ea: f64,
    /// Samples along the longest ray (ray marchers) or sweep planes, of the last frame.
    pub max_steps: u32,
    /// Null: the model has no transfer function to change (never today).
    pub tf_change: Option<Change>,
    /// Null: the model does not use the light (`Model::uses_light`).
    pub ls_change: Option<Change>,
    /// Null: the model has no phase function (`Model::has_phase_function`), or no option
    /// changes it yet.
    pub pf_change: Option<Change>,
    /// The paper's figures for this model on this row (the Supernova row only, and only
    /// for the models the paper has).
    pub paper: Option<PaperFigures>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ModelsRow {
    pub dataset: String,
    pub title: String,
    /// "stand-in", the original's path from --data-dir, or the scan's path.
    pub source: String,
    pub resolution: [u32; 3],
    pub viewport: [u32; 2],
    /// In the order of [`ModelsSettings::models`] (`--models`; default
    /// [`Model::benched`]).
    pub models: Vec<ModelRun>,
    /// The paper's figures of every model it has on this row (Supernova only), ours or
    /// not.
    pub paper: Vec<PaperFigures>,
}

/// A selected row that was not timed, and why.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SkippedRow {
    pub dataset: String,
    pub reason: String,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ModelsSettingsRecord {
    pub scale: f64,
    pub frames: u32,
    pub warmup: u32,
    pub viewport: u32,
    pub sample_distance: f32,
    pub termination_alpha: f32,
    pub orbit_deg_per_frame: f32,
    /// The rows timed.
    pub rows: Vec<String>,
    /// The models, in the order each frame renders them ([`ModelsSettings::models`]).
    pub models: Vec<String>,
    /// The model the ratios divide by.
    pub ratio_to: String,
    /// The scopes a change's cost sums ([`rebuild_scopes`]).
    pub rebuild_scopes: Vec<String>,
    pub tf_change: String,
    pub ls_change: String,
    pub pf_change: String,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ModelsReport {
    pub schema: String,
    pub meta: Meta,
    pub settings: ModelsSettingsRecord,
    pub rows: Vec<ModelsRow>,
    pub skipped: Vec<SkippedRow>,
}

/// The viewport side at `scale` (at least 8 pixels).
pub fn models_side(scale: f64) -> u32 {
    ((MODELS_VIEWPORT as f64 * scale).round() as u32).max(8)
}

/// `tf` with every opacity scaled by [`TF_CHANGE_OPACITY_SCALE`].
fn changed_tf(tf: &TransferFunctions) -> TransferFunctions {
    let mut t = tf.clone();
    for p in &mut t.opacity.points {
        p.1[0] *= TF_CHANGE_OPACITY_SCALE;
    }
    t
}

/// `opts` with the main light turned [`LS_CHANGE_DEG`] about the volume's centre (about an
/// axis perpendicular to the direction towards it): a directional light's direction, a
/// point light's position.
fn changed_light(opts: &RenderOptions) -> RenderOptions {
    use crate::light::LightSource;
    let mut o = opts.clone();
    let turn = |v: Vec3| {
        let axis = v.normalize_or_zero().any_orthonormal_vector();
        Quat::from_axis_angle(axis, LS_CHANGE_DEG.to_radians()) * v
    };
    let l = o.light_mut();
    l.source = match l.source {
        LightSource::Directional { towards } => LightSource::Directional {
            towards: turn(towards),
        },
        LightSource::Point { position } => LightSource::Point {
            position: turn(position),
        },
    };
    o
}

/// The phase-function change: `opts` with the anisotropy g of `model`'s phase function
/// moved by 0.01 (towards 0, so it stays valid), or None for a model without a phase
/// function (reported "n/a").
pub fn change_phase_function(opts: &RenderOptions, model: Model) -> Option<RenderOptions> {
    if !model.has_phase_function() {
        return None;
    }
    let mut changed = opts.clone();
    let g = opts.model_option(&SCATTER_G);
    let moved = if g > 0.0 { g - 0.01 } else { g + 0.01 };
    changed.models.set(&SCATTER_G, moved).ok()?;
    Some(changed)
}

/// Renders `model` once and returns what its rebuild scopes cost.
fn change_frame(
    renderer: &mut Renderer,
    model: Model,
    camera: &Camera,
    opts: &RenderOptions,
) -> Result<Change> {
    let f = renderer.render(model, camera, opts)?;
    Change::of(&f)
}

/// Why a row cannot be timed, if its data is missing.
fn missing(spec: &ModelsRowSpec, data_dir: &Path) -> Option<String> {
    let file = spec.scan_file?;
    let path = data_dir.join(file);
    (!path.exists()).then(|| {
        format!(
            "{} not found (run scripts/fetch-data, or point REFRAKT_DATA_DIR / --data-dir at \
             where it put the data)",
            path.display()
        )
    })
}

/// Frames one row renders: the interleaved frames, and per model one first frame and one
/// per applicable change.
fn frames_per_row(s: &ModelsSettings) -> u64 {
    let models = &s.models;
    let changes: u64 = models
        .iter()
        .map(|m| 2 + m.uses_light() as u64 + m.has_phase_function() as u64)
        .sum();
    (s.timing.warmup + s.timing.frames) as u64 * models.len() as u64 + changes
}

/// Times every model of `s.models` on every selected row.
pub fn models(ctx: &Context, s: &ModelsSettings) -> Result<ModelsReport> {
    ensure!(s.timing.frames >= 1, "--frames must be at least 1");
    standins::check_scale(s.timing.scale).context("--scale")?;
    let specs = select_models_rows(&s.timing.rows)?;
    let models = s.models.clone();
    ensure!(
        models.contains(&Model::Ea),
        "the models timed must include ea (the ratios' base)"
    );
    let ea = models.iter().position(|m| *m == Model::Ea).unwrap_or(0);
    let side = models_side(s.timing.scale);
    let mut skipped = Vec::new();
    let mut timed = Vec::new();
    for spec in specs {
        match missing(&spec, &s.timing.data_dir) {
            Some(reason) => skipped.push(SkippedRow {
                dataset: spec.name.to_string(),
                reason,
            }),
            None => timed.push(spec),
        }
    }
    let pb = progress_bar(timed.len() as u64 * frames_per_row(s), s.timing.progress);
    for k in &skipped {
        pb.println(format!("skipping {}: {}", k.dataset, k.reason));
    }
    let nm = models.len();
    let mut out = Vec::new();
    for spec in timed {
        pb.set_message(format!("{}: preparing the volume", spec.name));
        let (row, mut renderer) =
            prepare_builtin(ctx, spec.name, s.timing.scale, side, &s.timing.data_dir)?;
        if let Some(t) = &s.ambient_table {
            renderer.set_ambient_table(t)?;
        }
        let mut opts = row.opts.clone();
        opts.termination_alpha = MODELS_TERMINATION_ALPHA;
        let mut times = vec![(Vec::new(), Vec::new()); nm];
        let mut steps = vec![0u32; nm];
        for k in 0..s.timing.warmup + s.timing.frames {
            let warm = k < s.timing.warmup;
            pb.set_message(s.timing.frame_message(spec.name, k));
            let camera = orbit(&row.scene.camera, k);
            for (i, m) in models.iter().enumerate() {
                let f = renderer.render(*m, &camera, &opts)?;
                let ms = frame_ms(&f)?;
                steps[i] = f.max_steps;
                if warm {
                    times[i].0.push(ms);
                } else {
                    times[i].1.push(ms);
                }
                pb.inc(1);
            }
        }
        // The changes, one model at a time, each on a renderer of its own (as an
        // application showing that model alone would have): a shared renderer rebuilds
        // every model's data in whichever frame comes first after a change.
        drop(renderer);
        let camera = orbit(&row.scene.camera, s.timing.warmup + s.timing.frames);
        let mut changes = Vec::new();
        for &m in &models {
            pb.set_message(format!("{}: {} changes", spec.name, m.name()));
            let (_, mut renderer) =
                prepare_builtin(ctx, spec.name, s.timing.scale, side, &s.timing.data_dir)?;
            if let Some(t) = &s.ambient_table {
                renderer.set_ambient_table(t)?;
            }
            // The model's first frame makes what it needs.
            renderer.render(m, &camera, &opts)?;
            pb.inc(1);
            let tf = changed_tf(renderer.transfer_functions());
            renderer.set_transfer_functions(&tf)?;
            let tf_change = Some(change_frame(&mut renderer, m, &camera, &opts)?);
            pb.inc(1);
            let ls_change = if m.uses_light() {
                let c = change_frame(&mut renderer, m, &camera, &changed_light(&opts))?;
                pb.inc(1);
                Some(c)
            } else {
                None
            };
            // From the options the renderer last saw (the moved light), so that only the
            // phase function differs.
            let last = if m.uses_light() {
                changed_light(&opts)
            } else {
                opts.clone()
            };
            let pf_change = if m.has_phase_function() {
                let c = match change_phase_function(&last, m) {
                    Some(o) => Some(change_frame(&mut renderer, m, &camera, &o)?),
                    None => None,
                };
                pb.inc(1);
                c
            } else {
                None
            };
            changes.push((tf_change, ls_change, pf_change));
        }
        let is_paper_row = spec.name == PAPER_ROW;
        let mut runs = Vec::new();
        for (i, ((warmup_ms, frames_ms), (tf_change, ls_change, pf_change))) in
            times.into_iter().zip(changes).enumerate()
        {
            let m = models[i];
            let stats = Stats::of(&frames_ms)?;
            runs.push(ModelRun {
                model: m.name().to_string(),
                warmup_ms,
                frames_ms,
                fps: 1000.0 / stats.median,
                stats,
                ratio_to_ea: 0.0,
                max_steps: steps[i],
                tf_change,
                ls_change,
                pf_change,
                paper: if is_paper_row {
                    paper_supernova(m)
                } else {
                    None
                },
            });
        }
        let base = runs[ea].stats.median;
        for r in &mut runs {
            r.ratio_to_ea = r.stats.median / base;
        }
        out.push(ModelsRow {
            dataset: spec.name.to_string(),
            title: spec.title.to_string(),
            source: match (spec.scan_file, row.original) {
                (None, None) => "stand-in".into(),
                (_, Some(p)) => p.display().to_string(),
                (Some(f), None) => f.to_string(),
            },
            resolution: row.resolution,
            viewport: [side, side],
            models: runs,
            paper: if is_paper_row {
                PAPER_SUPERNOVA.iter().map(paper_figures).collect()
            } else {
                Vec::new()
            },
        });
    }
    pb.finish_and_clear();
    Ok(ModelsReport {
        schema: MODELS_SCHEMA.into(),
        meta: meta(ctx),
        settings: ModelsSettingsRecord {
            scale: s.timing.scale,
            frames: s.timing.frames,
            warmup: s.timing.warmup,
            viewport: side,
            sample_distance: THESIS_SAMPLE_DISTANCE,
            termination_alpha: MODELS_TERMINATION_ALPHA,
            orbit_deg_per_frame: ORBIT_DEG_PER_FRAME,
            rows: out.iter().map(|r| r.dataset.clone()).collect(),
            models: models.iter().map(|m| m.name().to_string()).collect(),
            ratio_to: models[ea].name().to_string(),
            rebuild_scopes: rebuild_scopes().iter().map(|s| s.to_string()).collect(),
            tf_change: format!("every opacity × {TF_CHANGE_OPACITY_SCALE}"),
            ls_change: format!("light direction turned by {LS_CHANGE_DEG}°"),
            pf_change: "the phase function's anisotropy g moved by 0.01 (models with one)".into(),
        },
        rows: out,
        skipped,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_the_thesis_rows_then_the_scans() {
        let all = select_models_rows(&[]).unwrap();
        let names: Vec<&str> = all.iter().map(|r| r.name).collect();
        assert_eq!(names.len(), DATASETS.len() + SCAN_ROWS.len());
        assert_eq!(&names[DATASETS.len()..], ["lung-ct", "mri-head"]);
        let r = select_models_rows(&["mri-head".into(), "kiwi".into()]).unwrap();
        assert_eq!(
            r.iter().map(|r| r.name).collect::<Vec<_>>(),
            ["kiwi", "mri-head"]
        );
        assert_eq!(r[1].scan_file, Some("mri/ch2.nii.gz"));
        let e = select_models_rows(&["teapot".into()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("teapot") && e.contains("lung-ct"), "{e}");
    }

    #[test]
    fn the_paper_supernova_figures_are_table_1s() {
        let ea = paper_supernova(Model::Ea).unwrap();
        assert_eq!((ea.fps, ea.ratio, ea.tf_change_ms), (64.0, 1.0, None));
        let ao = paper_supernova(Model::Ao).unwrap();
        assert_eq!((ao.tf_change_ms, ao.ls_change_ms), (Some(532.0), None));
        assert!((ao.ms - 1000.0 / 27.0).abs() < 1e-12);
        // The stated ratios are the fps ratios, rounded.
        for p in PAPER_SUPERNOVA.iter().map(paper_figures) {
            assert!((64.0 / p.fps - p.ratio).abs() < 0.05, "{}", p.model);
        }
        assert!(paper_supernova(Model::Refract).is_none());
    }

    #[test]
    fn the_changes_differ_from_the_original() {
        let tf = TransferFunctions::load("supernova").unwrap();
        assert_ne!(changed_tf(&tf), tf);
        let o = RenderOptions::default();
        let c = changed_light(&o);
        let cos = c
            .light()
            .towards()
            .normalize()
            .dot(o.light().towards().normalize());
        assert!(cos < 1.0 && cos > 0.999, "{cos}");
    }
}
