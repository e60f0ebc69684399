use super::*;
use crate::render::Light;
use crate::transfer::Piecewise;

pub(super) fn f32_volume(n: u32, f: impl Fn(DVec3) -> f32) -> Volume {
    let mut v = Vec::with_capacity((n as usize).pow(3));
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = DVec3::new(x as f64, y as f64, z as f64);
                v.push(f((p + 0.5) / n as f64 - 0.5));
            }
        }
    }
    let mut vol = Volume::new([n; 3], [1.0; 3], Voxels::F32(v)).unwrap();
    vol.range = Some((0.0, 1.0));
    vol
}

pub(super) fn axial() -> Camera {
    Camera {
        azimuth: 0.0,
        elevation: 0.0,
        distance: 2.2,
        fov_y: 35.0,
        ..Default::default()
    }
}

pub(super) fn options(size: u32, towards: Vec3, colour: [f32; 3]) -> RenderOptions {
    let mut o = RenderOptions {
        width: size,
        height: size,
        ..Default::default()
    };
    o.lights = vec![Light {
        softness: 0.0,
        ..Light::directional(towards.normalize(), colour)
    }];
    o
}

fn popts(ppp: u32, jitter: bool) -> PhotonOptions {
    PhotonOptions {
        photons_per_pixel: ppp,
        jitter,
        threads: 2,
        ..Default::default()
    }
}

#[test]
fn empty_volume_gives_the_light_colour() {
    let vol = f32_volume(32, |_| 0.0);
    let tf = TransferFunctions::default();
    let camera = Camera {
        azimuth: 30.0,
        elevation: 20.0,
        distance: 2.2,
        fov_y: 35.0,
        ..Default::default()
    };
    let colour = [0.9, 0.5, 0.25];
    let opts = options(32, Vec3::new(-0.3, 0.6, 1.0), colour);
    let p = planes(&vol, &camera, &opts).unwrap();
    let depth = p.depth(p.count / 2);
    for jitter in [false, true] {
        let img =
            trace_irradiance(&vol, &tf, &camera, &opts, depth, &popts(64, jitter), None).unwrap();
        assert_eq!(img.photons_per_pixel, 64);
        assert_eq!((img.absorbed, img.backward, img.lost), (0, 0, 0));
        // The launch cells tile the pixels: unobstructed light is exact, jittered or not
        // (far inside the Poisson error 1/sqrt(64)).
        let tol = 1e-5;
        let mut mean = [0.0f64; 3];
        for px in &img.pixels {
            for c in 0..3 {
                let rel = (px[c] / colour[c] - 1.0).abs();
                assert!(rel < tol, "jitter {jitter}: {px:?} vs {colour:?}");
                mean[c] += px[c] as f64 / img.pixels.len() as f64;
            }
        }
        for c in 0..3 {
            assert!((mean[c] / colour[c] as f64 - 1.0).abs() < 0.01, "{mean:?}");
        }
    }
}

#[test]
fn slab_follows_beer_lambert_per_channel() {
    let vol = f32_volume(32, |_| 1.0);
    let alpha = 0.05f64;
    let m = [0.9f64, 0.95, 0.99];
    let tf = TransferFunctions {
        opacity: Piecewise::new(vec![(0.0, [0.0]), (1.0, [alpha as f32])]),
        medium: Piecewise::new(vec![
            (0.0, [1.0; 3]),
            (1.0, [m[0] as f32, m[1] as f32, m[2] as f32]),
        ]),
        ..Default::default()
    };
    let camera = axial();
    let colour = [1.0, 0.8, 0.6];
    let ref_step = vol.min_voxel_size() as f64;
    for towards in [Vec3::Z, Vec3::new(0.25, 0.1, 1.0)] {
        let opts = options(32, towards, colour);
        let p = planes(&vol, &camera, &opts).unwrap();
        let depth = p.depth(p.count - 1);
        let img =
            trace_irradiance(&vol, &tf, &camera, &opts, depth, &popts(16, false), None).unwrap();
        let (eye, forward, right, up) = camera.frame();
        let travel = -towards.normalize().as_dvec3();
        let half = DVec3::splat(0.5);
        // Path length through the box of the straight line through a point of the plane.
        let path = |ux: f64, uy: f64| {
            let t = ((camera.fov_y as f64).to_radians() * 0.5).tan();
            let (nx, ny) = (2.0 * ux - 1.0, 2.0 * uy - 1.0);
            let q = eye.as_dvec3()
                + depth as f64
                    * (forward.as_dvec3() + nx * t * right.as_dvec3() - ny * t * up.as_dvec3());
            let (t0, t1) = ray_box(q, -travel, -half, half);
            if t0 < t1 {
                t1 - t0
            } else {
                0.0
            }
        };
        let mut tested = 0;
        let mut worst = 0.0f64;
        for y in 0..32 {
            for x in 0..32 {
                let (fx, fy) = (x as f64, y as f64);
                let l = path((fx + 0.5) / 32.0, (fy + 0.5) / 32.0);
                let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                    .map(|(a, b)| path((fx + a) / 32.0, (fy + b) / 32.0));
                if l < 0.9 || corners.iter().any(|c| (c - l).abs() > 1e-9) {
                    continue;
                }
                tested += 1;
                let px = img.pixel(x, y);
                for c in 0..3 {
                    let want = colour[c] as f64 * ((1.0 - alpha) * m[c]).powf(l / ref_step);
                    let rel = (px[c] as f64 / want - 1.0).abs();
                    worst = worst.max(rel);
                    assert!(rel < 0.01, "pixel {x},{y} channel {c}: {} vs {want}", px[c]);
                }
            }
        }
        assert!(tested > 100, "only {tested} pixels behind the slab");
        eprintln!("Beer-Lambert, light {towards:?}: {tested} pixels, worst {worst:.2e}");
    }
}

fn ball(n: u32, radius: f64, ramp_voxels: f64) -> Volume {
    let w = ramp_voxels / n as f64;
    f32_volume(n, |p| {
        (0.5 + (radius - p.length()) / w).clamp(0.0, 1.0) as f32
    })
}

fn glass() -> TransferFunctions {
    TransferFunctions {
        eta: Piecewise::new(vec![(0.0, [1.0]), (1.0, [1.5])]),
        ..Default::default()
    }
}

#[test]
fn glass_ball_conserves_power_and_focuses_paraxially() {
    let camera = axial();
    let colour = [1.0, 0.7, 0.4];
    let r = 0.3;
    let depth = 2.2 + 0.4; // 0.1 behind the ball, inside the box, before the focus
    let tanf = (35.0f64.to_radians() * 0.5).tan();
    let pix = 2.0 * depth as f64 * tanf / 32.0;
    let opts = options(32, Vec3::Z, colour);
    let vol = ball(32, r, 2.0);
    // Power: a glass ball (1.5) in water (1.33). In air, rays grazing the 2-voxel ramp
    // orbit in it (η r has a maximum there) and some leave backwards; with the smaller
    // index step none can, so every photon must land (no absorption anywhere).
    let water = TransferFunctions {
        eta: Piecewise::new(vec![(0.0, [1.33]), (1.0, [1.5])]),
        ..Default::default()
    };
    // Power is the sum of the flux per unit plane area.
    let flux = PhotonOptions {
        plane_flux: true,
        ..popts(16, false)
    };
    let img = trace_irradiance(&vol, &water, &camera, &opts, depth, &flux, None).unwrap();
    assert_eq!((img.absorbed, img.backward, img.lost), (0, 0, 0));
    let (mut total, mut disc, mut disc_px, mut peak) = (0.0, 0.0, 0usize, 0.0f32);
    for y in 0..32 {
        for x in 0..32 {
            let e = img.pixel(x, y)[1] as f64 * pix * pix;
            total += e;
            let c = DVec3::new(x as f64 - 15.5, y as f64 - 15.5, 0.0) * pix;
            if c.length() < r + 2.0 * pix {
                disc += e;
                disc_px += 1;
            } else {
                let rel = img.pixel(x, y)[1] / colour[1] - 1.0;
                assert!(rel.abs() < 1e-4, "straight light at {x},{y}: {rel}");
            }
            peak = peak.max(img.pixel(x, y)[1]);
        }
    }
    let incident = colour[1] as f64 * 32.0 * 32.0 * pix * pix;
    let incident_disc = colour[1] as f64 * disc_px as f64 * pix * pix;
    eprintln!(
        "power in water: viewport {:.3e}, disc {:.3e}, peak {:.2}",
        total / incident - 1.0,
        disc / incident_disc - 1.0,
        peak / colour[1]
    );
    assert!((total / incident - 1.0).abs() < 0.01);
    assert!((disc / incident_disc - 1.0).abs() < 0.01);
    assert!(
        peak > 1.5 * colour[1],
        "the ball must focus light: peak {peak}"
    );

    // In air: the flux that lands plus the photons that turned back is the incident
    // flux (up to rim rays bent out of the viewport), and only rays through the ramp
    // (R - w/2 < |y| < R + w/2 + 1 voxel of trilinear support) can turn back.
    let tf = glass();
    let img = trace_irradiance(&vol, &tf, &camera, &opts, depth, &flux, None).unwrap();
    assert_eq!((img.absorbed, img.lost), (0, 0));
    let cell = pix * pix / 16.0;
    let landed: f64 = img.pixels.iter().map(|p| p[1] as f64 * pix * pix).sum();
    let back = img.backward as f64 * cell * colour[1] as f64;
    let ring = std::f64::consts::PI * ((r + 3.0 / 32.0).powi(2) - (r - 1.0 / 32.0).powi(2));
    eprintln!(
        "air: {} photons turned back ({:.1} % of the ramp ring), balance {:.2e}",
        img.backward,
        100.0 * back / (colour[1] as f64 * ring),
        (landed + back) / incident - 1.0
    );
    assert!(img.backward > 0 && back < colour[1] as f64 * ring);
    assert!(((landed + back) / incident - 1.0).abs() < 0.01);

    // Focus: 64³ ball in air, near-axis rays; paraxial focus n D / (4 (n - 1)) from
    // the centre. The trilinear field's gradient across the axis is constant within
    // each cell between voxel centres (the cell centred on the axis is flat: no
    // bending within half a voxel of it), so heights are chosen where the ray meets
    // both surfaces at cell centres: entering at 3 (6) voxels, a paraxial ray leaves
    // at 1 (2), since the front surface alone focuses 3R inside the glass. (Entering
    // at 1 or 2 voxels gives 0.496 and 0.431.) Spherical aberration of a sharp ball at
    // these heights: -0.7 % and -2.8 %.
    let vol = ball(64, r, 2.0);
    let field = Field::new(&vol, &tf, &opts).unwrap();
    let want = 1.5 * 2.0 * r / (4.0 * 0.5);
    for y in [3.0f32 / 64.0, 6.0 / 64.0] {
        let end = field
            .trace_ray(&camera, Vec3::new(0.0, y, 0.6), -Vec3::Z, 2.2 + 0.35, 0.1)
            .unwrap()
            .expect("reaches the plane");
        let (p, d) = (end.position.as_dvec3(), end.direction.as_dvec3());
        assert!(d.y < 0.0, "bent towards the axis: {d:?}");
        let cross = -(p.z - p.y / d.y * d.z);
        eprintln!(
            "ray at height {y}: crosses the axis {cross:.5} from the centre ({:+.2} % from \
             the paraxial {want})",
            100.0 * (cross / want - 1.0)
        );
        assert!((cross / want - 1.0).abs() < 0.02, "focus {cross} vs {want}");
    }
}

#[test]
fn one_cell_gradient_equals_the_six_lookups() {
    let vol = ball(16, 0.3, 2.0);
    let field = Field::new(&vol, &glass(), &RenderOptions::default()).unwrap();
    let mut fast = 0;
    for i in 0..4000u64 {
        let u = [0, 1, 2].map(|k| uniform(splitmix(i * 3 + k)) - 0.5);
        let t = field.tex(DVec3::from(u) * 1.1);
        if let Some(g) = field.grad_eta_in_cell(t) {
            fast += 1;
            let mut slow = DVec3::ZERO;
            for k in 0..3 {
                let h = GRADIENT_STEP / 16.0;
                let mut e = DVec3::ZERO;
                e[k] = h;
                slow[k] = (lut(&field.eta, field.value_tex(t + e))
                    - lut(&field.eta, field.value_tex(t - e)))
                    / (2.0 * h)
                    * field.tex_per_world[k];
            }
            assert!(
                (g - slow).length() <= 1e-9 * (1.0 + slow.length()),
                "{g} vs {slow}"
            );
        }
    }
    assert!(fast > 2000, "{fast}");
}

#[test]
fn plane_numbers_out_of_range_are_errors() {
    let vol = f32_volume(16, |_| 0.0);
    let opts = options(8, Vec3::Z, [1.0; 3]);
    let p = planes(&vol, &axial(), &opts).unwrap();
    assert!(plane_depth(&vol, &axial(), &opts, p.count - 1).is_ok());
    let e = plane_depth(&vol, &axial(), &opts, p.count)
        .unwrap_err()
        .to_string();
    assert!(e.contains(&format!("0..{}", p.count - 1)), "{e}");
}

/// Measurements quoted in the module documentation (release build:
/// `cargo test --release --lib photons::tests::measure -- --ignored --nocapture`).
#[test]
#[ignore]
fn measure_tracer_error() {
    let tf = glass();
    let camera = axial();
    let opts = options(64, Vec3::new(0.2, 0.1, 1.0), [1.0; 3]);
    // Focus against the step.
    let vol = ball(64, 0.3, 2.0);
    let field = Field::new(&vol, &tf, &opts).unwrap();
    for step in [0.05f32, 0.1, 0.2, 0.4] {
        let end = field
            .trace_ray(
                &camera,
                Vec3::new(0.0, 3.0 / 64.0, 0.6),
                -Vec3::Z,
                2.55,
                step,
            )
            .unwrap()
            .unwrap();
        let (p, d) = (end.position.as_dvec3(), end.direction.as_dvec3());
        eprintln!("step {step}: focus {:.6}", -(p.z - p.y / d.y * d.z));
    }
    // Jittered noise in the open.
    let empty = f32_volume(32, |_| 0.0);
    let img = trace_irradiance(
        &empty,
        &TransferFunctions::default(),
        &camera,
        &opts,
        2.5,
        &popts(64, true),
        None,
    )
    .unwrap();
    let rms = (img
        .pixels
        .iter()
        .map(|p| (p[0] as f64 - 1.0).powi(2))
        .sum::<f64>()
        / img.pixels.len() as f64)
        .sqrt();
    eprintln!("jittered, 64 ppp: RMS {rms:.4}");
    // Caustic convergence against photons per pixel.
    let vol = ball(64, 0.3, 2.0);
    let depth = 2.2 + 0.45;
    let reference =
        trace_irradiance(&vol, &tf, &camera, &opts, depth, &popts(1024, true), None).unwrap();
    eprintln!("reference: {:.1} s", reference.seconds);
    let mean =
        reference.pixels.iter().map(|p| p[0] as f64).sum::<f64>() / reference.pixels.len() as f64;
    for ppp in [4, 16, 64, 256] {
        let img = trace_irradiance(
            &vol,
            &tf,
            &camera,
            &opts,
            depth,
            &PhotonOptions {
                seed: 7,
                ..popts(ppp, true)
            },
            None,
        )
        .unwrap();
        let rms = (img
            .pixels
            .iter()
            .zip(&reference.pixels)
            .map(|(a, b)| (a[0] as f64 - b[0] as f64).powi(2))
            .sum::<f64>()
            / img.pixels.len() as f64)
            .sqrt();
        eprintln!(
            "{ppp} ppp: RMS difference {:.4} of mean {mean:.3} ({:.2} %), {:.2} s, steep {}",
            rms,
            100.0 * rms / mean,
            img.seconds,
            img.steep
        );
    }
}

/// The two tallies against Snell and flux conservation: glass (η 1.5) fills the volume
/// behind the plane z = 0 (the camera looks down −z), lit 40° from the face's normal, the
/// view axis. On a plane inside the glass the flux per unit plane area is the incident
/// light's (the face conserves flux per unit of its area and nothing is Fresnel-split),
/// so `plane_flux` reads the colour; the refracted beam runs at θ = 25.4° to the axis,
/// narrowed to cos 40° / cos θ = 0.848 of its fluence, which the default tally reads.
#[test]
fn in_glass_the_fluence_is_the_beam_narrowed_by_refraction() {
    let n = 32u32;
    let vol = f32_volume(n, |p| (0.5 - p.z as f32 * n as f32).clamp(0.0, 1.0));
    let tf = TransferFunctions {
        eta: Piecewise::new(vec![(0.0, [1.0]), (1.0, [1.5])]),
        ..Default::default()
    };
    let camera = axial();
    let ti = 40f64.to_radians();
    let opts = options(
        32,
        Vec3::new(-(ti.sin() as f32), 0.0, ti.cos() as f32),
        [1.0; 3],
    );
    let p = planes(&vol, &camera, &opts).unwrap();
    // A plane 4 voxels into the glass: the light that enters through the box's side
    // (glass meets the air outside the box there) reaches it only left of x = -0.29,
    // outside the pixels read below.
    let depth = camera.distance + 4.0 / n as f32;
    let k = (0..p.count).find(|&k| p.depth(k) >= depth).unwrap();
    let tt = (ti.sin() / 1.5).asin();
    for (plane_flux, expected) in [(true, 1.0), (false, ti.cos() / tt.cos())] {
        let popts = PhotonOptions {
            plane_flux,
            ..popts(16, false)
        };
        let img = trace_irradiance(&vol, &tf, &camera, &opts, p.depth(k), &popts, None).unwrap();
        // The middle of the plane (x from -0.14 to 0.24 of the box's 1).
        let mut values = Vec::new();
        for y in 12..20 {
            for x in 13..21 {
                values.push(img.pixels[y * 32 + x][0] as f64);
            }
        }
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        let worst = values
            .iter()
            .map(|v| (v / expected - 1.0).abs())
            .fold(0.0, f64::max);
        assert!(
            worst < 0.01,
            "plane_flux {plane_flux}: mean {mean:.4}, worst pixel {:.2} % off {expected:.4}",
            worst * 100.0
        );
    }
}
