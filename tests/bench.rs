//! Issue 7: the benchmark mode never rots. A tiny `bench thesis` run (two rows, two frames)
//! must produce the documented structure: the Markdown table with the thesis' figures, a
//! JSON report that deserialises into the strict schema types, and a CSV with one record
//! per frame. Times are only checked to be GPU times (positive, finite), never compared.

mod common;

use refrakt::bench::{Report, Variant, SCHEMA};

fn refrakt(args: &[&str]) -> std::process::Output {
    common::refrakt_command(args)
        // A private stand-in cache, so the test also exercises generation.
        .env(
            "REFRAKT_CACHE_DIR",
            std::env::temp_dir().join("refrakt-bench-test-cache"),
        )
        .output()
        .expect("running refrakt")
}

#[test]
fn tiny_thesis_bench_has_the_documented_structure() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("r.json");
    let csv = dir.path().join("r.csv");
    let o = refrakt(&[
        "bench",
        "thesis",
        "--scale",
        "0.05",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--rows",
        "kiwi,supernova",
        "--baselines",
        "--quiet",
        "--json",
        json.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // Markdown: the thesis' figures beside ours, rows in table order.
    let sn = stdout.find("| Supernova | 432×432×432 |").expect(&stdout);
    let kiwi = stdout.find("| Kiwi | 256×256×128 |").expect(&stdout);
    assert!(sn < kiwi);
    for needle in [
        "108.53",
        "9.21",
        "155.15",
        "6.45",
        "Refract / EA",
        "Refract / floor",
        "Skeleton / floor",
    ] {
        assert!(stdout.contains(needle), "no {needle} in\n{stdout}");
    }

    // JSON: unknown or missing fields fail to deserialise (deny_unknown_fields).
    let r: Report = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    // The chart says which bars are whose, and that a 5 % run is not the thesis' size.
    let svg_path = dir.path().join("r.svg");
    refrakt::bench::plot_svg(&r, &svg_path).unwrap();
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    for needle in [
        "thesis: GTX 1070 / 980, full size",
        &format!("ours: {}, scale 0.05", r.meta.device),
        "not comparable",
    ] {
        assert!(svg.contains(needle), "the chart lacks {needle:?}");
    }
    assert_eq!(r.schema, SCHEMA);
    assert!(r.meta.device.contains("llvmpipe") || std::env::var("REFRAKT_DEVICE").is_ok());
    assert!(!r.meta.git_commit.is_empty() && !r.meta.date.is_empty());
    assert_eq!((r.settings.frames, r.settings.warmup), (2, 1));
    // No --variant: the default levers, recorded.
    assert_eq!(
        r.settings.variant,
        Some(refrakt::render::Levers::default().to_string())
    );
    // No --light-transport: the scenes' own, forward.
    assert_eq!(r.settings.light_transport.as_deref(), Some("forward"));
    let names: Vec<&str> = r.rows.iter().map(|r| r.dataset.as_str()).collect();
    assert_eq!(names, ["supernova", "kiwi"]);
    // Scale 0.05 of the thesis' resolutions (Table 6.1: supernova 432³, kiwi 256×256×128)
    // and of its 768² viewport.
    let expected = [[22, 22, 22], [13, 13, 6]];
    for (row, expect) in r.rows.iter().zip(expected) {
        assert_eq!(row.resolution, expect, "{}", row.dataset);
        assert_eq!(row.viewport, [38, 38]);
        assert!(row.planes >= 2);
        let names: Vec<&str> = row.variants().map(|v| v.variant.as_str()).collect();
        assert_eq!(names, ["refract", "ea", "floor", "skeleton"]);
        for v in row.variants() {
            assert_eq!(
                (v.frames_ms.len(), v.warmup_ms.len()),
                (2, 1),
                "{}",
                v.variant
            );
            assert!(v.frames_ms.iter().all(|t| t.is_finite() && *t > 0.0));
            // The statistics are those of the frames reported beside them.
            let mean = v.frames_ms.iter().sum::<f64>() / v.frames_ms.len() as f64;
            let lo = v.frames_ms.iter().cloned().fold(f64::INFINITY, f64::min);
            let hi = v.frames_ms.iter().cloned().fold(0.0, f64::max);
            assert!((v.stats.mean - mean).abs() <= 1e-9 * mean, "{}", v.variant);
            assert_eq!((v.stats.min, v.stats.max), (lo, hi), "{}", v.variant);
            assert!((v.stats.median - (lo + hi) / 2.0).abs() <= 1e-9 * hi);
        }
        assert!(
            row.refract.passes.sweep_ms > 0.0
                && row.refract.passes.sweep_ms <= row.refract.stats.max
        );
        // The ratios are those of the mean frame times.
        let ratio = |v: &Option<Variant>| row.refract.stats.mean / v.as_ref().unwrap().stats.mean;
        assert!((row.sweep_over_ea.unwrap() - ratio(&row.ea)).abs() < 1e-9);
        assert!((row.sweep_over_floor.unwrap() - ratio(&row.floor)).abs() < 1e-9);
        assert!((row.sweep_over_skeleton.unwrap() - ratio(&row.skeleton)).abs() < 1e-9);
        assert!(row.bytes_per_plane_pixel > 0.0);
        // Each state texel read and written once is part of what the shaders fetch.
        assert!(
            row.compulsory_bytes_per_plane_pixel > 0.0
                && row.compulsory_bytes_per_plane_pixel < row.bytes_per_plane_pixel,
            "{} compulsory of {} B/plane-pixel",
            row.compulsory_bytes_per_plane_pixel,
            row.bytes_per_plane_pixel
        );
    }

    // CSV: a header and one record per frame (warm-up included) of each variant.
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    for col in [
        "dataset",
        "variant",
        "frame",
        "warmup",
        "frame_ms",
        "device",
        "git_commit",
    ] {
        assert!(header.split(',').any(|c| c == col), "no {col} in {header}");
    }
    // 2 rows × 3 frames × 4 variants (the sweep, EA, floor, skeleton).
    assert_eq!(lines.count(), 2 * 3 * 4);

    // --light-transport backward reaches the sweep: the thesis' transport has no light
    // rays and fetches other state, so its bytes per plane-pixel (counted from what the
    // sweep ran) differ.
    let back = dir.path().join("b.json");
    let o = refrakt(&[
        "bench",
        "thesis",
        "--scale",
        "0.05",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--rows",
        "kiwi",
        "--light-transport",
        "backward",
        "--quiet",
        "--json",
        back.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("Light transport: backward."));
    let b: Report = serde_json::from_str(&std::fs::read_to_string(&back).unwrap()).unwrap();
    assert_eq!(b.settings.light_transport.as_deref(), Some("backward"));
    let forward_kiwi = &r.rows[1];
    assert!(
        b.rows[0].bytes_per_plane_pixel != forward_kiwi.bytes_per_plane_pixel,
        "backward {} B, forward {} B per plane-pixel",
        b.rows[0].bytes_per_plane_pixel,
        forward_kiwi.bytes_per_plane_pixel
    );
}

#[test]
fn bad_bench_arguments_fail_before_any_work() {
    for (args, needle) in [
        (vec!["--rows", "teapot"], "teapot"),
        (vec!["--scale", "0"], "scale"),
        (vec!["--frames", "0"], "frames"),
        (vec!["--csv", "/no/such/folder/x.csv"], "does not exist"),
        (vec!["--json", "x.txt"], ".json"),
        (vec!["--light-transport", "sideways"], "sideways"),
    ] {
        let mut a = vec!["bench", "thesis"];
        a.extend(&args);
        let o = refrakt(&a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{a:?} succeeded");
        assert!(
            err.contains(needle) && !err.contains("panicked"),
            "{a:?}: {err}"
        );
    }
}

#[test]
fn scaling_bench_reports_both_series_and_fits() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("s.json");
    let o = refrakt(&[
        "bench",
        "scaling",
        "--volume-size",
        "24",
        "--sample-distances",
        "1,2",
        "--sides",
        "32,48",
        "--side",
        "32",
        "--frames",
        "1",
        "--quiet",
        "--json",
        json.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        stdout.contains("ms per plane") && stdout.contains("R²"),
        "{stdout}"
    );
    let r: refrakt::bench::ScalingReport =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let planes: Vec<u32> = r.by_planes.iter().map(|p| p.planes).collect();
    // Twice the sample distance, about half the planes.
    assert!(
        planes[1] < planes[0] && planes[1] * 2 + 2 >= planes[0],
        "{planes:?}"
    );
    let pixels: Vec<u64> = r.by_pixels.iter().map(|p| p.pixels).collect();
    assert_eq!(pixels, [32 * 32, 48 * 48]);
    assert!(r.planes_fit.r2.is_finite() && r.pixels_fit.r2.is_finite());
    // The region lever shades some of each plane, never more than all of it.
    for p in r.by_planes.iter().chain(&r.by_pixels) {
        assert!(
            p.shaded_pixels > 0.0 && p.shaded_pixels <= p.pixels as f64,
            "{p:?}"
        );
    }
    assert!(stdout.contains("per plane and shaded pixel"), "{stdout}");
}

/// `bench scaling` takes any scene `render` takes: a volume file without --tf (its
/// transfer functions derived from its data) failed with an internal "use load_all";
/// and a series of one point is refused before measuring, naming its flag.
#[test]
fn scaling_bench_takes_a_volume_file_and_refuses_a_one_point_series() {
    let dir = tempfile::tempdir().unwrap();
    let mut v = vec![0u8; 12 * 12 * 12];
    for z in 3..9 {
        for y in 3..9 {
            for x in 3..9 {
                v[x + 12 * (y + 12 * z)] = 200;
            }
        }
    }
    let raw = dir.path().join("cube_12x12x12_uint8.raw");
    std::fs::write(&raw, &v).unwrap();
    let base = [
        "bench",
        "scaling",
        "--scene",
        raw.to_str().unwrap(),
        "--side",
        "8",
        "--frames",
        "1",
        "--quiet",
    ];
    let o = refrakt(&[&base[..], &["--sides", "8,12", "--sample-distances", "4,8"]].concat());
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("ms per plane"), "{stdout}");
    let o = refrakt(&[&base[..], &["--sides", "8", "--sample-distances", "4,8"]].concat());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("--sides: give at least two different values"),
        "{err}"
    );
}
