//! The single-scattering model (`--model single`, src/render/single): the radiance of a
//! camera ray through a homogeneous block lit by a directional light, against the
//! closed-form single-scattering integral (computed here by quadrature in f64), for two
//! light directions (the transmittance cache is rebuilt when the light moves), forward
//! and isotropic phase functions, and a transfer-function change.

mod common;

use common::{constant_tf, f32_volume, face_on, single_scattering_block, with_context};
use refrakt::render::{Light, Model, RenderOptions, Renderer, ScatterOptions};

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
            let mut opts = RenderOptions {
                width: 33,
                height: 33,
                background: [0.0, 0.0, 0.0, 1.0],
                lights: vec![Light {
                    softness: 0.0,
                    ..Light::directional(t, [1.0; 3])
                }],
                ..Default::default()
            };
            ScatterOptions {
                g: g as f32,
                albedo: albedo as f32,
            }
            .set_in(&mut opts)
            .unwrap();
            let frame = renderer.render(Model::Single, &camera, &opts).unwrap();
            let got = frame.pixel(16, 16)[1] as f64;
            // σ_t per reference step (1/n of the unit cube) → per world unit.
            let k = -(1.0 - alpha).ln() * n as f64;
            let want =
                albedo * single_scattering_block(k, 0.5, [t.x as f64, t.y as f64, t.z as f64], g);
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
