//! The sweep with `--light-transport eikonal` (issue 35 item 5): the refractive model's
//! viewing rays lit by the eikonal light simulator's light volume instead of a light
//! propagated plane by plane, so the light may travel against the sweep. A homogeneous
//! block against the closed-form single-scattering integral for lights beside, behind
//! and in front of the camera; an opaque sphere's shadow on a floor, lit from behind the
//! sphere (a light the other transports refuse), where geometry puts it.

mod common;

use common::{f32_volume, face_on, single_scattering_block, with_context};
use glam::Vec3;
use refrakt::light::{Light, LightSource};
use refrakt::render::{Camera, LightTransport, Model, RenderOptions, Renderer};
use refrakt::transfer::TransferFunctions;

/// White matter of opacity `alpha` per reference step at value 1, clear at value 0, η 1:
/// the opacity rises over values 0.45–0.55, so a surface is where its ramp crosses 0.5.
fn white_tf(alpha: f32) -> TransferFunctions {
    let text = format!(
        "colour = [[0.0, 1, 1, 1]]\nopacity = [[0.0, 0.0], [0.45, 0.0], [0.55, {alpha}]]\n"
    );
    TransferFunctions::parse(&text, "white tf").unwrap()
}

fn directional(towards: Vec3) -> Light {
    Light {
        source: LightSource::Directional {
            towards: towards.normalize(),
        },
        colour: [1.0; 3],
        softness: 0.0,
    }
}

fn eikonal_options(width: u32, height: u32, light: Light) -> RenderOptions {
    let mut opts = RenderOptions {
        width,
        height,
        background: [0.0, 0.0, 0.0, 1.0],
        lights: vec![light],
        ..Default::default()
    };
    opts.sweep.light_transport = LightTransport::Eikonal;
    opts.sweep.specular = 0.0;
    opts
}

/// The radiance through the centre of a homogeneous block, seen by the sweep and lit from
/// the light volume, is the single-scattering integral of an isotropic medium of albedo 1
/// (the sweep's model: a sample returns its colour times the light): within 2 % for a
/// light beside the camera, behind it, and in front of it (travelling towards the eye,
/// against the sweep, which the forward and backward transports refuse). Measured:
/// within 0.27 %. Breaks it (measured): the light volume read with x and z swapped
/// (−72 % for the light above and behind the camera).
#[test]
fn a_homogeneous_block_lit_from_anywhere_matches_the_single_scattering_integral() {
    with_context(|ctx| {
        let n = 33u32;
        let camera = face_on(3.0, 10.0);
        let volume = f32_volume(n, |_| 1.0);
        let mut renderer = Renderer::new(ctx, &volume, &white_tf(0.1)).unwrap();
        let cases = [
            (0.1f64, [0.0, 1.0, 1.0]),
            (0.1, [0.0, 0.2, 1.0]),
            (0.04, [0.0, 1.0, 0.0]),
            (0.04, [0.0, 0.3, -1.0]),
        ];
        let mut worst = 0.0f64;
        for (alpha, towards) in cases {
            renderer
                .set_transfer_functions(&white_tf(alpha as f32))
                .unwrap();
            let t = Vec3::from(towards.map(|c: f64| c as f32));
            let opts = eikonal_options(33, 33, directional(t));
            let frame = renderer.render(Model::Refract, &camera, &opts).unwrap();
            let got = frame.pixels[16 * 33 + 16][1] as f64;
            let k = -(1.0 - alpha).ln() * n as f64;
            let tn = t.normalize();
            let want = single_scattering_block(k, 0.5, [tn.x, tn.y, tn.z].map(|c| c as f64), 0.0);
            let err = got / want - 1.0;
            eprintln!(
                "alpha {alpha} towards {towards:?}: {got:.5}, closed form {want:.5} ({:+.2} %)",
                100.0 * err
            );
            worst = worst.max(err.abs());
        }
        assert!(
            worst < 0.02,
            "worst error {:.2} % (bound 2 %)",
            100.0 * worst
        );
    });
}

/// Several lights, directional and point, light the sweep with the eikonal transport
/// (their wavefronts add in the light volume): in a homogeneous block, where nothing
/// depends on the light's direction, each pixel with both lights is the sum of the two
/// frames with one each, to 1e-4 of the brightest pixel; a light moved changes the
/// frame. The other transports refuse both a second light and a point light, naming the
/// eikonal transport. Measured: 3e-7 of the brightest pixel. Breaks it: only the first
/// light simulated (the point light's part, a third of the blue, would be missing).
#[test]
fn several_lights_and_point_lights_add_up() {
    with_context(|ctx| {
        let n = 33u32;
        let camera = face_on(3.0, 10.0);
        let volume = f32_volume(n, |_| 1.0);
        let mut renderer = Renderer::new(ctx, &volume, &white_tf(0.05)).unwrap();
        let sun = directional(Vec3::new(0.0, 1.0, 0.4));
        let lamp = Light {
            source: LightSource::Point {
                position: Vec3::new(0.9, -0.3, -0.6),
            },
            colour: [0.6, 0.8, 1.0],
            softness: 0.0,
        };
        let frame = |renderer: &mut Renderer, lights: Vec<Light>| {
            let mut opts = eikonal_options(24, 24, lights[0]);
            opts.lights = lights;
            renderer
                .render(Model::Refract, &camera, &opts)
                .unwrap()
                .pixels
        };
        let a = frame(&mut renderer, vec![sun]);
        let b = frame(&mut renderer, vec![lamp]);
        let both = frame(&mut renderer, vec![sun, lamp]);
        let peak = both
            .iter()
            .flat_map(|p| &p[..3])
            .fold(0.0f32, |m, &c| m.max(c));
        let worst = a
            .iter()
            .zip(&b)
            .zip(&both)
            .flat_map(|((a, b), s)| (0..3).map(move |c| (a[c] + b[c] - s[c]).abs()))
            .fold(0.0f32, f32::max);
        let lamp_share =
            b.iter().map(|p| p[2]).sum::<f32>() / both.iter().map(|p| p[2]).sum::<f32>();
        eprintln!(
            "brightest {peak:.4}; |one + other - both| at most {worst:.2e}; the point light's \
             share of the blue {lamp_share:.3}"
        );
        assert!(peak > 0.05, "the block must be lit: {peak}");
        assert!(
            lamp_share > 0.1,
            "the point light must light the block: {lamp_share}"
        );
        assert!(
            worst <= 1e-4 * peak,
            "lights do not add: {worst:.2e} of {peak:.4}"
        );
        let mut moved = lamp;
        moved.source = LightSource::Point {
            position: Vec3::new(-0.9, -0.3, -0.6),
        };
        let c = frame(&mut renderer, vec![moved]);
        let change = b
            .iter()
            .zip(&c)
            .map(|(p, q)| (p[2] - q[2]).abs())
            .fold(0.0f32, f32::max);
        assert!(
            change > 0.01 * peak,
            "moving the point light changed nothing"
        );

        for transport in [LightTransport::Forward, LightTransport::Backward] {
            for lights in [vec![sun, sun], vec![lamp]] {
                let mut opts = eikonal_options(24, 24, lights[0]);
                opts.lights = lights;
                opts.sweep.light_transport = transport;
                let err = renderer
                    .render(Model::Refract, &camera, &opts)
                    .err()
                    .map(|e| format!("{e:#}"))
                    .unwrap_or_default();
                assert!(
                    err.contains("refract model takes")
                        && err.contains("--light-transport eikonal"),
                    "{transport:?}: {err:?}"
                );
            }
        }
    });
}

/// A floor of opaque white matter below y = FLOOR_Y and an opaque white sphere above it.
const FLOOR_Y: f32 = -0.3;
const SPHERE_R: f32 = 0.18;
const SPHERE_C: [f32; 3] = [0.0, -0.1, -0.15];

fn sphere_and_floor(n: u32) -> refrakt::volume::Volume {
    let c = Vec3::from(SPHERE_C);
    // Value 1 inside, 0 outside, a one-voxel linear ramp at each surface (the world box
    // of a cube is [-0.5, 0.5]³, f32_volume's coordinates).
    f32_volume(n, |p| {
        let w = Vec3::from(p);
        let ball = 0.5 + (SPHERE_R - (w - c).length()) * n as f32;
        let floor = 0.5 + (FLOOR_Y - w.y) * n as f32;
        ball.max(floor)
    })
}

/// Where the straight camera ray through pixel (x, y) of a `size`² image meets the floor's
/// surface, if it does inside the box and passes the sphere by more than `margin`.
fn floor_point(camera: &Camera, size: u32, x: u32, y: u32, margin: f32) -> Option<Vec3> {
    let (eye, forward, right, up) = camera.frame();
    let tan = (camera.fov_y.to_radians() * 0.5).tan();
    let ndc = [
        (x as f32 + 0.5) / size as f32 * 2.0 - 1.0,
        (y as f32 + 0.5) / size as f32 * 2.0 - 1.0,
    ];
    let d = (forward + ndc[0] * tan * right - ndc[1] * tan * up).normalize();
    if d.y >= 0.0 {
        return None;
    }
    let s = (FLOOR_Y - eye.y) / d.y;
    let p = eye + d * s;
    // Passes the sphere: its distance from the ray.
    let c = Vec3::from(SPHERE_C);
    let along = (c - eye).dot(d);
    let miss = (eye + d * along - c).length();
    let inside = p.x.abs() < 0.45 && p.z.abs() < 0.45;
    (inside && (miss > SPHERE_R + margin || along > s)).then_some(p)
}

/// Whether the ray from floor point p towards the light (unit `towards`) meets the sphere.
fn in_shadow(p: Vec3, towards: Vec3) -> bool {
    let c = Vec3::from(SPHERE_C);
    let along = (c - p).dot(towards);
    along > 0.0 && (p + towards * along - c).length() < SPHERE_R
}

/// Lit from behind the sphere (the light travels towards the camera, 110° from the view
/// direction: the forward transport refuses it), the sweep with the eikonal transport
/// shows the sphere's shadow on the floor in front of it where geometry puts it: the
/// centroid of the floor pixels darker than half the lit floor within 2 % of R of the
/// centroid of those whose ray to the light meets the sphere, and the two sets agreeing
/// but for the penumbra. Measured: 1.56 % R. Breaks it (measured): the volume read with
/// x and z swapped (95 % R); a surface's light read at the viewing segment's middle
/// without the step upstream along the light (10 % R in a 48³ version of this scene,
/// and the floor banded at the plane spacing), at its front (3.6 % R there).
#[test]
fn a_light_from_behind_the_sphere_casts_its_shadow_where_geometry_puts_it() {
    with_context(|ctx| {
        let n = 64u32;
        let size = 160u32;
        let camera = Camera {
            azimuth: 0.0,
            elevation: 35.0,
            distance: 2.0,
            fov_y: 36.0,
            ..Default::default()
        };
        let towards = Vec3::new(0.2, 0.64, -0.74).normalize();
        let light = directional(towards);
        let (_, forward, _, _) = camera.frame();
        let angle = (-towards).dot(forward).acos().to_degrees();
        assert!(
            angle > 100.0,
            "the light must travel against the sweep ({angle:.1}°)"
        );
        let volume = sphere_and_floor(n);
        let mut renderer = Renderer::new(ctx, &volume, &white_tf(1.0)).unwrap();
        let mut opts = eikonal_options(size, size, light);
        opts.background = [0.0, 0.0, 0.0, 1.0];

        // The plane transports refuse this light, naming the eikonal one.
        let mut forward_opts = opts.clone();
        forward_opts.sweep.light_transport = LightTransport::Forward;
        let err = renderer
            .render(Model::Refract, &camera, &forward_opts)
            .err()
            .map(|e| format!("{e:#}"))
            .unwrap_or_default();
        assert!(
            err.contains("viewer's side") && err.contains("--light-transport eikonal"),
            "the forward transport should refuse a light from behind: {err:?}"
        );

        let frame = renderer.render(Model::Refract, &camera, &opts).unwrap();
        if let Ok(dir) = std::env::var("REFRAKT_TEST_DUMP") {
            let png: Vec<u8> = frame
                .pixels
                .iter()
                .flat_map(|p| {
                    let g = |c: f32| ((c / 1.2).clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0) as u8;
                    [g(p[0]), g(p[1]), g(p[2])]
                })
                .collect();
            image::save_buffer(
                std::path::Path::new(&dir).join("eikonal-transport-backlit.png"),
                &png,
                size,
                size,
                image::ColorType::Rgb8,
            )
            .unwrap();
        }
        let voxel = 1.0 / n as f32;
        let lum = |p: [f32; 4]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
        // The floor pixels, their geometric shadow, and the lit level away from its edge
        // (three voxels: the light volume's trilinear penumbra).
        let mut floor = Vec::new();
        for y in 0..size {
            for x in 0..size {
                if let Some(p) = floor_point(&camera, size, x, y, 2.0 * voxel) {
                    let l = lum(frame.pixels[(y * size + x) as usize]);
                    floor.push((p, l, in_shadow(p, towards)));
                }
            }
        }
        let far_from_edge = |p: Vec3| {
            let probe = |o: Vec3| in_shadow(p + o, towards);
            let k = 3.0 * voxel;
            [Vec3::X, Vec3::Z, -Vec3::X, -Vec3::Z]
                .into_iter()
                .all(|o| probe(o * k) == in_shadow(p, towards))
        };
        let mut lit: Vec<f32> = floor
            .iter()
            .filter(|(p, _, s)| !s && far_from_edge(*p))
            .map(|&(_, l, _)| l)
            .collect();
        lit.sort_by(f32::total_cmp);
        let lit_level = lit[lit.len() / 2];
        assert!(lit_level > 0.1, "the lit floor reads {lit_level}");
        let centroid = |pts: &mut dyn Iterator<Item = Vec3>| {
            let (mut s, mut k) = (Vec3::ZERO, 0usize);
            for p in pts {
                s += p;
                k += 1;
            }
            (s / k.max(1) as f32, k)
        };
        let (want, want_n) = centroid(&mut floor.iter().filter(|f| f.2).map(|f| f.0));
        let (got, got_n) =
            centroid(&mut floor.iter().filter(|f| f.1 < 0.5 * lit_level).map(|f| f.0));
        // Pixels classified differently away from the penumbra.
        let wrong = floor
            .iter()
            .filter(|f| far_from_edge(f.0) && (f.1 < 0.5 * lit_level) != f.2)
            .count();
        let off = Vec3::new(got.x - want.x, 0.0, got.z - want.z).length() / SPHERE_R;
        eprintln!(
            "light {angle:.1}° from the view direction; lit floor {lit_level:.4}; shadow \
             pixels {got_n} (geometry {want_n}), centroid ({:.4}, {:.4}) against ({:.4}, \
             {:.4}): {:.2} % R off; {wrong} pixels away from the penumbra on the wrong side",
            got.x,
            got.z,
            want.x,
            want.z,
            100.0 * off
        );
        assert!(want_n > 200, "the shadow must be seen: {want_n} pixels");
        assert!(
            off < 0.02,
            "shadow centroid {:.2} % R off (bound 2 %)",
            100.0 * off
        );
        assert!(
            wrong * 100 < want_n,
            "{wrong} pixels away from the penumbra on the wrong side of the shadow"
        );
    });
}
