//! Backend: render passes, framebuffers over single layers of a 2-layer array, full-screen
//! graphics pipelines with push constants, and sampling one layer while rendering another
//! (the ping-pong the plane sweep is built on). Validation and sync validation on.

mod common;

use common::with_context;
use refrakt::shaders;
use refrakt::vk::{
    usage, Access, Binding, DescriptorSet, Filter, Format, Framebuffer, GraphicsDesc,
    GraphicsPipeline, Image, ImageDesc, ImageKind, RenderPass, Sampler,
};

#[test]
fn render_pass_ping_pong_between_layers() {
    with_context(|ctx| {
        let (w, h) = (16u32, 8u32);
        let image = Image::new(
            ctx,
            ImageDesc {
                kind: ImageKind::D2Array,
                format: Format::R32G32B32A32_SFLOAT,
                extent: [w, h, 1],
                layers: 2,
                usage: usage::COLOR_ATTACHMENT | usage::SAMPLED | usage::TRANSFER_SRC,
            },
            "ping-pong",
        )
        .unwrap();
        let l0 = image.layer_view(0).unwrap();
        let l1 = image.layer_view(1).unwrap();
        let sampler = Sampler::new(ctx, Filter::Nearest, "nearest").unwrap();
        let pass = RenderPass::new(
            ctx,
            &[Format::R32G32B32A32_SFLOAT],
            Access::ColorAttachment,
            "pass",
        )
        .unwrap();
        let fb0 = Framebuffer::new(ctx, &pass, &[&l0], w, h, "fb layer 0").unwrap();
        let fb1 = Framebuffer::new(ctx, &pass, &[&l1], w, h, "fb layer 1").unwrap();
        let set = DescriptorSet::new(
            ctx,
            &[Binding::LayerTexture(&l0, &sampler, Access::Sampled)],
            "read layer 0",
        )
        .unwrap();
        let fill = GraphicsPipeline::new(
            ctx,
            &GraphicsDesc::fullscreen(
                shaders::FULLSCREEN_VERT,
                shaders::SELFTEST_FILL_FRAG,
                &pass,
                &set,
                16,
            ),
            "fill",
        )
        .unwrap();
        let scale = GraphicsPipeline::new(
            ctx,
            &GraphicsDesc::fullscreen(
                shaders::FULLSCREEN_VERT,
                shaders::SELFTEST_SCALE_FRAG,
                &pass,
                &set,
                16,
            ),
            "scale",
        )
        .unwrap();
        let colour = [0.25f32, 0.5, 0.75, 1.0];
        ctx.execute(|rec| {
            rec.begin_render_pass(&pass, &fb0, &[(&image, 0)])?;
            rec.bind_graphics(&fill, &set, w, h);
            rec.draw_fullscreen(&fill, bytemuck::cast_slice(&colour))?;
            rec.end_render_pass();
            rec.transition(&image, 0..1, Access::Sampled);
            rec.begin_render_pass(&pass, &fb1, &[(&image, 1)])?;
            rec.bind_graphics(&scale, &set, w, h);
            rec.draw_fullscreen(&scale, bytemuck::cast_slice(&[2.0f32; 4]))?;
            rec.end_render_pass();
            Ok(())
        })
        .unwrap();
        let bytes = ctx.read_image(&image, 1).unwrap();
        let px: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
        for y in 0..h {
            for x in 0..w {
                let expected = [
                    2.0 * colour[0] + x as f32 + 0.5,
                    2.0 * colour[1] + y as f32 + 0.5,
                    2.0 * colour[2],
                    2.0 * colour[3],
                ];
                assert_eq!(px[(y * w + x) as usize], expected, "pixel ({x}, {y})");
            }
        }
    });
}

#[test]
fn render_pass_rejects_a_framebuffer_of_the_wrong_shape() {
    with_context(|ctx| {
        let image = Image::new(
            ctx,
            ImageDesc {
                kind: ImageKind::D2Array,
                format: Format::R32G32B32A32_SFLOAT,
                extent: [4, 4, 1],
                layers: 2,
                usage: usage::COLOR_ATTACHMENT,
            },
            "two layers",
        )
        .unwrap();
        let (a, b) = (image.layer_view(0).unwrap(), image.layer_view(1).unwrap());
        let pass = RenderPass::new(
            ctx,
            &[Format::R32G32B32A32_SFLOAT],
            Access::ColorAttachment,
            "one",
        )
        .unwrap();
        let err = Framebuffer::new(ctx, &pass, &[&a, &b], 4, 4, "bad")
            .err()
            .unwrap();
        assert!(err.to_string().contains("2 views for a pass of 1"), "{err}");
        assert!(image.layer_view(2).is_err());
    });
}

/// The plane sweep's pattern in miniature: N passes, pass i renders layer i % 2 and samples
/// layer 1 - i % 2 through per-layer views of one descriptor set chosen by push constant,
/// with GENERAL layouts and a memory barrier on exactly the two layers between passes.
/// Returns the value left in the last layer written and the validation messages.
fn ping_pong(planes: u32, drop_barrier_at: Option<u32>) -> (f32, Vec<String>) {
    let ctx = common::context();
    let log = ctx.validation_log();
    let value = {
        let (w, h) = (8u32, 8u32);
        let image = Image::new(
            &ctx,
            ImageDesc {
                kind: ImageKind::D2Array,
                format: Format::R32G32B32A32_SFLOAT,
                extent: [w, h, 1],
                layers: 2,
                usage: usage::COLOR_ATTACHMENT | usage::SAMPLED | usage::TRANSFER_SRC,
            },
            "state",
        )
        .unwrap();
        let views = [image.layer_view(0).unwrap(), image.layer_view(1).unwrap()];
        let sampler = Sampler::new(&ctx, Filter::Nearest, "nearest").unwrap();
        let pass = RenderPass::new(
            &ctx,
            &[Format::R32G32B32A32_SFLOAT],
            Access::AttachmentGeneral,
            "plane",
        )
        .unwrap();
        let fbs = [
            Framebuffer::new(&ctx, &pass, &[&views[0]], w, h, "write 0").unwrap(),
            Framebuffer::new(&ctx, &pass, &[&views[1]], w, h, "write 1").unwrap(),
        ];
        let set = DescriptorSet::new(
            &ctx,
            &[
                Binding::LayerTexture(&views[0], &sampler, Access::SampledGeneral),
                Binding::LayerTexture(&views[1], &sampler, Access::SampledGeneral),
            ],
            "both layers",
        )
        .unwrap();
        let fill = GraphicsPipeline::new(
            &ctx,
            &GraphicsDesc::fullscreen(
                shaders::FULLSCREEN_VERT,
                shaders::SELFTEST_FILL_FRAG,
                &pass,
                &set,
                16,
            ),
            "fill",
        )
        .unwrap();
        let count = GraphicsPipeline::new(
            &ctx,
            &GraphicsDesc::fullscreen(
                shaders::FULLSCREEN_VERT,
                shaders::SELFTEST_COUNT_FRAG,
                &pass,
                &set,
                4,
            ),
            "count",
        )
        .unwrap();
        ctx.execute(|rec| {
            // Start both layers at zero (plane 0 reads layer 1). Every draw's descriptor set
            // names both layers, so both must hold defined, visible data from the start.
            for (layer, fb) in (0u32..).zip(&fbs) {
                rec.begin_render_pass(&pass, fb, &[(&image, layer)])?;
                rec.bind_graphics(&fill, &set, w, h);
                rec.draw_fullscreen(&fill, bytemuck::cast_slice(&[0.0f32; 4]))?;
                rec.end_render_pass();
                rec.transition(&image, layer..layer + 1, Access::SampledGeneral);
            }
            // Bound once; between planes only push constants change, as in the sweep.
            rec.bind_graphics(&count, &set, w, h);
            for i in 0..planes {
                let (write, read) = (i % 2, 1 - i % 2);
                if drop_barrier_at == Some(i) {
                    rec.assume_without_barrier(&image, read..read + 1, Access::SampledGeneral);
                } else {
                    rec.transition(&image, read..read + 1, Access::SampledGeneral);
                }
                rec.begin_render_pass(&pass, &fbs[write as usize], &[(&image, write)])?;
                rec.draw_fullscreen(&count, bytemuck::bytes_of(&read))?;
                rec.end_render_pass();
            }
            Ok(())
        })
        .unwrap();
        let bytes = ctx.read_image(&image, (planes - 1) % 2).unwrap();
        let px: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
        px[(h / 2 * w + w / 2) as usize][0]
    };
    drop(ctx);
    (value, log.messages())
}

#[test]
fn ping_pong_sweep_is_validation_clean() {
    let (value, msgs) = ping_pong(9, None);
    assert!(msgs.is_empty(), "{}", msgs.join("\n---\n"));
    assert_eq!(value, 9.0, "each of the 9 planes adds one");
}

#[test]
fn sync_validation_catches_a_dropped_inter_plane_barrier() {
    let (_, msgs) = ping_pong(9, Some(4));
    assert!(
        msgs.iter()
            .any(|m| m.contains("SYNC-HAZARD-READ-AFTER-WRITE")),
        "no read-after-write hazard reported; messages: {msgs:?}"
    );
}
