//! Issue 36: a sweep submitted in batches of planes (the viewer's refinement, which a
//! change of view may abandon between two batches) is the frame submitted whole, bit for
//! bit, on both sweep paths and both light transports: the setup goes with the first
//! batch only, the state waits in the images between submissions, and the composite
//! runs after the last plane.

mod common;

use common::*;
use refrakt::render::{Levers, LightTransport, Model, PlaneBatch, Slot, SweepPath};

#[test]
fn a_sweep_submitted_in_batches_of_planes_is_the_whole_frame() {
    with_context(|ctx| {
        let (scene, mut renderer, cam) = sphere_on_floor_oblique(ctx);
        for (path, transport) in [
            (SweepPath::Compute, LightTransport::Forward),
            (SweepPath::Fragment, LightTransport::Forward),
            (SweepPath::Compute, LightTransport::Backward),
            (SweepPath::Fragment, LightTransport::Backward),
        ] {
            let mut opts = scene.render_options().unwrap();
            opts.width = 40;
            opts.height = 40;
            opts.sweep.light_transport = transport;
            opts.sweep.levers = Levers {
                sweep: path,
                ..Levers::default()
            };
            let whole = renderer.render(Model::Refract, &cam, &opts).unwrap();
            let planes = whole.sweep.as_ref().unwrap().planes.count;
            assert!(planes > 20, "{planes} planes");
            // Uneven batches, the last one asked past the end ("through the last plane").
            let cuts = [0, 1, 4, planes / 2, planes - 1];
            for w in cuts.windows(2) {
                let mut o = opts.clone();
                o.sweep.batch = Some(PlaneBatch {
                    start: w[0],
                    end: w[1],
                });
                ctx.execute(|rec| {
                    renderer.record(rec, Slot::Main, Model::Refract, &cam, &o)?;
                    Ok(())
                })
                .unwrap();
            }
            let mut o = opts.clone();
            o.sweep.batch = Some(PlaneBatch {
                start: planes - 1,
                end: planes + 100,
            });
            let batched = renderer.render(Model::Refract, &cam, &o).unwrap();
            let lit = whole.pixels.iter().filter(|p| p[3] > 0.05).count();
            assert!(lit > 200, "the frame shows the volume ({lit} pixels)");
            let diff = linear_max(&whole.pixels, &batched.pixels);
            eprintln!("{path:?} {transport:?}: {planes} planes in 5 batches, max |Δ| {diff:e}");
            assert_eq!(
                diff, 0.0,
                "{path:?} {transport:?}: batched frame differs by {diff}"
            );
        }
        // A batch that starts past the last plane is refused with the counts.
        let mut opts = scene.render_options().unwrap();
        opts.width = 40;
        opts.height = 40;
        let planes = renderer
            .render(Model::Refract, &cam, &opts)
            .unwrap()
            .sweep
            .unwrap()
            .planes
            .count;
        opts.sweep.batch = Some(PlaneBatch {
            start: planes,
            end: planes + 1,
        });
        let err = format!(
            "{:#}",
            renderer.render(Model::Refract, &cam, &opts).unwrap_err()
        );
        assert!(err.contains(&format!("of {planes} planes")), "{err}");
    });
}
