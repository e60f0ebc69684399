//! Issue 36, "progress that informs": `render` on a terminal reports the fraction of the
//! frame done while the GPU works (`Renderer::render_observed`). The frame stays one
//! command buffer; the sweep leaves a mark in host-visible memory every 2 % of its planes
//! and the host reads the marks while it waits for the fence.
//!
//! What can go wrong: marks that the host cannot see before the frame ends (timestamp
//! queries on lavapipe: every mark of a 24 s frame turned available at its end, so the
//! bar sat at 0 and jumped to 100 %), fractions that run backwards, or marks whose
//! barriers change the frame.

mod common;

use common::{ball, face_on, frame_options, glass, headlight, with_context};
use refrakt::render::{Model, Renderer, SweepPath};

#[test]
fn the_sweep_reports_its_planes_while_it_runs_and_the_frame_is_unchanged() {
    with_context(|ctx| {
        // A glass ball, forward transport (the default): a frame of a second or more on
        // llvmpipe, so the host polls (every 0.2 s) while planes remain.
        let vol = ball(32, 0.3);
        let tf = glass(1.5);
        let cam = face_on(2.5, 30.0);
        for path in [SweepPath::Fragment, SweepPath::Compute] {
            let mut opts = frame_options(64, 64, 0.5);
            opts.lights = vec![headlight(&cam, 0.0)];
            opts.sweep.levers.sweep = path;
            let mut r = Renderer::new(ctx, &vol, &tf).expect("renderer");
            let plain = r.render(Model::Refract, &cam, &opts).expect("render");
            let mut seen = Vec::new();
            let started = std::time::Instant::now();
            let observed = r
                .render_observed(Model::Refract, &cam, &opts, &mut |f| {
                    seen.push((f, started.elapsed().as_secs_f64()))
                })
                .expect("render");
            let secs = started.elapsed().as_secs_f64();
            let planes = plain.sweep.as_ref().map(|s| s.planes.count).unwrap_or(0);
            println!("{path:?}: {planes} planes, {secs:.2} s, progress {seen:?}");
            let fractions: Vec<f64> = seen.iter().map(|s| s.0).collect();
            assert_eq!(fractions.first(), Some(&0.0), "{path:?}: starts at 0");
            assert_eq!(fractions.last(), Some(&1.0), "{path:?}: ends at 1");
            assert!(
                fractions.windows(2).all(|w| w[0] <= w[1] && w[1] <= 1.0),
                "{path:?}: progress runs backwards: {fractions:?}"
            );
            // Marks pass while the frame runs: something strictly between 0 and 1 was
            // seen, and the last of those no later than 0.3 s before the end (a mark read
            // only at the end would be the final 1).
            let middle: Vec<_> = seen.iter().filter(|s| s.0 > 0.0 && s.0 < 1.0).collect();
            assert!(
                secs < 0.6 || !middle.is_empty(),
                "{path:?}: a {secs:.2} s frame reported nothing between 0 and 1: {seen:?}"
            );
            // Every mark is a step of 2 % of the planes.
            for (f, _) in &middle {
                let steps = f * 50.0;
                assert!(
                    (steps - steps.round()).abs() < 1e-9,
                    "{path:?}: fraction {f} is not a 2 % step"
                );
            }
            assert!(
                plain.pixels == observed.pixels,
                "{path:?}: the marks changed the frame"
            );
        }
    });
}
