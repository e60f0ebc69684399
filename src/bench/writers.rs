//! The benchmark's outputs: Markdown tables (with the thesis' figures beside ours), CSV,
//! JSON and the SVG chart.

use super::*;

pub(super) fn dims(d: [u32; 3]) -> String {
    format!("{}×{}×{}", d[0], d[1], d[2])
}

/// A Markdown table's head: the header row (`columns`, separated by " | ") and the
/// alignment row, one letter of `align` per column (`l` left, `r` right: numbers).
pub(crate) fn table_head(columns: &str, align: &str) -> String {
    assert_eq!(
        columns.split(" | ").count(),
        align.len(),
        "one alignment per column"
    );
    let rule = align
        .chars()
        .map(|a| if a == 'r' { "---:" } else { "---" })
        .collect::<Vec<_>>();
    format!("| {columns} |\n|{}|\n", rule.join("|"))
}

/// The report as Markdown: the thesis table beside ours, the per-pass breakdown, and the
/// baselines when measured.
/// The first line of every report: device, driver, build and date.
pub(crate) fn device_line(m: &Meta) -> String {
    format!(
        "Device: {} ({}, {} {}, Vulkan {}); refrakt {} ({}); {}\n",
        m.device,
        m.device_type,
        m.driver,
        m.driver_info,
        m.vulkan,
        m.refrakt_version,
        m.git_commit,
        m.date
    )
}

pub fn markdown(r: &Report) -> String {
    let mut s = device_line(&r.meta);
    s += &format!(
        "Protocol: viewport {}² × scale {} , sample distance {}, {} frames after {} warm-up, camera orbiting {}°/frame; GPU timestamps of the whole frame.\n\
         Sweep variant: {}. Light transport: {}.\n\n",
        THESIS_VIEWPORT,
        r.settings.scale,
        r.settings.sample_distance,
        r.settings.frames,
        r.settings.warmup,
        r.settings.orbit_deg_per_frame,
        r.settings.variant.as_deref().unwrap_or("not recorded"),
        r.settings.light_transport.as_deref().unwrap_or("not recorded")
    );
    s += &table_head("Dataset | Thesis resolution | Ours | Viewport | Planes | Thesis ms | Thesis FPS | Thesis GPU | Mean ms | FPS | Median | Min | Max | Std-dev", "llllrrrlrrrrrr");
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
    s += &table_head("Dataset | Preintegration | Setup | Sweep | Composite | ms/plane | Plane-pixels/s | B/plane-pixel | Compulsory B/plane-pixel | Effective GB/s", "lrrrrrrrrr");
    for row in &r.rows {
        let p = &row.refract.passes;
        s += &format!(
            "| {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.3} | {:.3e} | {:.0} | {:.0} | {:.2} |\n",
            row.title,
            row.preintegration_ms,
            p.setup_ms,
            p.sweep_ms,
            p.composite_ms,
            row.ms_per_plane,
            row.plane_pixels_per_s,
            row.bytes_per_plane_pixel,
            row.compulsory_bytes_per_plane_pixel,
            row.effective_gb_per_s
        );
    }
    if r.settings.baselines {
        s += "\nBaselines in the same run (mean GPU ms per frame; the floor only moves the \
              state, the skeleton makes Algorithm 1's fetches and plain arithmetic, none of \
              the optics past it: docs/BENCH.md):\n\n";
        s += &table_head("Dataset | Refract | EA ray marcher | Sweep floor | Skeleton | Refract / EA | Refract / floor | Skeleton / floor | Skeleton / EA", "lrrrrrrrr");
        for row in &r.rows {
            let f = |v: &Option<Variant>| {
                v.as_ref()
                    .map(|v| format!("{:.2}", v.stats.mean))
                    .unwrap_or_default()
            };
            let g = |x: Option<f64>| x.map(|x| format!("{x:.2}")).unwrap_or_default();
            let over = |a: &Option<Variant>, b: &Option<Variant>| match (a, b) {
                (Some(a), Some(b)) => Some(a.stats.mean / b.stats.mean),
                _ => None,
            };
            s += &format!(
                "| {} | {:.2} | {} | {} | {} | {} | {} | {} | {} |\n",
                row.title,
                row.refract.stats.mean,
                f(&row.ea),
                f(&row.floor),
                f(&row.skeleton),
                g(row.sweep_over_ea),
                g(row.sweep_over_floor),
                g(over(&row.skeleton, &row.floor)),
                g(over(&row.skeleton, &row.ea))
            );
        }
    }
    s
}

/// One CSV record per measured or warm-up frame of every variant, each carrying the whole
/// context (device, commit, settings), so a file is self-describing and files concatenate.
pub fn write_csv(r: &Report, path: &Path) -> Result<()> {
    let mut csv = ReportCsv::new(
        &[
            "schema", "dataset", "variant", "frame", "warmup", "frame_ms",
        ],
        &["thesis_ms", "thesis_gpu"],
        &["levers"],
        &r.meta,
        (r.settings.scale, r.settings.sample_distance),
    )?;
    let levers = [r.settings.variant.clone().unwrap_or_default()];
    for row in &r.rows {
        let thesis = [row.thesis.ms.to_string(), row.thesis.gpu.clone()];
        for v in row.variants() {
            let all = v
                .warmup_ms
                .iter()
                .map(|t| (true, t))
                .chain(v.frames_ms.iter().map(|t| (false, t)));
            for (k, (warm, t)) in all.enumerate() {
                csv.record(
                    vec![
                        SCHEMA.to_string(),
                        row.dataset.clone(),
                        v.variant.clone(),
                        k.to_string(),
                        warm.to_string(),
                        format!("{t:.6}"),
                    ],
                    (row.resolution, row.viewport, row.planes),
                    &thesis,
                    &levers,
                )?;
            }
        }
    }
    csv.finish(path)
}

/// A report's CSV file, built in memory and written atomically ([`ReportCsv::finish`]):
/// every record is the report's own first columns, the row's size and the run's sampling
/// ([`SIZE_HEADER`]), the report's middle columns, the device and build ([`META_HEADER`],
/// the same in every record) and its last columns, so a file is self-describing and files
/// concatenate.
pub(crate) struct ReportCsv {
    w: csv::Writer<Vec<u8>>,
    meta: [String; 6],
    sampling: (f64, f32),
}

/// A row's size as [`size_columns`] takes it: volume resolution, viewport, planes (or
/// steps).
pub(crate) type RowSize = ([u32; 3], [u32; 2], u32);

impl ReportCsv {
    /// The header: `lead`, [`SIZE_HEADER`], `mid`, [`META_HEADER`], `tail`.
    pub(crate) fn new(
        lead: &[&str],
        mid: &[&str],
        tail: &[&str],
        meta: &Meta,
        sampling: (f64, f32),
    ) -> Result<Self> {
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(
            lead.iter()
                .chain(&SIZE_HEADER)
                .chain(mid)
                .chain(&META_HEADER)
                .chain(tail),
        )?;
        Ok(Self {
            w,
            meta: meta_columns(meta),
            sampling,
        })
    }

    /// One record, its columns in the header's order.
    pub(crate) fn record(
        &mut self,
        lead: Vec<String>,
        (resolution, viewport, planes): RowSize,
        mid: &[String],
        tail: &[String],
    ) -> Result<()> {
        let mut record = lead;
        record.extend(size_columns(resolution, viewport, planes, self.sampling));
        record.extend_from_slice(mid);
        record.extend_from_slice(&self.meta);
        record.extend_from_slice(tail);
        self.w.write_record(&record)?;
        Ok(())
    }

    /// Write the file to `path`, atomically.
    pub(crate) fn finish(self, path: &Path) -> Result<()> {
        finish_csv(self.w, path)
    }
}

/// Writes a CSV built in memory to `path`, atomically (crate::files).
pub(crate) fn finish_csv(w: csv::Writer<Vec<u8>>, path: &Path) -> Result<()> {
    let bytes = w
        .into_inner()
        .map_err(|e| anyhow::anyhow!("{}: writing the CSV file: {e}", path.display()))?;
    crate::files::write_atomically(path, &bytes)
}

/// The CSV header of a row's size and the run's sampling ([`size_columns`]).
pub(crate) const SIZE_HEADER: [&str; 7] = [
    "res_x",
    "res_y",
    "res_z",
    "viewport",
    "planes",
    "scale",
    "sample_distance",
];

/// CSV columns of a row's size and the run's sampling, as [`SIZE_HEADER`] names them.
pub(crate) fn size_columns(
    resolution: [u32; 3],
    viewport: [u32; 2],
    planes: u32,
    (scale, sample_distance): (f64, f32),
) -> [String; 7] {
    [
        resolution[0].to_string(),
        resolution[1].to_string(),
        resolution[2].to_string(),
        viewport[0].to_string(),
        planes.to_string(),
        scale.to_string(),
        sample_distance.to_string(),
    ]
}

/// The CSV header of the device and build columns every report ends its rows with
/// ([`meta_columns`]).
pub(crate) const META_HEADER: [&str; 6] = [
    "device",
    "driver",
    "vulkan",
    "refrakt_version",
    "git_commit",
    "date",
];

/// CSV columns of the device and build: device, driver, vulkan, refrakt_version,
/// git_commit, date.
pub(crate) fn meta_columns(meta: &Meta) -> [String; 6] {
    [
        meta.device.clone(),
        meta.driver.clone(),
        meta.vulkan.clone(),
        meta.refrakt_version.clone(),
        meta.git_commit.clone(),
        meta.date.clone(),
    ]
}

/// Any report (thesis, variants, models) as pretty JSON.
pub fn write_json<T: Serialize>(r: &T, path: &Path) -> Result<()> {
    let text = serde_json::to_string_pretty(r)?;
    crate::files::write_atomically(path, (text + "\n").as_bytes())
}

/// Checks an output path before hours of benchmarking, not after.
pub fn check_output(path: &Path, ext: &str) -> Result<()> {
    let e = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if !e.eq_ignore_ascii_case(ext) {
        bail!("{}: expected a .{ext} file", path.display());
    }
    crate::files::check_writable(path)
}

/// Bar chart of the thesis' mean frame time beside ours per row (log scale: on lavapipe
/// the two differ by orders of magnitude), as SVG. The legend says which bar is which
/// device at which size, and a run below full scale says in the caption that its bars do
/// not compare with the thesis' (a 5 % run on a CPU came out as tall as a GTX 1070's).
pub fn plot_svg(r: &Report, path: &Path) -> Result<()> {
    let groups: Vec<String> = r.rows.iter().map(|row| row.title.clone()).collect();
    let scale = r.settings.scale;
    let series = [
        BarSeries {
            label: "thesis: GTX 1070 / 980, full size".into(),
            values: r.rows.iter().map(|row| Some(row.thesis.ms)).collect(),
        },
        BarSeries {
            label: format!("ours: {}, scale {scale}", r.meta.device),
            values: r
                .rows
                .iter()
                .map(|row| Some(row.refract.stats.mean))
                .collect(),
        },
    ];
    let caption = if scale < 1.0 {
        format!(
            "Mean frame time. Ours at scale {scale} ({:.0} % of each side): not comparable \
             with the thesis' full size",
            100.0 * scale
        )
    } else {
        format!(
            "Mean frame time, both at full size: thesis GPU and {}",
            r.meta.device
        )
    };
    plot_grouped_bars(path, &caption, "ms per frame (log)", &groups, &series)
}

/// One series of [`plot_grouped_bars`]: its legend and one value per group (None: no bar).
pub(crate) struct BarSeries {
    pub label: String,
    pub values: Vec<Option<f64>>,
}

/// A grouped bar chart on a log scale as SVG: one group per `groups` entry, one bar per
/// series in each (the series' colours cycle through a fixed palette).
pub(crate) fn plot_grouped_bars(
    path: &Path,
    caption: &str,
    y_desc: &str,
    groups: &[String],
    series: &[BarSeries],
) -> Result<()> {
    use plotters::prelude::*;
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    let err = |e: &dyn std::fmt::Display| anyhow::anyhow!("{}: plotting: {e}", path.display());
    let n = groups.len();
    ensure!(n > 0 && !series.is_empty(), "nothing to plot");
    let all: Vec<f64> = series
        .iter()
        .flat_map(|s| s.values.iter().flatten().copied())
        .filter(|v| *v > 0.0 && v.is_finite())
        .collect();
    ensure!(!all.is_empty(), "no positive values to plot");
    let lo = all.iter().cloned().fold(f64::INFINITY, f64::min) / 2.0;
    // The bars fill the lower 70 % of the (log) axis; the legend sits in the rest, where
    // no bar reaches (drawn over the tallest group's bars, it hid them).
    let top = all.iter().cloned().fold(0.0, f64::max) * 2.0;
    let hi = lo * (top / lo).powf(1.0 / 0.7);
    let width = (40 * series.len() as u32 + 40) * n as u32 + 160;
    // Drawn into a string, then written to the file atomically (crate::files).
    let mut svg = String::new();
    // Wide enough for the caption too (about 9 px a character at 18 px).
    let width = width.max(480).max(9 * caption.chars().count() as u32 + 40);
    let root = SVGBackend::with_string(&mut svg, (width, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(caption, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(0f64..n as f64, (lo..hi).log_scale())
        .map_err(|e| err(&e))?;
    // Group names centred under their bars, drawn by hand: the axis' own labels sit at
    // tick positions plotters chooses (group boundaries), which left a group unnamed.
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_desc(y_desc)
        .draw()
        .map_err(|e| err(&e))?;
    let label_style = ("sans-serif", 12)
        .into_font()
        .into_text_style(&root)
        .pos(Pos::new(HPos::Center, VPos::Top));
    for (i, g) in groups.iter().enumerate() {
        let (x, y) = chart.backend_coord(&(i as f64 + 0.5, lo));
        root.draw(&Text::new(g.clone(), (x, y + 8), label_style.clone()))
            .map_err(|e| err(&e))?;
    }
    const PALETTE: [RGBColor; 6] = [
        RGBColor(120, 120, 120),
        RGBColor(200, 80, 40),
        RGBColor(40, 110, 190),
        RGBColor(60, 160, 80),
        RGBColor(150, 80, 170),
        RGBColor(210, 170, 40),
    ];
    let k = series.len() as f64;
    let bar = 0.7 / k;
    for (j, s) in series.iter().enumerate() {
        let colour = PALETTE[j % PALETTE.len()];
        chart
            .draw_series(s.values.iter().enumerate().filter_map(|(i, v)| {
                let v = (*v).filter(|v| *v > 0.0 && v.is_finite())?;
                let x = i as f64 + 0.15 + bar * j as f64;
                Some(Rectangle::new(
                    [(x, lo), (x + bar * 0.9, v)],
                    colour.filled(),
                ))
            }))
            .map_err(|e| err(&e))?
            .label(s.label.clone())
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], colour.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .border_style(BLACK)
        .background_style(WHITE)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    drop(chart);
    drop(root);
    crate::files::write_atomically(path, svg.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The head renders as GitHub-flavoured Markdown reads it: the header row, then one
    /// alignment cell per column (`---:` right-aligns a number column).
    #[test]
    fn table_heads_align_each_column() {
        assert_eq!(
            table_head("Row | Mean ms | Verdict", "lrl"),
            "| Row | Mean ms | Verdict |\n|---|---:|---|\n"
        );
    }

    /// The numbers of every `<rect x=.. y=.. width=.. height=..` in an SVG as [x, y, w, h].
    fn rects(svg: &str) -> Vec<[f64; 4]> {
        svg.lines()
            .filter(|l| l.starts_with("<rect "))
            .map(|l| {
                ["x", "y", "width", "height"].map(|k| {
                    let at = l.find(&format!(" {k}=\"")).unwrap() + k.len() + 3;
                    l[at..at + l[at..].find('"').unwrap()].parse().unwrap()
                })
            })
            .collect()
    }

    #[test]
    fn grouped_bars_name_every_group_under_its_bars_and_keep_the_legend_off_them() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.svg");
        let groups = ["Alpha".to_string(), "Beta".to_string()];
        let series: Vec<BarSeries> = [[20.0, 100.0], [5000.0, 9000.0], [60.0, 2.0]]
            .iter()
            .enumerate()
            .map(|(j, v)| BarSeries {
                label: format!("series{j}"),
                values: v.iter().map(|x| Some(*x)).collect(),
            })
            .collect();
        plot_grouped_bars(&path, "caption", "ms", &groups, &series).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        let all = rects(&svg);
        // The background, then 3 series × 2 groups of bars, then the legend's box.
        let bars = &all[1..7];
        let legend = all[7];
        for (i, g) in groups.iter().enumerate() {
            let at = svg.find(&format!(">\n{g}\n</text>")).expect(g);
            let open = svg[..at].rfind("<text x=\"").unwrap() + 9;
            let x: f64 = svg[open..open + svg[open..].find('"').unwrap()]
                .parse()
                .unwrap();
            // Group i's bars are i, i + 2, i + 4 (series by series).
            let left = (0..3).map(|j| bars[i + 2 * j][0]).fold(f64::MAX, f64::min);
            let right = (0..3)
                .map(|j| bars[i + 2 * j][0] + bars[i + 2 * j][2])
                .fold(0.0, f64::max);
            assert!(
                left < x && x < right,
                "{g} at {x}, its bars {left}..{right}"
            );
            assert!(
                ((left + right) / 2.0 - x).abs() < 0.05 * (right - left),
                "{g} at {x} is not centred under {left}..{right}"
            );
        }
        let legend_bottom = legend[1] + legend[3];
        for b in bars {
            let overlaps_x = b[0] < legend[0] + legend[2] && legend[0] < b[0] + b[2];
            assert!(
                !overlaps_x || b[1] > legend_bottom,
                "the legend {legend:?} covers the bar {b:?}"
            );
        }
    }
}
