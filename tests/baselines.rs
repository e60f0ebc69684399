//! A soft blob of tinted fog lit from the side: no surface, no change of η, so the sweep
//! uses none of its optics past the thesis' Algorithm 1. The benchmark skeleton
//! (`SweepOptions::skeleton`, `bench thesis --baselines`), which makes Algorithm 1's
//! fetches and plain arithmetic only, renders what the sweep renders there, and the floor
//! (which only moves the state) does not: the baselines are what docs/BENCH.md says.

mod common;

use common::with_context;
use refrakt::output::to_srgb8;
use refrakt::render::{Camera, Frame, Light, LightTransport, Model, RenderOptions, Renderer};
use refrakt::tone::ToneMap;
use refrakt::transfer::TransferFunctions;
use refrakt::vk::Context;

/// Mean |Δ| of display values (sRGB, 8 bit), in display range, over the colour channels.
fn mean_display_diff(a: &Frame, b: &Frame, tone: &ToneMap) -> f64 {
    let (a, b) = (to_srgb8(a, tone), to_srgb8(b, tone));
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (k, (x, y)) in a.iter().zip(&b).enumerate() {
        if k % 4 != 3 {
            sum += (*x as f64 - *y as f64).abs() / 255.0;
            n += 1;
        }
    }
    sum / n as f64
}

struct Fog {
    renderer: Renderer,
    camera: Camera,
    tone: ToneMap,
}

impl Fog {
    fn new(ctx: &Context) -> Self {
        let volume = common::f32_volume(24, |p| {
            (-(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) / 0.04).exp()
        });
        let tf = TransferFunctions::parse(
            "colour = [[0.0, 1.0, 0.7, 0.4]]\n\
             opacity = [[0.0, 0.0], [1.0, 0.12]]\n\
             medium = [[0.0, 1.0, 1.0, 1.0], [1.0, 0.9, 0.95, 1.0]]\n",
            "fog",
        )
        .unwrap();
        Fog {
            renderer: Renderer::new(ctx, &volume, &tf).unwrap(),
            camera: Camera {
                azimuth: 30.0,
                elevation: 20.0,
                distance: 2.5,
                ..Default::default()
            },
            tone: ToneMap::default(),
        }
    }

    /// Lit from the side, hard light, no specular or reflections (nothing to reflect).
    fn options(side: u32, sample_distance: f32, transport: LightTransport) -> RenderOptions {
        let mut opts = common::frame_options(side, side, sample_distance);
        opts.sweep.light = Light {
            towards: glam::Vec3::new(1.0, 0.6, 0.3).normalize(),
            colour: [1.0; 3],
            softness: 0.0,
        };
        opts.sweep.light_transport = transport;
        opts.sweep.specular = 0.0;
        opts.sweep.reflections = false;
        opts
    }

    fn render(&mut self, opts: &RenderOptions) -> Frame {
        self.renderer
            .render(Model::Refract, &self.camera, opts)
            .unwrap()
    }
}

#[test]
fn the_skeleton_renders_the_sweep_where_no_optics_past_algorithm_1_are_used() {
    with_context(|ctx| {
        let mut fog = Fog::new(ctx);
        for sample_distance in [1.0, 0.5] {
            let opts = Fog::options(48, sample_distance, LightTransport::Backward);
            let sweep = fog.render(&opts);
            let mut o = opts.clone();
            o.sweep.skeleton = true;
            let skeleton = fog.render(&o);
            let mut o = opts.clone();
            o.sweep.floor = true;
            let floor = fog.render(&o);
            let to_skeleton = mean_display_diff(&sweep, &skeleton, &fog.tone);
            let to_floor = mean_display_diff(&sweep, &floor, &fog.tone);
            eprintln!(
                "sample distance {sample_distance}: mean display |Δ| to the sweep: \
                 skeleton {to_skeleton:.5}, floor {to_floor:.5}"
            );
            assert!(to_skeleton < 0.004, "skeleton {to_skeleton}");
            assert!(to_floor > 5.0 * to_skeleton, "floor {to_floor}");
        }
    });
}
