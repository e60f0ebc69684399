//! `refrakt generate` and `refrakt bench`: the thesis stand-ins and the timing tables.

use std::path::Path;
use std::process::ExitCode;

use anyhow::{ensure, Context as _, Result};

use refrakt::scene::{self, Scene, VolumeSource};
use refrakt::vk::{Context, ContextDesc};
use refrakt::volume::standins;

use super::args::*;
use super::info::*;

/// A benchmark's report files, checked before minutes of measuring: each has its
/// extension and can be written, and no two are the same file.
fn check_reports(reports: &[(&str, Option<&Path>, &str)]) -> Result<()> {
    let mut outputs = Vec::new();
    for &(flag, path, ext) in reports {
        if let Some(p) = path {
            refrakt::bench::check_output(p, ext).context(flag.to_owned())?;
            outputs.push((flag, p));
        }
    }
    refrakt::files::check_outputs(&outputs, &[])
}

/// The settings every timing mode shares, checked before minutes of measuring: the scale,
/// the frame counts (`defaults`: frames and warm-up where the flags are not given), and
/// the report files with `more` of the mode's own.
fn timed(
    t: &TimedRows,
    [frames, warmup]: [u32; 2],
    more: &[(&str, Option<&Path>, &str)],
) -> Result<refrakt::bench::Timing> {
    standins::check_scale(t.scale).context("--scale")?;
    let frames = t.frames.unwrap_or(frames);
    ensure!(frames >= 1, "--frames must be at least 1");
    let mut reports = vec![
        ("--csv", t.csv.as_deref(), "csv"),
        ("--json", t.json.as_deref(), "json"),
    ];
    reports.extend_from_slice(more);
    check_reports(&reports)?;
    Ok(refrakt::bench::Timing {
        scale: t.scale,
        frames,
        warmup: t.warmup.unwrap_or(warmup),
        rows: t.rows.clone(),
        data_dir: t.data_dir.clone().unwrap_or_else(scene::data_dir),
        progress: !t.quiet,
    })
}

/// How one report file is written.
type WriteReport<R> = fn(&R, &Path) -> Result<()>;

/// Writes what the report files of a timing mode ask for (`write` per flag), printing
/// where each went.
fn write_reports<R>(report: &R, files: &[(Option<&Path>, WriteReport<R>)]) -> Result<()> {
    let mut first = true;
    for (path, write) in files {
        if let Some(p) = path {
            write(report, p)?;
            println!("{}wrote {}", if first { "\n" } else { "" }, p.display());
            first = false;
        }
    }
    Ok(())
}

pub fn generate(args: &GenerateArgs) -> Result<ExitCode> {
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

pub fn bench_thesis(desc: &ContextDesc, args: &ThesisArgs) -> Result<ExitCode> {
    let t = &args.timed;
    refrakt::bench::select_rows(&t.rows).context("--rows")?;
    // The thesis timed 100 frames per row.
    let timing = timed(t, [100, 3], &[("--plot", args.plot.as_deref(), "svg")])?;
    let ctx = Context::new(desc)?;
    let settings = refrakt::bench::ThesisSettings {
        timing,
        baselines: args.baselines,
        levers: args.variant.unwrap_or_default(),
        light_transport: args.transport.light_transport,
    };
    let report = refrakt::bench::thesis(&ctx, &settings)?;
    print!("{}", refrakt::bench::markdown(&report));
    write_reports(
        &report,
        &[
            (t.csv.as_deref(), refrakt::bench::write_csv),
            (t.json.as_deref(), refrakt::bench::write_json),
            (args.plot.as_deref(), refrakt::bench::plot_svg),
        ],
    )?;
    finish(ctx)
}

pub fn bench_variants(desc: &ContextDesc, args: &VariantsArgs) -> Result<ExitCode> {
    let t = &args.timed;
    refrakt::bench::select_rows(&t.rows).context("--rows")?;
    refrakt::bench::check_variants(&args.variant).context("--variant")?;
    let timing = timed(t, [20, 2], &[])?;
    let ctx = Context::new(desc)?;
    let settings = refrakt::bench::VariantsSettings {
        timing,
        variants: args.variant.clone(),
        light_transport: args.transport.light_transport,
    };
    let report = refrakt::bench::variants(&ctx, &settings)?;
    print!("{}", refrakt::bench::variants_markdown(&report));
    write_reports(
        &report,
        &[
            (t.csv.as_deref(), refrakt::bench::write_variants_csv),
            (t.json.as_deref(), refrakt::bench::write_json),
        ],
    )?;
    finish(ctx)
}

pub fn bench_models(desc: &ContextDesc, args: &ModelsArgs) -> Result<ExitCode> {
    let t = &args.timed;
    refrakt::bench::select_models_rows(&t.rows).context("--rows")?;
    let models = refrakt::bench::select_models(&args.models).context("--models")?;
    let timing = timed(t, [20, 2], &[("--svg", args.svg.as_deref(), "svg")])?;
    let ctx = Context::new(desc)?;
    // Loaded (or built, a minute on first use) only for the model that reads it.
    let ambient_table = if models.contains(&refrakt::render::Model::Ambient) {
        let albedo = refrakt::render::ScatterOptions::default().albedo;
        let (table, line) =
            super::ambient::table_for(args.ambient_table.as_deref(), albedo, t.quiet)?;
        println!("{line}");
        Some(table)
    } else {
        None
    };
    let settings = refrakt::bench::ModelsSettings {
        timing,
        models,
        ambient_table,
    };
    let report = refrakt::bench::models(&ctx, &settings)?;
    print!("{}", refrakt::bench::models_markdown(&report));
    write_reports(
        &report,
        &[
            (t.csv.as_deref(), refrakt::bench::write_models_csv),
            (t.json.as_deref(), refrakt::bench::write_json),
            (args.svg.as_deref(), refrakt::bench::plot_models_svg),
        ],
    )?;
    finish(ctx)
}

/// `bench compare`: no device needed. Exit status 1 with --fail-on-regression when a row
/// got slower.
pub fn bench_compare(args: &CompareArgs) -> Result<ExitCode> {
    let old = refrakt::bench::read_report(&args.old)?;
    let new = refrakt::bench::read_report(&args.new)?;
    let options = refrakt::bench::CompareOptions {
        noise_k: args.noise_k,
        min_change: args.min_change / 100.0,
        allow_mismatch: args.allow_mismatch,
    };
    let c = refrakt::bench::compare(&args.old, &old, &args.new, &new, options)?;
    print!("{}", refrakt::bench::compare_markdown(&c));
    let slower = c.with_verdict(refrakt::bench::Verdict::Slower);
    if args.fail_on_regression && !slower.is_empty() {
        let list: Vec<String> = slower
            .iter()
            .map(|l| match &l.outcome {
                refrakt::bench::Outcome::Compared(d) => {
                    format!("{} {} ({:+.1} %)", l.dataset, l.variant, d.median_pct)
                }
                _ => format!("{} {}", l.dataset, l.variant),
            })
            .collect();
        eprintln!(
            "regression: slower than {}: {}",
            args.old.display(),
            list.join(", ")
        );
        return Ok(ExitCode::from(1));
    }
    Ok(ExitCode::SUCCESS)
}

pub fn bench_scaling(desc: &ContextDesc, args: &ScalingArgs) -> Result<ExitCode> {
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
    // Each curve is a fit: two different x values at least, checked before measuring.
    let distinct = |v: &[f64]| v.iter().any(|x| *x != v[0]);
    let distances: Vec<f64> = args.sample_distances.iter().map(|&d| d as f64).collect();
    let sides: Vec<f64> = args.sides.iter().map(|&d| d as f64).collect();
    for (flag, values) in [("--sample-distances", distances), ("--sides", sides)] {
        ensure!(
            values.len() >= 2 && distinct(&values),
            "{flag}: give at least two different values (each is a point of a fitted line)"
        );
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
        refrakt::files::write_atomically(p, (serde_json::to_string_pretty(&r)? + "\n").as_bytes())?;
        println!("wrote {}", p.display());
    }
    finish(ctx)
}
