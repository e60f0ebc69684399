//! `bench compare OLD.json NEW.json`: two reports of the same kind (`bench thesis` or
//! `bench variants`) side by side, per row and variant, with a verdict that only calls a
//! change "faster" or "slower" when it stands out of the runs' own frame-to-frame noise.
//!
//! The rule (docs/BENCH.md, "A/B a change"): per side, the per-frame times give the
//! median m and the standard error of the mean se = s/√n (s the sample standard
//! deviation, n the frames). The change is Δ = m_new − m_old; it is "slower" when
//! Δ > k·√(se_old² + se_new²) and Δ > min_change·m_old, "faster" when −Δ passes both, else
//! "within noise". k = 3 and min_change = 2 % by default: frame times on a shared or
//! software device have heavy tails, and a change below 2 % is not worth a CI failure.

use super::*;

/// Default multiple of the combined standard error a change must exceed.
pub const NOISE_K: f64 = 3.0;
/// Default smallest relative change of the median that counts (2 %).
pub const MIN_CHANGE: f64 = 0.02;

#[derive(Clone, Copy, Debug)]
pub struct CompareOptions {
    /// Multiple of √(se_old² + se_new²) the change of the medians must exceed.
    pub noise_k: f64,
    /// Fraction of the old median the change must exceed.
    pub min_change: f64,
    /// Compare reports whose settings differ (scale, device, ...) instead of refusing.
    pub allow_mismatch: bool,
}

impl Default for CompareOptions {
    fn default() -> Self {
        Self {
            noise_k: NOISE_K,
            min_change: MIN_CHANGE,
            allow_mismatch: false,
        }
    }
}

/// A report of either kind, as read from a file.
#[derive(Clone, Debug)]
pub enum AnyReport {
    Thesis(Report),
    Variants(VariantsReport),
}

/// Reads a `bench thesis` or `bench variants` JSON report, telling which by its schema.
/// Every error names the file.
pub fn read_report(path: &Path) -> Result<AnyReport> {
    let p = path.display();
    let text = std::fs::read_to_string(path).with_context(|| format!("{p}: cannot read"))?;
    let value: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{p}: not valid JSON"))?;
    let schema = value
        .get("schema")
        .and_then(|s| s.as_str())
        .with_context(|| {
            format!(
                "{p}: no \"schema\" string; not a `bench thesis` ({SCHEMA}) or `bench variants` \
                 ({VARIANTS_SCHEMA}) report"
            )
        })?
        .to_string();
    let report = if schema == SCHEMA {
        AnyReport::Thesis(
            serde_json::from_value(value)
                .with_context(|| format!("{p}: not a valid {SCHEMA} report"))?,
        )
    } else if schema == VARIANTS_SCHEMA {
        AnyReport::Variants(
            serde_json::from_value(value)
                .with_context(|| format!("{p}: not a valid {VARIANTS_SCHEMA} report"))?,
        )
    } else {
        bail!("{p}: schema '{schema}' is neither {SCHEMA} nor {VARIANTS_SCHEMA}");
    };
    check_report(&p.to_string(), &report)?;
    Ok(report)
}

/// What a report must hold to be compared: rows, each dataset once, and as many frames
/// per row and variant as its settings say (a hand-edited or cut report was compared as
/// if whole).
fn check_report(p: &str, report: &AnyReport) -> Result<()> {
    let f = flatten(report);
    ensure!(!f.rows.is_empty(), "{p}: the report has no rows");
    for (i, row) in f.rows.iter().enumerate() {
        ensure!(
            !f.rows[..i].iter().any(|r| r.dataset == row.dataset),
            "{p}: row '{}' is there twice",
            row.dataset
        );
        for (variant, frames) in &row.entries {
            ensure!(
                frames.len() == f.frames as usize,
                "{p}: {} {variant}: {} measured frames where the settings say {}",
                row.dataset,
                frames.len(),
                f.frames
            );
        }
    }
    Ok(())
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    Faster,
    Slower,
    WithinNoise,
}

impl Verdict {
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Faster => "faster",
            Verdict::Slower => "slower",
            Verdict::WithinNoise => "within noise",
        }
    }
}

/// One figure's frame times, old against new.
#[derive(Clone, Debug, PartialEq)]
pub struct Delta {
    pub old: Stats,
    pub new: Stats,
    pub old_frames: usize,
    pub new_frames: usize,
    /// (new − old) / old of the means, in percent.
    pub mean_pct: f64,
    /// (new − old) / old of the medians, in percent.
    pub median_pct: f64,
    /// k·√(se_old² + se_new²), ms.
    pub noise_ms: f64,
    /// max(noise_ms, min_change·old median): how far the medians must move for a verdict.
    pub threshold_ms: f64,
    pub verdict: Verdict,
}

/// Standard error of the mean of n frames with sample standard deviation s.
fn standard_error(s: &Stats, n: usize) -> f64 {
    s.std_dev / (n as f64).sqrt()
}

/// The comparison of two lists of per-frame times under the module's rule.
pub fn delta(old: &[f64], new: &[f64], noise_k: f64, min_change: f64) -> Result<Delta> {
    let (o, n) = (Stats::of(old)?, Stats::of(new)?);
    ensure!(o.median > 0.0, "the old median frame time is not positive");
    let se = standard_error(&o, old.len()).hypot(standard_error(&n, new.len()));
    let noise_ms = noise_k * se;
    let threshold_ms = noise_ms.max(min_change * o.median);
    let change = n.median - o.median;
    let verdict = if change > threshold_ms {
        Verdict::Slower
    } else if -change > threshold_ms {
        Verdict::Faster
    } else {
        Verdict::WithinNoise
    };
    Ok(Delta {
        mean_pct: 100.0 * (n.mean / o.mean - 1.0),
        median_pct: 100.0 * (n.median / o.median - 1.0),
        old_frames: old.len(),
        new_frames: new.len(),
        old: o,
        new: n,
        noise_ms,
        threshold_ms,
        verdict,
    })
}

#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    Compared(Delta),
    OnlyOld,
    OnlyNew,
}

/// One (row, variant) of the comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    pub dataset: String,
    pub title: String,
    /// "refract", "ea", "floor", "skeleton" (thesis reports) or the variant's name.
    pub variant: String,
    pub outcome: Outcome,
}

#[derive(Clone, Debug)]
pub struct Comparison {
    pub schema: String,
    pub old_file: String,
    pub new_file: String,
    /// One line per file: version, commit, date, device, frames, variant.
    pub old_label: String,
    pub new_label: String,
    /// Differences that do not stop the comparison (frames, levers) and, with
    /// `allow_mismatch`, the mismatches it was told to accept.
    pub notes: Vec<String>,
    pub lines: Vec<Line>,
    pub options: CompareOptions,
}

impl Comparison {
    /// The lines whose verdict is `v`.
    pub fn with_verdict(&self, v: Verdict) -> Vec<&Line> {
        self.lines
            .iter()
            .filter(|l| matches!(&l.outcome, Outcome::Compared(d) if d.verdict == v))
            .collect()
    }
}

/// A report reduced to what a comparison reads.
struct Flat<'a> {
    schema: &'a str,
    meta: &'a Meta,
    scale: f64,
    sample_distance: f32,
    orbit: f32,
    frames: u32,
    warmup: u32,
    /// Variant names and their levers.
    levers: Vec<(String, String)>,
    /// The sweep's light transport; None in reports from before it was recorded.
    transport: Option<&'a str>,
    rows: Vec<FlatRow<'a>>,
}

struct FlatRow<'a> {
    dataset: &'a str,
    title: &'a str,
    source: &'a str,
    resolution: [u32; 3],
    viewport: [u32; 2],
    planes: u32,
    /// (variant, per-frame ms).
    entries: Vec<(&'a str, &'a [f64])>,
}

/// A report's row (thesis or variants: the same header fields) with `runs`, its variants'
/// runs, as (variant, per-frame ms).
macro_rules! flat_row {
    ($row:expr, $runs:expr) => {
        FlatRow {
            dataset: &$row.dataset,
            title: &$row.title,
            source: &$row.source,
            resolution: $row.resolution,
            viewport: $row.viewport,
            planes: $row.planes,
            entries: $runs
                .map(|v| (v.variant.as_str(), v.frames_ms.as_slice()))
                .collect(),
        }
    };
}

fn flatten(r: &AnyReport) -> Flat<'_> {
    match r {
        AnyReport::Thesis(t) => Flat {
            schema: &t.schema,
            meta: &t.meta,
            scale: t.settings.scale,
            sample_distance: t.settings.sample_distance,
            orbit: t.settings.orbit_deg_per_frame,
            frames: t.settings.frames,
            warmup: t.settings.warmup,
            levers: vec![(
                "refract".into(),
                t.settings
                    .variant
                    .clone()
                    .unwrap_or_else(|| "not recorded".into()),
            )],
            transport: t.settings.light_transport.as_deref(),
            rows: t
                .rows
                .iter()
                .map(|row| flat_row!(row, row.variants()))
                .collect(),
        },
        AnyReport::Variants(v) => Flat {
            schema: &v.schema,
            meta: &v.meta,
            scale: v.settings.scale,
            sample_distance: v.settings.sample_distance,
            orbit: v.settings.orbit_deg_per_frame,
            frames: v.settings.frames,
            warmup: v.settings.warmup,
            levers: v
                .settings
                .variants
                .iter()
                .map(|s| (s.name.clone(), s.levers.clone()))
                .collect(),
            transport: v.settings.light_transport.as_deref(),
            rows: v
                .rows
                .iter()
                .map(|row| flat_row!(row, row.variants.iter()))
                .collect(),
        },
    }
}

fn label(file: &str, f: &Flat) -> String {
    let m = f.meta;
    let mut s = format!(
        "{file}: refrakt {} ({}), {}, {}; {} frames after {} warm-up",
        m.refrakt_version, m.git_commit, m.date, m.device, f.frames, f.warmup
    );
    if f.schema == SCHEMA {
        s += &format!(", variant {}", f.levers[0].1);
    }
    s
}

/// Compares two reports of the same kind. Settings that make the times incomparable
/// (device, scale, sample distance, orbit; per row the viewport, resolution, planes and
/// data source) are refused, naming both values, unless `allow_mismatch`.
pub fn compare(
    old_file: &Path,
    old: &AnyReport,
    new_file: &Path,
    new: &AnyReport,
    options: CompareOptions,
) -> Result<Comparison> {
    ensure!(
        options.noise_k >= 0.0 && options.noise_k.is_finite(),
        "--noise-k must be a non-negative number"
    );
    ensure!(
        options.min_change >= 0.0 && options.min_change.is_finite(),
        "--min-change must be a non-negative percentage"
    );
    let (of, nf) = (
        old_file.display().to_string(),
        new_file.display().to_string(),
    );
    let (o, n) = (flatten(old), flatten(new));
    ensure!(
        o.schema == n.schema,
        "{of} is a {} report and {nf} a {} report; compare two of the same kind",
        o.schema,
        n.schema
    );
    let mut mismatches = Vec::new();
    let mut differ = |what: String, a: String, b: String| {
        if a != b {
            mismatches.push(format!("{what} {a} in {of}, {b} in {nf}"));
        }
    };
    differ(
        "device".into(),
        o.meta.device.clone(),
        n.meta.device.clone(),
    );
    differ("scale".into(), o.scale.to_string(), n.scale.to_string());
    differ(
        "sample distance".into(),
        o.sample_distance.to_string(),
        n.sample_distance.to_string(),
    );
    differ(
        "camera orbit (°/frame)".into(),
        o.orbit.to_string(),
        n.orbit.to_string(),
    );
    // The two transports are different algorithms (light rays and their splat, or the
    // thesis' backward step): their times are not one figure's noise.
    if let (Some(a), Some(b)) = (o.transport, n.transport) {
        differ("light transport".into(), a.to_string(), b.to_string());
    }
    for ro in &o.rows {
        let Some(rn) = n.rows.iter().find(|r| r.dataset == ro.dataset) else {
            continue;
        };
        let d = ro.dataset;
        let vp = |v: [u32; 2]| format!("{}×{}", v[0], v[1]);
        let res = |v: [u32; 3]| format!("{}×{}×{}", v[0], v[1], v[2]);
        differ(format!("{d}: viewport"), vp(ro.viewport), vp(rn.viewport));
        differ(
            format!("{d}: resolution"),
            res(ro.resolution),
            res(rn.resolution),
        );
        differ(
            format!("{d}: planes"),
            ro.planes.to_string(),
            rn.planes.to_string(),
        );
        differ(
            format!("{d}: source"),
            ro.source.to_string(),
            rn.source.to_string(),
        );
    }
    if !mismatches.is_empty() && !options.allow_mismatch {
        bail!(
            "{of} and {nf} were not measured alike: {}; pass --allow-mismatch to compare them anyway",
            mismatches.join("; ")
        );
    }
    let mut notes: Vec<String> = mismatches
        .into_iter()
        .map(|m| format!("settings differ (--allow-mismatch): {m}"))
        .collect();
    for (name, lo) in &o.levers {
        if let Some((_, ln)) = n.levers.iter().find(|(m, _)| m == name) {
            if lo != ln && o.schema == SCHEMA {
                notes.push(format!(
                    "the sweep's levers differ: {lo} in {of}, {ln} in {nf}"
                ));
            } else if lo != ln {
                notes.push(format!(
                    "variant {name} has levers {lo} in {of}, {ln} in {nf}"
                ));
            }
        }
    }
    for (file, f) in [(&of, &o), (&nf, &n)] {
        if f.transport.is_none() {
            notes.push(format!(
                "{file} does not record its light transport (a report from before \
                 --light-transport): it ran the scenes' own"
            ));
        }
        if f.frames < 2 {
            notes.push(format!(
                "{file} has one frame per figure: its spread is unknown (taken as 0), so \
                 verdicts rest on the {} % threshold alone",
                100.0 * options.min_change
            ));
        }
    }

    let mut lines = Vec::new();
    let only = |row: &FlatRow, outcome: &Outcome, lines: &mut Vec<Line>| {
        for (v, _) in &row.entries {
            lines.push(Line {
                dataset: row.dataset.into(),
                title: row.title.into(),
                variant: v.to_string(),
                outcome: outcome.clone(),
            });
        }
    };
    for ro in &o.rows {
        let Some(rn) = n.rows.iter().find(|r| r.dataset == ro.dataset) else {
            only(ro, &Outcome::OnlyOld, &mut lines);
            continue;
        };
        for (v, old_ms) in &ro.entries {
            let outcome = match rn.entries.iter().find(|(w, _)| w == v) {
                Some((_, new_ms)) => {
                    for (file, ms) in [(&of, old_ms), (&nf, new_ms)] {
                        ensure!(
                            ms.iter().all(|t| t.is_finite() && *t > 0.0),
                            "{file}: {} {v}: frame times must be positive numbers",
                            ro.dataset
                        );
                    }
                    Outcome::Compared(
                        delta(old_ms, new_ms, options.noise_k, options.min_change)
                            .with_context(|| format!("{} {v}", ro.dataset))?,
                    )
                }
                None => Outcome::OnlyOld,
            };
            lines.push(Line {
                dataset: ro.dataset.into(),
                title: ro.title.into(),
                variant: v.to_string(),
                outcome,
            });
        }
        for (v, _) in rn
            .entries
            .iter()
            .filter(|(v, _)| !ro.entries.iter().any(|(w, _)| w == v))
        {
            lines.push(Line {
                dataset: rn.dataset.into(),
                title: rn.title.into(),
                variant: v.to_string(),
                outcome: Outcome::OnlyNew,
            });
        }
    }
    for rn in n
        .rows
        .iter()
        .filter(|r| !o.rows.iter().any(|q| q.dataset == r.dataset))
    {
        only(rn, &Outcome::OnlyNew, &mut lines);
    }
    Ok(Comparison {
        schema: o.schema.to_string(),
        old_label: label(&of, &o),
        new_label: label(&nf, &n),
        old_file: of,
        new_file: nf,
        notes,
        lines,
        options,
    })
}

/// The comparison as Markdown: both files, the rule, one table line per row and variant,
/// and a summary.
pub fn compare_markdown(c: &Comparison) -> String {
    let k = c.options.noise_k;
    let mut s = format!("Old: {}\nNew: {}\n", c.old_label, c.new_label);
    for n in &c.notes {
        s += &format!("Note: {n}\n");
    }
    s += &format!(
        "\nVerdict: \"slower\"/\"faster\" when the median frame time moves by more than \
         {k} × √(se_old² + se_new²) (the noise column; se = s/√n of a side's per-frame times) \
         and by more than {} % of the old median; otherwise \"within noise\".\n\n",
        100.0 * c.options.min_change
    );
    s += &table_head(&format!("Row | Variant | Mean ms, old → new | Δ mean | Median ms, old → new | Δ median | Noise ({k}·se) ms | Verdict"), "llrrrrrl");
    for l in &c.lines {
        match &l.outcome {
            Outcome::Compared(d) => {
                let verdict = match d.verdict {
                    Verdict::WithinNoise => d.verdict.name().to_string(),
                    v => format!("**{}**", v.name()),
                };
                s += &format!(
                    "| {} | {} | {:.2} → {:.2} | {:+.1} % | {:.2} → {:.2} | {:+.1} % | {:.2} | {} |\n",
                    l.title,
                    l.variant,
                    d.old.mean,
                    d.new.mean,
                    d.mean_pct,
                    d.old.median,
                    d.new.median,
                    d.median_pct,
                    d.noise_ms,
                    verdict
                );
            }
            Outcome::OnlyOld | Outcome::OnlyNew => {
                let file = if l.outcome == Outcome::OnlyOld {
                    &c.old_file
                } else {
                    &c.new_file
                };
                s += &format!(
                    "| {} | {} | | | | | | only in {file} |\n",
                    l.title, l.variant
                );
            }
        }
    }
    let count = |v| c.with_verdict(v).len();
    // A whole row by its name, a variant of a row both files have as "row variant".
    let only = |o: Outcome| {
        let mut items: Vec<String> = Vec::new();
        for l in c.lines.iter().filter(|l| l.outcome == o) {
            let whole_row = c
                .lines
                .iter()
                .filter(|m| m.dataset == l.dataset)
                .all(|m| m.outcome == o);
            let item = if whole_row {
                l.dataset.clone()
            } else {
                format!("{} {}", l.dataset, l.variant)
            };
            if !items.contains(&item) {
                items.push(item);
            }
        }
        items.join(", ")
    };
    s += &format!(
        "\n{} slower, {} faster, {} within noise",
        count(Verdict::Slower),
        count(Verdict::Faster),
        count(Verdict::WithinNoise)
    );
    for (o, file) in [
        (Outcome::OnlyOld, &c.old_file),
        (Outcome::OnlyNew, &c.new_file),
    ] {
        let rows = only(o);
        if !rows.is_empty() {
            s += &format!("; only in {file}: {rows}");
        }
    }
    s += ".\n";
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdicts_follow_the_rule() {
        // Tight spread: s = √0.5 per side, se = √0.1, noise = 3·√0.2 ≈ 1.34 ms.
        let old = [100.0, 101.0, 99.0, 100.0, 100.0];
        let slower: Vec<f64> = old.iter().map(|t| t + 50.0).collect();
        let d = delta(&old, &slower, 3.0, 0.02).unwrap();
        assert_eq!(d.verdict, Verdict::Slower);
        assert!((d.median_pct - 50.0).abs() < 1e-12 && (d.mean_pct - 50.0).abs() < 1e-12);
        assert!((d.noise_ms - 3.0 * 0.2f64.sqrt()).abs() < 1e-12);
        let faster: Vec<f64> = old.iter().map(|t| t - 10.0).collect();
        assert_eq!(
            delta(&old, &faster, 3.0, 0.02).unwrap().verdict,
            Verdict::Faster
        );
        // 1.5 % beyond a noise of 0: below the relative threshold.
        let flat = [100.0; 4];
        let d = delta(&flat, &[101.5; 4], 3.0, 0.02).unwrap();
        assert_eq!((d.verdict, d.noise_ms), (Verdict::WithinNoise, 0.0));
        assert_eq!(d.threshold_ms, 2.0);
        // 10 % with a spread of s ≈ 15.8 per side: noise = 3·√(2·50) = 30 ms.
        let wide = [80.0, 120.0, 100.0, 90.0, 110.0];
        let wide_new: Vec<f64> = wide.iter().map(|t| t + 10.0).collect();
        let d = delta(&wide, &wide_new, 3.0, 0.02).unwrap();
        assert_eq!(d.verdict, Verdict::WithinNoise);
        assert!((d.noise_ms - 30.0).abs() < 1e-9, "{}", d.noise_ms);
        // ... which k = 0.3 calls.
        assert_eq!(
            delta(&wide, &wide_new, 0.3, 0.02).unwrap().verdict,
            Verdict::Slower
        );
        assert!(delta(&[], &old, 3.0, 0.02).is_err());
    }
}
