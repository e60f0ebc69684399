//! The single-scattering model (`--model single`, src/render/single): the radiance of a
//! camera ray through a homogeneous block lit by a directional light, against the
//! closed-form single-scattering integral (computed here by quadrature in f64), for two
//! light directions (the transmittance cache is rebuilt when the light moves), forward
//! and isotropic phase functions, and a transfer-function change.

mod common;

use common::{constant_tf, f32_volume, face_on, with_context};
use refrakt::render::{Light, Model, RenderOptions, Renderer, ScatterOptions};

/// L / (light colour · albedo · colour) along the ray through the centre of the cube
/// [-h, h]³ from +z (direction -z), light from `towards` (unit, y and z ≥ 0), extinction
/// `k` per world unit, phase 4π·p_HG(cos θ; g): ∫₀^{2h} k e^{-k t} T_light(t) dt with
/// T_light = e^{-k ℓ(t)}, ℓ the distance from (0, 0, h − t) along `towards` to the
/// cube's face.
fn closed_form(k: f64, h: f64, towards: [f64; 3], g: f64) -> f64 {
    let exit = |t: f64| -> f64 {
        let mut l = f64::INFINITY;
        if towards[1] > 0.0 {
            l = l.min(h / towards[1]);
        }
        if towards[2] > 0.0 {
            l = l.min(t / towards[2]);
        }
        l
    };
    let n = 200_000;
    let dt = 2.0 * h / n as f64;
    let integral: f64 = (0..n)
        .map(|i| {
            let t = (i as f64 + 0.5) * dt;
            k * (-k * t).exp() * (-k * exit(t)).exp() * dt
        })
        .sum();
    let cos = -towards[2]; // towards · (0, 0, -1)
    let d = 1.0 + g * g - 2.0 * g * cos;
    integral * (1.0 - g * g) / (d * d.sqrt())
}

#[test]
fn a_homogeneous_block_matches_the_single_scattering_integral() {
    with_context(|ctx| {
        let n = 33u32;
        let camera = face_on(3.0, 10.0);
        let mut renderer =
            Renderer::new(ctx, &f32_volume(n, |_| 1.0), &constant_tf([1.0; 3], 0.1)).unwrap();
        let cases = [
            (0.1f64, [0.0, 1.0, 1.0], 0.5f64, 1.0f64),
            (0.1, [0.0, 1.0, 0.3], 0.0, 0.9),
            (0.1, [0.0, 0.2, 1.0], -0.3, 0.6),
            (0.04, [0.0, 0.2, 1.0], 0.8, 1.0),
        ];
        for (alpha, towards, g, albedo) in cases {
            renderer
                .set_transfer_functions(&constant_tf([1.0; 3], alpha as f32))
                .unwrap();
            let t = glam::Vec3::from(towards.map(|c: f64| c as f32)).normalize();
            let opts = RenderOptions {
                width: 33,
                height: 33,
                background: [0.0, 0.0, 0.0, 1.0],
                scatter: ScatterOptions {
                    g: g as f32,
                    albedo: albedo as f32,
                },
                sweep: refrakt::render::SweepOptions {
                    light: Light {
                        towards: t,
                        colour: [1.0; 3],
                        softness: 0.0,
                    },
                    ..Default::default()
                },
                ..Default::default()
            };
            let frame = renderer.render(Model::Single, &camera, &opts).unwrap();
            let got = frame.pixel(16, 16)[1] as f64;
            // σ_t per reference step (1/n of the unit cube) → per world unit.
            let k = -(1.0 - alpha).ln() * n as f64;
            let want = albedo * closed_form(k, 0.5, [t.x as f64, t.y as f64, t.z as f64], g);
            eprintln!(
                "alpha {alpha} towards {towards:?} g {g} albedo {albedo}: {got:.5}, closed form {want:.5} ({:+.2} %)",
                100.0 * (got / want - 1.0)
            );
            assert!(
                (got - want).abs() <= 0.02 * want,
                "alpha {alpha}, light {towards:?}, g {g}: rendered {got}, closed form {want}"
            );
        }
    });
}
