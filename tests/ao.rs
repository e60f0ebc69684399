//! The ambient-occlusion model (`--model ao`, src/render/ao): its occlusion against the
//! closed form of nested box averages in a homogeneous medium (inside, at a face, at an
//! edge, outside), rebuilt when the transfer function changes, and what it does to an
//! image: a floor is darker beside an occluder than far from it, where the EA model's
//! floor is not.

mod common;

use common::{constant_tf, f32_volume, with_context};
use refrakt::render::ao::AoOptions;
use refrakt::render::{Camera, Model, RenderOptions, Renderer};

/// Opacity per reference step of the homogeneous medium: 0.25 is exact in any float
/// format the transfer-function texture may use, so σ_t = ln(4/3) exactly.
const ALPHA: f64 = 0.25;

/// The optical depth `glsl/ao.glsl` defines, computed from voxel counts alone: the
/// sample's voxel c reaches 0.5 voxel, then cubes of half-size 1, 2, 4, ... each
/// contribute their shell's mean extinction (the outside of the n³ volume empty) times
/// the radial distance the shell spans.
fn expected_tau(c: [i64; 3], n: i64, sigma: f64, shells: i32) -> f64 {
    let inside = |r: i64| -> f64 {
        (0..3)
            .map(|a| {
                let lo = (c[a] - r).max(0);
                let hi = (c[a] + r).min(n - 1);
                (hi - lo + 1).max(0) as f64
            })
            .product()
    };
    let mut tau = 0.5 * sigma * inside(0);
    let (mut inner, mut inner_volume, mut reach) = (inside(0), 1.0, 0.5);
    for k in 0..shells {
        let r = 1i64 << k;
        let outer = inside(r);
        let outer_volume = ((2 * r + 1) as f64).powi(3);
        let shell = sigma * (outer - inner) / (outer_volume - inner_volume);
        let next = r as f64 + 0.5;
        tau += shell * (next - reach);
        (inner, inner_volume, reach) = (outer, outer_volume, next);
    }
    tau
}

#[test]
fn occlusion_in_a_homogeneous_block_is_the_closed_form_of_its_box_averages() {
    with_context(|ctx| {
        let n = 40u32;
        let volume = f32_volume(n, |_| 1.0);
        let mut renderer =
            Renderer::new(ctx, &volume, &constant_tf([1.0; 3], ALPHA as f32)).expect("renderer");
        // Voxels: deep inside (every cube inside), at a face, at an edge, in a corner, and
        // two outside the volume (the cubes reach in from beyond a face).
        let voxels: [[i64; 3]; 6] = [
            [20, 20, 20],
            [0, 19, 22],
            [2, 39, 17],
            [0, 0, 0],
            [-3, 20, 20],
            [45, 45, 20],
        ];
        let points: Vec<[f32; 3]> = voxels
            .iter()
            .map(|v| v.map(|i| (i as f32 + 0.5) / n as f32))
            .collect();
        for (alpha, radius) in [(ALPHA, 8u32), (ALPHA, 1), (0.5, 4)] {
            if alpha != ALPHA {
                // A new transfer function: the extinction and its table are rebuilt.
                renderer
                    .set_transfer_functions(&constant_tf([1.0; 3], alpha as f32))
                    .unwrap();
            }
            let opts = AoOptions {
                radius,
                ..Default::default()
            };
            let got = renderer.ambient_occlusion_at(&points, &opts).unwrap();
            let sigma = -(1.0 - alpha).ln();
            for (v, g) in voxels.iter().zip(&got) {
                let want = (-expected_tau(*v, n as i64, sigma, opts.shells())).exp();
                eprintln!(
                    "alpha {alpha} radius {radius} voxel {v:?}: AO {g:.6} (closed form {want:.6})"
                );
                assert!(
                    (*g as f64 - want).abs() <= 1e-5 * want.max(1e-3),
                    "alpha {alpha}, radius {radius}, voxel {v:?}: AO {g}, closed form {want}"
                );
            }
            // Deep inside, every cube is full: the transmittance of the whole radius.
            let deep = (-sigma * (radius as f64 + 0.5)).exp();
            assert!((got[0] as f64 - deep).abs() <= 1e-5 * deep.max(1e-3));
        }
    });
}

#[test]
fn a_floor_is_darker_beside_a_ball_than_far_from_it() {
    with_context(|ctx| {
        // A slab floor (y < -0.3) and a ball resting on it off centre, both a light grey
        // medium of moderate opacity; seen from straight above.
        let n = 48;
        let volume = f32_volume(n, |p| {
            let ball = glam::Vec3::new(-0.15, -0.12, 0.0).distance(glam::Vec3::from(p)) < 0.18;
            if p[1] < -0.3 || ball {
                1.0
            } else {
                0.0
            }
        });
        let tf = constant_tf([0.8; 3], 0.3);
        // Value 0 must be empty: a step from 0 to the medium at 0.5.
        let tf = refrakt::transfer::TransferFunctions {
            opacity: refrakt::transfer::Piecewise::new(vec![
                (0.0, [0.0]),
                (0.49, [0.0]),
                (0.5, [0.3]),
                (1.0, [0.3]),
            ]),
            ..tf
        };
        let mut renderer = Renderer::new(ctx, &volume, &tf).expect("renderer");
        let camera = Camera {
            azimuth: 0.0,
            elevation: 89.0,
            distance: 2.5,
            fov_y: 30.0,
            ..Default::default()
        };
        let mut opts = RenderOptions {
            width: 96,
            height: 96,
            background: [0.0, 0.0, 0.0, 1.0],
            ..Default::default()
        };
        AoOptions {
            radius: 8,
            diffuse: 0.0,
        }
        .set_in(&mut opts)
        .unwrap();
        let ao = renderer.render(Model::Ao, &camera, &opts).unwrap();
        let ea = renderer.render(Model::Ea, &camera, &opts).unwrap();
        // Floor pixels along the row through the ball's centre: just beside the ball
        // (its right edge is at x = 0.03 in the volume) and far from it (x = 0.4).
        let column = |x: f32| {
            // The camera looks straight down from above the target: the image's x is
            // the world's x, and the visible half-width at the floor is about
            // tan(15°) * (2.5 + 0.3).
            let half = (15f32).to_radians().tan() * 2.8;
            ((x / half * 0.5 + 0.5) * 96.0) as u32
        };
        let lum = |f: &refrakt::render::Frame, x: f32| {
            let p = f.pixel(column(x), 48);
            0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
        };
        let (near_ao, far_ao) = (lum(&ao, 0.07), lum(&ao, 0.4));
        let (near_ea, far_ea) = (lum(&ea, 0.07), lum(&ea, 0.4));
        eprintln!(
            "AO floor beside the ball {near_ao:.4}, far {far_ao:.4}; EA {near_ea:.4}, {far_ea:.4}"
        );
        // Without occlusion the floor is uniform...
        assert!(
            (near_ea - far_ea).abs() <= 0.01 * far_ea,
            "EA floor {near_ea} vs {far_ea}"
        );
        // ...with it, the ball shades the floor beside it.
        assert!(
            near_ao < 0.9 * far_ao,
            "AO floor beside the ball {near_ao}, far from it {far_ao}"
        );
        assert!(
            far_ao > 0.0 && far_ao < far_ea,
            "AO {far_ao} vs EA {far_ea}"
        );
    });
}
