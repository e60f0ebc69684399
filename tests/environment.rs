//! Issue 5 (first part): environment maps and their summed-area table on the GPU.

mod common;

use common::with_context;
use refrakt::environment::{EnvironmentMap, SummedAreaTable};

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
        let img = m.upload(ctx).unwrap();
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
