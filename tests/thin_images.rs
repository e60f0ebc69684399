//! Thin, tiny and telephoto images (a strip of rows, one row, one column, a few pixels, a
//! 0.1° field of view): the forward transport's light-ray grid keeps at least 5 × 5 rays,
//! and where that floor took a thin grid past the ray images' capacity the frame failed
//! with an internal "indirect draws ... need N bytes" error (1024 × 1, `--fov 0.1`); images
//! of fewer than 25 pixel-rays failed to record. A strip must show what the same rows of
//! a square image show: the same camera, the field of view narrowed to the strip, so its
//! pixel centres are the square's.

mod common;

use common::with_context;
use refrakt::render::{Camera, LightTransport, Model, Renderer};
use refrakt::scene::Scene;

/// The vertical field of view that shows `rows` of a `full`-row image of `fov_y` degrees.
fn narrowed(fov_y: f32, rows: u32, full: u32) -> f32 {
    2.0 * ((fov_y.to_radians() * 0.5).tan() * rows as f32 / full as f32)
        .atan()
        .to_degrees()
}

#[test]
fn thin_and_telephoto_views_show_what_the_same_pixels_of_larger_views_show() {
    with_context(|ctx| {
        let mut scene = Scene::builtin("sphere-on-floor").unwrap().unwrap();
        if let refrakt::scene::VolumeSource::Procedural { size, .. } = &mut scene.volume {
            *size = 64;
        }
        let mut renderer = common::renderer_for(ctx, &scene);
        let n = 63u32;
        let render = |renderer: &mut Renderer, w: u32, h: u32, cam: &Camera| {
            let mut opts = scene.render_options().unwrap();
            opts.width = w;
            opts.height = h;
            opts.sweep.light_transport = LightTransport::Forward;
            renderer.render(Model::Refract, cam, &opts).unwrap()
        };
        let lum = |p: [f32; 4]| (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) as f64;
        // Strips of 3 rows and of 1 row through the middle (the field of view narrowed),
        // and of 3 columns (the same field of view: the square's width is its height),
        // the latter with the camera turned so that its column sees the floor beside the
        // sphere: a 3-pixel-wide view has 378 rays for the whole lit floor, and a caustic
        // seen through so coarse a grid is another image.
        let mid = n / 2;
        for (w, h, turn) in [(n, 3, 0.0), (n, 1, 0.0), (3, n, -50.0)] {
            let turned = Camera {
                azimuth: scene.camera.azimuth + turn,
                ..scene.camera
            };
            let square = render(&mut renderer, n, n, &turned);
            let cam = Camera {
                fov_y: if h < n {
                    narrowed(scene.camera.fov_y, h, n)
                } else {
                    scene.camera.fov_y
                },
                ..turned
            };
            let strip = render(&mut renderer, w, h, &cam);
            let x0 = if w < n { mid - w / 2 } else { 0 };
            let y0 = if h < n { mid - h / 2 } else { 0 };
            let (mut sum_strip, mut sum_square, mut diff) = (0.0, 0.0, 0.0);
            for y in 0..h {
                for x in 0..w {
                    let a = lum(strip.pixel(x, y));
                    let b = lum(square.pixel(x0 + x, y0 + y));
                    sum_strip += a;
                    sum_square += b;
                    diff += (a - b).abs();
                }
            }
            let pixels = (w * h) as f64;
            let (mean, rel) = (sum_square / pixels, (sum_strip / sum_square - 1.0).abs());
            println!(
                "{w}x{h}: mean {:.4} (square's rows {mean:.4}), mean |diff| {:.4}",
                sum_strip / pixels,
                diff / pixels
            );
            // The column's 378 rays sample the lit floor coarsely (issue 32's lattice,
            // ±15 % from row to row) and its view crosses the sphere's shadow: only its
            // mean is held, to what losing rays would break.
            let (max_rel, max_diff) = if w < n {
                (0.1, f64::INFINITY)
            } else {
                (0.03, 0.05)
            };
            assert!(
                rel < max_rel && diff / pixels < max_diff * mean,
                "a {w}x{h} strip differs from the square's pixels: mean {:.4} against \
                 {mean:.4}, mean |diff| {:.4}",
                sum_strip / pixels,
                diff / pixels
            );
        }
        // A telephoto view (the grid's trace-back is long along the light and a few
        // pixels across: its floor of five columns took it past the budget, and the frame
        // failed): 32² at half the field of view of 64², which it must match in the middle.
        let tele = Camera {
            fov_y: 0.2,
            ..scene.camera
        };
        let wide = render(&mut renderer, 64, 64, &tele);
        let narrow = render(
            &mut renderer,
            32,
            32,
            &Camera {
                fov_y: narrowed(0.2, 32, 64),
                ..tele
            },
        );
        let (mut sum_narrow, mut sum_wide, mut diff) = (0.0, 0.0, 0.0);
        for y in 0..32 {
            for x in 0..32 {
                let (a, b) = (lum(narrow.pixel(x, y)), lum(wide.pixel(16 + x, 16 + y)));
                sum_narrow += a;
                sum_wide += b;
                diff += (a - b).abs();
            }
        }
        println!(
            "telephoto: mean {:.4} (the wide view's middle {:.4}), mean |diff| {:.4}",
            sum_narrow / 1024.0,
            sum_wide / 1024.0,
            diff / 1024.0
        );
        assert!(
            (sum_narrow / sum_wide - 1.0).abs() < 0.01 && diff < 0.02 * sum_wide,
            "the telephoto view differs from the middle of the wider one"
        );
        // A few pixels in all: the grid still has its 5 × 5 rays.
        for (w, h) in [(1, 1), (2, 2), (3, 1)] {
            let f = render(&mut renderer, w, h, &scene.camera);
            assert!(f.pixels.iter().all(|p| p.iter().all(|c| c.is_finite())));
        }
    });
}
