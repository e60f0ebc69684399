//! `refrakt precompute ambient`: build (or find) the ambient-scattering light-transport
//! table and report its build time and Monte-Carlo errors.
//!
//! Writing the table is this job, so it fails when it cannot (issue 33): the target is
//! checked before the build (minutes at the default size): a folder, a folder that cannot
//! be made or written to, or an `--out` file that is not an ambient table (someone
//! else's: no table header) is refused, the last unless `--force`. A table file made with
//! other parameters, of another format version or corrupt is ours and is replaced (said
//! in one line). A write that fails after the build fails the command.

use std::io::IsTerminal;
use std::process::ExitCode;

use anyhow::{bail, ensure, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use refrakt::render::ambient::table::{self, AmbientTable, Existing, Source, TableParams};

use super::args::AmbientArgs;

pub fn ambient(args: &AmbientArgs) -> Result<ExitCode> {
    let params = TableParams {
        albedo: args.albedo,
        theta_bins: args.theta_bins,
        s_bins: args.extinction_bins,
        g_bins: args.g_bins,
        s_max: args.s_max,
        paths: args.paths,
        seed: args.seed,
    };
    params.validate()?;
    // The work, before any of it (issue 33): paths in all, against the limit. Measured:
    // 2.1·10⁶ paths per CPU-second (the default bins, --paths 512, 2 cores, release).
    ensure!(
        args.max_paths.is_finite() && args.max_paths > 0.0,
        "--max-paths {}: must be a positive number",
        args.max_paths
    );
    let work = params.entries() as f64 * params.paths as f64;
    ensure!(
        work <= args.max_paths,
        "{} entries × {} paths = {work:.2e} paths, more than the limit of {:.1e} (10¹⁰ is \
         about 40 min on 2 cores); use fewer --paths or bins, or raise it with --max-paths",
        params.entries(),
        params.paths,
        args.max_paths
    );
    let threads = refrakt::workers::count(args.threads.unwrap_or(0))?;
    let path = match &args.out {
        Some(p) => p.clone(),
        None => table::cache_dir(args.cache_dir.as_deref())?.join(params.file_name()),
    };
    // Before the build: can the table be written there, and whose file is there now?
    let existing = table::check_target(&params, &path)?;
    let cached = match existing {
        Existing::Table(t) if !args.force => Some(t),
        Existing::Foreign if args.out.is_some() && !args.force => bail!(
            "{}: exists and is not an ambient table (no table header); not replacing it \
             (--force replaces it)",
            path.display()
        ),
        // A file under the table's own name in the cache folder is the cache's, whatever
        // it holds now (zeroed, say): rebuilt.
        Existing::Foreign => {
            eprintln!(
                "{}: not an ambient table; replacing it{}",
                path.display(),
                if args.out.is_some() {
                    " (--force)"
                } else {
                    " (the cache's file)"
                }
            );
            None
        }
        Existing::Stale(why) => {
            eprintln!("{}: {why}; replacing it", path.display());
            None
        }
        Existing::Table(_) | Existing::Nothing => None,
    };
    let pb = if std::io::stderr().is_terminal() {
        let pb = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr());
        pb.set_style(
            ProgressStyle::with_template(
                "{elapsed_precise} [{bar:30}] {pos}/{len} columns, ETA {eta}",
            )
            .expect("static template")
            .progress_chars("=> "),
        );
        pb
    } else {
        ProgressBar::hidden()
    };
    let progress = |done: u64, total: u64| {
        pb.set_length(total);
        pb.set_position(done);
    };
    let (t, source) = match cached {
        Some(t) => (t, Source::Cached(path.clone())),
        None => {
            let t = AmbientTable::build(&params, threads, &progress)?;
            pb.finish_and_clear();
            // The job's output: a failed write fails the command (the table is lost; the
            // error names the file and the reason).
            t.save(&path)?;
            let seconds = t.build_seconds;
            (
                t,
                Source::Built {
                    seconds,
                    written: Some(path.clone()),
                },
            )
        }
    };
    pb.finish_and_clear();
    let p = &t.params;
    println!(
        "ambient table: albedo {}, {} θ × {} s × {} g nodes, s_max {}, {} paths per entry, seed {}",
        p.albedo, p.theta_bins, p.s_bins, p.g_bins, p.s_max, p.paths, p.seed
    );
    match &source {
        Source::Cached(file) => {
            println!("found cached: {}", file.display());
            println!(
                "(built earlier in {:.1} s; --force rebuilds it)",
                t.build_seconds
            );
        }
        Source::Built { seconds, written } => {
            println!("built in {seconds:.1} s with {threads} threads");
            match written {
                Some(file) => println!("written: {}", file.display()),
                None => println!("not written (see the warning above)"),
            }
        }
    }
    let e = t.errors();
    println!(
        "scattered: max {:.4e}; largest relative std error {:.2} % (entries above 1e-3 of \
         the max), largest absolute std error {:.3e}",
        e.scattered_max,
        100.0 * e.scattered_rel,
        e.scattered_abs
    );
    println!(
        "transmission: largest relative std error {:.2} %, largest absolute std error {:.3e}",
        100.0 * e.transmission_rel,
        e.transmission_abs
    );
    Ok(ExitCode::SUCCESS)
}
