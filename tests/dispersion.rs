//! Dispersion in the eikonal model (`--abbe`; render/eikonal/dispersion.rs, issue 35
//! item 3): each colour channel's light and viewing rays run through the field of that
//! channel's refractive index. A white beam through a prism fans out as Snell's law says
//! for each channel's index; a dispersive frame is, channel by channel, the frame of that
//! channel's index alone, light and view. The indices are computed here from the Abbe
//! number's definition and Cauchy's formula, independently of the renderer's.

mod common;

use common::{f32_volume, face_profile, glass_wedge, with_context};
use glam::Vec3;
use refrakt::light::{Light, LightSource};
use refrakt::render::light_simulator::{Receiver, WavefrontSettings};
use refrakt::render::{Model, RenderOptions, Renderer, SweepOptions};
use refrakt::transfer::{Piecewise, TransferFunctions};

/// The Abbe number used: beyond any glass (dense flints reach about 18), so that the fan
/// stands well clear of the simulator's error at a voxelised face.
const ABBE: f64 = 6.0;

/// The refractive index per channel (red, green, blue: the C, d and F lines) of a glass
/// of index `n_d` and Abbe number `v`: n_F − n_C = (n_d − 1) / v, the index following
/// Cauchy's A + B / λ² through the three lines.
fn indices(n_d: f64, v: f64) -> [f64; 3] {
    let l2 = [656.27f64, 587.56, 486.13].map(|l| 1.0 / (l * l));
    let b = (n_d - 1.0) / v / (l2[2] - l2[0]);
    let a = n_d - b * l2[1];
    l2.map(|x| a + b * x)
}

/// Render options asking for dispersion with Abbe number `v`.
fn dispersive(mut opts: RenderOptions, v: f64) -> RenderOptions {
    opts.models
        .set(&refrakt::render::eikonal::dispersion::ABBE, v)
        .unwrap();
    opts
}

/// The refractive-index scale that gives channel c of a glass of index `n_d` its index.
fn channel_scales(n_d: f64, v: f64) -> [f32; 3] {
    indices(n_d, v).map(|n| ((n - 1.0) / (n_d - 1.0)) as f32)
}

/// A white beam (radius 0.12) travelling −z enters a glass prism (η 1.5 at the d line)
/// through the face z = 0.45 at normal incidence and leaves through a face tilted 30°
/// (a tanh ramp of 3 voxels), each colour at its own index. The centroid of its flux on
/// two planes below the prism gives each channel's direction: the deviation
/// asin(n_c sin 30°) − 30° within 0.5° per channel, and the fan, blue's deviation less
/// red's (3.67° at V = 6), within 15 %: at 64³ and at 32³ (where the face's ramp reaches
/// the box's face, so the light enters across a step of η at the box's boundary), with
/// the simulator's step of 0.5 and 0.25 reference steps. Measured: within 0.11–0.28° per
/// channel, fans 2.3–10.7 % wide (without dispersion: none). Breaks it: a step's kick not brought back to |v| = η
/// along its direction (glsl/light_wavefront_step.comp, `on_shell`): at 32³ the light left
/// the face 4.8° short at step 0.5 and 0.5° over at 0.25.
#[test]
fn a_white_beam_through_a_prism_fans_out_as_snell_s_law_says() {
    with_context(|ctx| {
        let n = indices(1.5, ABBE);
        let snell = n.map(|n| ((n * 0.5).asin() - 30f64.to_radians()).to_degrees());
        let snell_fan = snell[2] - snell[0];
        let scales = channel_scales(1.5, ABBE);
        let light = Light {
            source: LightSource::Directional { towards: Vec3::Z },
            colour: [1.0; 3],
            softness: 0.0,
        };
        // Planes normal to the light below the prism's exit face, 1 × 1 in 128² pixels.
        let depths = [-0.36f32, -0.48];
        let plane = |z: f32| Receiver {
            origin: Vec3::new(-0.5, 0.5, z),
            u: Vec3::X / 128.0,
            v: -Vec3::Y / 128.0,
            width: 128,
            height: 128,
        };
        let receivers = depths.map(plane);
        for size in [64u32, 32] {
            let volume = glass_wedge(size, 30.0, Some(3.0));
            let renderer = Renderer::new(ctx, &volume, &common::glass(1.5)).unwrap();
            for step in [0.5f32, 0.25] {
                if size == 64 && step != 0.5 {
                    continue;
                }
                let settings = WavefrontSettings {
                    aperture: Some(0.12),
                    step,
                    substeps: (2.0 / step) as u32,
                    ..Default::default()
                };
                let mut deviation = [0.0f64; 3];
                for c in 0..3 {
                    let opts = RenderOptions {
                        sweep: SweepOptions {
                            eta_scale: scales[c],
                            ..Default::default()
                        },
                        ..Default::default()
                    };
                    let sim = renderer
                        .simulate_light(&opts, &light, &settings, &receivers, None)
                        .unwrap();
                    // The flux-weighted mean x on each plane.
                    let centroid = |k: usize| {
                        let (mut sum, mut moment) = (0.0f64, 0.0f64);
                        for (i, e) in sim.receivers[k].iter().enumerate() {
                            let x = ((i % 128) as f64 + 0.5) / 128.0 - 0.5;
                            sum += e[c] as f64;
                            moment += e[c] as f64 * x;
                        }
                        moment / sum
                    };
                    let shift = centroid(0) - centroid(1);
                    deviation[c] = (shift / (depths[0] - depths[1]) as f64).atan().to_degrees();
                }
                let fan = deviation[2] - deviation[0];
                eprintln!(
                    "{size}³, step {step}: deviation {deviation:.3?}°, Snell {snell:.3?}°; fan \
                     {fan:.3}° against {snell_fan:.3}°"
                );
                for c in 0..3 {
                    assert!(
                        (deviation[c] - snell[c]).abs() <= 0.5,
                        "{size}³, step {step}: channel {c} (η {}) deviated {}° where Snell's \
                         law gives {}°",
                        n[c],
                        deviation[c],
                        snell[c]
                    );
                }
                assert!(
                    (fan / snell_fan - 1.0).abs() <= 0.15,
                    "{size}³, step {step}: the fan is {fan}° wide where Snell's law gives \
                     {snell_fan}°"
                );
            }
        }
    });
}

/// Light and view, channel by channel: in a 24³ prism in a faint fog (the light refracted
/// into it, viewing rays refracted through the glass on their way), each channel of the
/// frame with `--abbe 6` is that channel of the frame rendered without dispersion at that
/// channel's index (its refractive-index scale), within 1e-5 of the level; and the
/// channels differ from one another by far more (dispersion is there to see). g = 0:
/// with one light direction per voxel, a voxel's direction mixes the channels' (the
/// phase function then reads the mix; isotropic scattering does not read it). Measured:
/// equal to the bit; the channels apart by up to 0.83 of the level. Breaks it: every
/// channel's light taken from the green wavefront (red off by 7.4 % of the level), blue's
/// viewing rays traced at green's index (off by 86 %).
#[test]
fn each_channel_of_a_dispersive_frame_is_the_frame_at_its_own_index() {
    with_context(|ctx| {
        let n = 24u32;
        let alpha = 30f32.to_radians();
        let normal = Vec3::new(alpha.sin(), 0.0, -alpha.cos());
        let volume = f32_volume(n, |p| {
            let p = Vec3::from(p);
            let entry = 0.3 - p.z;
            let exit = -(p - Vec3::new(0.0, 0.0, -0.1)).dot(normal);
            face_profile(entry.min(exit) * n as f32, Some(2.0))
        });
        // η 1 → 1.5 over values 0..1, a faint white fog in the air only.
        let tf = TransferFunctions {
            eta: Piecewise::new(vec![(0.0, [1.0]), (1.0, [1.5])]),
            opacity: Piecewise::new(vec![(0.0, [0.02]), (0.1, [0.0])]),
            colour: Piecewise::new(vec![(0.0, [1.0, 1.0, 1.0])]),
            ..Default::default()
        };
        let mut renderer = Renderer::new(ctx, &volume, &tf).unwrap();
        // Seen from above and aside, through the glass, lit from the side of the entry
        // face.
        let camera = refrakt::camera::Camera {
            azimuth: 20.0,
            elevation: 25.0,
            distance: 2.5,
            fov_y: 35.0,
            ..Default::default()
        };
        let base = RenderOptions {
            width: 32,
            height: 32,
            sample_distance: 0.5,
            background: [0.0, 0.0, 0.0, 1.0],
            lights: vec![Light {
                source: LightSource::Directional { towards: Vec3::Z },
                colour: [1.0; 3],
                softness: 0.0,
            }],
            ..Default::default()
        };
        let split = renderer
            .render(Model::Eikonal, &camera, &dispersive(base.clone(), ABBE))
            .unwrap();
        let level = split.pixels.iter().map(|p| p[1]).fold(0.0f32, f32::max);
        assert!(level > 0.0, "the frame is black");
        let scales = channel_scales(1.5, ABBE);
        let mut apart = 0.0f32;
        for c in 0..3 {
            let opts = RenderOptions {
                sweep: SweepOptions {
                    eta_scale: scales[c],
                    ..base.sweep.clone()
                },
                ..base.clone()
            };
            let alone = renderer.render(Model::Eikonal, &camera, &opts).unwrap();
            let worst = split
                .pixels
                .iter()
                .zip(&alone.pixels)
                .map(|(a, b)| (a[c] - b[c]).abs())
                .fold(0.0f32, f32::max);
            eprintln!(
                "channel {c} (scale {}): worst difference {:.2e} of the level",
                scales[c],
                worst / level
            );
            assert!(
                worst <= 1e-5 * level,
                "channel {c}: the dispersive frame differs from the frame at its index by {} \
                 ({} of the level)",
                worst,
                worst / level
            );
            if c == 1 {
                apart = split
                    .pixels
                    .iter()
                    .map(|p| (p[0] - p[1]).abs().max((p[2] - p[1]).abs()))
                    .fold(0.0f32, f32::max);
            }
        }
        eprintln!("channels apart by up to {:.3} of the level", apart / level);
        assert!(
            apart >= 0.02 * level,
            "the channels of the dispersive frame differ by only {} of the level",
            apart / level
        );
    });
}
