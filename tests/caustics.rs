//! Issue 12: the forward light transport against physics and against the CPU photon
//! tracer (src/photons.rs): power conserved through a focus, total internal reflection,
//! the paraxial focus of a ball lens at every sample distance, and the caustic of a glass
//! sphere on a floor.

mod common;

use common::*;
use glam::Vec3;
use refrakt::render::{
    Camera, Frame, Light, LightTransport, Model, Planes, RenderOptions, Renderer, StateBuffer,
    SweepOptions,
};
use refrakt::transfer::{Piecewise, TransferFunctions};
use refrakt::vk::Context;
use refrakt::volume::Volume;

fn sweep(
    ctx: &Context,
    vol: &Volume,
    tf: &TransferFunctions,
    cam: &Camera,
    opts: &RenderOptions,
) -> Frame {
    let mut r = Renderer::new(ctx, vol, tf).unwrap();
    r.render(Model::Refract, cam, opts).unwrap()
}

fn glass(eta: f32) -> TransferFunctions {
    TransferFunctions {
        eta: Piecewise::new(vec![(0.0, [1.0]), (1.0, [eta])]),
        ..Default::default()
    }
}

fn headlight(cam: &Camera, softness: f32) -> Light {
    Light {
        towards: cam.eye().normalize(),
        colour: [1.0; 3],
        softness,
    }
}

/// Mean of channel 0 over every pixel of a light-colour dump.
fn mean_light(f: &Frame, plane: u32) -> f64 {
    let d = f
        .dumps
        .iter()
        .find(|d| d.buffer == StateBuffer::LightColour && d.plane == plane)
        .unwrap();
    d.pixels.iter().map(|p| p[0] as f64).sum::<f64>() / d.pixels.len() as f64
}

/// A biconvex glass lens (η 1.5, nothing absorbs; two spheres of radius 0.4 whose centres
/// are 0.3 either side of the middle, cut to a radius of 0.18 so that no ray meets its
/// exit beyond the critical angle) lit along the view axis focuses its light about 0.35
/// behind its centre, inside the box, and the rays cross there and spread again. The frustum is wide enough that no light leaves it, so the mean
/// irradiance over the viewport (the power through the plane over its area) must stay that
/// of the unobstructed light on every plane: in front of the lens, inside it, through the
/// focus where rays cross, and beyond. (A full ball is not used: its rim rays meet the
/// exit at the critical angle, where a discrete normal decides between transmission and
/// total reflection; see docs/NOTES.md.)
#[test]
#[ignore = "open (issue 12): the forward transport drops 1.5-2 % of the power at the lens exit"]
fn power_is_conserved_through_a_focus() {
    with_context(|ctx| {
        let n = 48u32;
        let (rs, off) = (0.4f32, 0.3f32);
        let vol = f32_volume(n, |p| {
            let p = Vec3::from(p);
            let a = rs - (p - Vec3::new(0.0, 0.0, off)).length();
            let b = rs - (p + Vec3::new(0.0, 0.0, off)).length();
            let rim = 0.18 - (p.x * p.x + p.y * p.y).sqrt();
            0.5 + a.min(b).min(rim) * n as f32
        });
        let tf = glass(1.5);
        let cam = face_on(3.0, 24.0);
        let planes = Planes::for_box(&cam, Vec3::splat(0.5), 1.0 / n as f32).unwrap();
        for softness in [0.0f32, 1.0] {
            let mut opts = RenderOptions {
                width: 64,
                height: 64,
                ..Default::default()
            };
            opts.sweep = SweepOptions {
                light_transport: LightTransport::Forward,
                light: headlight(&cam, softness),
                dumps: (0..planes.count)
                    .map(|p| (StateBuffer::LightColour, p))
                    .collect(),
                ..Default::default()
            };
            let f = sweep(ctx, &vol, &tf, &cam, &opts);
            let stats = f.sweep.as_ref().unwrap();
            println!("softness {softness}: clamps {:?}", stats.clamps);
            let mut worst = 0.0f64;
            let mut peak = 0.0f32;
            for p in 0..planes.count {
                let m = mean_light(&f, p);
                worst = worst.max((m - 1.0).abs());
                let d = f.dumps.iter().find(|d| d.plane == p).unwrap();
                peak = peak.max(d.pixels.iter().map(|q| q[0]).fold(0.0, f32::max));
                if p % 6 == 0 {
                    println!(
                        "softness {softness}: plane {p} depth {:.3}: mean {m:.5}",
                        planes.depth(p)
                    );
                }
            }
            println!(
                "softness {softness}: worst power error {:.3} %, brightest {peak:.1}",
                worst * 100.0
            );
            // The lens must really focus (otherwise nothing crossed).
            assert!(peak > 20.0, "no focus: brightest irradiance {peak}");
            assert!(
                worst <= 0.01,
                "softness {softness}: power off by {:.2} %",
                worst * 100.0
            );
        }
    });
}
