//! Issue 16 item 5: the sweep's levers as A/B variants. `--variant` on `render` and
//! `bench thesis`; `bench variants` times variants interleaved in one process and compares
//! their images with the reference's; `bench compare` sets two reports side by side with a
//! noise-aware verdict. Times are never compared with fixed numbers: the GPU runs are
//! checked for structure and for facts known independently of the code (an image against
//! itself, variants that render the same image, ratios and interleaving recomputed from
//! the reported frames); the verdicts are checked on hand-made reports with known numbers.

mod common;

use std::path::{Path, PathBuf};

use refrakt::bench::{
    ImageDiff, Meta, Passes, Report, Row, SettingsRecord, Stats, Thesis, Variant, VariantRun,
    VariantSpec, VariantsReport, VariantsRow, VariantsSettingsRecord, SCHEMA, VARIANTS_SCHEMA,
};
use refrakt::render::Levers;

fn refrakt(args: &[&str]) -> std::process::Output {
    common::refrakt_command(args)
        // The same private stand-in cache as tests/bench.rs.
        .env(
            "REFRAKT_CACHE_DIR",
            std::env::temp_dir().join("refrakt-bench-test-cache"),
        )
        .output()
        .expect("running refrakt")
}

fn text(o: &std::process::Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        (s[n / 2 - 1] + s[n / 2]) / 2.0
    }
}

fn read_variants(path: &Path) -> VariantsReport {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn variants_are_timed_interleaved_and_compared_with_the_reference_image() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("v.json");
    let csv = dir.path().join("v.csv");
    let (frames, warmup) = (2usize, 1usize);
    let o = refrakt(&[
        "bench",
        "variants",
        "--scale",
        "0.05",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--rows",
        "supernova",
        "--variant",
        "reference",
        "--variant",
        "default",
        // Differs from the reference in the specialization constants alone, which
        // compile out only code whose result is unused: the same image.
        "--variant",
        "reference,specialize=on",
        "--quiet",
        "--json",
        json.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    assert!(
        stdout.contains("### Supernova: 22×22×22 (stand-in), 38²"),
        "{stdout}"
    );
    assert!(
        stdout.contains("| reference |") && stdout.contains("| inf |"),
        "{stdout}"
    );

    let r = read_variants(&json);
    assert_eq!(r.schema, VARIANTS_SCHEMA);
    assert_eq!((r.settings.frames, r.settings.warmup), (2, 1));
    assert_eq!(r.settings.ratio_to, "default");
    assert_eq!(r.settings.image_reference, "reference");
    assert!(r.settings.image_reference_timed);
    assert_eq!(r.rows.len(), 1);
    let row = &r.rows[0];
    assert_eq!(
        (row.dataset.as_str(), row.viewport),
        ("supernova", [38, 38])
    );
    let names: Vec<&str> = row.variants.iter().map(|v| v.variant.as_str()).collect();
    assert_eq!(names, ["reference", "default", "reference,specialize=on"]);
    let expect_levers = [
        Levers::REFERENCE,
        Levers::default(),
        Levers {
            specialize: true,
            ..Levers::REFERENCE
        },
    ];
    let base = median(&row.variants[1].frames_ms);
    for (v, levers) in row.variants.iter().zip(expect_levers) {
        assert_eq!(Levers::parse(&v.levers).unwrap(), levers, "{}", v.variant);
        assert_eq!(
            (v.frames_ms.len(), v.warmup_ms.len(), v.sweep_ms.len()),
            (frames, warmup, frames),
            "{}",
            v.variant
        );
        assert!(v.frames_ms.iter().all(|t| t.is_finite() && *t > 0.0));
        // Statistics and ratio are those of the frames reported beside them.
        assert!((v.stats.median - median(&v.frames_ms)).abs() <= 1e-9 * base);
        assert!(
            (v.ratio - median(&v.frames_ms) / base).abs() < 1e-9,
            "{}: ratio {} of medians {:?} / {base}",
            v.variant,
            v.ratio,
            v.frames_ms
        );
        assert!(v.bytes_per_plane_pixel > 0.0);
        assert!(v.passes.sweep_ms > 0.0 && v.passes.sweep_ms <= v.stats.max);
        // PSNR is infinite (null) exactly when the images are identical.
        assert_eq!(
            v.image.psnr_db.is_none(),
            v.image.max_abs == 0.0,
            "{}",
            v.variant
        );
        assert!(v.image.mean_abs <= v.image.max_abs && v.image.max_abs <= 1.0);
    }
    assert_eq!(row.variants[1].ratio, 1.0);
    // The reference against itself: identical.
    let reference = &row.variants[0].image;
    assert_eq!((reference.max_abs, reference.mean_abs), (0.0, 0.0));
    assert_eq!(reference.psnr_db, None);
    // Specialized and general pipelines render the same image (tests/sweep.rs: 1e-5).
    let spec = &row.variants[2].image;
    assert!(spec.max_abs < 1e-5, "{spec:?}");

    // Interleaved: every variant's frame k renders before any variant's frame k + 1, the
    // variants in the order given, warm-up before the measured frames.
    let all: Vec<Vec<u64>> = row
        .variants
        .iter()
        .map(|v| v.warmup_order.iter().chain(&v.order).copied().collect())
        .collect();
    let n = row.variants.len() as u64;
    for k in 0..frames + warmup {
        for (i, orders) in all.iter().enumerate() {
            assert_eq!(orders[k], all[0][k] + i as u64, "frame {k}: {all:?}");
        }
        if k + 1 < frames + warmup {
            assert_eq!(all[0][k + 1], all[0][k] + n, "{all:?}");
        }
    }

    // CSV: a header and one record per frame (warm-up included) of each variant.
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    for col in [
        "dataset", "variant", "levers", "order", "frame_ms", "sweep_ms",
    ] {
        assert!(header.split(',').any(|c| c == col), "no {col} in {header}");
    }
    assert_eq!(lines.count(), 3 * (frames + warmup));
}

#[test]
fn default_variants_are_the_reference_the_default_and_each_lever_off() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("v.json");
    let o = refrakt(&[
        "bench",
        "variants",
        "--scale",
        "0.05",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--rows",
        "kiwi",
        "--quiet",
        "--json",
        json.to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    let r = read_variants(&json);
    let names: Vec<&str> = r
        .settings
        .variants
        .iter()
        .map(|v| v.name.as_str())
        .collect();
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
    // Each flipped variant differs from the default in one lever.
    let count = |a: &str, b: &str| {
        a.split(',')
            .zip(b.split(','))
            .filter(|(x, y)| x != y)
            .count()
    };
    let default = Levers::default().to_string();
    for v in &r.settings.variants[2..] {
        assert_eq!(count(&v.levers, &default), 1, "{}", v.levers);
    }
    let row = &r.rows[0];
    assert_eq!(row.dataset, "kiwi");
    assert_eq!(row.variants.len(), 12);
    assert!(row.variants.iter().all(|v| v.frames_ms.len() == 1));
    assert_eq!(row.variants[0].image.psnr_db, None);
}

#[test]
fn without_the_reference_variant_it_is_rendered_for_the_images_only() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("v.json");
    let o = refrakt(&[
        "bench",
        "variants",
        "--scale",
        "0.05",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--rows",
        "kiwi",
        "--variant",
        "specialize=off",
        "--variant",
        "reference,specialize=on",
        "--quiet",
        "--json",
        json.to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    assert!(
        stdout.contains("image reference only, not timed"),
        "{stdout}"
    );
    let r = read_variants(&json);
    assert!(!r.settings.image_reference_timed);
    assert_eq!(r.settings.image_reference, "reference");
    // No default among them: the ratios are to the first variant.
    assert_eq!(r.settings.ratio_to, "specialize=off");
    let row = &r.rows[0];
    let names: Vec<&str> = row.variants.iter().map(|v| v.variant.as_str()).collect();
    assert_eq!(names, ["specialize=off", "reference,specialize=on"]);
    assert_eq!(row.variants[0].ratio, 1.0);
    // The reference with specialization constants renders the reference's image.
    assert!(
        row.variants[1].image.max_abs < 1e-5,
        "{:?}",
        row.variants[1].image
    );
    // The whole run: the two timed frames, then three images (the reference's first).
    assert_eq!((row.variants[0].order[0], row.variants[1].order[0]), (0, 1));
}

#[test]
fn bad_variants_fail_at_once_with_one_line_naming_the_problem() {
    for (args, needle) in [
        (
            vec!["bench", "variants", "--variant", "nonsense"],
            "'nonsense'",
        ),
        (
            vec!["bench", "variants", "--variant", "speed=11"],
            "'speed'",
        ),
        (
            vec!["bench", "thesis", "--variant", "field=maybe"],
            "on or off",
        ),
        (
            vec!["render", "--variant", "region=polygon"],
            "full, rect or octagon",
        ),
        (
            vec![
                "bench",
                "variants",
                "--variant",
                "default",
                "--variant",
                "region=octagon",
            ],
            "same levers",
        ),
        (
            vec!["render", "--model", "ea", "--variant", "region=full"],
            "--variant only applies to --model refract",
        ),
    ] {
        let o = refrakt(&args);
        let (_, err) = text(&o);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(
            err.contains(needle) && !err.contains("panicked"),
            "{args:?}: {err}"
        );
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    }
}

#[test]
fn help_lists_the_variant_syntax() {
    for args in [
        vec!["render", "--help"],
        vec!["bench", "thesis", "--help"],
        vec!["bench", "variants", "--help"],
    ] {
        let o = refrakt(&args);
        let (out, _) = text(&o);
        assert!(o.status.success());
        assert!(out.contains(Levers::SYNTAX), "{args:?}: {out}");
    }
}

#[test]
fn render_takes_a_variant_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("r.png");
    let o = refrakt(&[
        "render",
        "--volume-size",
        "16",
        "--width",
        "24",
        "--height",
        "24",
        "--variant",
        "reference",
        "-o",
        png.to_str().unwrap(),
    ]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(
        out.contains(&format!("sweep variant: {}", Levers::REFERENCE)),
        "{out}"
    );
    assert!(png.is_file());
}

// ---- bench compare, on hand-made reports with known numbers ----

fn meta() -> Meta {
    Meta {
        device: "test device".into(),
        device_type: "CPU".into(),
        driver: "test".into(),
        driver_info: "test".into(),
        vulkan: "1.3".into(),
        refrakt_version: "0.1.0".into(),
        git_commit: "abc".into(),
        date: "2026-01-01T00:00:00Z".into(),
    }
}

fn stats(v: &[f64]) -> Stats {
    Stats::of(v).unwrap()
}

fn variant(name: &str, frames: &[f64]) -> Variant {
    Variant {
        variant: name.into(),
        warmup_ms: vec![],
        frames_ms: frames.to_vec(),
        stats: stats(frames),
        fps: 1000.0 / stats(frames).mean,
        passes: Passes::default(),
        sweep_ms: frames.to_vec(),
    }
}

/// A thesis report at `scale` with one row per (dataset, frame times).
fn thesis_report(scale: f64, rows: &[(&str, &str, Vec<f64>)]) -> Report {
    Report {
        schema: SCHEMA.into(),
        meta: meta(),
        settings: SettingsRecord {
            scale,
            // As many as the rows measured (a report's frames match its settings).
            frames: rows.first().map_or(0, |r| r.2.len() as u32),
            warmup: 1,
            baselines: false,
            sample_distance: 1.0,
            orbit_deg_per_frame: 0.5,
            rows: rows.iter().map(|r| r.0.to_string()).collect(),
            variant: Some(Levers::default().to_string()),
            light_transport: Some("forward".into()),
        },
        rows: rows
            .iter()
            .map(|(name, title, frames)| Row {
                dataset: name.to_string(),
                title: title.to_string(),
                thesis: Thesis {
                    table: "6.1".into(),
                    gpu: "GTX 1070".into(),
                    resolution: [1, 1, 1],
                    ms: 1.0,
                    fps: 1000.0,
                },
                source: "stand-in".into(),
                resolution: [22, 22, 22],
                viewport: [38, 38],
                planes: 36,
                preintegration_ms: 1.0,
                refract: variant("refract", frames),
                ms_per_plane: 1.0,
                plane_pixels_per_s: 1.0,
                bytes_per_plane_pixel: 400.0,
                compulsory_bytes_per_plane_pixel: 192.0,
                effective_gb_per_s: 1.0,
                ea: None,
                floor: None,
                skeleton: None,
                sweep_over_ea: None,
                sweep_over_floor: None,
                sweep_over_skeleton: None,
            })
            .collect(),
    }
}

fn write(dir: &Path, name: &str, value: &impl serde::Serialize) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, serde_json::to_string_pretty(value).unwrap()).unwrap();
    p
}

/// The table line of a row and variant.
fn line<'a>(stdout: &'a str, title: &str, variant: &str) -> &'a str {
    let start = format!("| {title} | {variant} |");
    stdout
        .lines()
        .find(|l| l.starts_with(&start))
        .unwrap_or_else(|| panic!("no line {start} in\n{stdout}"))
}

#[test]
fn compare_gives_the_known_deltas_and_verdicts() {
    let dir = tempfile::tempdir().unwrap();
    let tight = vec![100.0, 101.0, 99.0, 100.0, 100.0];
    let plus = |v: &[f64], d: f64| v.iter().map(|t| t + d).collect::<Vec<f64>>();
    let wide = vec![80.0, 120.0, 100.0, 90.0, 110.0];
    let old = thesis_report(
        0.05,
        &[
            ("supernova", "Supernova", tight.clone()),
            ("glass", "Glass", tight.clone()),
            ("hand", "Hand", wide.clone()),
            ("head", "Head", tight.clone()),
            ("water", "Water", tight.clone()),
        ],
    );
    let new = thesis_report(
        0.05,
        &[
            // +50 %, spread ±1: slower.
            ("supernova", "Supernova", plus(&tight, 50.0)),
            // +1 %: below the 2 % threshold whatever the spread.
            ("glass", "Glass", plus(&tight, 1.0)),
            // +10 % with s ≈ 16 ms per side: noise 3·√(2·250/5) = 30 ms.
            ("hand", "Hand", plus(&wide, 10.0)),
            // −20 %: faster.
            ("head", "Head", plus(&tight, -20.0)),
            ("kiwi", "Kiwi", tight.clone()),
        ],
    );
    // A report from before --variant existed has no settings.variant.
    let mut old_json = serde_json::to_value(&old).unwrap();
    old_json["settings"]
        .as_object_mut()
        .unwrap()
        .remove("variant");
    let old_path = write(dir.path(), "old.json", &old_json);
    let new_path = write(dir.path(), "new.json", &new);
    let (op, np) = (old_path.to_str().unwrap(), new_path.to_str().unwrap());

    let o = refrakt(&["bench", "compare", op, np]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let sn = line(&out, "Supernova", "refract");
    assert!(
        sn.contains("| 100.00 → 150.00 | +50.0 % | 100.00 → 150.00 | +50.0 % |")
            && sn.ends_with("| **slower** |"),
        "{sn}"
    );
    let glass = line(&out, "Glass", "refract");
    assert!(
        glass.contains("+1.0 %") && glass.ends_with("| within noise |"),
        "{glass}"
    );
    let hand = line(&out, "Hand", "refract");
    assert!(
        hand.contains("| 100.00 → 110.00 | +10.0 %") && hand.contains("| 30.00 | within noise |"),
        "{hand}"
    );
    let head = line(&out, "Head", "refract");
    assert!(
        head.contains("-20.0 %") && head.ends_with("| **faster** |"),
        "{head}"
    );
    assert!(line(&out, "Water", "refract").ends_with(&format!("only in {op} |")));
    assert!(line(&out, "Kiwi", "refract").ends_with(&format!("only in {np} |")));
    assert!(
        out.contains("1 slower, 1 faster, 2 within noise")
            && out.contains(&format!("only in {op}: water"))
            && out.contains(&format!("only in {np}: kiwi")),
        "{out}"
    );
    assert!(out.contains("not recorded"), "{out}");

    // CI: a slower row fails the check; without one (new → old: faster and within noise)
    // it passes.
    let o = refrakt(&["bench", "compare", "--fail-on-regression", op, np]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("supernova refract (+50.0 %)"), "{err}");
    assert!(
        !err.contains("hand refract") && !err.contains("glass refract"),
        "{err}"
    );
    // Old → new reversed: what was faster is slower.
    let o = refrakt(&["bench", "compare", "--fail-on-regression", np, op]);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}\n{err}");
    assert!(line(&out, "Supernova", "refract").ends_with("| **faster** |"));
    assert!(
        line(&out, "Head", "refract").ends_with("| **slower** |"),
        "{out}"
    );
    assert!(err.contains("head refract (+25.0 %)"), "{err}");
    // Only faster and unchanged rows: the check passes.
    let better = thesis_report(
        0.05,
        &[
            ("supernova", "Supernova", plus(&tight, -50.0)),
            ("glass", "Glass", tight.clone()),
        ],
    );
    let better = write(dir.path(), "better.json", &better);
    let o = refrakt(&[
        "bench",
        "compare",
        "--fail-on-regression",
        op,
        better.to_str().unwrap(),
    ]);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}\n{err}");
    assert!(line(&out, "Supernova", "refract").contains("-50.0 %"));
    assert!(out.contains("0 slower, 1 faster, 1 within noise"), "{out}");
}

/// A variants report of one row (kiwi) and two variants with these frame times.
fn variants_report(default: &[f64], reference: &[f64]) -> VariantsReport {
    let run = |name: &str, levers: Levers, frames: &[f64]| VariantRun {
        variant: name.into(),
        levers: levers.to_string(),
        warmup_ms: vec![],
        frames_ms: frames.to_vec(),
        warmup_order: vec![],
        order: (0..frames.len() as u64).collect(),
        stats: stats(frames),
        fps: 1.0,
        passes: Passes::default(),
        sweep_ms: frames.to_vec(),
        ratio: 1.0,
        bytes_per_plane_pixel: 400.0,
        image: ImageDiff {
            max_abs: 0.0,
            mean_abs: 0.0,
            psnr_db: None,
        },
    };
    VariantsReport {
        schema: VARIANTS_SCHEMA.into(),
        meta: meta(),
        settings: VariantsSettingsRecord {
            scale: 0.05,
            frames: default.len() as u32,
            warmup: 0,
            sample_distance: 1.0,
            orbit_deg_per_frame: 0.5,
            rows: vec!["kiwi".into()],
            variants: [
                ("default", Levers::default()),
                ("reference", Levers::REFERENCE),
            ]
            .iter()
            .map(|(n, l)| VariantSpec {
                name: n.to_string(),
                levers: l.to_string(),
            })
            .collect(),
            ratio_to: "default".into(),
            image_reference: "reference".into(),
            image_reference_timed: true,
            light_transport: Some("forward".into()),
        },
        rows: vec![VariantsRow {
            dataset: "kiwi".into(),
            title: "Kiwi".into(),
            source: "stand-in".into(),
            resolution: [13, 13, 6],
            viewport: [38, 38],
            planes: 16,
            preintegration_ms: 1.0,
            variants: vec![
                run("default", Levers::default(), default),
                run("reference", Levers::REFERENCE, reference),
            ],
        }],
    }
}

#[test]
fn compare_reads_variants_reports_per_variant() {
    let dir = tempfile::tempdir().unwrap();
    let old = write(
        dir.path(),
        "old.json",
        &variants_report(&[40.0, 40.0, 40.0, 40.0], &[80.0, 80.0, 80.0, 80.0]),
    );
    let new = write(
        dir.path(),
        "new.json",
        &variants_report(&[60.0, 60.0, 60.0, 60.0], &[80.0, 80.0, 80.0, 80.4]),
    );
    let o = refrakt(&[
        "bench",
        "compare",
        "--fail-on-regression",
        old.to_str().unwrap(),
        new.to_str().unwrap(),
    ]);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}\n{err}");
    let d = line(&out, "Kiwi", "default");
    assert!(
        d.contains("+50.0 %") && d.ends_with("| **slower** |"),
        "{d}"
    );
    let r = line(&out, "Kiwi", "reference");
    assert!(
        r.contains("+0.1 %") && r.ends_with("| within noise |"),
        "{r}"
    );
    assert!(
        err.contains("kiwi default") && !err.contains("reference"),
        "{err}"
    );
}

#[test]
fn compare_refuses_reports_not_measured_alike() {
    let dir = tempfile::tempdir().unwrap();
    let rows = [("supernova", "Supernova", vec![100.0, 101.0, 99.0])];
    let old = write(dir.path(), "old.json", &thesis_report(0.05, &rows));
    let new = write(dir.path(), "new.json", &thesis_report(0.25, &rows));
    let (op, np) = (old.to_str().unwrap(), new.to_str().unwrap());
    let o = refrakt(&["bench", "compare", op, np]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        err.contains(&format!("scale 0.05 in {op}, 0.25 in {np}"))
            && err.contains("--allow-mismatch")
            && !err.contains("panicked"),
        "{err}"
    );
    let o = refrakt(&["bench", "compare", "--allow-mismatch", op, np]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        out.contains("settings differ") && out.contains("scale 0.05"),
        "{out}"
    );
    assert!(line(&out, "Supernova", "refract").ends_with("| within noise |"));
}

#[test]
fn compare_refuses_reports_of_different_light_transports() {
    let dir = tempfile::tempdir().unwrap();
    let rows = [("supernova", "Supernova", vec![100.0, 101.0, 99.0])];
    let old = thesis_report(0.25, &rows);
    let mut new = old.clone();
    new.settings.light_transport = Some("backward".into());
    let mut unrecorded = old.clone();
    unrecorded.settings.light_transport = None;
    let old = write(dir.path(), "old.json", &old);
    let new = write(dir.path(), "new.json", &new);
    let unrecorded = write(dir.path(), "unrecorded.json", &unrecorded);
    let (op, np) = (old.to_str().unwrap(), new.to_str().unwrap());
    let o = refrakt(&["bench", "compare", op, np]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!(
            "light transport forward in {op}, backward in {np}"
        )),
        "{err}"
    );
    // A report from before the transport was recorded compares, with a note.
    let up = unrecorded.to_str().unwrap();
    let o = refrakt(&["bench", "compare", up, op]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        out.contains(&format!("{up} does not record its light transport")),
        "{out}"
    );
}

#[test]
fn compare_names_the_file_it_cannot_use() {
    let dir = tempfile::tempdir().unwrap();
    let good = write(
        dir.path(),
        "good.json",
        &thesis_report(0.05, &[("kiwi", "Kiwi", vec![1.0])]),
    );
    let garbage = dir.path().join("garbage.json");
    std::fs::write(&garbage, "{ not json").unwrap();
    let scaling = dir.path().join("scaling.json");
    std::fs::write(&scaling, r#"{"meta": {}, "scene": "x"}"#).unwrap();
    let other = dir.path().join("other.json");
    std::fs::write(&other, r#"{"schema": "refrakt-bench-scaling/9"}"#).unwrap();
    let partial = dir.path().join("partial.json");
    std::fs::write(
        &partial,
        r#"{"schema": "refrakt-bench-thesis/1", "rows": []}"#,
    )
    .unwrap();
    let missing = dir.path().join("missing.json");
    for (bad, needle) in [
        (&garbage, "not valid JSON"),
        (&scaling, "no \"schema\""),
        (&other, "schema 'refrakt-bench-scaling/9'"),
        (&partial, "not a valid refrakt-bench-thesis/1 report"),
        (&missing, "cannot read"),
    ] {
        for args in [[bad, &good], [&good, bad]] {
            let o = refrakt(&[
                "bench",
                "compare",
                args[0].to_str().unwrap(),
                args[1].to_str().unwrap(),
            ]);
            let (_, err) = text(&o);
            assert_eq!(o.status.code(), Some(1), "{args:?}");
            assert!(
                err.contains(&format!("{}: {needle}", bad.display())) && !err.contains("panicked"),
                "{args:?}: {err}"
            );
        }
    }
    // Two kinds of report.
    let v = write(dir.path(), "v.json", &variants_report(&[1.0], &[1.0]));
    let o = refrakt(&[
        "bench",
        "compare",
        good.to_str().unwrap(),
        v.to_str().unwrap(),
    ]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(err.contains("compare two of the same kind"), "{err}");
}

/// A report cut or edited by hand is refused by name, not compared as if whole: no rows,
/// a row twice, fewer frames than its settings say.
#[test]
fn compare_refuses_reports_that_do_not_hold_together() {
    let dir = tempfile::tempdir().unwrap();
    let good = write(
        dir.path(),
        "good.json",
        &thesis_report(0.05, &[("kiwi", "Kiwi", vec![1.0, 1.1])]),
    );
    let mut empty = thesis_report(0.05, &[("kiwi", "Kiwi", vec![1.0, 1.1])]);
    empty.rows.clear();
    let mut twice = thesis_report(
        0.05,
        &[
            ("kiwi", "Kiwi", vec![1.0, 1.1]),
            ("kiwi", "Kiwi", vec![1.0, 1.1]),
        ],
    );
    twice.settings.rows.dedup();
    let mut cut = thesis_report(0.05, &[("kiwi", "Kiwi", vec![1.0, 1.1])]);
    cut.rows[0].refract.frames_ms.pop();
    for (name, report, needle) in [
        ("empty.json", &empty, "the report has no rows"),
        ("twice.json", &twice, "row 'kiwi' is there twice"),
        (
            "cut.json",
            &cut,
            "kiwi refract: 1 measured frames where the settings say 2",
        ),
    ] {
        let bad = write(dir.path(), name, report);
        let o = refrakt(&[
            "bench",
            "compare",
            good.to_str().unwrap(),
            bad.to_str().unwrap(),
        ]);
        let (_, err) = text(&o);
        assert!(
            o.status.code() == Some(1) && err.contains(&format!("{}: {needle}", bad.display())),
            "{name}: {err}"
        );
    }
}
