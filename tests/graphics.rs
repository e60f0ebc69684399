//! Backend: render passes, framebuffers over single layers of a 2-layer array, full-screen
//! graphics pipelines with push constants, and sampling one layer while rendering another
//! (the ping-pong the plane sweep is built on). Validation and sync validation on.

mod common;

use common::with_context;
use refrakt::shaders;
use refrakt::vk::{
    usage, Access, Binding, DescriptorSet, Filter, Format, Framebuffer, GraphicsPipeline, Image,
    ImageDesc, ImageKind, RenderPass, Sampler,
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
        let set = DescriptorSet::new(ctx, &[Binding::LayerTexture(&l0, &sampler)], "read layer 0")
            .unwrap();
        let fill = GraphicsPipeline::fullscreen(
            ctx,
            shaders::FULLSCREEN_VERT,
            shaders::SELFTEST_FILL_FRAG,
            &pass,
            &set,
            16,
            "fill",
        )
        .unwrap();
        let scale = GraphicsPipeline::fullscreen(
            ctx,
            shaders::FULLSCREEN_VERT,
            shaders::SELFTEST_SCALE_FRAG,
            &pass,
            &set,
            16,
            "scale",
        )
        .unwrap();
        let colour = [0.25f32, 0.5, 0.75, 1.0];
        ctx.execute(|rec| {
            rec.begin_render_pass(&pass, &fb0, &[(&image, 0)])?;
            rec.draw_fullscreen(&fill, &set, bytemuck::cast_slice(&colour))?;
            rec.end_render_pass();
            rec.transition(&image, 0..1, Access::Sampled);
            rec.begin_render_pass(&pass, &fb1, &[(&image, 1)])?;
            rec.draw_fullscreen(&scale, &set, bytemuck::cast_slice(&[2.0f32; 4]))?;
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
