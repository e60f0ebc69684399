//! Uses follow from bindings (issue 34 item 4): a compute dispatch takes every image its
//! descriptor set binds to the use the binding declares (storage: GENERAL, read and
//! written; texture: sampled), so a chain of dispatches needs no hand-written barrier.
//! Validation and synchronization validation on (`with_context` fails on any message).

mod common;

use common::with_context;
use refrakt::shaders;
use refrakt::vk::{
    usage, Binding, Buffer, ComputePipeline, DescriptorSet, Filter, Format, Image, ImageDesc,
    ImageKind, ImageUsageFlags, Memory, Sampler,
};

fn volume(ctx: &refrakt::vk::Context, usage: ImageUsageFlags, name: &str) -> Image {
    let desc = ImageDesc {
        kind: ImageKind::D3,
        format: Format::R16G16B16A16_SFLOAT,
        extent: [8, 8, 8],
        layers: 1,
        usage,
    };
    Image::new(ctx, desc, name).unwrap()
}

/// The gradient kernel's push constants (glsl/gradient.comp).
fn push(axis: i32) -> Vec<u8> {
    let mut bytes = Vec::new();
    bytes.extend_from_slice(&axis.to_le_bytes());
    bytes.extend_from_slice(&1.0f32.to_le_bytes());
    bytes.extend_from_slice(&3i32.to_le_bytes());
    bytes
}

/// Three dispatches where each samples what the one before it wrote as a storage image,
/// and the first image is then written again: each needs a layout transition and an
/// execution dependency that no line here records. Without the derived barriers the
/// validation layer reports the sampled image in GENERAL layout (InvalidImageLayout) and
/// this test fails.
#[test]
fn a_chain_of_dispatches_is_ordered_by_its_bindings() {
    with_context(|ctx| {
        let u = usage::SAMPLED | usage::STORAGE;
        let a = volume(ctx, u, "a");
        let b = volume(ctx, u, "b");
        let sampler = Sampler::new(ctx, Filter::Linear, "linear").unwrap();
        let ab = DescriptorSet::new(
            ctx,
            &[Binding::Texture(&a, &sampler), Binding::StorageImage(&b)],
            "a -> b",
        )
        .unwrap();
        let ba = DescriptorSet::new(
            ctx,
            &[Binding::Texture(&b, &sampler), Binding::StorageImage(&a)],
            "b -> a",
        )
        .unwrap();
        let pipeline =
            ComputePipeline::new(ctx, shaders::GRADIENT_COMP, &ab, 12, "gradient").unwrap();
        ctx.execute(|rec| {
            for (axis, set) in [&ab, &ba, &ab].into_iter().enumerate() {
                rec.dispatch(&pipeline, set, &push(axis as i32), [1, 1, 8])?;
            }
            Ok(())
        })
        .unwrap();
    });
}

/// A set does not keep the images it binds alive; dispatching it after one was destroyed
/// is refused with the set's and the image's names, not recorded against a dead handle.
#[test]
fn a_dispatch_whose_set_binds_a_destroyed_image_is_refused() {
    with_context(|ctx| {
        let u = usage::SAMPLED | usage::STORAGE;
        let a = volume(ctx, u, "source volume");
        let b = volume(ctx, u, "gone volume");
        let sampler = Sampler::new(ctx, Filter::Linear, "linear").unwrap();
        let set = DescriptorSet::new(
            ctx,
            &[Binding::Texture(&a, &sampler), Binding::StorageImage(&b)],
            "stale set",
        )
        .unwrap();
        let pipeline =
            ComputePipeline::new(ctx, shaders::GRADIENT_COMP, &set, 12, "gradient").unwrap();
        drop(b);
        let err = ctx
            .execute(|rec| rec.dispatch(&pipeline, &set, &push(0), [1, 1, 8]))
            .unwrap_err();
        let text = format!("{err:#}");
        assert!(
            text.contains("stale set")
                && text.contains("gone volume")
                && text.contains("destroyed"),
            "{text}"
        );
    });
}

/// The same for a storage buffer: the set's storage bindings are what a dispatch waits on,
/// and a destroyed one is refused by name.
#[test]
fn a_dispatch_whose_set_binds_a_destroyed_buffer_is_refused() {
    with_context(|ctx| {
        let table = volume(ctx, usage::SAMPLED, "table");
        let sampler = Sampler::new(ctx, Filter::Nearest, "nearest").unwrap();
        let buffer = |name: &str| Buffer::new(ctx, 64, usage::STORAGE_BUFFER, Memory::Gpu, name);
        let boxes = buffer("boxes").unwrap();
        let averages = buffer("averages that went").unwrap();
        let set = DescriptorSet::new(
            ctx,
            &[
                Binding::Texture(&table, &sampler),
                Binding::Storage(&boxes),
                Binding::Storage(&averages),
            ],
            "probe set",
        )
        .unwrap();
        let pipeline =
            ComputePipeline::new(ctx, shaders::SAT3D_PROBE_COMP, &set, 32, "probe").unwrap();
        drop(averages);
        let err = ctx
            .execute(|rec| rec.dispatch(&pipeline, &set, &[0; 32], [1, 1, 1]))
            .unwrap_err();
        let text = format!("{err:#}");
        assert!(
            text.contains("probe set")
                && text.contains("buffer 'averages that went'")
                && text.contains("destroyed"),
            "{text}"
        );
    });
}
