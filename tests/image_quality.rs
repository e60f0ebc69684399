//! Issue 13: clean images. A flat lit floor must not be striped at the plane spacing, and
//! its level must be the one the model's continuous limit gives, under both light
//! transports, for a soft and a hard surface, softness 0 and 1.

mod common;

use common::*;
use glam::Vec3;
use refrakt::render::gradient::GradientStatus;
use refrakt::render::{
    Camera, Light, LightTransport, Model, RenderOptions, Renderer, SweepOptions,
};
use refrakt::transfer::{Piecewise, TransferFunctions};
use refrakt::vk::Context;

/// A camera on the floor of the tests below (its top at world y = -0.2), `angle` degrees
/// from its normal, seeing the top surface only, about ±0.3 around the target along it.
fn floor_camera(angle: f32) -> Camera {
    Camera {
        azimuth: 0.0,
        elevation: 90.0 - angle,
        distance: 2.0,
        fov_y: 2.0
            * (0.3 * (90.0 - angle).to_radians().sin() / 2.0)
                .atan()
                .to_degrees(),
        target: Vec3::new(0.0, -0.2, 0.0),
    }
}

/// A flat opaque white floor (its top at world y = -0.2, a one-voxel ramp) lit from
/// straight above, seen `angle` degrees from its normal. Returns the detrended row-to-row
/// variation of the lit floor's brightness, relative to its level: the RMS of the
/// differences between consecutive row means after removing a quadratic trend over the
/// rows (the floor's real brightness changes smoothly with distance: fog-free, it should
/// not change at all, but the perspective makes far rows average more of the floor), or
/// the same of the column means if larger (light that does not tile the plane stripes the
/// floor along the columns). `thin`: the opacity rises over a fifth of the surface's one-voxel ramp (a hard
/// surface); otherwise over all of it. Also returns the level relative to the continuous
/// limit of the model (emission-absorption, light attenuated on its way in): an opaque
/// layer lit along its normal and seen at μ = cos(angle) from it returns
/// ∫ e^-τ/μ e^-τ dτ/μ = 1 / (1 + μ) of the light, whatever its opacity profile (the
/// centre rows are seen at very nearly `angle`).
fn floor_banding(
    ctx: &Context,
    angle: f32,
    softness: f32,
    transport: LightTransport,
    thin: bool,
) -> (f64, f64) {
    floor_banding_lit(ctx, angle, softness, transport, thin, Vec3::Y, None)
}

/// `floor_banding` with the light travelling against `towards` (normalised) and an η
/// function for the floor's values.
fn floor_banding_lit(
    ctx: &Context,
    angle: f32,
    softness: f32,
    transport: LightTransport,
    thin: bool,
    towards: Vec3,
    eta: Option<Piecewise<1>>,
) -> (f64, f64) {
    let n = 64u32;
    let vol = f32_volume(n, |p| 0.5 + (-0.2 - p[1]) * n as f32);
    let opacity = if thin {
        vec![(0.0, [0.0]), (0.4, [0.0]), (0.6, [1.0])]
    } else {
        vec![(0.0, [0.0]), (1.0, [1.0])]
    };
    let mut tf = TransferFunctions {
        opacity: Piecewise::new(opacity),
        ..Default::default()
    };
    if let Some(eta) = eta {
        tf.eta = eta;
    }
    let cam = floor_camera(angle);
    let (w, h) = (96u32, 96u32);
    let mut opts = RenderOptions {
        width: w,
        height: h,
        background: [0.0, 0.0, 0.0, 1.0],
        ..Default::default()
    };
    opts.sweep = SweepOptions {
        light_transport: transport,
        specular: 0.0,
        ..Default::default()
    };
    opts.lights = vec![Light {
        source: refrakt::light::LightSource::Directional {
            towards: towards.normalize(),
        },
        colour: [1.0; 3],
        softness,
    }];
    let mut r = Renderer::new(ctx, &vol, &tf).unwrap();
    let f = r.render(Model::Refract, &cam, &opts).unwrap();
    // Row means over the central half of the columns, for rows showing the floor.
    let rows = floor_rows(&f);
    // Column means over the same rows: light that fails to tile the plane (splats
    // narrower than the light rays' spacing) stripes the floor along the columns instead.
    let (y0, y1) = (rows[0].0 as u32, rows[rows.len() - 1].0 as u32 + 1);
    let cols: Vec<f64> = (w / 4..3 * w / 4)
        .map(|x| (y0..y1).map(|y| f.pixel(x, y)[0] as f64).sum::<f64>() / (y1 - y0) as f64)
        .collect();
    let col_mean = cols.iter().sum::<f64>() / cols.len() as f64;
    let col_rel = (cols.iter().map(|c| (c - col_mean).powi(2)).sum::<f64>() / cols.len() as f64)
        .sqrt()
        / col_mean;
    let (rel, level, max_rel) = detrended_row_to_row(&rows);
    println!(
        "{} {} floor at {angle}° softness {softness}: level {level:.4}, row-to-row {:.3} % \
         (max {:.3} %), column to column {:.3} %",
        transport.name(),
        if thin { "thin" } else { "soft" },
        100.0 * rel,
        100.0 * max_rel,
        100.0 * col_rel
    );
    let mu = angle.to_radians().cos() as f64;
    (rel.max(col_rel), level * (1.0 + mu))
}

/// Row to row and column to column within 1 % of the level, and the level within 1 % of
/// the continuous limit, for both transports, soft and hard surfaces, softness 0 and 1,
/// seen 45° to 80° from the normal. At 80° the light is 80° from the sweep axis and the
/// forward transport's ray grid is coarser than 8 pixels: with splats at most 8 pixels
/// across the floor had dark columns (−63 % / +22 % column means; row to row 1.02 %).
/// Before issue 13 (the segment shaded with its front plane's light): backward
/// 1.0–1.4 % soft and 18–25 % hard, forward 1.7–5.4 % and 34–39 %, levels 0.77–0.93 of
/// the light instead of 1 / (1 + μ).
#[test]
fn a_lit_floor_is_unstriped_at_its_physical_level() {
    with_context(|ctx| {
        let mut worst = (0.0f64, 0.0f64);
        let mut failures = Vec::new();
        for transport in [LightTransport::Forward, LightTransport::Backward] {
            for thin in [false, true] {
                for angle in [45.0f32, 60.0, 75.0, 80.0] {
                    for softness in [0.0f32, 1.0] {
                        let (b, level) = floor_banding(ctx, angle, softness, transport, thin);
                        worst = (worst.0.max(b), worst.1.max((level - 1.0).abs()));
                        if b > 0.01 || (level - 1.0).abs() > 0.01 {
                            failures.push(format!(
                                "{} {} {angle}° softness {softness}: row-to-row or column to \
                                 column {:.2} %, level {:.3} of 1/(1+μ)",
                                transport.name(),
                                if thin { "thin" } else { "soft" },
                                100.0 * b,
                                level
                            ));
                        }
                    }
                }
            }
        }
        println!(
            "worst row-to-row {:.3} %, worst level error {:.3} %",
            100.0 * worst.0,
            100.0 * worst.1
        );
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    });
}

/// The demo floor's skin, lit: where the floor's value ramp passes through a glass's η band
/// (0.2–0.3 → η 1.5, as the demo floor's edge passes through the glass sphere's band),
/// the classification dresses it in a skin of glass a fraction of a voxel thick. The
/// skin belongs to no matter of the scene, so the lit floor must look as it does without
/// it: unstriped within 1 % row to row and column to column, at the same level within
/// 1 %, with the light 35° off the normal (straight down, Snell does not turn it) and the
/// floor seen 60° and 75° from its normal, both transports. Turned into and out of the
/// skin on some planes only (light rays by Snell steps, the backward light and the
/// viewing rays by the kick of eq. 4.5 / 4.3), the floor striped 6.6 / 14.9 % row to row
/// at 60° / 75° in both transports, at 0.98 / 0.92 of its level without the skin.
#[test]
fn a_skin_of_glass_on_a_lit_floor_changes_nothing() {
    with_context(|ctx| {
        let skin = Piecewise::new(vec![
            (0.0, [1.0]),
            (0.2, [1.0]),
            (0.21, [1.5]),
            (0.3, [1.5]),
            (0.31, [1.0]),
            (1.0, [1.0]),
        ]);
        let towards = Vec3::new(0.45, 1.0, 0.5);
        let mut failures = Vec::new();
        for transport in [LightTransport::Forward, LightTransport::Backward] {
            for angle in [60.0f32, 75.0] {
                let (b0, level0) =
                    floor_banding_lit(ctx, angle, 0.0, transport, false, towards, None);
                let (b, level) = floor_banding_lit(
                    ctx,
                    angle,
                    0.0,
                    transport,
                    false,
                    towards,
                    Some(skin.clone()),
                );
                println!(
                    "{} {angle}°: striping {:.3} % with the skin, {:.3} % without; level \
                     ratio {:.4}",
                    transport.name(),
                    100.0 * b,
                    100.0 * b0,
                    level / level0
                );
                if b > 0.01 || (level / level0 - 1.0).abs() > 0.01 {
                    failures.push(format!(
                        "{} {angle}°: striping {:.2} % (without the skin {:.2} %), level \
                         ratio {:.4}",
                        transport.name(),
                        100.0 * b,
                        100.0 * b0,
                        level / level0
                    ));
                }
            }
        }
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    });
}

/// Median and 95th percentile of a sample (sorted in place).
fn median_p95(v: &mut [f64]) -> (f64, f64) {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    (q(0.5), q(0.95))
}

/// The glass ball of the refraction tests: 64³, radius 26 voxels (one-voxel ramp), η 1.5,
/// seen face-on from 2.5 with a 22° field of view. (n, radius, volume, TFs, camera).
fn glass_ball() -> (u32, f32, refrakt::volume::Volume, TransferFunctions, Camera) {
    let n = 64u32;
    let radius = 26.0 / n as f32;
    (n, radius, ball(n, radius), glass(1.5), face_on(2.5, 22.0))
}

/// Exit directions of viewing rays through a glass sphere (η 1.5, radius 26 voxels, a
/// one-voxel ramp) seen face-on: each pixel's direction after the last plane against
/// Snell's law at a perfect sphere of the ramp's middle radius, and against the photon
/// tracer's trace of the same ray through the volume's exact trilinear η field (RK4 of
/// the ray equation, 0.05-voxel steps). Over the pixels whose eye ray meets the sphere:
/// (median, 95th percentile) in degrees against Snell, the same against the tracer, the
/// tracer's own against Snell, and the pixel count.
fn view_exit_errors(ctx: &Context, sd: f32, gradient_budget: Option<u64>) -> [(f64, f64); 3] {
    let (n, radius, vol, tf, cam) = glass_ball();
    let (w, h) = (64u32, 64u32);
    let planes = refrakt::render::Planes::for_box(&cam, Vec3::splat(0.5), sd / n as f32).unwrap();
    // The pass for plane k leaves the rays on plane k + 1: dump the last but one.
    let k = planes.count - 2;
    let mut opts = frame_options(w, h, sd);
    opts.sweep = SweepOptions {
        dumps: vec![(refrakt::render::StateBuffer::ViewDirection, k)],
        specular: 0.0,
        ..Default::default()
    };
    let mut r = Renderer::new(ctx, &vol, &tf).unwrap();
    if let Some(bytes) = gradient_budget {
        r.set_gradient_budget(bytes);
    }
    let f = r.render(Model::Refract, &cam, &opts).unwrap();
    let have_volume = *r.gradient_status() == GradientStatus::Built;
    assert_eq!(
        have_volume,
        gradient_budget.is_none(),
        "{:?}",
        r.gradient_status()
    );
    let dirs = &f.dumps[0].pixels;
    let field = refrakt::photons::Field::new(&vol, &tf, &opts).unwrap();
    let (eye, forward, right, up) = cam.frame();
    let t = (cam.fov_y.to_radians() * 0.5).tan();
    let angle = |a: Vec3, b: Vec3| (a.dot(b).clamp(-1.0, 1.0) as f64).acos().to_degrees();
    let (mut vs_snell, mut vs_tracer, mut tracer_vs_snell) = (Vec::new(), Vec::new(), Vec::new());
    for y in 0..h {
        for x in 0..w {
            let ndc = [
                (x as f32 + 0.5) / w as f32 * 2.0 - 1.0,
                (y as f32 + 0.5) / h as f32 * 2.0 - 1.0,
            ];
            let d = (forward + right * ndc[0] * t * (w as f32 / h as f32) - up * ndc[1] * t)
                .normalize();
            // Impact parameter of the eye ray against the sphere at the origin.
            if (eye - d * eye.dot(d)).length() >= radius {
                continue;
            }
            let v = dirs[(y * w + x) as usize];
            let swept = (right * v[0] + up * v[1] + forward * v[2]).normalize();
            let snell = sphere_exit(eye, d, radius, 1.5);
            vs_snell.push(angle(swept, snell));
            let origin = eye + d * ((eye.length() - 0.8) / d.dot(-eye.normalize()));
            if let Some(end) = field
                .trace_ray(&cam, origin, d, planes.depth(k + 1), 0.05)
                .unwrap()
            {
                vs_tracer.push(angle(swept, end.direction));
                tracer_vs_snell.push(angle(end.direction, snell));
            }
        }
    }
    assert!(
        vs_snell.len() > 1000,
        "too few rays through the sphere ({})",
        vs_snell.len()
    );
    [
        median_p95(&mut vs_snell),
        median_p95(&mut vs_tracer),
        median_p95(&mut tracer_vs_snell),
    ]
}

/// Issue 13: viewing rays leave a glass sphere (radius 26 voxels, one-voxel ramp, η 1.5)
/// in the directions Snell's law gives at the ramp's middle sphere: median ≤ 0.3°, 95th
/// percentile ≤ 1° at every sample distance (measured 0.09° / 0.55–0.59° at 2, 1, 0.5 and
/// 0.25; the error grows towards the rim, where the exit direction turns fastest with
/// the impact parameter: 0.33° median over the outer tenth of the radius). Before the
/// sharp-face turn and the smoothed gradient volume: 0.45° / 3.0° at 1, 1.08° / 4.5° at
/// 0.5; the thesis' kick 1.09° / 10.3°. Against the tracer in the exact trilinear field
/// the figures are printed only: that field's one-voxel clamped ramp is itself no sphere
/// (the tracer's rays leave it 1.3° / 12° off Snell), see docs/NOTES.md.
#[test]
fn viewing_rays_leave_a_glass_sphere_as_snell_says() {
    with_context(|ctx| {
        let mut failures = Vec::new();
        for sd in [2.0f32, 1.0, 0.5, 0.25] {
            let [snell, tracer, own] = view_exit_errors(ctx, sd, None);
            println!(
                "sample distance {sd}: exit directions vs Snell median {:.3}° p95 {:.3}°; \
                 vs the tracer {:.3}° / {:.3}° (the tracer vs Snell {:.3}° / {:.3}°)",
                snell.0, snell.1, tracer.0, tracer.1, own.0, own.1
            );
            if snell.0 > 0.3 || snell.1 > 1.0 {
                failures.push(format!("sd {sd}: {snell:?}"));
            }
        }
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    });
}

/// Without the gradient volume (a volume too large for the device's memory) the sweep
/// takes its normals from a 3D Sobel on the fly: the same scheme with normals ~1.5° off
/// (median). Measured: median / p95 1.29° / 4.3° at sample distance 1 and 0.5 (the
/// thesis' kick: 1.09° / 10.3°); bounds median 1.6°, p95 5°.
#[test]
fn viewing_rays_without_the_gradient_volume_stay_near_snell() {
    with_context(|ctx| {
        for sd in [1.0f32, 0.5] {
            let [snell, _, _] = view_exit_errors(ctx, sd, Some(0));
            println!(
                "sample distance {sd}, normals on the fly: vs Snell median {:.3}° p95 {:.3}°",
                snell.0, snell.1
            );
            assert!(snell.0 <= 1.6 && snell.1 <= 5.0, "sd {sd}: {snell:?}");
        }
    });
}

/// The glass sphere of `view_exit_errors` in front of a smooth environment (a linear
/// ramp in the direction's x and y), softness and specular off: the mean absolute
/// difference between each pixel and the median of its 3×3 neighbourhood over the pixels
/// within 0.8 R of the centre, relative to their mean (the median residual noise).
fn noise_inside_sphere(ctx: &Context, sd: f32) -> f64 {
    let (_, radius, vol, tf, cam) = glass_ball();
    let (w, h) = (64u32, 64u32);
    let map = environment_from(256, |d| [0.5 + 0.4 * d.x, 0.5 + 0.4 * d.y, 0.5, 1.0]);
    let mut opts = frame_options(w, h, sd);
    opts.sweep = SweepOptions {
        specular: 0.0,
        ..Default::default()
    };
    let mut r = Renderer::new(ctx, &vol, &tf).unwrap();
    r.set_environment(Some(&map)).unwrap();
    let f = r.render(Model::Refract, &cam, &opts).unwrap();
    let (mut resid, mut level, mut count) = (0.0f64, 0.0f64, 0);
    let rpx = radius / (cam.distance * (cam.fov_y.to_radians() * 0.5).tan()) * h as f32 * 0.5;
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let (dx, dy) = (
                x as f32 + 0.5 - w as f32 / 2.0,
                y as f32 + 0.5 - h as f32 / 2.0,
            );
            if (dx * dx + dy * dy).sqrt() > 0.8 * rpx {
                continue;
            }
            for c in 0..2 {
                let mut nb: Vec<f32> = (0..9)
                    .map(|k| f.pixel(x + k % 3 - 1, y + k / 3 - 1)[c])
                    .collect();
                nb.sort_by(|a, b| a.partial_cmp(b).unwrap());
                let v = f.pixel(x, y)[c];
                resid += (v - nb[4]).abs() as f64;
                level += v as f64;
                count += 1;
            }
        }
    }
    assert!(count > 500, "too few pixels inside the sphere ({count})");
    resid / level
}

/// Issue 13: inside a glass sphere in front of a smooth background the image is smooth.
/// Bound: the 3 % of the level. Measured 0.04 % (sample distance 1 and 0.5; with
/// Snell sub-steps it was 0.20 %). The salt-and-pepper the issue saw inside the sphere on
/// its floor was the floor's banding seen through the lens (gone with the banding).
#[test]
fn glass_in_front_of_a_smooth_background_is_smooth() {
    with_context(|ctx| {
        for sd in [1.0f32, 0.5] {
            let noise = noise_inside_sphere(ctx, sd);
            println!(
                "sample distance {sd}: median residual noise {:.2} %",
                100.0 * noise
            );
            assert!(noise <= 0.03, "sd {sd}: noise {:.2} %", 100.0 * noise);
        }
    });
}

/// Exit direction of a ray from `eye` along unit `d` through a perfect sphere (radius r at
/// the origin, index eta in air): Snell's law at both faces.
fn sphere_exit(eye: Vec3, d: Vec3, r: f32, eta: f32) -> Vec3 {
    let refract = |d: Vec3, n: Vec3, ratio: f32| {
        let ci = -n.dot(d);
        let k = 1.0 - ratio * ratio * (1.0 - ci * ci);
        d * ratio + n * (ratio * ci - k.sqrt())
    };
    let b = eye.dot(d);
    let c = eye.dot(eye) - r * r;
    let p = eye + d * (-b - (b * b - c).sqrt());
    let d2 = refract(d, p / r, 1.0 / eta).normalize();
    let b = p.dot(d2);
    let c = p.dot(p) - r * r;
    let p2 = p + d2 * (-b + (b * b - c).sqrt());
    refract(d2, -p2 / r, eta).normalize()
}

/// Unpolarised Fresnel reflectance from the Fresnel equations (not the shader's
/// Cook–Torrance form): light in a medium of index n1 meeting one of n2 at `cos_i`.
fn fresnel_unpolarised(cos_i: f64, n1: f64, n2: f64) -> f64 {
    let sin_t = n1 / n2 * (1.0 - cos_i * cos_i).sqrt();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i);
    0.5 * (rs * rs + rp * rp)
}

/// A glass slab (η 1.5, 0.2 thick, one-voxel faces) whose normal makes `incidence`
/// degrees with the view axis (its faces meet the central ray at least 13 voxels inside
/// the box: the box's side is a face of the field too, value 0 beyond it, and the
/// smoothed gradient reaches 5 voxels), in front of an environment that is red on the camera's
/// side of the slab's plane and green beyond it: red measures what the faces reflect,
/// green what the slab transmits. Returns (reflected, transmitted, expected reflected,
/// expected transmitted) over the central pixels. Clear (`black_inside` false): the front
/// face reflects F, the back face F of what reaches it (its reflection is not traced back
/// through the front face: reflections are unoccluded), the rest goes through:
/// F + (1 − F) F and (1 − F)². With `black_inside` the glass turns opaque black once past
/// its face's middle (value 0.8 on), so only the front face's F is seen.
fn slab_fresnel(
    ctx: &Context,
    incidence: f32,
    sd: f32,
    black_inside: bool,
) -> (f64, f64, f64, f64) {
    slab_fresnel_with(ctx, incidence, sd, black_inside, true)
}

/// [`slab_fresnel`] with reflections switched on or off.
fn slab_fresnel_with(
    ctx: &Context,
    incidence: f32,
    sd: f32,
    black_inside: bool,
    reflections: bool,
) -> (f64, f64, f64, f64) {
    let n = 64u32;
    let a = incidence.to_radians();
    let normal = Vec3::new(0.0, a.sin(), a.cos());
    let vol = f32_volume(n, |p| {
        0.5 + (0.1 - Vec3::from(p).dot(normal).abs()) * n as f32
    });
    let mut tf = glass(1.5);
    if black_inside {
        tf.colour = Piecewise::new(vec![(0.0, [0.0, 0.0, 0.0])]);
        tf.opacity = Piecewise::new(vec![(0.0, [0.0]), (0.8, [0.0]), (1.0, [1.0])]);
    }
    let cam = face_on(2.5, 6.0);
    let map = environment_from(512, |d| {
        if d.dot(normal) > 0.0 {
            [1.0, 0.0, 0.0, 1.0]
        } else {
            [0.0, 1.0, 0.0, 1.0]
        }
    });
    let (w, h) = (32u32, 32u32);
    let mut opts = frame_options(w, h, sd);
    opts.sweep = SweepOptions {
        specular: 0.0,
        reflections,
        ..Default::default()
    };
    // No early termination: at 0.99 a ray stops with up to 1 % of what lies behind still
    // to come, and the black glass would let that much of the green through.
    opts.termination_alpha = 1.0;
    let mut r = Renderer::new(ctx, &vol, &tf).unwrap();
    r.set_environment(Some(&map)).unwrap();
    let f = r.render(Model::Refract, &cam, &opts).unwrap();
    let (mut red, mut green, mut count) = (0.0f64, 0.0f64, 0);
    for y in h / 2 - 4..h / 2 + 4 {
        for x in w / 2 - 4..w / 2 + 4 {
            let p = f.pixel(x, y);
            red += p[0] as f64;
            green += p[1] as f64;
            count += 1;
        }
    }
    let cos_i = (a as f64).cos();
    let f1 = fresnel_unpolarised(cos_i, 1.0, 1.5);
    let cos_t = (1.0 - (1.0 - cos_i * cos_i) / 2.25).sqrt();
    let f2 = fresnel_unpolarised(cos_t, 1.5, 1.0);
    if black_inside {
        return (red / count as f64, green / count as f64, f1, 0.0);
    }
    (
        red / count as f64,
        green / count as f64,
        f1 + (1.0 - f1) * f2,
        (1.0 - f1) * (1.0 - f2),
    )
}

/// Issue 13: Fresnel reflection of viewing rays, at every sample distance (the faces fall
/// differently between planes). One face (black glass behind it): the Fresnel equations
/// within 0.5 % absolute at normal incidence and 1 % at 30°–70° (measured within 0.07 %).
/// A clear slab: reflected F + (1 − F) F and transmitted (1 − F)² within 0.5 % at normal
/// incidence (exact to 0.01 %), 1 % at 60° (measured within 0.05 %). With reflections off
/// the face reflects nothing.
#[test]
fn glass_reflects_and_transmits_by_fresnel() {
    with_context(|ctx| {
        assert!((fresnel_unpolarised(1.0, 1.0, 1.5) - 0.04).abs() < 1e-12);
        let mut failures = Vec::new();
        for sd in [1.0f32, 0.5] {
            for incidence in [0.0f32, 30.0, 45.0, 60.0, 70.0] {
                let (r, t, er, _) = slab_fresnel(ctx, incidence, sd, true);
                let tol = if incidence == 0.0 { 0.005 } else { 0.01 };
                println!(
                    "sample distance {sd}, one face at {incidence}°: reflected {r:.4} \
                     (Fresnel {er:.4}), behind it {t:.4}"
                );
                if (r - er).abs() > tol || t > 1e-3 {
                    failures.push(format!("sd {sd}, one face {incidence}°: {r} vs {er}"));
                }
            }
            for (incidence, tol) in [(0.0f32, 0.005), (60.0, 0.01)] {
                let (r, t, er, et) = slab_fresnel(ctx, incidence, sd, false);
                println!(
                    "sample distance {sd}, clear slab at {incidence}°: reflected {r:.4} \
                     (Fresnel {er:.4}), transmitted {t:.4} (Fresnel {et:.4})"
                );
                if (r - er).abs() > tol || (t - et).abs() > tol {
                    failures.push(format!(
                        "sd {sd}, slab {incidence}°: reflected {r} vs {er}, transmitted {t} vs {et}"
                    ));
                }
            }
        }
        // --reflections off: the thesis' model, the face reflects nothing.
        let (r, _, _, _) = slab_fresnel_with(ctx, 60.0, 1.0, true, false);
        println!("reflections off, one face at 60°: reflected {r:.5}");
        if r > 1e-4 {
            failures.push(format!("reflections off still reflect {r}"));
        }
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    });
}

/// Detrended row-to-row variation of an image's channel 0 over its central half of
/// columns and the rows `rows`, relative to the level (as in `floor_banding`).
fn row_to_row(f: &refrakt::render::Frame, rows: std::ops::Range<u32>) -> (f64, f64) {
    let w = f.width;
    let pts: Vec<(f64, f64)> = rows
        .map(|y| {
            let s: f64 = (w / 4..3 * w / 4).map(|x| f.pixel(x, y)[0] as f64).sum();
            (y as f64, s / (w / 2) as f64)
        })
        .collect();
    let (rel, level, _) = detrended_row_to_row(&pts);
    (rel, level)
}

/// Issue 13: highlights without rings. A glass face (η 1.5, one-voxel ramp, tilted 30°
/// from the view axis, black glass past the face's middle so only this face shows) lit
/// from the mirror direction: its Cook–Torrance highlight is the same at every sample
/// distance (within 3 %) and varies over the face row to row by at most 2 % of its level
/// (detrended as for the floor). Measured: levels 0.0405 / 0.0406 / 0.0406 at sample
/// distance 1 / 0.5 / 0.25, row to row 0.51 / 0.51 / 0.50 %. With the Sobel normal (26
/// trilinear fetches) instead of the smoothed gradient volume: 5.8 / 9.0 / 6.7 % (its
/// tilt across the voxel grid was the rings); before issue 13 (F from consecutive η
/// samples per plane): levels 0.019 / 0.013 / 0.007 (a fraction of the face's F,
/// shrinking with the spacing) and 11 / 20 / 19 %.
#[test]
fn highlights_on_glass_have_no_rings() {
    with_context(|ctx| {
        let n = 64u32;
        let a = 30f32.to_radians();
        let normal = Vec3::new(0.0, a.sin(), a.cos());
        let vol = f32_volume(n, |p| {
            0.5 + (0.1 - Vec3::from(p).dot(normal).abs()) * n as f32
        });
        // Black inside, past the face's middle: only the face's own highlight is seen (the
        // back face's, lit by light refracted through the one-voxel ramp, carries that
        // light's stripes: the trilinear field's, which the photon tracer shares).
        let mut tf = glass(1.5);
        tf.colour = Piecewise::new(vec![(0.0, [0.0, 0.0, 0.0])]);
        tf.opacity = Piecewise::new(vec![(0.0, [0.0]), (0.8, [0.0]), (1.0, [1.0])]);
        let cam = face_on(2.5, 8.0);
        let mirror = Vec3::NEG_Z - 2.0 * Vec3::NEG_Z.dot(normal) * normal;
        let (mut worst, mut levels) = (0.0f64, Vec::new());
        for sd in [1.0f32, 0.5, 0.25] {
            let mut opts = RenderOptions {
                width: 64,
                height: 64,
                sample_distance: sd,
                background: [0.0, 0.0, 0.0, 1.0],
                ..Default::default()
            };
            opts.sweep = SweepOptions {
                specular: 1.0,
                roughness: 0.5,
                reflections: false,
                ..Default::default()
            };
            opts.lights = vec![Light {
                source: refrakt::light::LightSource::Directional { towards: mirror },
                colour: [1.0; 3],
                softness: 0.0,
            }];
            let mut r = Renderer::new(ctx, &vol, &tf).unwrap();
            r.set_environment(None).unwrap();
            let f = r.render(Model::Refract, &cam, &opts).unwrap();
            let (b, level) = row_to_row(&f, 8..56);
            println!(
                "sample distance {sd}: highlight level {level:.4}, row-to-row {:.3} %",
                100.0 * b
            );
            assert!(level > 0.01, "no highlight at sd {sd} ({level})");
            worst = worst.max(b);
            levels.push(level);
        }
        let (lo, hi) = levels
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), &l| (a.min(l), b.max(l)));
        assert!(
            hi <= 1.03 * lo,
            "highlight depends on the sample distance: {levels:?}"
        );
        assert!(worst <= 0.02, "highlight rings: {:.2} %", 100.0 * worst);
    });
}

/// Unpolarised Fresnel reflectance of a face between η 1 and `n` at `angle_deg` from its
/// normal (the textbook s and p amplitudes, in f64: independent of the shader's form).
fn fresnel_air_to(n: f64, angle_deg: f64) -> f64 {
    let ci = angle_deg.to_radians().cos();
    let si = angle_deg.to_radians().sin();
    let ct = (1.0 - (si / n).powi(2)).sqrt();
    let rs = (ci - n * ct) / (ci + n * ct);
    let rp = (ct - n * ci) / (ct + n * ci);
    0.5 * (rs * rs + rp * rp)
}

/// The demo's striped shadow (docs/NOTES.md): where a value ramp between two matters
/// passes through a third's η band, a 1D transfer function dresses the surface in a skin of
/// that third matter (here η 1.5 over 0.3 voxels, between air and an opaque black floor
/// of η 1.33, as the demo floor's edge passes through the glass's band). Seen 60° and 75°
/// from its normal against a white background, all the floor shows is its reflection. At
/// every sample distance (1, 0.5, 0.25) it must be the same on every row (within 2 %,
/// detrended as for the lit floor) and be the face the scene has, air to η 1.33, with F
/// the Fresnel reflectance at that angle (within 3 %): the skin is the classification's
/// and thinner than a face as the sweep knows faces (by the plateaus either side, which
/// also turn the ray). Judged from the plane samples (the sweep before 2026-11-25) the skin
/// reflected as glass only on rows where a sample landed inside it: at 60° row to row
/// 38 / 7.4 / 12 % at sample distance 1 / 0.5 / 0.25, levels 0.068–0.094 for 0.059.
#[test]
fn a_thin_skin_of_glass_reflects_alike_wherever_the_planes_fall() {
    with_context(|ctx| {
        let n = 64u32;
        let vol = f32_volume(n, |p| 0.5 + (-0.2 - p[1]) * n as f32);
        let tf = TransferFunctions {
            colour: Piecewise::new(vec![(0.0, [0.0, 0.0, 0.0]), (1.0, [0.0, 0.0, 0.0])]),
            opacity: Piecewise::new(vec![(0.0, [0.0]), (0.75, [0.0]), (0.85, [1.0])]),
            eta: Piecewise::new(vec![
                (0.0, [1.0]),
                (0.34, [1.0]),
                (0.35, [1.5]),
                (0.65, [1.5]),
                (0.66, [1.33]),
                (1.0, [1.33]),
            ]),
            ..Default::default()
        };
        let mut failures = Vec::new();
        for angle in [60.0f32, 75.0] {
            for sd in [1.0f32, 0.5, 0.25] {
                let cam = floor_camera(angle);
                let (w, h) = (96u32, 96u32);
                let mut opts = RenderOptions {
                    width: w,
                    height: h,
                    sample_distance: sd,
                    background: [1.0, 1.0, 1.0, 1.0],
                    // No early termination: a ray stopped at 0.99 would let up to 1 % of
                    // the white background through, more or less as the planes cut the
                    // floor's opacity ramp (row to row 13 % of the reflection at 60°).
                    termination_alpha: 1.0,
                    ..Default::default()
                };
                opts.sweep.specular = 0.0;
                let mut r = Renderer::new(ctx, &vol, &tf).unwrap();
                let f = r.render(Model::Refract, &cam, &opts).unwrap();
                // The floor's rows: opaque (the floor stops every ray) over the central
                // half of the columns.
                let rows: Vec<(f64, f64)> = (0..h)
                    .filter(|&y| (w / 4..3 * w / 4).all(|x| f.pixel(x, y)[3] > 0.99))
                    .map(|y| {
                        let s: f64 = (w / 4..3 * w / 4).map(|x| f.pixel(x, y)[0] as f64).sum();
                        (y as f64, s / (w / 2) as f64)
                    })
                    .collect();
                assert!(rows.len() > 40, "too few floor rows ({})", rows.len());
                let (rel, _, max_rel) = detrended_row_to_row(&rows);
                // The centre rows are seen at very nearly `angle`.
                let centre = rows[rows.len() / 2 - 2..rows.len() / 2 + 2]
                    .iter()
                    .map(|p| p.1)
                    .sum::<f64>()
                    / 4.0;
                let want = fresnel_air_to(1.33, angle as f64);
                println!(
                    "skin at {angle}°, sample distance {sd}: level {centre:.4} (air to floor \
                     {want:.4}), row to row {:.3} % (max {:.3} %)",
                    100.0 * rel,
                    100.0 * max_rel
                );
                if rel > 0.02 || (centre / want - 1.0).abs() > 0.03 {
                    failures.push(format!(
                        "{angle}° sd {sd}: level {centre:.4} against {want:.4}, row to row \
                         {:.2} %",
                        100.0 * rel
                    ));
                }
            }
        }
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    });
}
