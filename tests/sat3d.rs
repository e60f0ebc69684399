//! The GPU 3D summed-area table (src/render/sat3d.rs): the table against the exact integer
//! SAT of the quantised field, and box averages — from the read-back table and from the
//! shader helper (glsl/sat3d.glsl) — against brute-force f64 sums, on a small random volume
//! with boxes of every kind and on a large one with a large offset and a step.

mod common;

use refrakt::render::sat3d::{quantise, Sat3d, Sat3dReadback, VoxelBox, AXIS_SCOPES, SCOPE};
use refrakt::vk::{self, Context, Image, ImageDesc, ImageKind};

/// Box averages must agree with the f64 sum within this, relative...
const REL: f64 = 1e-5;
/// ...or absolute, for averages near zero.
const ABS: f64 = 1e-6;

fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Uniform in [0, 1).
fn uniform(state: &mut u64) -> f64 {
    (splitmix(state) >> 11) as f64 / (1u64 << 53) as f64
}

/// Uniform integer in [lo, hi].
fn int_in(state: &mut u64, lo: i32, hi: i32) -> i32 {
    lo + (splitmix(state) % (hi - lo + 1) as u64) as i32
}

/// A field as it is on the host and on the GPU (an R32F 3D texture).
struct Field {
    extent: [u32; 3],
    values: Vec<f32>,
}

impl Field {
    fn new(extent: [u32; 3], mut f: impl FnMut([u32; 3]) -> f32) -> Self {
        let mut values = Vec::new();
        for z in 0..extent[2] {
            for y in 0..extent[1] {
                for x in 0..extent[0] {
                    values.push(f([x, y, z]));
                }
            }
        }
        Self { extent, values }
    }

    fn upload(&self, ctx: &Context) -> Image {
        let image = Image::new(
            ctx,
            ImageDesc {
                kind: ImageKind::D3,
                format: vk::Format::R32_SFLOAT,
                extent: self.extent,
                layers: 1,
                usage: vk::usage::SAMPLED | vk::usage::TRANSFER_DST,
            },
            "test field",
        )
        .unwrap();
        ctx.upload_image(&image, 0, bytemuck::cast_slice(&self.values))
            .unwrap();
        image
    }

    fn index(&self, p: [usize; 3]) -> usize {
        let [w, h, _] = self.extent.map(|e| e as usize);
        p[0] + w * (p[1] + h * p[2])
    }

    /// The brute-force average over `b`: f64 sum of the voxels inside, the outside zero,
    /// divided by the whole box's voxel count.
    fn box_average(&self, b: VoxelBox) -> f64 {
        if b.volume() == 0 {
            return 0.0;
        }
        let lo: [usize; 3] = std::array::from_fn(|i| b.lo[i].max(0) as usize);
        let hi: [i64; 3] = std::array::from_fn(|i| (b.hi[i] as i64).min(self.extent[i] as i64 - 1));
        let mut sum = 0.0f64;
        for z in lo[2] as i64..=hi[2] {
            for y in lo[1] as i64..=hi[1] {
                let row = self.index([0, y as usize, z as usize]);
                for x in lo[0] as i64..=hi[0] {
                    sum += self.values[row + x as usize] as f64;
                }
            }
        }
        sum / b.volume() as f64
    }

    /// The exact integer SAT of the quantised field, summed in the order x, y, z.
    fn integer_sat(&self, bound: f32, k: i32) -> Vec<i64> {
        let mut s: Vec<i64> = self.values.iter().map(|&v| quantise(v, bound, k)).collect();
        let [w, h, _] = self.extent.map(|e| e as usize);
        let strides = [1, w, w * h];
        for (axis, &stride) in strides.iter().enumerate() {
            for i in 0..s.len() {
                let c = [i % w, i / w % h, i / (w * h)][axis];
                if c > 0 {
                    s[i] += s[i - stride];
                }
            }
        }
        s
    }
}

fn within(got: f64, want: f64) -> bool {
    (got - want).abs() <= ABS.max(REL * want.abs())
}

/// Random boxes of every kind for `extent`: single voxels, the whole volume, thin slabs,
/// boxes clipped at each of the six faces, boxes wholly outside, random boxes.
fn boxes(extent: [u32; 3], random: usize, seed: u64) -> Vec<VoxelBox> {
    let e = extent.map(|e| e as i32);
    let mut s = seed;
    let mut out = vec![
        VoxelBox {
            lo: [0; 3],
            hi: e.map(|e| e - 1),
        },
        // The whole volume and more on every side: the average shrinks by the volume ratio.
        VoxelBox {
            lo: [-3, -2, -1],
            hi: [e[0] + 2, e[1] + 1, e[2]],
        },
        // Wholly outside, and empty.
        VoxelBox {
            lo: [e[0], 0, 0],
            hi: [e[0] + 4, 3, 3],
        },
        VoxelBox {
            lo: [5, 5, 5],
            hi: [4, 9, 9],
        },
    ];
    for corner in 0..8u32 {
        let p: [i32; 3] = std::array::from_fn(|i| if corner >> i & 1 == 1 { e[i] - 1 } else { 0 });
        out.push(VoxelBox { lo: p, hi: p });
    }
    for _ in 0..random / 4 {
        let p: [i32; 3] = std::array::from_fn(|i| int_in(&mut s, 0, e[i] - 1));
        out.push(VoxelBox { lo: p, hi: p });
    }
    // Clipped at each face: reaching past it by up to 6 voxels.
    for axis in 0..3 {
        for high in [false, true] {
            for _ in 0..random / 12 {
                let mut lo: [i32; 3] = std::array::from_fn(|i| int_in(&mut s, 0, e[i] - 1));
                let mut hi: [i32; 3] = std::array::from_fn(|i| int_in(&mut s, lo[i], e[i] - 1));
                if high {
                    hi[axis] = e[axis] - 1 + int_in(&mut s, 1, 6);
                } else {
                    lo[axis] = -int_in(&mut s, 1, 6);
                }
                out.push(VoxelBox { lo, hi });
            }
        }
    }
    // Thin slabs one voxel thick along each axis.
    for axis in 0..3 {
        let c = int_in(&mut s, 0, e[axis] - 1);
        let mut lo = [0; 3];
        let mut hi = e.map(|e| e - 1);
        lo[axis] = c;
        hi[axis] = c;
        out.push(VoxelBox { lo, hi });
    }
    // Anywhere, of any size, possibly clipped on several faces.
    for _ in 0..random / 2 {
        let lo: [i32; 3] = std::array::from_fn(|i| int_in(&mut s, -4, e[i] - 1));
        let hi: [i32; 3] = std::array::from_fn(|i| int_in(&mut s, lo[i], e[i] + 3));
        out.push(VoxelBox { lo, hi });
    }
    out
}

/// Checks every box from the read-back table and from the shader helper; returns the
/// largest relative (to max(|want|, ABS / REL)) error of each.
fn check_boxes(
    ctx: &Context,
    field: &Field,
    sat: &Sat3d,
    table: &Sat3dReadback,
    boxes: &[VoxelBox],
) -> (f64, f64) {
    let gpu = sat.box_averages_on_gpu(ctx, boxes).unwrap();
    let (mut worst_host, mut worst_gpu) = (0.0f64, 0.0f64);
    for (b, &g) in boxes.iter().zip(&gpu) {
        let want = field.box_average(*b);
        let host = table.box_average(*b);
        let scale = want.abs().max(ABS / REL);
        worst_host = worst_host.max((host - want).abs() / scale);
        worst_gpu = worst_gpu.max((g as f64 - want).abs() / scale);
        assert!(
            within(host, want),
            "{b:?}: read-back table {host}, brute force {want}"
        );
        assert!(
            within(g as f64, want),
            "{b:?}: sat_box_average on the GPU {g}, brute force {want}"
        );
    }
    (worst_host, worst_gpu)
}

#[test]
fn box_averages_on_a_random_volume_match_brute_force() {
    // Non-power-of-two sides; values in [0, 1) with one voxel in ten negative, so that the
    // two's-complement paths and near-zero averages are exercised.
    let extent = [37, 29, 23];
    let mut s = 17u64;
    let field = Field::new(extent, |_| {
        let v = uniform(&mut s) as f32;
        if uniform(&mut s) < 0.1 {
            -v
        } else {
            v
        }
    });
    common::with_context(|ctx| {
        let image = field.upload(ctx);
        let (sat, timings) = Sat3d::build(ctx, &image, 1.0).unwrap();
        assert!(ctx.info().timestamps == timings.get(SCOPE).is_some());
        let table = sat.read(ctx).unwrap();
        // Bit for bit the integer SAT of the quantised field: every axis scanned, in order.
        assert_exact(&field, &sat, &table);
        let boxes = boxes(extent, 2000, 5);
        let (host, gpu) = check_boxes(ctx, &field, &sat, &table, &boxes);
        println!(
            "{} boxes, largest relative error: read-back {host:.2e}, shader {gpu:.2e}",
            boxes.len()
        );
    });
}

/// The bit-for-bit check of a read-back table against the quantised field's integer SAT.
fn assert_exact(field: &Field, sat: &Sat3d, table: &Sat3dReadback) {
    let want = field.integer_sat(sat.bound(), sat.exponent());
    let wrong = table
        .table
        .iter()
        .zip(&want)
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(wrong, 0, "{wrong} table texels differ from the integer SAT");
}

#[test]
fn rebuilds_in_place_when_the_field_changes() {
    // A transfer-function change: the same field image rewritten with other values (and a
    // larger bound, so another scale), the table rebuilt in place.
    let extent = [19, 24, 13];
    let mut s = 23u64;
    let first = Field::new(extent, |_| uniform(&mut s) as f32);
    let second = Field::new(extent, |[x, y, z]| ((x * y + z) % 7) as f32 * 0.75);
    common::with_context(|ctx| {
        let image = first.upload(ctx);
        let (mut sat, _) = Sat3d::build(ctx, &image, 1.0).unwrap();
        assert_exact(&first, &sat, &sat.read(ctx).unwrap());
        let k = sat.exponent();
        ctx.upload_image(&image, 0, bytemuck::cast_slice(&second.values))
            .unwrap();
        let timings = sat.rebuild(ctx, &image, 4.5).unwrap();
        assert!(ctx.info().timestamps == timings.get(SCOPE).is_some());
        assert!(sat.exponent() < k, "a larger bound, a coarser scale");
        let table = sat.read(ctx).unwrap();
        assert_exact(&second, &sat, &table);
        let boxes = boxes(extent, 200, 9);
        check_boxes(ctx, &second, &sat, &table, &boxes);
        // Only from the image it was built from (its descriptor set refers to that one).
        let other = second.upload(ctx);
        assert!(sat.rebuild(ctx, &other, 4.5).is_err());
        assert!(sat.rebuild(ctx, &image, f32::INFINITY).is_err());
    });
}

#[test]
fn precision_holds_on_a_large_volume_with_a_large_offset() {
    // 160³: 1000 + noise in half the volume (x < 80), noise alone in the other half. Corner
    // sums reach 2·10⁹, which f32 holds to ±128 only, and even with the mean subtracted
    // (the environment map's trick) the sums across the step reach ~10⁹.
    let n = 160u32;
    let extent = [n; 3];
    let mut s = 3u64;
    let field = Field::new(extent, |[x, _, _]| {
        let noise = uniform(&mut s) as f32;
        if x < n / 2 {
            1000.0 + noise
        } else {
            noise
        }
    });
    let bound = 1001.0;
    common::with_context(|ctx| {
        let image = field.upload(ctx);
        let (sat, timings) = Sat3d::build(ctx, &image, bound).unwrap();
        let table = sat.read(ctx).unwrap();
        let boxes = boxes(extent, 400, 11);
        let (host, gpu) = check_boxes(ctx, &field, &sat, &table, &boxes);
        println!(
            "160³ build {:?} ms; {} boxes, largest relative error: read-back {host:.2e}, \
             shader {gpu:.2e}",
            timings.get(SCOPE),
            boxes.len()
        );
        // The tolerance has teeth: an f32 table with the mean offset and Kahan sums (as the
        // environment map's SAT) fails it on the same boxes.
        let f32_table = f32_mean_offset_sat(&field);
        let failed = boxes
            .iter()
            .filter(|b| {
                !within(
                    f32_box_average(&f32_table, &field, **b),
                    field.box_average(**b),
                )
            })
            .count();
        println!("an f32 mean-offset SAT misses the tolerance on {failed} of them");
        assert!(failed > 0, "the check would not tell an f32 table apart");
    });
}

/// The f32 SAT of (v - mean) with Kahan-compensated scans along x, y, z (glsl/sat.comp's
/// method in 3D), and the mean.
fn f32_mean_offset_sat(field: &Field) -> (Vec<f32>, f32) {
    let mean =
        (field.values.iter().map(|&v| v as f64).sum::<f64>() / field.values.len() as f64) as f32;
    let mut s: Vec<f32> = field.values.iter().map(|&v| v - mean).collect();
    let [w, h, d] = field.extent.map(|e| e as usize);
    let strides = [1, w, w * h];
    let lens = [w, h, d];
    for axis in 0..3 {
        for start in 0..s.len() {
            let c = [start % w, start / w % h, start / (w * h)][axis];
            if c != 0 {
                continue;
            }
            let (mut sum, mut carry) = (0.0f32, 0.0f32);
            for i in 0..lens[axis] {
                let idx = start + i * strides[axis];
                let y = s[idx] - carry;
                let t = sum + y;
                carry = (t - sum) - y;
                sum = t;
                s[idx] = sum;
            }
        }
    }
    (s, mean)
}

fn f32_box_average(sat: &(Vec<f32>, f32), field: &Field, b: VoxelBox) -> f64 {
    let (table, mean) = sat;
    let at = |p: [i64; 3]| -> f64 {
        if p.iter().any(|&c| c < 0) {
            0.0
        } else {
            table[field.index(p.map(|c| c as usize))] as f64
        }
    };
    if b.volume() == 0 {
        return 0.0;
    }
    let a: [i64; 3] = std::array::from_fn(|i| b.lo[i].max(0) as i64 - 1);
    let c: [i64; 3] = std::array::from_fn(|i| (b.hi[i] as i64).min(field.extent[i] as i64 - 1));
    if (0..3).any(|i| c[i] <= a[i]) {
        return 0.0;
    }
    let mut sum = 0.0f32;
    for corner in 0..8u32 {
        let p: [i64; 3] = std::array::from_fn(|i| if corner >> i & 1 == 1 { a[i] } else { c[i] });
        let sign = if corner.count_ones() % 2 == 0 {
            1.0
        } else {
            -1.0
        };
        sum += sign * at(p) as f32;
    }
    let inside: i64 = (0..3).map(|i| c[i] - a[i]).product();
    (sum as f64 + *mean as f64 * inside as f64) / b.volume() as f64
}

/// The build's GPU time at 128³ and 256³ (`cargo test --release --test sat3d -- --ignored
/// --nocapture`): figures for the module docs and the issue.
#[test]
#[ignore]
fn build_time() {
    common::with_context(|ctx| {
        for n in [128u32, 256] {
            let mut s = 1u64;
            let field = Field::new([n; 3], |_| uniform(&mut s) as f32);
            let image = field.upload(ctx);
            let (mut sat, first) = Sat3d::build(ctx, &image, 1.0).unwrap();
            let mut runs = vec![("build", first)];
            for _ in 0..3 {
                runs.push(("rebuild", sat.rebuild(ctx, &image, 1.0).unwrap()));
            }
            for (what, timings) in runs {
                let axes = AXIS_SCOPES.map(|a| timings.get(a).unwrap_or(0.0));
                println!(
                    "{n}³ {what}: sat3d {:.1} ms (x {:.1}, y {:.1}, z {:.1})",
                    timings.get(SCOPE).unwrap_or(0.0),
                    axes[0],
                    axes[1],
                    axes[2]
                );
            }
        }
    });
}
