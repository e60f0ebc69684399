//! `refrakt view` (issue 8): the GPU tone-map pass the window shows must equal the PNG
//! path's CPU tone mapping, and frames recorded with Renderer::record (the viewer's path)
//! must equal what Renderer::render reads back.

mod common;

use refrakt::output::{self, ToneMap, ToneOperator};
use refrakt::render::{Camera, Model, RenderOptions, Renderer, ToneMapPass};
use refrakt::transfer::TransferFunctions;
use refrakt::vk::{self, Framebuffer, Image, ImageDesc, ImageKind};
use refrakt::volume::procedural;

/// Tone map `frame` with the GPU pass into an RGBA8 UNORM image and read it back.
fn gpu_tonemap(
    ctx: &vk::Context,
    renderer: &mut Renderer,
    model: Model,
    camera: &Camera,
    opts: &RenderOptions,
    tone: &ToneMap,
) -> (Vec<u8>, Vec<[f32; 4]>) {
    let target = Image::new(
        ctx,
        ImageDesc {
            kind: ImageKind::D2,
            format: vk::Format::R8G8B8A8_UNORM,
            extent: [opts.width, opts.height, 1],
            layers: 1,
            usage: vk::usage::COLOR_ATTACHMENT | vk::usage::TRANSFER_SRC,
        },
        "tonemap target",
    )
    .unwrap();
    let mut pass = ToneMapPass::new(ctx, vk::Format::R8G8B8A8_UNORM, false).unwrap();
    let view = target.layer_view(0).unwrap();
    let fb = Framebuffer::new(
        ctx,
        pass.render_pass(),
        &[&view],
        opts.width,
        opts.height,
        "tonemap fb",
    )
    .unwrap();
    let linear = renderer.render(model, camera, opts).unwrap().pixels;
    ctx.execute(|rec| {
        let out = renderer.record(rec, model, camera, opts)?;
        pass.record(rec, out.image, &target, &fb, tone)
    })
    .unwrap();
    (ctx.read_image(&target, 0).unwrap(), linear)
}

fn max_difference(a: &[u8], b: &[u8]) -> (u8, usize) {
    assert_eq!(a.len(), b.len());
    let mut worst = (0u8, 0usize);
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        let d = x.abs_diff(*y);
        if d > worst.0 {
            worst = (d, i);
        }
    }
    worst
}

#[test]
fn gpu_tone_mapping_matches_the_png_path() {
    common::with_context(|ctx| {
        let volume = procedural::sphere_on_floor(24).unwrap();
        let tf = TransferFunctions::load("glass-floor").unwrap();
        let mut renderer = Renderer::new(ctx, &volume, &tf).unwrap();
        let env = refrakt::environment::EnvironmentMap::procedural(256).unwrap();
        renderer.set_environment(Some(&env)).unwrap();
        let camera = Camera::default();
        let opts = RenderOptions {
            width: 48,
            height: 40,
            ..Default::default()
        };
        // Every operator, and exposures that push much of the image past 1 and far below.
        for tone in [
            ToneMap::default(),
            ToneMap {
                exposure: 1.5,
                operator: ToneOperator::Reinhard,
            },
            ToneMap {
                exposure: -2.0,
                operator: ToneOperator::None,
            },
            ToneMap {
                exposure: 3.0,
                operator: ToneOperator::Aces,
            },
        ] {
            for model in [Model::Refract, Model::Ea] {
                let (gpu, linear) = gpu_tonemap(ctx, &mut renderer, model, &camera, &opts, &tone);
                let frame = refrakt::render::Frame {
                    width: opts.width,
                    height: opts.height,
                    pixels: linear,
                    timings: Default::default(),
                    max_steps: 0,
                    dumps: Vec::new(),
                    sweep: None,
                };
                let cpu = output::to_srgb8(&frame, &tone);
                let (d, at) = max_difference(&gpu, &cpu);
                assert!(
                    d <= 1,
                    "{tone:?} {model:?}: GPU {} vs CPU {} at byte {at} (pixel {:?})",
                    gpu[at],
                    cpu[at],
                    frame.pixels[at / 4]
                );
            }
        }
    });
}

#[test]
fn recorded_frames_equal_rendered_frames() {
    // Renderer::record (the viewer's path) leaves in its image exactly what render reads
    // back, also when several recordings share a submission.
    common::with_context(|ctx| {
        let volume = procedural::sphere(20, 0.35, 1.0).unwrap();
        let tf = TransferFunctions::load("glass").unwrap();
        let mut renderer = Renderer::new(ctx, &volume, &tf).unwrap();
        let camera = Camera::default();
        let opts = RenderOptions {
            width: 24,
            height: 20,
            ..Default::default()
        };
        let expected = renderer.render(Model::Refract, &camera, &opts).unwrap();
        let readback = vk::Buffer::readback(ctx, 24 * 20 * 16, "readback").unwrap();
        ctx.execute(|rec| {
            renderer.record(rec, Model::Ea, &camera, &opts)?;
            renderer.record(rec, Model::Refract, &camera, &opts)?;
            let out = renderer.record(rec, Model::Refract, &camera, &opts)?;
            rec.copy_image_to_buffer(out.image, 0, &readback);
            Ok(())
        })
        .unwrap();
        let got: Vec<[f32; 4]> = readback.read_values(24 * 20).unwrap();
        assert_eq!(got, expected.pixels);
    });
}
