//! `bench models`' report as the reader sees it: the Markdown table (with the paper's
//! figures beside ours), the CSV of every frame and change, and the SVG chart.

use super::*;

/// A change's cost for the table: "n/a" when not applicable, "0" when nothing was rebuilt.
fn change_text(c: &Option<Change>) -> String {
    match c {
        None => "n/a".into(),
        Some(c) if c.ms == 0.0 => "0".into(),
        Some(c) => format!("{:.2}", c.ms),
    }
}

/// A paper figure for the table: "—" when the paper has no such model, "-" (as the paper
/// prints it) when the change does not apply.
fn paper_text(p: &Option<PaperFigures>, f: impl Fn(&PaperFigures) -> Option<f64>) -> String {
    match p {
        None => "—".into(),
        Some(p) => f(p)
            .map(|v| format!("{v:.1}"))
            .unwrap_or_else(|| "-".into()),
    }
}

/// The report as Markdown: the protocol, one table of every row and model with the
/// paper's Supernova figures beside ours, the skipped rows, and the paper's Table 1.
pub fn models_markdown(r: &ModelsReport) -> String {
    let st = &r.settings;
    let mut s = device_line(&r.meta);
    s += &format!(
        "Protocol (Ament et al., Table 1): viewport {}² × scale {} = {}², volumes × scale, \
         sample distance {}, early ray termination at α = {}; {} frames after {} warm-up per \
         model, models interleaved (frame k of every model before frame k+1 of any), camera \
         orbiting {}°/frame; rendering time = GPU timestamps of the frame (`render` scope). \
         Change = the rebuild scopes ({}) in the first frame after it; TF: {}; LS: {}; PF: \
         {}. Ratio: median over {}'s median on the same row.\n\n",
        MODELS_VIEWPORT,
        st.scale,
        st.viewport,
        st.sample_distance,
        st.termination_alpha,
        st.frames,
        st.warmup,
        st.orbit_deg_per_frame,
        st.rebuild_scopes.join(", "),
        st.tf_change,
        st.ls_change,
        st.pf_change,
        st.ratio_to
    );
    s += &table_head(&format!("Dataset | Resolution | Model | Median ms | Mean ms | Min | Max | FPS | Ratio to {} | TF change ms | LS change ms | PF change ms | Paper ms | Paper ratio | Paper TF ms | Paper LS ms | Paper PF ms", st.ratio_to), "lllrrrrrrrrrrrrrr");
    for row in &r.rows {
        let res = format!(
            "{}{}",
            dims(row.resolution),
            match row.source.as_str() {
                "stand-in" => " (stand-in)",
                _ => "",
            }
        );
        for m in &row.models {
            let t = &m.stats;
            s += &format!(
                "| {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
                row.title,
                res,
                m.model,
                t.median,
                t.mean,
                t.min,
                t.max,
                m.fps,
                m.ratio_to_ea,
                change_text(&m.tf_change),
                change_text(&m.ls_change),
                change_text(&m.pf_change),
                paper_text(&m.paper, |p| Some(p.ms)),
                paper_text(&m.paper, |p| Some(p.ratio)),
                paper_text(&m.paper, |p| p.tf_change_ms),
                paper_text(&m.paper, |p| p.ls_change_ms),
                paper_text(&m.paper, |p| p.pf_change_ms),
            );
        }
        let unmatched: Vec<&PaperFigures> = row
            .paper
            .iter()
            .filter(|p| !row.models.iter().any(|m| m.paper.as_ref() == Some(p)))
            .collect();
        for p in unmatched {
            let p = Some(p.clone());
            s += &format!(
                "| {} | | {} (paper only) | | | | | | | | | | {} | {} | {} | {} | {} |\n",
                row.title,
                p.as_ref().map(|p| p.model.as_str()).unwrap_or_default(),
                paper_text(&p, |p| Some(p.ms)),
                paper_text(&p, |p| Some(p.ratio)),
                paper_text(&p, |p| p.tf_change_ms),
                paper_text(&p, |p| p.ls_change_ms),
                paper_text(&p, |p| p.pf_change_ms),
            );
        }
    }
    if !r.skipped.is_empty() {
        s += "\nSkipped rows:\n\n";
        for k in &r.skipped {
            s += &format!("- {}: {}\n", k.dataset, k.reason);
        }
    }
    s += "\nChange costs: \"n/a\" = the change does not apply to the model; \"0\" = it \
          rebuilt nothing. Paper columns: the Supernova row of Table 1 (NVIDIA GTX 560, 432³, \
          512²; ms = 1000 / fps); \"—\" = the paper has no such model, \"-\" = as the paper \
          prints it (not applicable).\n";
    s += "\nReference: Table 1 of Ament, Sadlo, Weiskopf, \"Ambient Volume Scattering\" (IEEE \
          TVCG 19(12), 2013), as printed (models per row in its colour-code order: \
          emission-absorption, ambient occlusion, single scattering, ambient scattering, \
          those the row shows; GTX 560, 512², α = 0.98):\n\n";
    s += PAPER_TABLE_1;
    if st.models.iter().any(|m| m == Model::Eikonal.name()) {
        s += &format!("\n{PAPER_EIKONAL}\n");
    }
    s
}

/// One CSV record per warm-up and measured frame of every row and model, and one per
/// applicable change (kind `tf-change`, `ls-change`, `pf-change`: ms is the rebuild
/// scopes' sum), each with its whole context, as `bench thesis --csv`.
pub fn write_models_csv(r: &ModelsReport, path: &Path) -> Result<()> {
    let mut csv = ReportCsv::new(
        &["schema", "dataset", "model", "kind", "frame", "ms"],
        &["termination_alpha"],
        &[],
        &r.meta,
        (r.settings.scale, r.settings.sample_distance),
    )?;
    let alpha = [r.settings.termination_alpha.to_string()];
    for row in &r.rows {
        for m in &row.models {
            let frames = m
                .warmup_ms
                .iter()
                .map(|t| ("warmup", Some(*t)))
                .chain(m.frames_ms.iter().map(|t| ("frame", Some(*t))));
            let changes = [
                ("tf-change", &m.tf_change),
                ("ls-change", &m.ls_change),
                ("pf-change", &m.pf_change),
            ]
            .into_iter()
            .filter_map(|(k, c)| c.as_ref().map(|c| (k, Some(c.ms))));
            for (k, (kind, ms)) in frames.chain(changes).enumerate() {
                csv.record(
                    vec![
                        MODELS_SCHEMA.to_string(),
                        row.dataset.clone(),
                        m.model.clone(),
                        kind.to_string(),
                        k.to_string(),
                        ms.map(|t| format!("{t:.6}")).unwrap_or_default(),
                    ],
                    (row.resolution, row.viewport, m.max_steps),
                    &alpha,
                    &[],
                )?;
            }
        }
    }
    csv.finish(path)
}

/// Median rendering ms per model per row as an SVG bar chart (log scale).
pub fn plot_models_svg(r: &ModelsReport, path: &Path) -> Result<()> {
    let groups: Vec<String> = r.rows.iter().map(|row| row.title.clone()).collect();
    let series: Vec<BarSeries> = r
        .settings
        .models
        .iter()
        .map(|name| BarSeries {
            label: name.clone(),
            values: r
                .rows
                .iter()
                .map(|row| {
                    row.models
                        .iter()
                        .find(|m| &m.model == name)
                        .map(|m| m.stats.median)
                })
                .collect(),
        })
        .collect();
    let caption = format!(
        "Median rendering time per model, {} (scale {})",
        r.meta.device, r.settings.scale
    );
    plot_grouped_bars(path, &caption, "ms per frame (log)", &groups, &series)
}
