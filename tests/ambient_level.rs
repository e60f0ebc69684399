//! Issue 36: the ambient level (`SweepOptions::ambient`, `--ambient-level`, and the
//! environment map's mean irradiance with `--light env`). Every sample receives it
//! unoccluded and returns colour × ambient, as it returns colour × the light's irradiance
//! (the thesis' model has no phase function). So a frame lit by the ambient level alone
//! is, channel by channel, the ambient times the `unlit` diagnostic's frame (light 1
//! everywhere, no highlights), whatever the geometry: the same refracted paths, the same
//! opacities and media, composited the same way.

mod common;

use common::*;
use refrakt::render::{Camera, LightTransport};

#[test]
fn a_frame_lit_by_the_ambient_level_alone_is_the_ambient_times_the_unlit_frame() {
    with_context(|ctx| {
        // A tinted glass ball with a soft surface (opacity and medium colour rise with the
        // value, η to 1.3): layers seen at every angle from the centre to the rim.
        let vol = ball(32, 0.3);
        let mut tf = constant_tf([0.9, 0.6, 0.3], 0.4);
        tf.eta = glass(1.3).eta;
        let cam = Camera {
            azimuth: 30.0,
            elevation: 20.0,
            ..Camera::default()
        };
        let ambient = [0.5, 0.25, 0.125];
        for (transport, sd) in [
            (LightTransport::Forward, 1.0),
            (LightTransport::Backward, 0.5),
        ] {
            let mut opts = frame_options(40, 40, sd);
            opts.background = [0.0; 4];
            opts.sweep.light_transport = transport;
            opts.sweep.reflections = false;
            opts.sweep.specular = 0.0;
            let mut unlit = opts.clone();
            unlit.sweep.unlit = true;
            let base = sweep(ctx, &vol, &tf, &cam, &unlit);
            let mut lit = opts.clone();
            lit.light_mut().colour = [0.0; 3];
            lit.sweep.ambient = ambient;
            let amb = sweep(ctx, &vol, &tf, &cam, &lit);
            let (mut worst, mut seen) = (0.0f32, 0);
            for (b, a) in base.pixels.iter().zip(&amb.pixels) {
                if b[3] < 0.05 {
                    continue;
                }
                seen += 1;
                for k in 0..3 {
                    let expected = ambient[k] * b[k];
                    worst = worst.max((a[k] - expected).abs() / expected.max(1e-3));
                }
            }
            eprintln!("{transport:?} sd {sd}: {seen} pixels, worst relative error {worst:.2e}");
            assert!(seen > 300, "the ball covers {seen} pixels");
            assert!(
                worst < 1e-4,
                "{transport:?}: off by {worst:.2e} of the expected"
            );
        }
    });
}

/// The furnace test: in a uniform environment of radiance L, with the ambient level the
/// environment gives (L) and no light, a white, non-absorbing object returns exactly the
/// light it is bathed in, so it is as bright as the map behind it and vanishes. The object
/// is an opaque white ball with a soft surface (every opacity from 0 to 1 at the rim), η 1;
/// both transports. An ambient level in other units (the mean irradiance π L, say) or one
/// weighted like the light's path through a layer shows the ball.
#[test]
fn a_white_ball_in_a_uniform_environment_lit_by_its_ambient_level_vanishes() {
    use refrakt::render::{Model, Renderer};
    with_context(|ctx| {
        let radiance = 0.3f32;
        let map = environment_from(256, |_| [radiance, radiance, radiance, 1.0]);
        let vol = ball(32, 0.3);
        // Clear outside (value 0), white and opaque inside.
        let tf = refrakt::transfer::TransferFunctions::parse(
            "colour = [[0.0, 1.0, 1.0, 1.0]]\nopacity = [[0.0, 0.0], [0.5, 0.0], [1.0, 1.0]]\n",
            "white ball",
        )
        .unwrap();
        let mut renderer = Renderer::new(ctx, &vol, &tf).unwrap();
        renderer.set_environment(Some(&map)).unwrap();
        let cam = Camera {
            azimuth: 30.0,
            elevation: 20.0,
            ..Camera::default()
        };
        for transport in [LightTransport::Forward, LightTransport::Backward] {
            let mut opts = frame_options(64, 64, 1.0);
            opts.sweep.light_transport = transport;
            opts.sweep.reflections = false;
            opts.sweep.specular = 0.0;
            opts.light_mut().colour = [0.0; 3];
            // Without the ambient level the ball is a black disk on the map: where it is
            // and where its rim lets the map through in part.
            let dark = renderer.render(Model::Refract, &cam, &opts).unwrap();
            let seen = |p: &[f32; 4]| p[0] / radiance;
            let ball_pixels = dark.pixels.iter().filter(|p| seen(p) < 0.95).count();
            let rim = dark
                .pixels
                .iter()
                .filter(|p| (0.05..0.95).contains(&seen(p)))
                .count();
            opts.sweep.ambient = [radiance; 3];
            let f = renderer.render(Model::Refract, &cam, &opts).unwrap();
            let worst = f
                .pixels
                .iter()
                .flat_map(|p| p[..3].iter())
                .map(|c| (c - radiance).abs() / radiance)
                .fold(0.0f32, f32::max);
            eprintln!(
                "{transport:?}: {ball_pixels} pixels of ball, {rim} of its rim, worst {worst:.2e}"
            );
            assert!(
                ball_pixels > 300 && ball_pixels < 3000 && rim > 10,
                "the ball covers {ball_pixels} pixels, its rim {rim}"
            );
            assert!(
                worst < 1e-3,
                "{transport:?}: the ball shows, off by {worst:.2e}"
            );
        }
    });
}

/// The level from a scene file and from the command line reaches the sweep's options;
/// a negative one is refused with the value.
#[test]
fn the_ambient_level_is_read_from_scene_files_and_checked() {
    use refrakt::scene::Scene;
    let path = std::path::Path::new("ambient.toml");
    let text =
        "[volume]\nbuiltin = \"sphere\"\nsize = 16\n[light]\nambient_level = [0.1, 0.2, 0.3]\n";
    let scene = Scene::parse(text, path).unwrap();
    assert_eq!(
        scene.render_options().unwrap().sweep.ambient,
        [0.1, 0.2, 0.3]
    );
    let text = text.replace("0.1, 0.2, 0.3", "0.1, -0.2, 0.3");
    let err = Scene::parse(&text, path)
        .and_then(|s| s.render_options().map(|_| ()))
        .unwrap_err();
    let err = format!("{err:#}");
    assert!(err.contains("ambient") && err.contains("-0.2"), "{err}");
    let o = refrakt(&[
        "render",
        "sphere",
        "--ambient-level",
        "1,-1,0",
        "--volume-size",
        "8",
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && stderr.contains("ambient"),
        "{stderr}"
    );
}
