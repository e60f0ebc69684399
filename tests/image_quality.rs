//! Issue 13 (open): clean images. A flat lit floor must not be striped at the plane
//! spacing. Measured for both light transports; the forward transport's goal is an
//! ignored test until its light grid resolves oblique light (docs/NOTES.md).

mod common;

use common::*;
use glam::Vec3;
use refrakt::render::{
    Camera, Light, LightTransport, Model, RenderOptions, Renderer, SweepOptions,
};
use refrakt::transfer::{Piecewise, TransferFunctions};
use refrakt::vk::Context;

/// A flat opaque white floor (its top at world y = -0.2, a one-voxel ramp) lit from
/// straight above, seen `angle` degrees from its normal. Returns the detrended row-to-row
/// variation of the lit floor's brightness, relative to its level: the RMS of the
/// differences between consecutive row means after removing a quadratic trend over the
/// rows (the floor's real brightness changes smoothly with distance: fog-free, it should
/// not change at all, but the perspective makes far rows average more of the floor).
/// `thin`: the opacity rises over a fifth of the surface's one-voxel ramp (a hard
/// surface); otherwise over all of it.
fn floor_banding(
    ctx: &Context,
    angle: f32,
    softness: f32,
    transport: LightTransport,
    thin: bool,
) -> f64 {
    let n = 64u32;
    let vol = f32_volume(n, |p| 0.5 + (-0.2 - p[1]) * n as f32);
    let opacity = if thin {
        vec![(0.0, [0.0]), (0.4, [0.0]), (0.6, [1.0])]
    } else {
        vec![(0.0, [0.0]), (1.0, [1.0])]
    };
    let tf = TransferFunctions {
        opacity: Piecewise::new(opacity),
        ..Default::default()
    };
    let cam = Camera {
        azimuth: 0.0,
        elevation: 90.0 - angle,
        distance: 2.0,
        // The top surface only, about ±0.3 around the target along the floor.
        fov_y: 2.0
            * (0.3 * (90.0 - angle).to_radians().sin() / 2.0)
                .atan()
                .to_degrees(),
        target: Vec3::new(0.0, -0.2, 0.0),
    };
    let (w, h) = (96u32, 96u32);
    let mut opts = RenderOptions {
        width: w,
        height: h,
        background: [0.0, 0.0, 0.0, 1.0],
        ..Default::default()
    };
    opts.sweep = SweepOptions {
        light_transport: transport,
        light: Light {
            towards: Vec3::Y,
            colour: [1.0; 3],
            softness,
        },
        specular: 0.0,
        ..Default::default()
    };
    let mut r = Renderer::new(ctx, &vol, &tf).unwrap();
    let f = r.render(Model::Refract, &cam, &opts).unwrap();
    // Row means over the central half of the columns, for rows showing the floor.
    let mut rows = Vec::new();
    for y in 0..h {
        let (mut s, mut c) = (0.0f64, 0);
        for x in w / 4..3 * w / 4 {
            let p = f.pixel(x, y);
            if p[3] > 0.99 {
                s += p[0] as f64;
                c += 1;
            }
        }
        if c == w / 2 {
            rows.push((y as f64, s / c as f64));
        }
    }
    assert!(rows.len() > 40, "too few floor rows ({})", rows.len());
    // Least-squares quadratic trend.
    let fit = |x: f64, c: &[f64; 3]| c[0] + c[1] * x + c[2] * x * x;
    let (mut m, mut rhs) = (glam::DMat3::ZERO, glam::DVec3::ZERO);
    for &(x, v) in &rows {
        let b = glam::DVec3::new(1.0, x, x * x);
        m += glam::DMat3::from_cols(b * b.x, b * b.y, b * b.z);
        rhs += b * v;
    }
    let sol = m.inverse() * rhs;
    let c = [sol.x, sol.y, sol.z];
    let level = rows.iter().map(|r| r.1).sum::<f64>() / rows.len() as f64;
    let res: Vec<f64> = rows.iter().map(|&(x, v)| v - fit(x, &c)).collect();
    let diffs: Vec<f64> = res.windows(2).map(|p| p[1] - p[0]).collect();
    let rms = (diffs.iter().map(|d| d * d).sum::<f64>() / diffs.len() as f64).sqrt();
    println!(
        "{} {} floor at {angle}° softness {softness}: level {level:.4}, row-to-row {:.3} % \
         (max {:.3} %)",
        transport.name(),
        if thin { "thin" } else { "soft" },
        100.0 * rms / level,
        100.0 * diffs.iter().fold(0.0f64, |a, d| a.max(d.abs())) / level
    );
    rms / level
}

/// The thesis' backward step on a floor whose opacity rises over its whole one-voxel
/// surface ramp, seen 60° and 75° from its normal: within 1.5 % row to row (measured 1.0 %
/// and 1.4 %). Its hard-surface case measures 18–25 % (printed, the issue-13 goal).
#[test]
fn the_thesis_step_keeps_a_soft_floor_unstriped() {
    with_context(|ctx| {
        for angle in [60.0f32, 75.0] {
            for softness in [0.0f32, 1.0] {
                let b = floor_banding(ctx, angle, softness, LightTransport::Backward, false);
                assert!(
                    b <= 0.015,
                    "{angle}° softness {softness}: {:.2} %",
                    b * 100.0
                );
                floor_banding(ctx, angle, softness, LightTransport::Backward, true);
            }
        }
    });
}

/// Issue 13's goal for the default transport: a lit floor varies row to row by at most
/// 1 % of its level. Open: the forward transport's irradiance lives on its rays' boxes,
/// which the viewing rays sample at the plane spacing; with a ray per pixel of plane 0
/// (within a budget of 4 rays per screen pixel) soft floors vary by a few per cent and
/// hard ones by more (docs/NOTES.md has the figures).
#[test]
#[ignore = "open (issue 13): lit surfaces still striped under the forward transport"]
fn the_forward_transport_keeps_a_floor_unstriped() {
    with_context(|ctx| {
        let mut worst = 0.0f64;
        for thin in [false, true] {
            for angle in [60.0f32, 75.0] {
                for softness in [0.0f32, 1.0] {
                    let b = floor_banding(ctx, angle, softness, LightTransport::Forward, thin);
                    worst = worst.max(b);
                }
            }
        }
        assert!(
            worst <= 0.01,
            "worst row-to-row variation {:.2} %",
            worst * 100.0
        );
    });
}
