//! The ambient-scattering model's preintegrated table for a command: a file the user
//! names, or the cached table for the albedo (built on first use, with a progress bar).

use std::path::Path;

use anyhow::{ensure, Result};

use refrakt::render::ambient::table::{self, AmbientTable, Source, TableParams};

/// The table for `albedo`: read from `file` (which must have been built for that albedo),
/// else from the cache, built there first if missing. Returns it with a line saying
/// where it came from.
pub fn table_for(file: Option<&Path>, albedo: f32, quiet: bool) -> Result<(AmbientTable, String)> {
    if let Some(f) = file {
        // The user's file: one that fails its check (checksum, size, version) is an
        // error naming it, never rebuilt or replaced.
        let t = AmbientTable::load(f)?;
        ensure!(
            t.params.albedo == albedo,
            "{}: the table was built for albedo {}, the scene asks for {albedo} (pass --albedo \
             {} or build one: refrakt precompute ambient --albedo {albedo} --out FILE)",
            f.display(),
            t.params.albedo,
            t.params.albedo
        );
        let line = format!("ambient-scattering table: {}", f.display());
        return Ok((t, line));
    }
    let params = TableParams {
        albedo,
        ..Default::default()
    };
    let bar = if quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(0)
    };
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "building the ambient-scattering table (once; then cached) {bar:30} {pos}/{len} ({eta})",
    ) {
        bar.set_style(style);
    }
    let progress = |done: u64, total: u64| {
        bar.set_length(total);
        bar.set_position(done);
    };
    // The implicit cache: a damaged table there is rebuilt; a table that cannot be
    // written there is only a warning (rendering is this command's job, not caching;
    // `precompute ambient`, whose job the file is, fails instead).
    let (t, source) = table::load_or_build(&params, None, 0, &progress)?;
    bar.finish_and_clear();
    let line = match source {
        Source::Cached(p) => format!("ambient-scattering table: {} (cached)", p.display()),
        Source::Built { seconds, written } => format!(
            "ambient-scattering table: built in {seconds:.1} s{}",
            match written {
                Some(p) => format!(", cached in {}", p.display()),
                None => " (could not be cached: see the warning)".into(),
            }
        ),
    };
    Ok((t, line))
}
