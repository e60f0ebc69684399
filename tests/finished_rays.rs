//! Issue 31, "finished rays cost nothing": a viewing ray of the forward transport whose
//! opacity reached `termination_alpha` stops (glsl/sweep_plane.glsl): its state is copied
//! to the other layer once, the plane after it finished, and from then on the planes leave
//! its pixel alone (the fragment path discards it, the compute path stores nothing).
//!
//! What can go wrong is the ping-pong: a pixel left alone one plane too early keeps, in
//! the layer the next plane reads, its state from before it finished, and the ray goes on
//! compositing what lies behind, or the last plane leaves its pixel holding a state from
//! before it finished. So: a red front layer that finishes the rays, a green layer behind
//! it, unlit (each sample's colour as it is) over a black background; every pixel is red
//! to at least the termination opacity, with not a trace of green, on both sweep paths,
//! at sample distances 1 and 0.5.

mod common;

use common::{f32_volume, face_on, frame_options, headlight, sweep, with_context};
use refrakt::render::SweepPath;
use refrakt::transfer::{Piecewise, TransferFunctions};

#[test]
fn a_finished_ray_takes_nothing_from_behind() {
    with_context(|ctx| {
        let n = 32u32;
        // The camera is on +z: the front layer (value 0.25, red) is the 8 voxels z > 0.25
        // (its value ramps to the back's over the last voxel, from 7.5 voxels deep); behind
        // it value 0.75, green.
        let vol = f32_volume(n, |p| if p[2] > 0.25 { 0.25 } else { 0.75 });
        let tf = TransferFunctions {
            colour: Piecewise::new(vec![
                (0.0, [1.0, 0.0, 0.0]),
                (0.5, [1.0, 0.0, 0.0]),
                (0.5, [0.0, 1.0, 0.0]),
                (1.0, [0.0, 1.0, 0.0]),
            ]),
            // 0.5 per reference step: opacity 0.99 after 6.64 voxels, a plane or two before
            // the ramp: a ray that went on two planes more would composite green.
            opacity: Piecewise::constant([0.5]),
            ..Default::default()
        };
        let cam = face_on(2.5, 20.0);
        for path in [SweepPath::Fragment, SweepPath::Compute] {
            for sd in [1.0f32, 0.5] {
                let mut opts = frame_options(24, 24, sd);
                opts.background = [0.0, 0.0, 0.0, 1.0];
                opts.sweep.unlit = true;
                opts.lights = vec![headlight(&cam, 0.0)];
                opts.sweep.levers.sweep = path;
                let f = sweep(ctx, &vol, &tf, &cam, &opts);
                // Unlit, a sample's premultiplied colour is its opacity times its colour,
                // so a pixel's red is the opacity its ray reached in the front layer: at
                // least termination_alpha where the ray finished there (every ray does:
                // all enter through the front face). A stale layer read after the ray
                // finished holds less (measured: 0.984 with the copy left out).
                let (mut least_red, mut most_green) = (f32::MAX, 0.0f32);
                for p in &f.pixels {
                    least_red = least_red.min(p[0]);
                    most_green = most_green.max(p[1]);
                }
                println!("{path:?}, sd {sd}: red at least {least_red}, green at most {most_green}");
                assert!(
                    least_red >= opts.termination_alpha - 1e-4 && least_red <= 1.0,
                    "{path:?}, sd {sd}: a pixel's red {least_red}: its ray did not finish"
                );
                assert!(
                    most_green <= 1e-6,
                    "{path:?}, sd {sd}: green {most_green} from behind a finished ray"
                );
            }
        }
    });
}
