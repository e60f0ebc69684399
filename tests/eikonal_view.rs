//! The eikonal model's view renderer (render/eikonal_view.rs, glsl/eikonal_view.comp;
//! issue 35 item 2, seed 001 sect. 4.1 and 5.3) lit by the light simulator's fluence
//! volume: a homogeneous block seen through its centre against the closed-form
//! single-scattering integral (Beer–Lambert light, the Henyey–Greenstein phase function),
//! for lights beside, behind and in front of the camera, isotropic, forward and backward
//! phase functions.

mod common;

use common::{f32_volume, face_on, single_scattering_block, with_context};
use glam::Vec3;
use refrakt::light::{Light, LightSource};
use refrakt::render::light_simulator::WavefrontSettings;
use refrakt::render::{RenderOptions, Renderer, ScatterOptions};
use refrakt::transfer::TransferFunctions;

/// White matter of opacity `alpha` per reference step at value 1, clear at value 0 (the
/// value outside the box), η 1.
fn block_tf(alpha: f32) -> TransferFunctions {
    let text =
        format!("colour = [[0.0, 1, 1, 1]]\nopacity = [[0.0, 0.0], [0.9, 0.0], [1.0, {alpha}]]\n");
    TransferFunctions::parse(&text, "block tf").unwrap()
}

/// The radiance through the centre of a homogeneous block, lit by the simulator's light,
/// is the single-scattering integral: within 1 % for every light and phase function (the
/// single model is held to 2 %; measured here: 0.10–0.58 %). Breaks it (the angle turned
/// round: +586 %): a phase function not normalised (mean 1 over the
/// sphere), the angle taken against the light's direction the wrong way round (g and -g
/// swap), the light volume read a voxel off, light attenuated as it travels in the clear
/// space outside the box.
#[test]
fn a_homogeneous_block_matches_the_single_scattering_integral() {
    with_context(|ctx| {
        let n = 33u32;
        let camera = face_on(3.0, 10.0);
        let volume = f32_volume(n, |_| 1.0);
        let mut renderer = Renderer::new(ctx, &volume, &block_tf(0.1)).unwrap();
        // (opacity, towards the light, g, albedo): beside and behind the camera (z > 0),
        // in front of it (z < 0: forward scattering towards the eye).
        let cases = [
            (0.1f64, [0.0, 1.0, 1.0], 0.5f64, 1.0f64),
            (0.1, [0.0, 1.0, 0.3], 0.0, 0.9),
            (0.1, [0.0, 0.2, 1.0], -0.3, 0.6),
            (0.04, [0.0, 0.2, 1.0], 0.8, 1.0),
            (0.04, [0.0, 0.3, -1.0], 0.8, 1.0),
            (0.04, [0.0, 0.3, -1.0], -0.8, 1.0),
        ];
        for (alpha, towards, g, albedo) in cases {
            renderer
                .set_transfer_functions(&block_tf(alpha as f32))
                .unwrap();
            let t = Vec3::from(towards.map(|c: f64| c as f32)).normalize();
            let light = Light {
                source: LightSource::Directional { towards: t },
                colour: [1.0; 3],
                softness: 0.0,
            };
            let mut opts = RenderOptions {
                width: 33,
                height: 33,
                background: [0.0, 0.0, 0.0, 1.0],
                ..Default::default()
            };
            ScatterOptions {
                g: g as f32,
                albedo: albedo as f32,
            }
            .set_in(&mut opts)
            .unwrap();
            let settings = WavefrontSettings {
                fluence: true,
                ..Default::default()
            };
            let sim = renderer
                .simulate_light(&opts, &light, &settings, &[], None)
                .unwrap();
            let fluence = sim.fluence.as_ref().unwrap();
            let frame = renderer
                .render_eikonal_view(&opts, &camera, fluence)
                .unwrap();
            let got = frame.pixels[16 * 33 + 16][1] as f64;
            let k = -(1.0 - alpha).ln() * n as f64;
            let tn = [t.x as f64, t.y as f64, t.z as f64];
            let want = albedo * single_scattering_block(k, 0.5, tn, g);
            eprintln!(
                "alpha {alpha} towards {towards:?} g {g} albedo {albedo}: {got:.5}, closed form \
                 {want:.5} ({:+.2} %)",
                100.0 * (got / want - 1.0)
            );
            assert!(
                (got - want).abs() <= 0.01 * want,
                "alpha {alpha}, light {towards:?}, g {g}: rendered {got}, closed form {want}"
            );
        }
    });
}

/// Viewing rays bend as the CPU photon tracer's do: a clear glass ball lens (η 1.5, a
/// two-voxel ramp) seen face on against an environment whose radiance is linear in the
/// direction, (1 + d) / 2, so each pixel reads the direction its ray leaves the box with.
/// The reference: the CPU tracer's ray through the same pixel centre at a step of 0.02
/// voxel (converged). Rays whose exit the tracer itself cannot pin down (a 0.2 mrad turn
/// of the start moves it more than 20 mrad: the rim, where a ray grazing the ramp either
/// skims it or dives in) and rays the lens turns back are left out, and counted. At every
/// sample distance the 95th percentile of the others' errors is bounded, and at the finest
/// their worst: RK4's error through the ramp, shrinking with the step. Measured: sample
/// distance 0.5, 0.25, 0.1: 95th percentile 25.4, 4.6, 0.49 mrad; worst at 0.1 1.4 mrad,
/// where the lens turns rays by up to 1.5 rad. Breaks it: the gradient's sign turned
/// (rays bend away), the environment read in the ray's entry direction.
#[test]
fn viewing_rays_refract_as_the_photon_tracer_traces_them() {
    use refrakt::render::light_simulator::FluenceVolume;
    use refrakt::transfer::Piecewise;
    with_context(|ctx| {
        let n = 48u32;
        let r = 0.3f32;
        let volume = f32_volume(n, |p| 0.5 + (r - Vec3::from(p).length()) * n as f32 / 2.0);
        let tf = TransferFunctions {
            eta: Piecewise::new(vec![(0.0, [1.0]), (1.0, [1.5])]),
            opacity: Piecewise::new(vec![(0.0, [0.0])]),
            ..Default::default()
        };
        let mut renderer = Renderer::new(ctx, &volume, &tf).unwrap();
        let env = common::environment_from(1024, |d| {
            [0.5 * (1.0 + d.x), 0.5 * (1.0 + d.y), 0.5 * (1.0 + d.z), 1.0]
        });
        renderer.set_environment(Some(&env)).unwrap();
        let camera = face_on(2.0, 24.0);
        let (w, h) = (24u32, 24u32);
        let (eye, forward, right, up) = camera.frame();
        let tan_half = (camera.fov_y.to_radians() * 0.5).tan();
        let field = refrakt::photons::Field::new(&volume, &tf, &RenderOptions::default()).unwrap();
        let exit = |dir: Vec3| {
            field
                .trace_ray(&camera, eye, dir, camera.distance + 1.0, 0.02)
                .unwrap()
                .map(|e| e.direction)
        };
        // Per pixel: the reference exit direction where it is well conditioned.
        let (mut turned, mut bent, mut back, mut unsure) = (0.0f32, 0, 0, 0);
        let mut reference = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let ndc = glam::Vec2::new(
                    (x as f32 + 0.5) / w as f32 * 2.0 - 1.0,
                    (y as f32 + 0.5) / h as f32 * 2.0 - 1.0,
                );
                let dir = (forward + ndc.x * tan_half * right - ndc.y * tan_half * up).normalize();
                let nudged = (dir + 2e-4 * right).normalize();
                let end = match (exit(dir), exit(nudged)) {
                    (Some(a), Some(b)) if a.angle_between(b) < 0.02 => Some(a),
                    (Some(_), Some(_)) => {
                        unsure += 1;
                        None
                    }
                    _ => {
                        back += 1;
                        None
                    }
                };
                if let Some(e) = end {
                    let turn = e.angle_between(dir);
                    turned = turned.max(turn);
                    bent += (turn > 0.01) as u32;
                }
                reference.push(end);
            }
        }
        eprintln!(
            "{bent} of {} rays turned by the lens (up to {turned:.3} rad), {back} turned back, \
             {unsure} ill-conditioned",
            w * h
        );
        assert!(
            turned > 1.0 && bent > 150,
            "the lens hardly bends the rays: {turned} rad"
        );
        assert!(
            unsure + back <= 40,
            "{unsure} + {back} of the rays left out"
        );
        let voxels = (n * n * n) as usize;
        let dark = FluenceVolume {
            dims: [n; 3],
            fluence: vec![[0.0; 3]; voxels],
            direction: vec![[0.0; 3]; voxels],
        };
        for (sd, p95_bound, worst_bound) in [
            (0.5f32, 0.035, None),
            (0.25, 0.008, None),
            (0.1, 0.001, Some(0.003)),
        ] {
            let opts = RenderOptions {
                width: w,
                height: h,
                sample_distance: sd,
                ..Default::default()
            };
            let frame = renderer.render_eikonal_view(&opts, &camera, &dark).unwrap();
            let mut errors: Vec<f32> = frame
                .pixels
                .iter()
                .zip(&reference)
                .filter_map(|(p, e)| {
                    let seen = Vec3::new(2.0 * p[0] - 1.0, 2.0 * p[1] - 1.0, 2.0 * p[2] - 1.0);
                    e.map(|e| seen.normalize().angle_between(e))
                })
                .collect();
            errors.sort_by(f32::total_cmp);
            let p95 = errors[(errors.len() - 1) * 95 / 100];
            let worst = *errors.last().unwrap();
            eprintln!(
                "sample distance {sd}: direction error 95th percentile {:.2} mrad, worst {:.2} mrad",
                1e3 * p95,
                1e3 * worst
            );
            assert!(
                p95 <= p95_bound,
                "sample distance {sd}: 95th percentile {p95} rad"
            );
            if let Some(b) = worst_bound {
                assert!(worst <= b, "sample distance {sd}: a ray {worst} rad off");
            }
        }
    });
}
