//! `bench variants`: the sweep's speed levers A/B'd on the thesis rows. Every variant is
//! rendered interleaved with the others in one process (frame k of every variant before
//! frame k+1 of any), so that a change in machine load hits all of them alike and their
//! ratios stay fair; each variant's image is compared with the reference variant's.

use super::*;
use crate::output;

/// Version of the variants report's JSON layout.
pub const VARIANTS_SCHEMA: &str = "refrakt-bench-variants/1";

#[derive(Clone, Debug)]
pub struct VariantsSettings {
    pub timing: Timing,
    /// The variants to time, in this order; empty = [`default_variants`].
    pub variants: Vec<Levers>,
    /// As [`ThesisSettings::light_transport`].
    pub light_transport: Option<LightTransport>,
}

/// What `bench variants` times when no `--variant` is given: the reference, the default,
/// and the default with each lever flipped alone (what each lever is worth).
pub fn default_variants() -> Vec<Levers> {
    let mut v = vec![Levers::REFERENCE, Levers::default()];
    v.extend(Levers::default().each_flipped());
    v
}

/// A variant's name in reports: `default`, `reference`, or the levers that differ from
/// the default (`arrays=off`) or from the reference (`reference,arrays=on`), whichever
/// names fewer levers (the default's on a tie). [`Levers::parse`] reads every name back
/// to its levers.
pub fn variant_name(l: Levers) -> String {
    if l == Levers::default() {
        return "default".into();
    }
    if l == Levers::REFERENCE {
        return "reference".into();
    }
    // Display lists every lever as key=value in a fixed order.
    let differing = |base: Levers| {
        let (a, b) = (l.to_string(), base.to_string());
        a.split(',')
            .zip(b.split(','))
            .filter(|(x, y)| x != y)
            .map(|(x, _)| x.to_string())
            .collect::<Vec<_>>()
    };
    let from_default = differing(Levers::default());
    let from_reference = differing(Levers::REFERENCE);
    if from_reference.len() < from_default.len() {
        format!("reference,{}", from_reference.join(","))
    } else {
        from_default.join(",")
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct VariantSpec {
    /// [`variant_name`]: the key rows, ratios and `bench compare` use.
    pub name: String,
    /// Every lever, in [`Levers`]' text form.
    pub levers: String,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct VariantsSettingsRecord {
    pub scale: f64,
    pub frames: u32,
    pub warmup: u32,
    pub sample_distance: f32,
    pub orbit_deg_per_frame: f32,
    pub rows: Vec<String>,
    /// The variants timed, in the order each frame renders them.
    pub variants: Vec<VariantSpec>,
    /// The variant whose median frame time the ratios divide by: `default` if timed,
    /// else the first.
    pub ratio_to: String,
    /// The variant the images are compared with: the reference levers.
    pub image_reference: String,
    /// False when the reference was not among the variants and was rendered for the image
    /// comparison only.
    pub image_reference_timed: bool,
    /// As the thesis report's: the light transport every row's sweep ran.
    #[serde(default)]
    pub light_transport: Option<String>,
}

/// A variant's image against the reference's, both tone mapped to display values in
/// [0, 1] as `refrakt render` writes a PNG (before rounding to 8 bits), over every RGB
/// channel of every pixel.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ImageDiff {
    pub max_abs: f64,
    pub mean_abs: f64,
    /// 10·log10(1 / mean squared difference), peak 1; null when the images are identical
    /// (infinite PSNR).
    pub psnr_db: Option<f64>,
}

impl ImageDiff {
    pub fn of(a: &[[f32; 3]], b: &[[f32; 3]]) -> Result<ImageDiff> {
        ensure!(
            a.len() == b.len() && !a.is_empty(),
            "images of {} and {} pixels cannot be compared",
            a.len(),
            b.len()
        );
        let (mut max, mut sum, mut sq) = (0.0f64, 0.0f64, 0.0f64);
        for (p, q) in a.iter().zip(b) {
            for c in 0..3 {
                let d = (p[c] as f64 - q[c] as f64).abs();
                max = max.max(d);
                sum += d;
                sq += d * d;
            }
        }
        let n = 3.0 * a.len() as f64;
        let mse = sq / n;
        Ok(ImageDiff {
            max_abs: max,
            mean_abs: sum / n,
            psnr_db: (mse > 0.0).then(|| -10.0 * mse.log10()),
        })
    }
}

/// One variant of one row.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct VariantRun {
    /// [`variant_name`].
    pub variant: String,
    pub levers: String,
    pub warmup_ms: Vec<f64>,
    pub frames_ms: Vec<f64>,
    /// Position of each warm-up frame in the run's sequence of rendered frames (0-based,
    /// over all rows, variants and the image frames).
    pub warmup_order: Vec<u64>,
    /// Position of each measured frame (as `frames_ms`) in the same sequence.
    pub order: Vec<u64>,
    pub stats: Stats,
    pub fps: f64,
    /// Mean GPU ms per pass over the measured frames.
    pub passes: Passes,
    /// Per-frame sweep pass ms.
    pub sweep_ms: Vec<f64>,
    /// Median frame time over the `ratio_to` variant's.
    pub ratio: f64,
    /// `SweepStats::bytes_per_plane` / pixels, as this variant's sweep reports it.
    pub bytes_per_plane_pixel: f64,
    /// The image at the row's first camera against the reference variant's.
    pub image: ImageDiff,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct VariantsRow {
    pub dataset: String,
    pub title: String,
    /// "stand-in" or the original's path from --data-dir.
    pub source: String,
    pub resolution: [u32; 3],
    pub viewport: [u32; 2],
    pub planes: u32,
    pub preintegration_ms: f64,
    pub variants: Vec<VariantRun>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct VariantsReport {
    pub schema: String,
    pub meta: Meta,
    pub settings: VariantsSettingsRecord,
    pub rows: Vec<VariantsRow>,
}

/// Refuses a list that names the same levers twice (their names would collide).
pub fn check_variants(list: &[Levers]) -> Result<()> {
    for (i, l) in list.iter().enumerate() {
        if let Some(j) = list[..i].iter().position(|m| m == l) {
            bail!(
                "variants {} and {} are the same levers ({}); give each once",
                j + 1,
                i + 1,
                variant_name(*l)
            );
        }
    }
    Ok(())
}

/// Times the variants interleaved on every selected row and compares their images.
pub fn variants(ctx: &Context, s: &VariantsSettings) -> Result<VariantsReport> {
    ensure!(s.timing.frames >= 1, "--frames must be at least 1");
    let rows = select_rows(&s.timing.rows)?;
    let list = if s.variants.is_empty() {
        default_variants()
    } else {
        s.variants.clone()
    };
    check_variants(&list)?;
    let names: Vec<String> = list.iter().map(|l| variant_name(*l)).collect();
    let ratio_to = list
        .iter()
        .position(|l| *l == Levers::default())
        .unwrap_or(0);
    let reference = list.iter().position(|l| *l == Levers::REFERENCE);
    let nv = list.len();
    let image_frames = nv + reference.is_none() as usize;
    let per_row = (s.timing.warmup + s.timing.frames) as u64 * nv as u64 + image_frames as u64;
    let pb = progress_bar(rows.len() as u64 * per_row, s.timing.progress);
    let mut order = 0u64;
    let mut out = Vec::new();
    let mut transports = Vec::new();
    for d in rows {
        pb.set_message(format!("{}: preparing the volume", d.name));
        let (mut row, mut renderer) = prepare_row(ctx, d, s.timing.scale, &s.timing.data_dir)?;
        if let Some(t) = s.light_transport {
            row.opts.sweep.light_transport = t;
        }
        transports.push(row.opts.sweep.light_transport);
        let tone = row.scene.tone_map()?;
        let opts: Vec<RenderOptions> = list
            .iter()
            .map(|l| {
                let mut o = row.opts.clone();
                o.sweep.levers = *l;
                o
            })
            .collect();
        let mut collectors: Vec<Collector> = (0..nv).map(|_| Collector::default()).collect();
        let mut orders = vec![(Vec::new(), Vec::new()); nv];
        for k in 0..s.timing.warmup + s.timing.frames {
            let warm = k < s.timing.warmup;
            pb.set_message(s.timing.frame_message(d.name, k));
            let camera = orbit(&row.scene.camera, k);
            for v in 0..nv {
                let f = renderer.render(Model::Refract, &camera, &opts[v])?;
                collectors[v].add(&f, warm)?;
                let (warm_order, measured_order) = &mut orders[v];
                if warm {
                    warm_order.push(order);
                } else {
                    measured_order.push(order);
                }
                order += 1;
                pb.inc(1);
            }
        }
        // The images, all at the row's first camera: the reference's first.
        pb.set_message(format!("{}: images", d.name));
        let mut image = |o: &RenderOptions| -> Result<Vec<[f32; 3]>> {
            let f = renderer.render(Model::Refract, &row.scene.camera, o)?;
            order += 1;
            pb.inc(1);
            Ok(output::to_display(&f, &tone))
        };
        let reference_image = match reference {
            Some(r) => image(&opts[r])?,
            None => {
                let mut o = row.opts.clone();
                o.sweep.levers = Levers::REFERENCE;
                image(&o)?
            }
        };
        let mut diffs = Vec::new();
        for (v, o) in opts.iter().enumerate() {
            diffs.push(if Some(v) == reference {
                ImageDiff::of(&reference_image, &reference_image)?
            } else {
                ImageDiff::of(&reference_image, &image(o)?)?
            });
        }

        let pixels = row.side as f64 * row.side as f64;
        let mut runs = Vec::new();
        let mut planes = None;
        for (v, (c, ((warmup_order, order), image))) in collectors
            .into_iter()
            .zip(orders.into_iter().zip(diffs))
            .enumerate()
        {
            let (t, p, bytes) = c.finish(&names[v])?;
            planes = planes.or(p);
            runs.push(VariantRun {
                variant: t.variant,
                levers: list[v].to_string(),
                warmup_ms: t.warmup_ms,
                frames_ms: t.frames_ms,
                warmup_order,
                order,
                stats: t.stats,
                fps: t.fps,
                passes: t.passes,
                sweep_ms: t.sweep_ms,
                ratio: 0.0,
                bytes_per_plane_pixel: bytes.map_or(0, |b| b.0) as f64 / pixels,
                image,
            });
        }
        let base = runs[ratio_to].stats.median;
        for r in &mut runs {
            r.ratio = r.stats.median / base;
        }
        out.push(VariantsRow {
            dataset: d.name.to_string(),
            title: d.title.to_string(),
            source: row
                .original
                .map(|p| p.display().to_string())
                .unwrap_or_else(|| "stand-in".into()),
            resolution: row.resolution,
            viewport: [row.side, row.side],
            planes: planes.context("the sweep reported no planes")?,
            preintegration_ms: row.preintegration_ms,
            variants: runs,
        });
    }
    pb.finish_and_clear();
    Ok(VariantsReport {
        schema: VARIANTS_SCHEMA.into(),
        meta: meta(ctx),
        settings: VariantsSettingsRecord {
            scale: s.timing.scale,
            frames: s.timing.frames,
            warmup: s.timing.warmup,
            sample_distance: THESIS_SAMPLE_DISTANCE,
            orbit_deg_per_frame: ORBIT_DEG_PER_FRAME,
            rows: out.iter().map(|r| r.dataset.clone()).collect(),
            variants: list
                .iter()
                .zip(&names)
                .map(|(l, n)| VariantSpec {
                    name: n.clone(),
                    levers: l.to_string(),
                })
                .collect(),
            ratio_to: names[ratio_to].clone(),
            image_reference: reference
                .map(|r| names[r].clone())
                .unwrap_or_else(|| variant_name(Levers::REFERENCE)),
            image_reference_timed: reference.is_some(),
            light_transport: Some(transport_record(&transports)),
        },
        rows: out,
    })
}

/// A difference for the table: 0 exactly, else three significant digits.
fn diff_text(d: f64) -> String {
    if d == 0.0 {
        "0".into()
    } else {
        format!("{d:.2e}")
    }
}

/// PSNR for the table: "inf" for identical images.
pub(crate) fn psnr_text(p: Option<f64>) -> String {
    p.map(|p| format!("{p:.1}")).unwrap_or_else(|| "inf".into())
}

/// The report as Markdown: the protocol, the variants' levers, and one table per row.
pub fn variants_markdown(r: &VariantsReport) -> String {
    let st = &r.settings;
    let mut s = device_line(&r.meta);
    s += &format!(
        "Protocol: viewport {}² × scale {}, sample distance {}, {} frames after {} warm-up per \
         variant, interleaved (frame k of every variant before frame k+1 of any), camera \
         orbiting {}°/frame; GPU timestamps of the whole frame. Light transport: {}.\n\n",
        THESIS_VIEWPORT,
        st.scale,
        st.sample_distance,
        st.frames,
        st.warmup,
        st.orbit_deg_per_frame,
        st.light_transport.as_deref().unwrap_or("not recorded")
    );
    s += "Variants (in the order each frame renders them):\n\n";
    for v in &st.variants {
        s += &format!("- `{}`: {}\n", v.name, v.levers);
    }
    if !st.image_reference_timed {
        s += &format!(
            "- `{}` (image reference only, not timed): {}\n",
            st.image_reference,
            Levers::REFERENCE
        );
    }
    s += &format!(
        "\nRatio: median frame time over `{}`'s. Δ: absolute difference to `{}`'s image at \
         the row's first camera, of tone-mapped display values in [0, 1] (sRGB, as the PNG \
         before 8-bit rounding; 1/255 = 3.9e-3), over all RGB channels; PSNR with peak 1. \
         B/plane-pixel: state-buffer traffic as the sweep counts it.\n",
        st.ratio_to, st.image_reference
    );
    for row in &r.rows {
        s += &format!(
            "\n### {}: {}{}, {}², {} planes\n\n",
            row.title,
            dims(row.resolution),
            if row.source == "stand-in" {
                " (stand-in)"
            } else {
                " (original)"
            },
            row.viewport[0],
            row.planes
        );
        s += &table_head(&format!("Variant | Mean ms | Median | Min | Max | Sweep ms | Ratio to {} | B/plane-pixel | Max Δ | Mean Δ | PSNR dB", st.ratio_to), "lrrrrrrrrrr");
        for v in &row.variants {
            let t = &v.stats;
            s += &format!(
                "| {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.3} | {:.0} | {} | {} | {} |\n",
                v.variant,
                t.mean,
                t.median,
                t.min,
                t.max,
                v.passes.sweep_ms,
                v.ratio,
                v.bytes_per_plane_pixel,
                diff_text(v.image.max_abs),
                diff_text(v.image.mean_abs),
                psnr_text(v.image.psnr_db)
            );
        }
    }
    s
}

/// One CSV record per frame (warm-up included) of every row and variant, each with its
/// whole context, as `bench thesis --csv`.
pub fn write_variants_csv(r: &VariantsReport, path: &Path) -> Result<()> {
    let mut csv = ReportCsv::new(
        &[
            "schema", "dataset", "variant", "levers", "frame", "warmup", "order", "frame_ms",
            "sweep_ms",
        ],
        &[],
        &[],
        &r.meta,
        (r.settings.scale, r.settings.sample_distance),
    )?;
    for row in &r.rows {
        for v in &row.variants {
            let warm = v
                .warmup_ms
                .iter()
                .zip(&v.warmup_order)
                .map(|(t, o)| (true, t, o, None));
            let measured = v
                .frames_ms
                .iter()
                .zip(&v.order)
                .zip(v.sweep_ms.iter().map(Some).chain(std::iter::repeat(None)))
                .map(|((t, o), sw)| (false, t, o, sw));
            for (k, (warmup, t, o, sweep)) in warm.chain(measured).enumerate() {
                csv.record(
                    vec![
                        VARIANTS_SCHEMA.to_string(),
                        row.dataset.clone(),
                        v.variant.clone(),
                        v.levers.clone(),
                        k.to_string(),
                        warmup.to_string(),
                        o.to_string(),
                        format!("{t:.6}"),
                        sweep.map(|x| format!("{x:.6}")).unwrap_or_default(),
                    ],
                    (row.resolution, row.viewport, row.planes),
                    &[],
                    &[],
                )?;
            }
        }
    }
    csv.finish(path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{Region, Splat};

    #[test]
    fn names_read_back_to_their_levers() {
        for region in [Region::Full, Region::Rect, Region::Octagon] {
            for bits in 0..32u32 {
                let l = Levers {
                    region,
                    clear: bits & 16 != 0,
                    needed_rays: bits % 3 != 1,
                    field: bits & 1 != 0,
                    arrays: bits & 2 != 0,
                    specialize: bits & 4 != 0,
                    splat: if bits & 8 != 0 {
                        Splat::Compute
                    } else if bits % 7 == 0 {
                        Splat::Groups
                    } else {
                        Splat::Raster
                    },
                    sweep: crate::render::SweepPath::Auto,
                    gather: if bits % 5 == 0 {
                        crate::render::Gather::Pixels
                    } else if bits % 3 == 1 {
                        crate::render::Gather::Blocks
                    } else {
                        crate::render::Gather::Pairs
                    },
                    deposit: if bits % 3 == 0 {
                        crate::render::Deposit::Boxes
                    } else {
                        crate::render::Deposit::Cells
                    },
                    tile: [None, Some(Levers::DEFAULT_TILE_HALO), Some(2)][(bits % 3) as usize],
                };
                let n = variant_name(l);
                assert_eq!(Levers::parse(&n).unwrap(), l, "{n}");
            }
        }
        assert_eq!(variant_name(Levers::default()), "default");
        assert_eq!(variant_name(Levers::REFERENCE), "reference");
        let one_off = Levers {
            arrays: false,
            ..Levers::default()
        };
        assert_eq!(variant_name(one_off), "arrays=off");
        let one_on = Levers {
            arrays: true,
            ..Levers::REFERENCE
        };
        assert_eq!(variant_name(one_on), "reference,arrays=on");
    }

    #[test]
    fn default_variants_are_reference_default_and_each_lever_flipped() {
        let v = default_variants();
        let names: Vec<String> = v.iter().map(|l| variant_name(*l)).collect();
        assert_eq!(
            names,
            [
                "reference",
                "default",
                "region=full",
                "region=rect",
                "field=on",
                "arrays=off",
                "specialize=off",
                "clear=off",
                "rays=all",
                "splat=compute",
                "sweep=fragment",
                "sweep=compute",
            ]
        );
    }

    #[test]
    fn image_diff_of_known_images() {
        let a = vec![[0.5f32; 3]; 4];
        let same = ImageDiff::of(&a, &a).unwrap();
        assert_eq!(
            (same.max_abs, same.mean_abs, same.psnr_db),
            (0.0, 0.0, None)
        );
        // One channel of one pixel off by 0.25 (exact in f32): 12 channels in all.
        let mut b = a.clone();
        b[2][1] = 0.75;
        let d = ImageDiff::of(&a, &b).unwrap();
        assert_eq!(d.max_abs, 0.25);
        assert!((d.mean_abs - 0.25 / 12.0).abs() < 1e-15);
        let psnr = 10.0 * (12.0f64 / 0.0625).log10();
        assert!((d.psnr_db.unwrap() - psnr).abs() < 1e-12);
        assert!(ImageDiff::of(&a, &b[..3]).is_err());
    }
}
