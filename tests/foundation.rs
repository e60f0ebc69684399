//! Issue 2: backend round trips and the emission-absorption baseline against analytic
//! values. All on lavapipe with validation + synchronization validation.

mod common;

use common::*;
use refrakt::render::RenderOptions;
use refrakt::transfer::TransferFunctions;
use refrakt::volume::{procedural, Volume, Voxels};

fn lcg(seed: &mut u64) -> u64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    *seed >> 33
}

#[test]
fn volume_upload_round_trip_is_byte_exact() {
    with_context(|ctx| {
        let dims = [7, 5, 3];
        let n = 7 * 5 * 3;
        let mut seed = 42;
        let u8s: Vec<u8> = (0..n).map(|_| lcg(&mut seed) as u8).collect();
        let u16s: Vec<u16> = (0..n).map(|_| lcg(&mut seed) as u16).collect();
        let f32s: Vec<f32> = (0..n)
            .map(|_| (lcg(&mut seed) % 10_000) as f32 / 9_999.0)
            .collect();
        for voxels in [Voxels::U8(u8s), Voxels::U16(u16s), Voxels::F32(f32s)] {
            let mut v = Volume::new(dims, [1.0, 2.0, 0.5], voxels.clone()).unwrap();
            v.range = Some((0.0, 1.0));
            let tex = refrakt::render::upload::volume_texture(ctx, &v).unwrap();
            let back = ctx.read_image(&tex, 0).unwrap();
            let expected: Vec<u8> = match &voxels {
                Voxels::U8(x) => x.clone(),
                Voxels::U16(x) => x.iter().flat_map(|v| v.to_le_bytes()).collect(),
                Voxels::F32(x) => x.iter().flat_map(|v| v.to_le_bytes()).collect(),
            };
            assert_eq!(back, expected, "{} round trip", voxels.type_name());
        }
    });
}

#[test]
fn f32_volumes_are_normalised_by_their_range() {
    let v = Volume::new(
        [2, 2, 2],
        [1.0; 3],
        Voxels::F32(vec![-2.0, 0.0, 2.0, 6.0, 6.0, 6.0, 6.0, 6.0]),
    )
    .unwrap();
    let bytes = v.texel_bytes();
    let vals: Vec<f32> = bytes
        .chunks(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(&vals[..4], &[0.0, 0.25, 0.5, 1.0]);
}

/// Opacity of the slab after `thickness` reference steps of per-step opacity `alpha`:
/// Beer-Lambert in its discrete form 1 - (1 - α)^(d/Δx) (thesis eqs. 3.8, 3.13).
fn beer_lambert(alpha: f32, thickness: f32) -> f32 {
    1.0 - (1.0 - alpha).powf(thickness)
}

fn slab_alpha(
    ctx: &refrakt::vk::Context,
    alpha: f32,
    sample_distance: f32,
    preintegrated: bool,
) -> f32 {
    // 16 x 16 x 8 voxels: the box is 1 x 1 x 0.5 world units and 8 voxels thick along z.
    let slab = procedural::slab([16, 16, 8], 1.0).unwrap();
    let tf = constant_tf([1.0, 1.0, 1.0], alpha);
    let opts = RenderOptions {
        width: 32,
        height: 32,
        sample_distance,
        preintegrated,
        background: [0.0; 4],
        ..Default::default()
    };
    let frame = render(ctx, &slab, &tf, &face_on(3.0, 10.0), &opts);
    // Central pixels look straight through both faces.
    let mut acc = 0.0;
    for y in 15..17 {
        for x in 15..17 {
            acc += frame.pixel(x, y)[3];
        }
    }
    acc / 4.0
}

#[test]
fn homogeneous_slab_follows_beer_lambert() {
    with_context(|ctx| {
        for alpha in [0.05f32, 0.2] {
            let expected = beer_lambert(alpha, 8.0);
            for preintegrated in [false, true] {
                let got = slab_alpha(ctx, alpha, 1.0, preintegrated);
                assert!(
                    (got - expected).abs() <= 1.0 / 255.0,
                    "alpha {alpha} preintegrated {preintegrated}: rendered {got}, Beer-Lambert {expected}"
                );
            }
        }
    });
}

#[test]
fn opacity_correction_makes_alpha_independent_of_sample_distance() {
    with_context(|ctx| {
        let alpha = 0.2;
        for preintegrated in [false, true] {
            let reference = slab_alpha(ctx, alpha, 1.0, preintegrated);
            // 0.37 does not divide the thickness: the last, shorter step must be corrected too.
            for sd in [0.25f32, 0.37, 2.0, 3.0] {
                let got = slab_alpha(ctx, alpha, sd, preintegrated);
                assert!(
                    (got - reference).abs() <= 1.0 / 255.0,
                    "sample distance {sd} (preintegrated {preintegrated}): {got} vs {reference} at 1.0"
                );
            }
        }
    });
}

#[test]
fn empty_volume_renders_the_background_exactly() {
    with_context(|ctx| {
        let empty = Volume::new([8, 8, 8], [1.0; 3], Voxels::U8(vec![0; 512])).unwrap();
        let bg = [0.2, 0.4, 0.6, 1.0];
        for preintegrated in [false, true] {
            let opts = RenderOptions {
                width: 24,
                height: 16,
                background: bg,
                preintegrated,
                ..Default::default()
            };
            let frame = render(
                ctx,
                &empty,
                &TransferFunctions::default(),
                &Default::default(),
                &opts,
            );
            assert!(
                frame.pixels.iter().all(|p| *p == bg),
                "a pixel differs from the background"
            );
        }
    });
}

#[test]
fn renders_are_deterministic() {
    with_context(|ctx| {
        let vol = procedural::shell(32, 3).unwrap();
        let tf = TransferFunctions::load("supernova").unwrap();
        let opts = RenderOptions {
            width: 48,
            height: 40,
            ..Default::default()
        };
        let a = render(ctx, &vol, &tf, &Default::default(), &opts);
        let b = render(ctx, &vol, &tf, &Default::default(), &opts);
        let bytes = |f: &refrakt::render::Frame| -> Vec<u8> {
            f.pixels
                .iter()
                .flat_map(|p| p.iter().flat_map(|c| c.to_le_bytes()))
                .collect()
        };
        assert_eq!(bytes(&a), bytes(&b));
        // And the image is not trivially empty: the shell covers the centre.
        let centre = a.pixel(24, 20);
        assert!(centre[0] > 0.1, "centre pixel {centre:?} shows no volume");
    });
}
