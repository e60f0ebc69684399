//! The reference renderer (`refrakt reference`, src/photons/reference.rs) from the command
//! line, and the sweep against it on a lit scene without refraction, where the two
//! compute the same image formation by different means (planes and a splatted light
//! against photons binned in the volume and rays by the ray equation).

mod common;

use common::{refrakt, with_context};
use glam::Vec3;
use refrakt::photons::{render_reference, ReferenceOptions};
use refrakt::render::{Camera, Light, LightTransport, Model, RenderOptions, Renderer};

use refrakt::transfer::TransferFunctions;

#[test]
fn reference_writes_an_image_and_refuses_what_it_does_not_render() {
    let dir = std::env::temp_dir().join(format!("refrakt-reference-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("ref.png");
    let o = refrakt(&[
        "reference",
        "--volume-size",
        "16",
        "--width",
        "24",
        "--height",
        "16",
        "-o",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        stdout.contains("light: ") && stdout.contains("view: "),
        "{stdout}"
    );
    let img = image::open(&out).unwrap();
    assert_eq!((img.width(), img.height()), (24, 16));
    // Not every pixel alike: the scene is there.
    let rgb = img.to_rgb8();
    let first = *rgb.get_pixel(0, 0);
    assert!(rgb.pixels().any(|p| *p != first));
    for (args, needle) in [
        (
            vec!["--specular", "1"],
            "--specular does not apply to the reference renderer",
        ),
        (
            vec!["--light-bins", "0"],
            "light bins per voxel side 0 must be between 1 and 8",
        ),
        (vec!["--step", "0"], "step 0 must be in (0, 4] voxels"),
        (
            vec!["--light", "point:0,2,1"],
            "the reference renderer follows directional lights",
        ),
        (vec!["--step", "1e-6"], "exceed the limit of"),
    ] {
        let mut all = vec!["reference", "--volume-size", "16", "-o", "x.png"];
        all.extend(args.iter());
        let o = refrakt(&all);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{all:?} succeeded");
        assert!(!err.contains("panicked"), "{all:?}: {err}");
        assert!(
            err.contains(needle),
            "{all:?}: expected '{needle}' in {err}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The built-in sphere on its floor, both matte (opacity 0.5 per voxel, no refraction,
/// colour 0.9), lit obliquely with a hard light, seen obliquely, on a dark background.
fn matte_sphere_on_floor(
    sd: f32,
) -> (
    refrakt::volume::Volume,
    TransferFunctions,
    Camera,
    RenderOptions,
) {
    let volume = refrakt::volume::procedural::sphere_on_floor(40).unwrap();
    let tf = TransferFunctions::parse(
        "colour = [[0.0, 0.9, 0.9, 0.9]]\n\
         opacity = [[0.0, 0.0], [0.3, 0.0], [0.45, 0.5], [1.0, 0.5]]\n\
         medium = [[0.0, 1.0, 1.0, 1.0]]\n\
         eta = [[0.0, 1.0]]\n",
        "matte",
    )
    .unwrap();
    let camera = Camera {
        azimuth: 35.0,
        elevation: 35.0,
        distance: 2.0,
        fov_y: 35.0,
        ..Default::default()
    };
    let mut opts = RenderOptions {
        width: 96,
        height: 96,
        sample_distance: sd,
        background: [0.05, 0.05, 0.05, 1.0],
        ..Default::default()
    };
    opts.lights = vec![Light {
        softness: 0.0,
        ..Light::directional(Vec3::new(-0.4, 1.0, 0.3).normalize(), [1.0; 3])
    }];
    opts.sweep.specular = 0.0;
    opts.sweep.reflections = false;
    (volume, tf, camera, opts)
}

fn luminance(px: &[[f32; 4]]) -> Vec<f64> {
    px.iter()
        .map(|p| (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) as f64)
        .collect()
}

fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    sab / (saa * sbb).sqrt()
}

/// What geometry says of a frame of [`matte_sphere_on_floor`], from the floor pixels whose
/// floor point lies at least `margin` world units inside the sphere's shadow or outside it
/// (and whose view the sphere does not cover):
/// - how many of the shadowed ones are not dark (above 15 % of the lit floor's median) and
///   of the lit ones not lit (below 85 %), and how many pixels each set holds;
/// - the lit ones' mean ratio to the radiance of a lit half-space of layers seen from
///   outside: c mu_l / (mu_l + mu_v) for colour c, the cosines mu_l and mu_v of the light
///   and the view with the floor's normal, whatever the opacity's profile in depth (the
///   emission integral of c sigma e^(-tau / mu_l) e^(-tau / mu_v) over depth; the floor,
///   4.8 voxels of opacity 0.5 per voxel, passes e^(-9) of the light behind it).
fn floor_against_geometry(
    camera: &Camera,
    opts: &RenderOptions,
    px: &[[f32; 4]],
    margin: f32,
) -> ([usize; 4], f64) {
    let (eye, forward, right, up) = camera.frame();
    let (w, h) = (opts.width, opts.height);
    let t = (camera.fov_y.to_radians() * 0.5).tan();
    let towards = match opts.lights[0].source {
        refrakt::light::LightSource::Directional { towards } => towards.normalize(),
        _ => unreachable!(),
    };
    // The sphere and the floor of volume::procedural::sphere_on_floor, the floor's colour.
    let (centre, radius, floor_y, colour) = (Vec3::new(0.0, 0.02, 0.0), 0.24f32, -0.38f32, 0.9);
    let line_distance = |from: Vec3, dir: Vec3| {
        let q = centre - from;
        let along = q.dot(dir);
        if along < 0.0 {
            q.length()
        } else {
            (q - along * dir).length()
        }
    };
    let (mut dark, mut lit, mut ratio) = (Vec::new(), Vec::new(), Vec::new());
    for j in 0..h {
        for i in 0..w {
            let nx = (i as f32 + 0.5) / w as f32 * 2.0 - 1.0;
            let ny = (j as f32 + 0.5) / h as f32 * 2.0 - 1.0;
            let d = (forward + nx * t * (w as f32 / h as f32) * right - ny * t * up).normalize();
            if d.y >= 0.0 || line_distance(eye, d) < radius + margin {
                continue;
            }
            let f = eye + d * ((floor_y - eye.y) / d.y);
            if f.x.abs() > 0.45 || f.z.abs() > 0.45 {
                continue;
            }
            let p = px[(j * w + i) as usize];
            let l = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
            let s = line_distance(f, towards);
            if s < radius - margin {
                dark.push(l);
            } else if s > radius + margin {
                lit.push(l);
                let (mu_l, mu_v) = (towards.y, -d.y);
                ratio.push(l as f64 / (colour * mu_l / (mu_l + mu_v)) as f64);
            }
        }
    }
    let mut sorted = lit.clone();
    sorted.sort_by(f32::total_cmp);
    let level = sorted[sorted.len() / 2];
    let misses = [
        dark.iter().filter(|&&l| l > 0.15 * level).count(),
        dark.len(),
        lit.iter().filter(|&&l| l < 0.85 * level).count(),
        lit.len(),
    ];
    (misses, ratio.iter().sum::<f64>() / ratio.len() as f64)
}

#[test]
fn the_sweep_agrees_with_the_reference_without_refraction() {
    with_context(|ctx| {
        let ropts = ReferenceOptions {
            threads: 2,
            ..Default::default()
        };
        let (volume, tf, camera, opts) = matte_sphere_on_floor(1.0);
        let reference = render_reference(&volume, &tf, None, &camera, &opts, &ropts, None).unwrap();
        // The reference's shadow is where geometry puts it, to 1.5 voxels (of 1/40; the
        // light's bins and the floor's ramp blur its edge over about one), and its lit
        // floor is the lit half-space's radiance (measured 0.998 of it).
        let (misses, lit) = floor_against_geometry(&camera, &opts, &reference.pixels, 0.0375);
        println!("reference: shadow misses {misses:?}, lit floor / analytic {lit:.4}");
        assert!(misses[1] > 300 && misses[3] > 1000, "{misses:?}");
        assert_eq!((misses[0], misses[2]), (0, 0), "{misses:?}");
        assert!((lit - 1.0).abs() < 0.005, "reference's lit floor {lit}");
        let b = luminance(&reference.pixels);
        let mb = b.iter().sum::<f64>() / b.len() as f64;
        for transport in [LightTransport::Forward, LightTransport::Backward] {
            for sd in [1.0, 0.5] {
                let (_, _, _, mut opts) = matte_sphere_on_floor(sd);
                opts.sweep.light_transport = transport;
                let mut renderer = Renderer::new(ctx, &volume, &tf).unwrap();
                let frame = renderer.render(Model::Refract, &camera, &opts).unwrap();
                let a = luminance(&frame.pixels);
                let ma = a.iter().sum::<f64>() / a.len() as f64;
                let corr = correlation(&a, &b);
                let (misses, lit) = floor_against_geometry(&camera, &opts, &frame.pixels, 0.0375);
                let what = format!("{transport:?}, sample distance {sd}");
                println!(
                    "{what}: mean sweep {ma:.4}, reference {mb:.4} (ratio {:.4}), \
                     correlation {corr:.4}; sweep's shadow misses {misses:?}, lit floor / \
                     analytic {lit:.4}",
                    ma / mb
                );
                // The shadow where geometry puts it: the skin chain's light read where the
                // light comes from (glsl/sweep_viewing.glsl, chain_start_uv). Read at the
                // ray's own point on the plane before, the shadow lagged by up to a plane
                // along the light: 13 of 388 shadowed pixels lit at sample distance 1,
                // correlation 0.938 (0.971 at 0.5), means 2.7 % (1.0 %) high, the sphere
                // lit too far round (docs/NOTES.md, "The sweep's light, read where it comes
                // from"). Now measured: 0 pixels (1 backward at 0.5, whose bilinear
                // resampling on every plane blurs the edge more, the more planes);
                // correlation 0.978 and 0.987 forward, 0.978 and 0.987 backward; means
                // within 0.9 %; lit floor within 0.4 %.
                let blur = usize::from(transport == LightTransport::Backward && sd < 1.0);
                assert!(misses[0] <= blur && misses[2] == 0, "{what}: {misses:?}");
                assert!((lit - 1.0).abs() < 0.01, "{what}: lit floor {lit}");
                assert!(
                    (ma / mb - 1.0).abs() < 0.015,
                    "{what}: means {ma} against {mb}"
                );
                assert!(
                    corr > if sd < 1.0 { 0.98 } else { 0.97 },
                    "{what}: correlation {corr}"
                );
            }
        }
    });
}
