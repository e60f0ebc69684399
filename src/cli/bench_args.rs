//! The `bench` subcommand's syntax: its modes and their flags.

use std::path::PathBuf;

use clap::{Args, Subcommand};

use refrakt::render::{Levers, LightTransport};

use super::args::{parse_transport, parse_variant, variant_help};

#[derive(Subcommand)]
pub enum BenchCommand {
    /// One row per data set of Tables 6.1 and 6.2 (stand-ins at the thesis' resolutions
    /// unless --data-dir holds the originals): 768² viewport, sample distance 1, 100
    /// frames, the camera orbiting 0.5° per frame; the thesis' figures beside ours.
    Thesis(ThesisArgs),
    /// Sweep time against plane count (several sample distances) and against pixel count
    /// (several viewports), with least-squares fits.
    Scaling(ScalingArgs),
    /// A/B the sweep's speed levers: the thesis rows with several variants (--variant)
    /// rendered interleaved in one process, each variant's time, its ratio to the default
    /// and its image difference to the reference (max and mean |Δ|, PSNR).
    Variants(VariantsArgs),
    /// Compare two `bench thesis` (or two `bench variants`) JSON reports: per row the
    /// mean and median frame time old → new with a noise-aware verdict; with
    /// --fail-on-regression, exit status 1 when any row got slower (for CI).
    Compare(CompareArgs),
    /// Every optical model (EA, AO, refract, ...) on the same rows after Table 1 of Ament
    /// et al., "Ambient Volume Scattering": rendering time, its ratio to EA, and what a
    /// transfer-function, light or phase-function change costs; the paper's figures beside
    /// ours.
    #[command(long_about = MODELS_ABOUT)]
    Models(ModelsArgs),
}

const MODELS_ABOUT: &str = "\
Every optical model refrakt has (`render --model`; EA first, the ratios' base; the \
experimental eikonal model only when --models names it: its light simulation takes seconds to \
minutes on lavapipe, issue 35) on the same rows, after the protocol of Table 1 of Ament, Sadlo and Weiskopf, \"Ambient Volume \
Scattering\" (IEEE TVCG 2013):

- Rows: the thesis stand-ins of `bench thesis` (--rows, --data-dir as there), then the real \
scans lung-ct and mri-head when scripts/fetch-data has put them in the data folder; a \
selected row whose data is missing is reported as skipped, with the reason.
- Viewport 512² × --scale (the stand-in volumes shrink by --scale too; the scans are read \
as they are), sample distance 1, early ray termination at alpha 0.98.
- Rendering time: GPU timestamps of the frame (the `render` scope), median and mean over \
--frames frames after --warmup warm-up frames; the models are rendered interleaved (frame k \
of every model before frame k+1 of any) with the camera orbiting 0.5° per frame. Ratio: a \
model's median over EA's median on the same row.
- Change costs, as the paper's TF/PF/LS columns: the GPU time of everything the renderer \
rebuilds (preintegration table, field texture, extinction volume and its 3D SAT, ...) in \
the first frame of the model after the change, each model on a renderer of its own (a \
shared one would rebuild every model's data in whichever frame came first). TF: every opacity × 0.999. LS: the light \
direction turned by 1° (models that use the light; else n/a): for the eikonal model, its \
light update (the simulation run again). PF: the phase function's g moved by 0.01 (models \
with one: single, ambient, eikonal; else n/a). \"0\" means the change rebuilt nothing.
- The paper's Supernova figures (GTX 560) are printed beside ours on the supernova row, \
and its whole Table 1 as a reference; with the eikonal model, Eikonal Rendering's own \
figures (Ihrke et al. 2007: 128³ on a GeForce 8800 GTX, about 25 fps at 800 × 600, light \
updates of 5 to 10 s).

Markdown on stdout; --csv, --json (schema refrakt-bench-models/1) and --svg write the \
details. See docs/BENCH.md (\"bench models\").";

#[derive(Args)]
pub struct GenerateArgs {
    /// Stand-ins to generate (supernova, piggy-bank, glass, hand, head, water, ship,
    /// kiwi); default: all.
    #[arg(value_delimiter = ',')]
    pub names: Vec<String>,
    /// Fraction of the thesis resolution.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub scale: f64,
}

/// What every timing mode of `bench` over the thesis' rows takes.
#[derive(Args)]
pub struct TimedRows {
    /// Shrinks viewport and volumes together (e.g. 0.25 on lavapipe, where a full-size
    /// frame takes tens of seconds). Recorded in the report.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub scale: f64,
    /// Measured frames per row (and per variant or model). Default: 100 for `bench
    /// thesis` (the thesis' count), 20 for the others.
    #[arg(long, allow_negative_numbers = true)]
    pub frames: Option<u32>,
    /// Warm-up frames per row (and per variant or model), interleaved like the measured
    /// ones and excluded from the statistics (reported). Default: 3 for `bench thesis`,
    /// 2 for the others.
    #[arg(long, allow_negative_numbers = true)]
    pub warmup: Option<u32>,
    /// Rows to run, comma-separated: the thesis' supernova, piggy-bank, glass, hand,
    /// head, water, ship, kiwi and, for `bench models`, the fetched scans lung-ct and
    /// mri-head. Default: all.
    #[arg(long, value_delimiter = ',')]
    pub rows: Vec<String>,
    /// Folder with the thesis originals (<name>.<ext>, e.g. supernova.nrrd) that replace
    /// the stand-ins, and the fetched scans (scripts/fetch-data). Default:
    /// $REFRAKT_DATA_DIR or ~/.cache/refrakt/data.
    #[arg(long, value_name = "DIR")]
    pub data_dir: Option<PathBuf>,
    /// Write every frame time (warm-up included) with the full context as CSV.
    #[arg(long, value_name = "FILE.csv")]
    pub csv: Option<PathBuf>,
    /// Write the whole report as JSON (schemas in docs/BENCH.md).
    #[arg(long, value_name = "FILE.json")]
    pub json: Option<PathBuf>,
    /// No progress bar on stderr.
    #[arg(long)]
    pub quiet: bool,
}

/// The sweep's light transport of a timing mode's rows.
#[derive(Args)]
pub struct TransportArg {
    /// The sweep's light transport on every row, instead of the scenes' own (forward):
    /// "backward" is the thesis' Algorithm 1, the method its Tables 6.1 and 6.2 time;
    /// "forward" traces light rays and splats their flux (caustics where geometric optics
    /// puts them), a different algorithm at several times the cost. Recorded in the
    /// report; `bench compare` refuses to compare reports of different transports.
    #[arg(long, value_name = "forward|backward", value_parser = parse_transport)]
    pub light_transport: Option<LightTransport>,
}

#[derive(Args)]
pub struct ThesisArgs {
    #[command(flatten)]
    pub timed: TimedRows,
    /// Also time, interleaved with the sweep, the EA ray marcher, the sweep's floor (same
    /// buffers, a shader that only carries the state) and its skeleton (Algorithm 1's
    /// fetches and plain arithmetic, none of the optics past it) per row, and print the
    /// ratios (docs/BENCH.md)
    #[arg(long)]
    pub baselines: bool,
    /// Draw the thesis' mean frame times beside ours as an SVG bar chart.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
    #[arg(
        long,
        value_name = "SPEC",
        value_parser = parse_variant,
        help = variant_help("The sweep's levers every row uses (the floor baseline too), \
            recorded in the report [default: default].")
    )]
    pub variant: Option<Levers>,
    #[command(flatten)]
    pub transport: TransportArg,
}

#[derive(Args)]
pub struct VariantsArgs {
    #[command(flatten)]
    pub timed: TimedRows,
    #[arg(
        long,
        value_name = "SPEC",
        value_parser = parse_variant,
        help = variant_help("A variant to time; repeat the flag for more (a SPEC has commas \
            of its own). Default: reference, default, and the default with each lever flipped \
            alone.")
    )]
    pub variant: Vec<Levers>,
    #[command(flatten)]
    pub transport: TransportArg,
}

#[derive(Args)]
pub struct ModelsArgs {
    #[command(flatten)]
    pub timed: TimedRows,
    /// Models to time, comma-separated (ea, ao, single, ambient, refract, eikonal); ea is
    /// always timed (the ratios' base). Default: all but the experimental eikonal model.
    #[arg(long, value_delimiter = ',', value_name = "MODELS")]
    pub models: Vec<String>,
    /// Draw the median rendering time per model and row as an SVG bar chart.
    #[arg(long, value_name = "FILE.svg", visible_alias = "plot")]
    pub svg: Option<PathBuf>,
    /// The ambient-scattering model's preintegrated table, a file written by `refrakt
    /// precompute ambient --out` (albedo 0.9, the paper's). Default: the cached table,
    /// built on first use.
    #[arg(long, value_name = "FILE")]
    pub ambient_table: Option<PathBuf>,
}

#[derive(Args)]
pub struct CompareArgs {
    /// The earlier report (e.g. measured on main).
    #[arg(value_name = "OLD.json")]
    pub old: PathBuf,
    /// The later report (e.g. measured on the branch).
    #[arg(value_name = "NEW.json")]
    pub new: PathBuf,
    /// Exit with status 1 when any row (or variant) is "slower".
    #[arg(long)]
    pub fail_on_regression: bool,
    /// Compare reports whose settings differ (device, scale, sample distance, a row's
    /// viewport, resolution, planes or data) instead of refusing; the differences are
    /// printed.
    #[arg(long)]
    pub allow_mismatch: bool,
    /// A change of the median counts only beyond K × √(se_old² + se_new²), se = s/√n of
    /// each side's per-frame times.
    #[arg(long, value_name = "K", default_value_t = refrakt::bench::NOISE_K)]
    pub noise_k: f64,
    /// ... and beyond this percentage of the old median.
    #[arg(long, value_name = "PERCENT", default_value_t = 100.0 * refrakt::bench::MIN_CHANGE)]
    pub min_change: f64,
}

#[derive(Args)]
pub struct ScalingArgs {
    /// Scene to time (any `refrakt render` scene).
    #[arg(long, default_value = "sphere-on-floor")]
    pub scene: String,
    /// Voxels per side for a procedural scene.
    #[arg(long, default_value_t = 64, allow_negative_numbers = true)]
    pub volume_size: u32,
    /// Sample distances for the plane-count series.
    #[arg(long, value_delimiter = ',', default_value = "0.5,1,2,4")]
    pub sample_distances: Vec<f32>,
    /// Viewport sides for the pixel-count series.
    #[arg(long, value_delimiter = ',', default_value = "64,96,128,192")]
    pub sides: Vec<u32>,
    /// Viewport side for the plane-count series.
    #[arg(long, default_value_t = 128, allow_negative_numbers = true)]
    pub side: u32,
    /// Measured frames per point (after one warm-up).
    #[arg(long, default_value_t = 3, allow_negative_numbers = true)]
    pub frames: u32,
    /// Write the report as JSON.
    #[arg(long, value_name = "FILE.json")]
    pub json: Option<PathBuf>,
    /// Folder of fetched data (see `render --data-dir`).
    #[arg(long, value_name = "DIR")]
    pub data_dir: Option<PathBuf>,
    /// No progress bar on stderr.
    #[arg(long)]
    pub quiet: bool,
}
