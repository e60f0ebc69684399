//! Issue 5 (first part): environment maps and their summed-area table on the GPU.

mod common;

use common::with_context;
use refrakt::environment::EnvironmentMap;
use refrakt::render::SummedAreaTable;

/// A 2048 x 1024 HDR map: the procedural sky and ground, a 1e5-bright sun disc and
/// deterministic noise, the kind of data that breaks a plain f32 prefix sum.
fn hdr_map() -> EnvironmentMap {
    let mut m = EnvironmentMap::procedural(2048).unwrap();
    let mut seed = 7u64;
    for (i, p) in m.pixels.iter_mut().enumerate() {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let n = (seed >> 40) as f32 / (1u64 << 24) as f32;
        let (x, y) = (i as u32 % 2048, i as u32 / 2048);
        let sun = if (x as i32 - 1500).pow(2) + (y as i32 - 300).pow(2) < 64 {
            1000.0
        } else {
            0.0
        };
        // Physical-ish HDR units: a sky of ~100, a sun of 1e5.
        for c in &mut p[..3] {
            *c = 100.0 * (*c * (0.5 + n) + sun);
        }
    }
    m
}

fn cpu_average(m: &EnvironmentMap, x0: u32, x1: u32, y0: u32, y1: u32) -> [f64; 4] {
    let mut acc = [0f64; 4];
    let mut n = 0f64;
    let xs: Vec<u32> = if x0 <= x1 {
        (x0..x1).collect()
    } else {
        (x0..m.width).chain(0..x1).collect()
    };
    for y in y0..y1 {
        for &x in &xs {
            let p = m.pixels[(y * m.width + x) as usize];
            for i in 0..4 {
                acc[i] += p[i] as f64;
            }
            n += 1.0;
        }
    }
    acc.map(|a| a / n)
}

#[test]
fn sat_box_averages_match_double_precision() {
    with_context(|ctx| {
        let m = hdr_map();
        let img = refrakt::render::upload::environment_texture(ctx, &m).unwrap();
        let (sat, timings) = SummedAreaTable::build(ctx, &m, &img).unwrap();
        println!(
            "SAT build of 2048x1024: {:?} ms",
            timings.get("environment SAT")
        );
        let table = sat.read(ctx).unwrap();
        // Large regions, as the issue asks (1e-3 relative). Single-texel boxes are limited
        // by f32 S values of ~1e5 near the sun (1 % measured); the composite should read
        // footprints of a few texels from the map directly.
        let boxes = [
            (0, 2048, 0, 1024),     // the whole map
            (100, 1900, 50, 1000),  // most of it
            (1400, 1600, 200, 400), // around the sun
            (1900, 300, 0, 1024),   // a wide box across the ±180° seam
            (1948, 100, 600, 800),  // a block across the seam
            (10, 2000, 1000, 1024), // a strip at the bottom
            (700, 900, 650, 850),   // away from everything
            (1200, 1232, 900, 932), // 32 x 32 far from the origin corner
            (2030, 10, 1000, 1020), // 20 x 20 across the seam, bottom rows
        ];
        let mut worst = 0.0f64;
        for (x0, x1, y0, y1) in boxes {
            let gpu = table.box_average(x0, x1, y0, y1);
            let cpu = cpu_average(&m, x0, x1, y0, y1);
            for i in 0..3 {
                let rel = (gpu[i] - cpu[i]).abs() / cpu[i].abs().max(1e-6);
                worst = worst.max(rel);
                // The issue asks for 1e-3. We hold 1e-4 so the test notices a regression to
                // plain f32 prefix sums, which measured 9e-4 on these boxes (ours: 9e-6).
                assert!(
                    rel <= 1e-4,
                    "box {:?} channel {i}: SAT {} vs CPU {}",
                    (x0, x1, y0, y1),
                    gpu[i],
                    cpu[i]
                );
            }
        }
        println!("worst relative error of SAT box averages: {worst:.2e}");
    });
}

#[test]
fn maps_load_from_exr_hdr_and_png() {
    let dir = tempfile::tempdir().unwrap();
    let m = EnvironmentMap::procedural(64).unwrap();
    let exr = dir.path().join("m.exr");
    refrakt::output::write_pixels(m.width, m.height, &m.pixels, &exr).unwrap();
    assert_eq!(EnvironmentMap::load(&exr).unwrap(), m);
    // sRGB 188/255 in a PNG is linear 0.5029.
    let png = dir.path().join("m.png");
    image::RgbImage::from_pixel(8, 4, image::Rgb([188, 188, 188]))
        .save(&png)
        .unwrap();
    let l = EnvironmentMap::load(&png).unwrap();
    assert!((l.pixels[0][0] - 0.5029).abs() < 1e-3, "{:?}", l.pixels[0]);
    let hdr = dir.path().join("m.hdr");
    image::Rgb32FImage::from_pixel(8, 4, image::Rgb([2.0, 0.5, 0.25]))
        .save(&hdr)
        .unwrap();
    let h = EnvironmentMap::load(&hdr).unwrap();
    assert_eq!(&h.pixels[0][..3], &[2.0, 0.5, 0.25]);
}

#[test]
fn bad_environment_files_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let err = |p: &std::path::Path| format!("{:#}", EnvironmentMap::load(p).unwrap_err());
    let missing = dir.path().join("none.exr");
    assert!(err(&missing).contains("no such file"));
    for name in ["bad.exr", "bad.hdr", "bad.png"] {
        let p = dir.path().join(name);
        std::fs::write(&p, b"definitely not an image").unwrap();
        let e = err(&p);
        assert!(e.contains(name) && e.contains("not a readable"), "{e}");
    }
    let square = dir.path().join("square.png");
    image::RgbImage::from_pixel(8, 8, image::Rgb([1, 2, 3]))
        .save(&square)
        .unwrap();
    let e = err(&square);
    assert!(
        e.contains("twice as wide as high") && e.contains("8x8"),
        "{e}"
    );
    let txt = dir.path().join("map.txt");
    std::fs::write(&txt, b"x").unwrap();
    assert!(err(&txt).contains("unknown extension"));
}

mod composite {
    use super::common::{face_on, with_context};
    use glam::Vec3;
    use refrakt::environment::EnvironmentMap;
    use refrakt::render::{Model, RenderOptions, Renderer, SweepOptions};
    use refrakt::transfer::{Piecewise, TransferFunctions};
    use refrakt::volume::{Volume, Voxels};

    fn f32_volume(n: u32, f: impl Fn(Vec3) -> f32) -> Volume {
        let mut v = Vec::new();
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let p = Vec3::new(x as f32, y as f32, z as f32) / n as f32
                        + Vec3::splat(0.5 / n as f32 - 0.5);
                    v.push(f(p).clamp(0.0, 1.0));
                }
            }
        }
        let mut vol = Volume::new([n; 3], [1.0; 3], Voxels::F32(v)).unwrap();
        vol.range = Some((0.0, 1.0));
        vol
    }

    #[test]
    fn constant_map_behind_empty_and_tinted_volumes() {
        with_context(|ctx| {
            let colour = [0.3f32, 0.6, 0.9];
            let map = EnvironmentMap::constant(64, colour).unwrap();
            // Empty volume: the map's colour exactly, in the linear frame and after 8-bit
            // encoding without tone mapping.
            let empty = f32_volume(16, |_| 0.0);
            let mut r = Renderer::new(ctx, &empty, &TransferFunctions::default()).unwrap();
            r.set_environment(Some(&map)).unwrap();
            let opts = RenderOptions {
                width: 24,
                height: 16,
                ..Default::default()
            };
            let f = r
                .render(Model::Refract, &face_on(2.5, 20.0), &opts)
                .unwrap();
            for p in &f.pixels {
                for k in 0..3 {
                    assert!((p[k] - colour[k]).abs() < 1e-6, "{p:?}");
                }
            }
            let none = refrakt::output::ToneMap {
                exposure: 0.0,
                operator: refrakt::output::ToneOperator::None,
            };
            let bytes = refrakt::output::to_srgb8(&f, &none);
            let expect =
                colour.map(|c| (refrakt::output::linear_to_srgb(c) * 255.0).round() as i32);
            for k in 0..3 {
                assert!((bytes[k] as i32 - expect[k]).abs() <= 1);
            }
            // A non-absorbing medium, 8 voxels thick along the view (one-voxel ramps inside
            // the volume), medium m^s so the ramps add what they take away: tinted by m^8.
            let m = [0.95f32, 0.8, 0.9];
            let tf = TransferFunctions {
                medium: Piecewise::new(
                    (0..=64)
                        .map(|i| {
                            let s = i as f32 / 64.0;
                            (s, m.map(|c| c.powf(s)))
                        })
                        .collect(),
                ),
                ..Default::default()
            };
            let slab = f32_volume(16, |p| {
                let z = (p.z + 0.5) * 16.0;
                (z - 3.5).clamp(0.0, 1.0).min((12.5 - z).clamp(0.0, 1.0))
            });
            let mut r = Renderer::new(ctx, &slab, &tf).unwrap();
            r.set_environment(Some(&map)).unwrap();
            let opts = RenderOptions {
                width: 24,
                height: 16,
                sweep: SweepOptions {
                    specular: 0.0,
                    ..Default::default()
                },
                ..Default::default()
            };
            let f = r
                .render(Model::Refract, &face_on(2.5, 20.0), &opts)
                .unwrap();
            let p = f.pixel(12, 8);
            for k in 0..3 {
                let expected = colour[k] * m[k].powf(8.0);
                assert!(
                    (p[k] - expected).abs() <= 1.0 / 255.0,
                    "channel {k}: {} vs {expected}",
                    p[k]
                );
            }
        });
    }

    /// Behind a refracting sphere, neighbouring rays leave in very different directions;
    /// averaging the map over their footprint removes the noise a single lookup shows.
    /// Pixels whose rays were not bent are the same either way.
    #[test]
    fn footprint_filtering_smooths_refracted_environment() {
        with_context(|ctx| {
            let (vol, tf, map, cam) = super::common::glass_ball_in_the_sky();
            let (w, h) = (64u32, 64u32);
            let mut r = Renderer::new(ctx, &vol, &tf).unwrap();
            r.set_environment(Some(&map)).unwrap();
            let render = |r: &mut Renderer, footprint: bool| {
                let opts = RenderOptions {
                    width: w,
                    height: h,
                    sweep: SweepOptions {
                        specular: 0.0,
                        env_footprint: footprint,
                        ..Default::default()
                    },
                    ..Default::default()
                };
                r.render(Model::Refract, &cam, &opts).unwrap()
            };
            let (sat, single) = (render(&mut r, true), render(&mut r, false));
            let lum = |p: [f32; 4]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
            // Mean |Laplacian| over the sphere's centre region (refracted) and a corner (not).
            let laplacian = |f: &refrakt::render::Frame, x0: u32, x1: u32, y0: u32, y1: u32| {
                let mut acc = 0.0f64;
                for y in y0..y1 {
                    for x in x0..x1 {
                        let c = lum(f.pixel(x, y));
                        let l = lum(f.pixel(x - 1, y))
                            + lum(f.pixel(x + 1, y))
                            + lum(f.pixel(x, y - 1))
                            + lum(f.pixel(x, y + 1))
                            - 4.0 * c;
                        acc += l.abs() as f64;
                    }
                }
                acc / ((x1 - x0) * (y1 - y0)) as f64
            };
            let (in_sat, in_single) = (
                laplacian(&sat, 24, 40, 24, 40),
                laplacian(&single, 24, 40, 24, 40),
            );
            println!(
                "mean |Laplacian| inside the sphere: SAT {in_sat:.4}, single lookup {in_single:.4}"
            );
            assert!(
                in_sat < 0.8 * in_single,
                "SAT {in_sat} vs single {in_single}"
            );
            for y in 1..8 {
                for x in 1..8 {
                    assert_eq!(
                        sat.pixel(x, y),
                        single.pixel(x, y),
                        "unbent pixel ({x}, {y}) differs"
                    );
                }
            }
        });
    }
}

/// The maps shipped in assets/env (CC0, from Blender): they load, are 2:1, and their DWAB
/// ringing below zero is set to 0 rather than refused; a clearly negative map is refused.
#[test]
fn shipped_maps_load_and_negative_ringing_is_handled() {
    for name in ["city", "courtyard"] {
        let p =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("assets/env/{name}.exr"));
        let m = EnvironmentMap::load(&p).unwrap();
        assert_eq!((m.width, m.height), (1024, 512));
        assert!(m
            .pixels
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)));
        let mean: f32 = m.pixels.iter().map(|p| p[0]).sum::<f32>() / m.pixels.len() as f32;
        assert!(mean > 0.01, "{name}: mean red {mean}");
    }
    let mut px = vec![[1.0f32, 1.0, 1.0, 1.0]; 8];
    px[3][1] = -1e-4;
    let m = EnvironmentMap::new(4, 2, px.clone(), "ringing").unwrap();
    assert_eq!(m.pixels[3][1], 0.0);
    px[3][1] = -0.5;
    let e = EnvironmentMap::new(4, 2, px, "negative")
        .unwrap_err()
        .to_string();
    assert!(e.contains("negative") && e.contains("(3, 0)"), "{e}");
}

/// Issue 15 item 12: EXR maps through lossy and lossless compression, written with the exr
/// crate and read back with it before they go through refrakt.
mod exr_compression {
    use std::path::Path;
    use std::sync::{Mutex, Once};

    use exr::prelude::*;
    use refrakt::environment::EnvironmentMap;

    const W: usize = 64;
    const H: usize = 32;
    /// Where the test maps hold their special value (green channel): x = 10, y = 5.
    const SPOT: usize = 5 * W + 10;

    /// A smooth 64 x 32 sky (mean ~0.6) with `value` in the green channel of pixel (10, 5).
    fn sky_with(value: f32) -> Vec<[f32; 3]> {
        let mut px: Vec<[f32; 3]> = (0..W * H)
            .map(|i| {
                let (x, y) = ((i % W) as f32, (i / W) as f32);
                let t = 0.2 + 0.7 * y / H as f32 + 0.013 * x;
                [t, 0.9 * t, 0.7 * t]
            })
            .collect();
        px[SPOT][1] = value;
        px
    }

    /// A scan-line RGB EXR, half or single floats.
    fn write_exr(path: &Path, px: &[[f32; 3]], compression: Compression, half: bool) {
        let encoding = Encoding {
            compression,
            blocks: Blocks::ScanLines,
            line_order: LineOrder::Increasing,
        };
        let at = |p: Vec2<usize>| px[p.y() * W + p.x()];
        if half {
            let f = |c: [f32; 3]| c.map(f16::from_f32);
            let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
                let c = f(at(p));
                (c[0], c[1], c[2])
            });
            Image::from_encoded_channels((W, H), encoding, channels)
                .write()
                .to_file(path)
                .unwrap();
        } else {
            let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
                let c = at(p);
                (c[0], c[1], c[2])
            });
            Image::from_encoded_channels((W, H), encoding, channels)
                .write()
                .to_file(path)
                .unwrap();
        }
    }

    /// The file's compression and what the exr crate itself decodes from it.
    fn read_exr(path: &Path) -> (Compression, Vec<[f32; 3]>) {
        let img = read_first_rgba_layer_from_file(
            path,
            |r, _| (r.width(), vec![[0f32; 3]; r.width() * r.height()]),
            |(w, px): &mut (usize, Vec<[f32; 3]>), p, (r, g, b, _a): (f32, f32, f32, f32)| {
                px[p.y() * *w + p.x()] = [r, g, b];
            },
        )
        .unwrap();
        (
            img.layer_data.encoding.compression,
            img.layer_data.channel_data.pixels.1,
        )
    }

    /// Warnings logged by the library, kept so a test can pick those naming its own file.
    static WARNINGS: Mutex<Vec<String>> = Mutex::new(Vec::new());
    struct Capture;
    impl log::Log for Capture {
        fn enabled(&self, m: &log::Metadata) -> bool {
            m.level() <= log::Level::Warn
        }
        fn log(&self, r: &log::Record) {
            if self.enabled(r.metadata()) {
                WARNINGS.lock().unwrap().push(r.args().to_string());
            }
        }
        fn flush(&self) {}
    }

    fn warnings_naming(path: &Path) -> Vec<String> {
        let name = path.display().to_string();
        WARNINGS
            .lock()
            .unwrap()
            .iter()
            .filter(|w| w.contains(&name))
            .cloned()
            .collect()
    }

    fn capture_warnings() {
        static ONCE: Once = Once::new();
        ONCE.call_once(|| {
            log::set_logger(&Capture).unwrap();
            log::set_max_level(log::LevelFilter::Warn);
        });
    }

    fn load_error(path: &Path) -> String {
        format!("{:#}", EnvironmentMap::load(path).unwrap_err())
    }

    /// Lossy EXRs (as the CC0 DWAB maps of the issue, one ringing down to -3394): every
    /// negative value becomes 0, one warning counts them and names the file, the most
    /// negative value and the compression; everything else is what the exr crate decodes.
    #[test]
    fn lossy_exr_negative_values_are_set_to_zero_with_one_warning() {
        capture_warnings();
        let dir = tempfile::tempdir().unwrap();
        let original = sky_with(-3394.0);
        for (compression, half, name) in [
            (Compression::PXR24, false, "PXR24"),
            (Compression::B44, true, "B44"),
            (Compression::B44A, true, "B44A"),
            (Compression::DWAA(None), true, "DWAA"),
            (Compression::DWAB(None), true, "DWAB"),
            (Compression::DWAB(None), false, "DWAB"),
        ] {
            let path = dir.path().join(format!("{name}-{half}.exr"));
            write_exr(&path, &original, compression, half);
            let (written, decoded) = read_exr(&path);
            assert_eq!(written, compression);
            // The negative really is in the file (B44 decodes it as -2484).
            assert!(decoded[SPOT][1] < -1000.0, "{name}: {:?}", decoded[SPOT]);
            let negatives = decoded.iter().flatten().filter(|c| **c < 0.0).count();
            let lowest = decoded.iter().flatten().fold(0f32, |a, c| a.min(*c));

            let m = EnvironmentMap::load(&path)
                .unwrap_or_else(|e| panic!("{name} (half {half}): {e:#}"));
            assert_eq!((m.width, m.height), (W as u32, H as u32));
            for (l, d) in m.pixels.iter().zip(&decoded) {
                assert_eq!(&l[..3], &d.map(|c| c.max(0.0)), "{name}");
                assert_eq!(l[3], 1.0);
            }
            assert_eq!(m.pixels[SPOT][1], 0.0);
            let warnings = warnings_naming(&path);
            assert_eq!(warnings.len(), 1, "{name}: {warnings:?}");
            let w = &warnings[0];
            assert!(
                w.contains(&format!("{negatives} negative channel values"))
                    && w.contains(&format!("most negative {lowest} at pixel (10, 5)"))
                    && w.contains(&format!("lossy {name} compression")),
                "{w}"
            );
            if compression == Compression::PXR24 {
                // 24-bit floats: the rest is within 2^-15 of what was written, but not
                // all of it exactly (the data did go through the lossy codec).
                let mut changed = 0;
                for (i, (l, o)) in m.pixels.iter().zip(&original).enumerate() {
                    if i != SPOT {
                        for k in 0..3 {
                            assert!((l[k] - o[k]).abs() <= o[k] / 32768.0, "{l:?} vs {o:?}");
                            changed += usize::from(l[k] != o[k]);
                        }
                    }
                }
                assert!(changed > 0);
            }
        }
    }

    /// Lossless EXRs keep the rule of `EnvironmentMap::new`: values within 1 % of the
    /// map's mean below zero are set to 0 with a warning, anything more negative is
    /// refused. PXR24 is lossless for half floats, B44 leaves single floats uncompressed.
    #[test]
    fn lossless_exr_negative_values_keep_the_one_percent_rule() {
        capture_warnings();
        let dir = tempfile::tempdir().unwrap();
        for (compression, half) in [
            (Compression::Uncompressed, false),
            (Compression::ZIP16, false),
            (Compression::PIZ, true),
            (Compression::PXR24, true),
            (Compression::B44, false),
        ] {
            let path = dir.path().join(format!("{compression:?}-{half}-clear.exr"));
            write_exr(&path, &sky_with(-3394.0), compression, half);
            let (written, decoded) = read_exr(&path);
            assert_eq!(written, compression);
            assert_eq!(decoded[SPOT][1], -3394.0, "{compression:?}");
            let e = load_error(&path);
            assert!(
                e.contains(&path.display().to_string())
                    && e.contains("(10, 5)")
                    && e.contains("-3394")
                    && e.contains("not a radiance map"),
                "{e}"
            );
            assert!(warnings_naming(&path).is_empty());

            let path = dir
                .path()
                .join(format!("{compression:?}-{half}-slight.exr"));
            write_exr(&path, &sky_with(-1e-3), compression, half);
            assert!(read_exr(&path).1[SPOT][1] < 0.0);
            let m = EnvironmentMap::load(&path).unwrap();
            assert_eq!(m.pixels[SPOT][1], 0.0);
            let warnings = warnings_naming(&path);
            assert_eq!(warnings.len(), 1, "{warnings:?}");
            assert!(
                warnings[0].contains("1 slightly negative channel values")
                    && warnings[0].contains("(10, 5)")
                    && warnings[0].contains("within 1 %")
                    && !warnings[0].contains("lossy"),
                "{}",
                warnings[0]
            );
        }
    }

    /// NaN and ±infinity are refused whatever the compression; the error names the file and
    /// the pixel. (B44 and DWA cannot store them: they decode as finite values.)
    #[test]
    fn non_finite_exr_values_are_refused() {
        capture_warnings();
        let dir = tempfile::tempdir().unwrap();
        for (compression, half) in [
            (Compression::PXR24, false), // lossy
            (Compression::ZIP16, false),
            (Compression::PIZ, true),
            (Compression::Uncompressed, true),
        ] {
            for (label, value) in [
                ("nan", f32::NAN),
                ("inf", f32::INFINITY),
                ("-inf", f32::NEG_INFINITY),
            ] {
                let path = dir
                    .path()
                    .join(format!("{compression:?}-{half}-{label}.exr"));
                write_exr(&path, &sky_with(value), compression, half);
                let decoded = read_exr(&path).1[SPOT][1];
                assert!(
                    !decoded.is_finite() && decoded.is_nan() == value.is_nan(),
                    "{compression:?} {label}: decoded {decoded}"
                );
                let e = load_error(&path);
                assert!(
                    e.contains(&path.display().to_string())
                        && e.contains("pixel (10, 5)")
                        && e.contains("not a finite colour"),
                    "{e}"
                );
                assert!(warnings_naming(&path).is_empty());
            }
        }
    }

    /// On the command line: a DWAB map ringing far below zero renders, with the warning on
    /// stderr; the same map stored losslessly is refused, naming the file.
    #[test]
    fn render_with_lossy_map_warns_and_succeeds() {
        let dir = tempfile::tempdir().unwrap();
        let lossy = dir.path().join("dwab.exr");
        write_exr(&lossy, &sky_with(-3394.0), Compression::DWAB(None), true);
        assert!(read_exr(&lossy).1[SPOT][1] < -1000.0);
        let out = dir.path().join("out.png");
        let args = |env: &Path| {
            super::common::refrakt(&[
                "render",
                "sphere",
                "--env",
                env.to_str().unwrap(),
                "--width",
                "16",
                "--height",
                "16",
                "--volume-size",
                "16",
                "-o",
                out.to_str().unwrap(),
            ])
        };
        let o = args(&lossy);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{stderr}");
        assert!(out.exists());
        assert!(
            stderr.contains(&lossy.display().to_string())
                && stderr.contains("negative channel values")
                && stderr.contains("most negative -3394")
                && stderr.contains("DWAB"),
            "{stderr}"
        );
        let lossless = dir.path().join("zip.exr");
        write_exr(&lossless, &sky_with(-3394.0), Compression::ZIP16, true);
        let o = args(&lossless);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success());
        assert!(
            stderr.contains(&lossless.display().to_string()) && stderr.contains("(10, 5)"),
            "{stderr}"
        );
    }
}

/// `--light env` (issue 36): under a map with one bright spot, the key light comes from the
/// spot: its direction and its irradiance (radiance × the disk's solid angle, computed
/// here from the disk's size, not from the map's pixels). The render equals one lit
/// explicitly from there, shadow and all; a light 30° away gives a visibly different
/// image (so the comparison can fail).
#[test]
fn the_environment_lights_the_scene_from_its_brightest_spot() {
    use exr::prelude::write_rgba_file;
    use refrakt::environment::{direction, pixel_angles};
    let dir = tempfile::tempdir().unwrap();
    let map = dir.path().join("spot.exr");
    let (w, h) = (512usize, 256usize);
    let spot = glam::Vec3::new(0.25, 0.75, 0.6).normalize();
    let (radius, radiance, dim) = (4f32.to_radians(), 60.0f32, 0.02f32);
    let radiance_at = |x: usize, y: usize| {
        let (phi, theta) = pixel_angles(w as u32, h as u32, x as f32 + 0.5, y as f32 + 0.5);
        let d = glam::Vec3::from(direction(phi, theta));
        if d.dot(spot) >= radius.cos() {
            radiance
        } else {
            dim
        }
    };
    write_rgba_file(&map, w, h, |x, y| {
        let v = radiance_at(x, y);
        (v, v, v, 1.0)
    })
    .unwrap();
    // The disk's irradiance on a surface facing it: L · 2π(1 − cos r).
    let e = radiance * 2.0 * std::f32::consts::PI * (1.0 - radius.cos());
    let base = [
        "render",
        "sphere-on-floor",
        "--volume-size",
        "32",
        "--width",
        "40",
        "--height",
        "40",
    ];
    let run_with = |env: &std::path::Path, extra: &[&str], out: &str| {
        let out = dir.path().join(out);
        let mut args = base.to_vec();
        args.extend(["--env", env.to_str().unwrap()]);
        args.extend(extra);
        args.extend(["-o", out.to_str().unwrap()]);
        let o = common::refrakt(&args);
        let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        (common::read_exr_rgb(&out).1, stdout)
    };
    let run = |extra: &[&str], out: &str| run_with(&map, extra, out);
    let (from_env, log) = run(&["--light", "env"], "env.exr");
    assert!(
        log.contains("light from the environment's brightest region"),
        "{log}"
    );
    // The rest of the map, uniform radiance `dim` over 4π − Ω, as the ambient level: its
    // mean radiance over the sphere, dim (4π − Ω) / 4π.
    let omega = 2.0 * std::f32::consts::PI * (1.0 - radius.cos());
    let ambient = dim * (1.0 - omega / (4.0 * std::f32::consts::PI));
    let said: f32 = log
        .split("ambient (")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .and_then(|a| a.trim().parse().ok())
        .unwrap_or_else(|| panic!("no ambient level in: {log}"));
    println!("ambient level: {said} (expected {ambient:.4})");
    assert!(
        (said - ambient).abs() < 2e-4,
        "ambient {said}, expected {ambient}"
    );
    let v = |d: glam::Vec3| format!("{},{},{}", d.x, d.y, d.z);
    let c = format!("{e},{e},{e}");
    let a = format!("{ambient},{ambient},{ambient}");
    let lit_by = |towards: glam::Vec3, out: &str| {
        let l = v(towards);
        run(
            &["--light", &l, "--light-colour", &c, "--ambient-level", &a],
            out,
        )
        .0
    };
    let explicit = lit_by(spot, "explicit.exr");
    // 30° further round the vertical: the shadow moves.
    let turned = glam::Quat::from_rotation_y(30f32.to_radians()) * spot;
    let elsewhere = lit_by(turned, "turned.exr");
    let mean_diff = |a: &[[f32; 3]], b: &[[f32; 3]]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).abs()).sum::<f32>() / 3.0)
            .sum::<f32>()
            / a.len() as f32
    };
    let mean_level = explicit
        .iter()
        .map(|p| (p[0] + p[1] + p[2]) / 3.0)
        .sum::<f32>()
        / explicit.len() as f32;
    let same = mean_diff(&from_env, &explicit) / mean_level;
    let moved = mean_diff(&elsewhere, &explicit) / mean_level;
    println!("relative mean difference: env vs explicit {same:.4}, 30° away {moved:.4}");
    // The spot's direction is found to about 0.1°; under the glass the caustic's crossing
    // rays move with the slightest turn. Measured 0.025 while the planes held the flux
    // per plane area, 0.042 since they hold the fluence (2026-11-29: rays turned towards
    // the planes weigh up to 10 times their flux there); 30° away it is 0.196.
    assert!(
        same < 0.06,
        "--light env differs from the spot's light by {same:.4} of the mean"
    );
    // (5 times until the fluence; 4.7 times since.)
    assert!(
        moved > 3.0 * same.max(0.005),
        "a light 30° away differs by only {moved:.4}"
    );
    // --env-rotation turns the light with the map. With rotation r a world direction of
    // longitude φ sees the map at φ + r (glsl/sweep_composite.comp), so the map rolled
    // back by r (a column shift of r / 360 · width) and turned by r shows the same
    // background as the map itself unturned, and must be lit from the same place.
    let rolled = dir.path().join("rolled.exr");
    let shift = w / 8; // 45°
    write_rgba_file(&rolled, w, h, |x, y| {
        let v = radiance_at((x + w - shift) % w, y);
        (v, v, v, 1.0)
    })
    .unwrap();
    let (turned_map, _) = run_with(
        &rolled,
        &["--env-rotation", "45", "--light", "env"],
        "rot.exr",
    );
    let rotated = mean_diff(&turned_map, &from_env) / mean_level;
    println!("rolled map turned back by --env-rotation 45: {rotated:.6}");
    assert!(
        rotated < 1e-3,
        "--env-rotation 45 on the rolled map differs by {rotated:.4} of the mean"
    );
}
