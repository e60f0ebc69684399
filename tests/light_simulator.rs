//! The eikonal light simulator (render/light_simulator.rs, glsl/light_wavefront*; issue
//! 35, seed 001 sect. 4.2 and 5.2): a wavefront of patches through the refractive-index
//! field, held to conservation of power through a focus, to Beer–Lambert per channel, to
//! a ball lens' paraxial focus and to its own tessellation bound.

mod common;

use common::floor::{caustic_scene, compare_floors};
use common::*;
use glam::Vec3;
use refrakt::light::{Light, LightSource};
use refrakt::render::light_simulator::{
    FocusPolicy, LightSimulation, RayGradient, Receiver, WavefrontSettings,
};
use refrakt::render::{RenderOptions, Renderer};
use refrakt::transfer::{Piecewise, TransferFunctions};

/// A glass ball lens' value: radius `r` (world units) in a cube of `n` voxels, a
/// two-voxel ramp (with `glass(1.5)`: η 1.5 inside).
fn lens(n: u32, r: f32) -> refrakt::volume::Volume {
    f32_volume(n, |p| 0.5 + (r - Vec3::from(p).length()) * n as f32 / 2.0)
}

/// Simulate `light` with `settings`, counting it on `receivers` (default render options).
fn simulate(
    renderer: &Renderer,
    light: &Light,
    settings: &WavefrontSettings,
    receivers: &[Receiver],
) -> LightSimulation {
    renderer
        .simulate_light(&RenderOptions::default(), light, settings, receivers, None)
        .unwrap()
}

/// A white directional light travelling along `travel`.
fn light_along(travel: Vec3) -> Light {
    Light {
        source: LightSource::Directional { towards: -travel },
        colour: [1.0; 3],
        softness: 0.0,
    }
}

/// A square receiver normal to `travel` through `centre`, `size` world units on a side in
/// `pixels` pixels, its normal along `travel`.
fn receiver_across(travel: Vec3, centre: Vec3, size: f32, pixels: u32) -> Receiver {
    let t = travel.normalize();
    let helper = if t.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let a = helper.cross(t).normalize();
    // u × v = t: u = a, v = t × a.
    let b = t.cross(a);
    let px = size / pixels as f32;
    Receiver {
        origin: centre - (a + b) * (0.5 * size),
        u: a * px,
        v: b * px,
        width: pixels,
        height: pixels,
    }
}

/// The power a receiver counted: irradiance × pixel area, summed, per channel (world
/// units: the light's irradiance × area).
fn power(sim: &LightSimulation, k: usize, r: &Receiver) -> [f64; 3] {
    let area = r.u.cross(r.v).length() as f64;
    let mut p = [0.0; 3];
    for e in &sim.receivers[k] {
        for c in 0..3 {
            p[c] += e[c] as f64 * area;
        }
    }
    p
}

/// Launched power in world units (the stats count it in the light's colour × reference
/// step²).
fn launched(sim: &LightSimulation, reference: f64) -> [f64; 3] {
    sim.stats.launched_flux.map(|f| f * reference * reference)
}

/// A clear glass ball lens (η 1.5, radius 12 voxels of 48, a two-voxel ramp) lit along
/// −z by a beam of radius 0.8 R: the flux crossing planes normal to the light before the
/// ball, through it, at the paraxial focus (1.5 R from the centre) and beyond must stay
/// the launched flux within 0.1 % (the issue asks 1 %; nothing absorbs, the rays stay
/// in the box; measured within 1e-4), with the patches that crossed the focus kept (a
/// split patch straddling a plane counted by each child whose centre crossed it, before
/// the receivers kept a mask of the planes a patch has reached, gave 1.0013). The
/// paper's policy (discard them) loses most of the light beyond the focus: measured, and
/// required to lose at least a quarter there.
/// After every cycle no kept patch spans more than a voxel.
#[test]
fn power_is_conserved_through_a_ball_lens_focus() {
    with_context(|ctx| {
        let n = 48u32;
        let r = 12.0 / n as f32;
        let vol = lens(n, r);
        let tf = glass(1.5);
        let renderer = Renderer::new(ctx, &vol, &tf).unwrap();
        let travel = Vec3::new(0.0, 0.0, -1.0);
        let light = light_along(travel);
        let depths = [0.4f32, 0.1, 0.0, -0.3, -1.5 * r, -0.45];
        let receivers: Vec<Receiver> = depths
            .iter()
            .map(|z| receiver_across(travel, Vec3::new(0.0, 0.0, *z), 1.0, 96))
            .collect();
        let reference = 1.0 / n as f64;
        let mut beyond = Vec::new();
        for policy in [FocusPolicy::Keep, FocusPolicy::Discard] {
            let settings = WavefrontSettings {
                aperture: Some(0.8 * r),
                at_foci: policy,
                ..Default::default()
            };
            let sim = simulate(&renderer, &light, &settings, &receivers);
            let s = &sim.stats;
            let total = launched(&sim, reference)[0];
            println!(
                "{policy:?}: {} patches launched, peak {}, {} cycles, worst span {:.3} voxel, \
                 {} unsplit, {} foci crossed carrying {:.4} of the launched flux, {:.1} ms",
                s.launched,
                s.peak_patches,
                s.cycles,
                s.worst_span,
                s.unsplit,
                s.foci,
                s.at_foci[0] / s.launched_flux[0],
                s.gpu_ms
            );
            let mut ratios = Vec::new();
            for (k, rc) in receivers.iter().enumerate() {
                let p = power(&sim, k, rc);
                println!(
                    "  z = {:+.3}: power {:.5} of the launched",
                    depths[k],
                    p[0] / total
                );
                ratios.push(p[0] / total);
            }
            assert!(
                s.worst_span <= 1.0,
                "a kept patch spans {} voxels",
                s.worst_span
            );
            assert_eq!(s.unsplit, 0, "patches kept whole at the level limit");
            assert_eq!(s.live_at_end, 0, "light still travelling at the end");
            if policy == FocusPolicy::Keep {
                for (k, q) in ratios.iter().enumerate() {
                    assert!(
                        (q - 1.0).abs() <= 0.001,
                        "z = {}: power {q:.4} of the launched",
                        depths[k]
                    );
                }
                assert!(s.foci > 0, "no patch crossed the focus");
            }
            beyond.push(*ratios.last().unwrap());
        }
        assert!(
            beyond[1] <= 0.75 * beyond[0],
            "discarding at foci kept {:.3} of the light beyond the focus (keeping: {:.3})",
            beyond[1],
            beyond[0]
        );
    });
}

/// A uniform tinted medium (η 1, passing 0.9, 0.8, 0.7 per reference step) fills the box:
/// the power of a beam between two planes normal to it falls as Beer–Lambert says,
/// m^(distance / reference step) per channel, within 1 %, along an axis and at 30° to it.
#[test]
fn beam_power_follows_beer_lambert() {
    with_context(|ctx| {
        let n = 32u32;
        let vol = f32_volume(n, |_| 1.0);
        let m = [0.9f32, 0.8, 0.7];
        let tf = TransferFunctions {
            medium: Piecewise::new(vec![(0.0, [1.0, 1.0, 1.0]), (1.0, m)]),
            ..Default::default()
        };
        let renderer = Renderer::new(ctx, &vol, &tf).unwrap();
        let reference = 1.0 / n as f64;
        for angle in [0.0f32, 30.0] {
            let a = angle.to_radians();
            let travel = Vec3::new(a.sin(), 0.0, -a.cos());
            let light = light_along(travel);
            let (c0, c1) = (travel * -0.2, travel * 0.15);
            let receivers = [
                receiver_across(travel, c0, 0.5, 32),
                receiver_across(travel, c1, 0.5, 32),
            ];
            let settings = WavefrontSettings {
                aperture: Some(0.12),
                ..Default::default()
            };
            let sim = simulate(&renderer, &light, &settings, &receivers);
            let (p0, p1) = (power(&sim, 0, &receivers[0]), power(&sim, 1, &receivers[1]));
            let d = (c1 - c0).length() as f64 / reference;
            for c in 0..3 {
                let expected = (m[c] as f64).powf(d);
                let got = p1[c] / p0[c];
                println!(
                    "{angle}°, channel {c}: {got:.6} against {expected:.6} ({:+.3} %)",
                    (got / expected - 1.0) * 100.0
                );
                assert!(
                    (got / expected - 1.0).abs() <= 0.01,
                    "{angle}°, channel {c}: {got} against Beer–Lambert's {expected}"
                );
            }
        }
    });
}

/// A ball lens (η 1.5, radius 16 voxels of 64, a two-voxel ramp) lit along −z by a beam of
/// radius 0.4 R: the fluence on the axis peaks at the paraxial focus nD/(4(n−1)) = 1.5 R
/// from the centre within 3 % (by Snell's law, exactly, the beam's rim crosses the axis at
/// 1.432 R, its paraxial rays at 1.5 R); the light's direction there is along the axis.
/// With the beam at 0.8 R, the peak moves towards the ball, as the aberration says it
/// must. Both through the trilinear field and with η from the cubic B-spline of the values
/// (`RayGradient::Cubic`, the eikonal model's `--cubic-eta 1`), which reproduces the
/// linear ramp and smooths only its corrugation.
#[test]
fn fluence_peaks_at_the_ball_lens_focus() {
    with_context(|ctx| {
        let n = 64u32;
        let r = 16.0 / n as f32;
        let vol = lens(n, r);
        let renderer = Renderer::new(ctx, &vol, &glass(1.5)).unwrap();
        let light = light_along(Vec3::new(0.0, 0.0, -1.0));
        for gradient in [RayGradient::Differences, RayGradient::Cubic] {
            ball_lens_focus(&renderer, &light, n, r, gradient);
        }
    });
}

fn ball_lens_focus(renderer: &Renderer, light: &Light, n: u32, r: f32, gradient: RayGradient) {
    {
        let mut peaks = Vec::new();
        for beam in [0.4f32, 0.8] {
            let settings = WavefrontSettings {
                aperture: Some(beam * r),
                fluence: true,
                gradient,
                ..Default::default()
            };
            let sim = simulate(renderer, light, &settings, &[]);
            let f = sim.fluence.as_ref().unwrap();
            let d = n as usize;
            // The axis x = y = 0 lies between voxel columns 31 and 32: their mean.
            let on_axis = |k: usize| {
                let mut s = 0.0f64;
                for (i, j) in [(31, 31), (31, 32), (32, 31), (32, 32)] {
                    s += f.fluence[(k * d + j) * d + i][0] as f64;
                }
                s / 4.0
            };
            let z_of = |k: usize| (k as f32 + 0.5) / n as f32 - 0.5;
            // Behind the ball only (inside it the light converges but is not focused).
            let (k_best, best) = (0..d)
                .filter(|k| z_of(*k) < -r)
                .map(|k| (k, on_axis(k)))
                .fold((0, f64::MIN), |a, b| if b.1 > a.1 { b } else { a });
            // Parabolic refinement of the peak between voxel centres.
            let (a, c) = (on_axis(k_best - 1), on_axis(k_best + 1));
            let shift = 0.5 * (a - c) / (a - 2.0 * best + c);
            let z_peak = z_of(k_best) + shift as f32 / n as f32;
            let focus = -z_peak / r;
            let dir = f.direction[(k_best * d + 31) * d + 31];
            println!(
                "{gradient:?}, beam {beam} R: axis fluence peaks at {focus:.4} R from the centre \
                 ({best:.2} of the light; paraxial 1.5 R), direction there {dir:?}; {} patches \
                 at peak, worst kept patch {:.2} voxels, {:.1} ms",
                sim.stats.peak_patches, sim.stats.worst_span, sim.stats.gpu_ms
            );
            peaks.push(focus);
            if beam == 0.4 {
                assert!(
                    (focus / 1.5 - 1.0).abs() <= 0.03,
                    "the fluence peaks {focus:.4} R from the centre, not at 1.5 R"
                );
                assert!(best > 10.0, "the focus is only {best} times the light");
                assert!(
                    dir[2] < -0.95,
                    "the light at the focus travels along {dir:?}"
                );
            }
        }
        assert!(
            peaks[1] < peaks[0] - 0.05,
            "a wider beam must focus nearer (spherical aberration): {peaks:?}"
        );
    }
}

/// The validation scene of the caustics (tests/caustics.rs): a clear glass sphere (η 1.5,
/// R = 24 voxels of 64) above an opaque floor, a directional light 23° from the vertical,
/// the floor's irradiance on the plane two voxels above it, seen from straight above.
/// The simulator against the photon tracer on the same volume and plane: the shadow's
/// centre within 1 % R, its semi-axes within 2 % R, the caustic's brightest point within
/// 0.05 R, the mean light in discs of 0.05, 0.1 and 0.2 R around it within 20 %, and the
/// light inside the shadow within 10 %.
#[test]
fn sphere_on_floor_matches_the_photon_tracer() {
    with_context(|ctx| {
        let scene = caustic_scene();
        let (vol, tf, cam, light) = (&scene.volume, &scene.tf, &scene.camera, scene.light);
        let (w, h) = (scene.width, scene.height);
        let depth = scene.floor_depth();
        let r_px = scene.radius_px(depth);
        let opts = RenderOptions {
            width: w as u32,
            height: h as u32,
            lights: vec![light],
            ..Default::default()
        };
        let traced = refrakt::photons::trace_irradiance(
            vol,
            tf,
            cam,
            &opts,
            depth,
            &refrakt::photons::PhotonOptions {
                photons_per_pixel: 16,
                // The receiver counts the flux crossing it.
                plane_flux: true,
                ..Default::default()
            },
            None,
        )
        .unwrap()
        .pixels;
        let renderer = Renderer::new(ctx, vol, tf).unwrap();
        let receiver = Receiver::view_plane(cam, w as u32, h as u32, depth);
        let sim = renderer
            .simulate_light(
                &opts,
                &light,
                &WavefrontSettings::default(),
                &[receiver],
                None,
            )
            .unwrap();
        // The tracer's image is in units of the light crossing a plane parallel to this
        // one; the receiver's, of the light's irradiance square to it: divide by the cosine.
        let cos = light.travel().dot(receiver.u.cross(receiver.v).normalize());
        let simulated: Vec<[f32; 4]> = sim.receivers[0]
            .iter()
            .map(|e| [e[0] / cos, e[1] / cos, e[2] / cos, 1.0])
            .collect();
        let s = &sim.stats;
        println!(
            "simulator: {} patches launched, peak {}, {} cycles, worst span {:.3} ({} kept \
             whole at the level limit), {} foci, {} coarse deposits, {:.1} ms; torn {:.4}, \
             diluted {:.4}, absorbed {:.4}, left {:.4} of the launched flux, {} live at the \
             end; list {:?}",
            s.launched,
            s.peak_patches,
            s.cycles,
            s.worst_span,
            s.unsplit,
            s.foci,
            s.coarse_deposits,
            s.gpu_ms,
            s.torn[0] / s.launched_flux[0],
            s.diluted[0] / s.launched_flux[0],
            s.absorbed[0] / s.launched_flux[0],
            s.left[0] / s.launched_flux[0],
            s.live_at_end,
            s.list_sizes
        );
        if let Ok(dir) = std::env::var("REFRAKT_TEST_DUMP") {
            let dump = |name: &str, img: &[[f32; 4]]| {
                let bytes: Vec<u8> = img
                    .iter()
                    .map(|p| (p[0] / 4.0).clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0)
                    .map(|v| v as u8)
                    .collect();
                image::GrayImage::from_raw(w as u32, h as u32, bytes)
                    .unwrap()
                    .save(format!("{dir}/{name}.png"))
                    .unwrap();
            };
            dump("eikonal-floor", &simulated);
            dump("photons-floor", &traced);
        }
        // The simulator follows light inside the box only (a patch leaving it retires);
        // the tracer lights the plane beyond it too. Both are measured on the square of
        // pixels whose centres lie over the box (x, z within ±0.5).
        let (inner, cw, x0, y0) = {
            let to_px = |p: Vec3| {
                let q = p - receiver.origin;
                (
                    q.dot(receiver.u) / receiver.u.length_squared(),
                    q.dot(receiver.v) / receiver.v.length_squared(),
                )
            };
            let (ax, ay) = to_px(Vec3::new(-0.5, 0.0, -0.5));
            let (bx, by) = to_px(Vec3::new(0.5, 0.0, 0.5));
            let (x0, x1) = (ax.min(bx).ceil() as usize, ax.max(bx).floor() as usize);
            let (y0, y1) = (ay.min(by).ceil() as usize, ay.max(by).floor() as usize);
            (y1 - y0, x1 - x0, x0, y0)
        };
        let crop = |img: &[[f32; 4]]| -> Vec<[f32; 4]> {
            (0..inner)
                .flat_map(|y| (0..cw).map(move |x| (x, y)))
                .map(|(x, y)| img[(y0 + y) * w + x0 + x])
                .collect()
        };
        let (simulated, traced) = (crop(&simulated), crop(&traced));
        let (w, h) = (cw, inner);
        println!("measured over {w} x {h} pixels from ({x0}, {y0})");
        let cmp = compare_floors(&simulated, &traced, w, h, r_px);
        cmp.print("simulator against the photon tracer", "simulator");
        cmp.assert_close("simulator");
    });
}

/// A point light in clear space (η 1, nothing absorbs), outside the box and inside it:
/// the irradiance on a plane is the light's colour × cos θ / r² (the inverse square and
/// cosine laws) within 1 % at every pixel, and the power on the plane is that law's
/// integral within 0.5 %. The pixels are a voxel wide: a patch (up to a voxel) deposits
/// a uniform irradiance, so pixels finer than the patches see the law as steps (half a
/// box from the light, where it changes by about 9 % a voxel: 3 % errors at half-voxel
/// pixels, 5 % at quarter-voxel ones, measured).
#[test]
fn point_light_irradiance_falls_off_with_the_square_of_distance() {
    with_context(|ctx| {
        let n = 32u32;
        let vol = f32_volume(n, |_| 0.0);
        let renderer = Renderer::new(ctx, &vol, &glass(1.5)).unwrap();
        for position in [Vec3::new(0.3, -0.2, 1.2), Vec3::new(0.1, 0.05, 0.2)] {
            let light = Light {
                source: LightSource::Point { position },
                colour: [1.0, 0.5, 0.25],
                softness: 0.0,
            };
            // The plane z = -0.3, normal -z (away from the light), over x, y in ±0.4.
            let px = 24u32;
            let size = 0.8f32;
            let receiver = Receiver {
                origin: Vec3::new(-0.4, 0.4, -0.3),
                u: Vec3::X * (size / px as f32),
                v: -Vec3::Y * (size / px as f32),
                width: px,
                height: px,
            };
            let sim = simulate(
                &renderer,
                &light,
                &WavefrontSettings::default(),
                &[receiver],
            );
            let (mut worst, mut got, mut want) = (0.0f64, 0.0f64, 0.0f64);
            let mut at = (0, 0);
            let area = (size as f64 / px as f64).powi(2);
            for j in 0..px {
                for i in 0..px {
                    // The law averaged over the pixel (4 x 4 points).
                    let mut e = 0.0f64;
                    for b in 0..4 {
                        for a in 0..4 {
                            let p = receiver.origin
                                + receiver.u * (i as f32 + (a as f32 + 0.5) / 4.0)
                                + receiver.v * (j as f32 + (b as f32 + 0.5) / 4.0);
                            let d = (p - position).as_dvec3();
                            let r = d.length();
                            e += (-d.z / r) / (r * r) / 16.0;
                        }
                    }
                    let simulated = sim.receivers[0][(j * px + i) as usize];
                    for (c, colour) in light.colour.iter().enumerate() {
                        let expected = e * *colour as f64;
                        let off = (simulated[c] as f64 / expected - 1.0).abs();
                        if off > worst {
                            worst = off;
                            at = (i, j);
                        }
                    }
                    got += simulated[0] as f64 * area;
                    want += e * area;
                }
            }
            let s = &sim.stats;
            println!(
                "point light at {position}: {} patches launched, peak {}, worst pixel {:.3} % \
                 (at {at:?}), power {:.5} of the law's, {:.1} ms",
                s.launched,
                s.peak_patches,
                worst * 100.0,
                got / want,
                s.gpu_ms
            );
            assert!(
                worst <= 0.01,
                "a pixel is {:.2} % off the law",
                worst * 100.0
            );
            assert!(
                (got / want - 1.0).abs() <= 0.005,
                "power {} of the law's",
                got / want
            );
        }
    });
}

/// A patch budget too small for the wavefront is refused with the count it needed, not
/// cut short: the light a truncated list would drop is not silently lost.
#[test]
fn a_wavefront_over_its_patch_budget_is_refused() {
    with_context(|ctx| {
        let n = 32u32;
        let r = 8.0 / n as f32;
        let vol = lens(n, r);
        let renderer = Renderer::new(ctx, &vol, &glass(1.5)).unwrap();
        let light = light_along(Vec3::new(0.0, 0.0, -1.0));
        let launch = |budget: u32| {
            renderer.simulate_light(
                &RenderOptions::default(),
                &light,
                &WavefrontSettings {
                    max_patches: Some(budget),
                    ..Default::default()
                },
                &[],
                None,
            )
        };
        // The plane wave over a 32³ box is 58 x 58 patches: 512 cannot launch it.
        let e = launch(512).unwrap_err().to_string();
        assert!(e.contains("patch budget is 512"), "{e}");
        // Enough to launch it, too few once the lens' focus makes the list grow.
        let fits = launch(1 << 16).unwrap();
        let peak = fits.stats.peak_patches;
        println!("launched {}, peak {peak}", fits.stats.launched);
        assert!(peak > fits.stats.launched, "the list never grew");
        let budget = fits.stats.launched.div_ceil(256) * 256;
        if budget < peak {
            let e = launch(budget).unwrap_err().to_string();
            assert!(
                e.contains("needed") && e.contains(&budget.to_string()),
                "{e}"
            );
        }
    });
}

/// The clear-space fast path (`WavefrontSettings::clear_space`: corners whose whole cycle
/// stays where one η holds move along lines instead of integrating the ray equation) must
/// give the light the ray equation gives, and must be taken where the light crosses air:
/// - a glass ball lens (η 1.5, radius 12 voxels of 48) lit obliquely by a beam of 0.8 R:
///   on receivers in the ball, at its focus and beyond, the power within 1e-4 of the
///   integrated light's, every 4 × 4 block of pixels within 1e-3 of the brightest block
///   and every pixel within 5e-3 of the brightest (measured 2.6e-4 and 1.5e-3 beyond the
///   focus, where folds make a pixel hang on a patch's tiny area and rounding moves
///   light between neighbours; at the focus 6e-7 and 4.5e-4); the list the same size
///   after every submission; at least 0.3 of the patch-cycles straight (0.338; none
///   without);
/// - a box of tinted glass (η 1.5 throughout, Beer–Lambert per channel): the same number
///   of cycles (lines must move at the ray equation's speed 1 / η, eq. 14, or the light
///   leaves the box sooner or later), the same light at a receiver inside, at least 0.85
///   of the patch-cycles straight (0.893).
#[test]
fn clear_space_lines_give_the_integrated_light() {
    with_context(|ctx| {
        let n = 48u32;
        let r = 12.0 / n as f32;
        let m = [0.9f32, 0.8, 0.7];
        let lens_tf = glass(1.5);
        let tinted = TransferFunctions {
            medium: Piecewise::new(vec![(0.0, [1.0, 1.0, 1.0]), (1.0, m)]),
            ..glass(1.5)
        };
        let travel = Vec3::new(0.25, 0.15, -1.0).normalize();
        let cases = [
            // (name, volume, transfer functions, receivers' depths, beam radius, the
            // least share of straight patch-cycles: measured 0.338 and 0.893)
            (
                "ball lens",
                lens(n, r),
                &lens_tf,
                vec![-0.1f32, -1.5 * r, -0.45],
                0.8 * r,
                0.3,
            ),
            (
                "tinted glass",
                f32_volume(n, |_| 1.0),
                &tinted,
                vec![-0.2f32],
                0.15,
                0.85,
            ),
        ];
        for (name, vol, tf, depths, aperture, least) in cases {
            let renderer = Renderer::new(ctx, &vol, tf).unwrap();
            let light = light_along(travel);
            let receivers: Vec<Receiver> = depths
                .iter()
                .map(|z| receiver_across(travel, Vec3::new(0.0, 0.0, *z), 0.8, 64))
                .collect();
            let run = |clear_space: bool| {
                // Patches launched 0.9 voxels apart: at 1.0 a parallel beam's patches in
                // air span a voxel to rounding, and whether each splits would turn on it.
                let settings = WavefrontSettings {
                    aperture: Some(aperture),
                    clear_space,
                    launch_spacing: 0.9,
                    ..Default::default()
                };
                simulate(&renderer, &light, &settings, &receivers)
            };
            let (lines, curves) = (run(true), run(false));
            let straight = |s: &LightSimulation| {
                s.stats.straight_cycles as f64 / s.stats.patch_cycles.max(1) as f64
            };
            println!(
                "{name}: straight {:.3} of {} patch-cycles ({:.0} ms) against {:.3} of {} \
                 ({:.0} ms); cycles {} / {}",
                straight(&lines),
                lines.stats.patch_cycles,
                lines.stats.gpu_ms,
                straight(&curves),
                curves.stats.patch_cycles,
                curves.stats.gpu_ms,
                lines.stats.cycles,
                curves.stats.cycles
            );
            assert_eq!(
                curves.stats.straight_cycles, 0,
                "{name}: lines with clear_space off"
            );
            assert!(
                straight(&lines) >= least,
                "{name}: only {:.3} of the patch-cycles straight (at least {least})",
                straight(&lines)
            );
            assert_eq!(lines.stats.cycles, curves.stats.cycles, "{name}: cycles");
            assert_eq!(
                lines.stats.list_sizes, curves.stats.list_sizes,
                "{name}: list sizes"
            );
            for (k, rc) in receivers.iter().enumerate() {
                let (a, b) = (power(&lines, k, rc), power(&curves, k, rc));
                let peak = curves.receivers[k]
                    .iter()
                    .map(|e| e[1])
                    .fold(0.0f32, f32::max);
                let worst = lines.receivers[k]
                    .iter()
                    .zip(&curves.receivers[k])
                    .map(|(x, y)| (0..3).map(|c| (x[c] - y[c]).abs()).fold(0.0f32, f32::max))
                    .fold(0.0f32, f32::max);
                // 4 x 4 blocks (green): where a fold makes a pixel's irradiance hang on a
                // patch's tiny area, rounding moves light between neighbouring pixels.
                let blocks = |img: &[[f32; 3]]| {
                    let mut out = vec![0.0f64; 16 * 16];
                    for (i, e) in img.iter().enumerate() {
                        out[(i / 64 / 4) * 16 + (i % 64) / 4] += e[1] as f64;
                    }
                    out
                };
                let (ba, bb) = (blocks(&lines.receivers[k]), blocks(&curves.receivers[k]));
                let block_peak = bb.iter().cloned().fold(0.0, f64::max);
                let block_worst = ba
                    .iter()
                    .zip(&bb)
                    .map(|(x, y)| (x - y).abs())
                    .fold(0.0, f64::max);
                println!(
                    "  receiver at {:+.3}: power {:.6} of the integrated light's, worst pixel \
                     {:.2e} of the brightest ({peak:.3}), worst 4 x 4 block {:.2e}",
                    depths[k],
                    a[1] / b[1],
                    worst / peak,
                    block_worst / block_peak
                );
                assert!(peak > 0.0, "{name}: no light at receiver {k}");
                for c in 0..3 {
                    assert!(
                        (a[c] / b[c] - 1.0).abs() <= 1e-4,
                        "{name}, receiver {k}, channel {c}: power {} against {}",
                        a[c],
                        b[c]
                    );
                }
                assert!(
                    block_worst <= 1e-3 * block_peak && worst <= 5e-3 * peak,
                    "{name}, receiver {k}: a 4 x 4 block {block_worst} off the integrated \
                     light (brightest {block_peak}), a pixel {worst} (brightest {peak})"
                );
            }
        }
    });
}
