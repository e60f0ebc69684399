//! The 3D summed-area table (SAT) of a scalar field on the GPU (`glsl/sat3d_scan.comp`), the
//! first building block of issue 17: box averages of a per-voxel field (extinction or
//! opacity) over axis-aligned boxes of any size in O(1) — eight table reads per box.
//!
//! What for: SAT-based volumetric ambient occlusion (Schlegel et al., the method Ament et al.
//! compare against) averages extinction over boxes around each sample; the ambient
//! extinction volume of Ament et al. (seed 002, sect. 4.2.1, eq. 13) is
//! σ̃_t(x) ≈ SAT(C_r(x)) / V_s, the average over a cube C_r(x) standing in for the sphere
//! of radius r. Both depend on the transfer function, so the table is rebuilt on the GPU
//! whenever it changes ([`Sat3d::rebuild`], in place); the build's GPU time is the timings
//! scope [`SCOPE`].
//!
//! Layout: one R32G32_UINT texel per voxel, the same extent as the field: S(x, y, z) = the
//! sum over [0, x] × [0, y] × [0, z] of round(v · scale), a 64-bit two's-complement integer
//! as (low, high) words. Built by three passes, one per axis (x, then y, then z, the last two
//! in place), one invocation per line doing a sequential prefix sum with carries. The read
//! side in GLSL is `glsl/sat3d.glsl` (`sat_box_average(lo, hi)`); on the host,
//! [`Sat3dReadback::box_average`].
//!
//! Boxes clip at the volume's faces as extinction-based occlusion (Schlegel et al.) treats
//! the outside: empty, zero extinction, averaged over the whole box's volume (a box half
//! outside a homogeneous medium averages to half its σ_t; a box wholly outside to 0).
//!
//! Precision: a plain f32 prefix sum over 256³ voxels reaches 1.6·10⁷ × the values and keeps
//! ~7 digits of that, so a single voxel's value read back from eight corners would be lost
//! entirely; subtracting the mean (as the environment map's SAT does) only helps while the
//! field is stationary — a half-opaque volume still has corner sums ~ N · mean / 2. Here the
//! values are quantised to fixed point (scale = 2^k, so v · scale is exact in f32 and only
//! the rounding to an integer errs, by ≤ 0.5 / scale per voxel) and summed as 64-bit
//! integers, which is exact and order-independent: the table is bit for bit the integer SAT
//! of the quantised field, box sums from eight corners are exact, and a box average's only
//! error is the quantisation, averaged: |error| ≤ 0.5 / scale absolute, whatever the box.
//! [`Sat3d::build`] picks the largest k with voxels · bound · 2^k ≤ 2^61 (so no partial sum
//! nears 2^63), where every |v| ≤ bound: 2^k > 2^60 / (voxels · bound), so the absolute
//! error is < 2^-61 · voxels · bound — for 256³ 7.3·10⁻¹² · bound (4.7·10⁻¹⁰ · bound at
//! 1024³): within 10⁻⁵ relative for any average above 10⁻⁶ · bound at 256³. (Values that f32
//! holds exactly at that resolution, like the test's in [0, 1), are not rounded at all.) On
//! the GPU (`sat_box_average`) the exact box sum is converted to f32 (≤ 1.5 ulp; the
//! magnitude is converted, so a small negative sum does not cancel between the words) and
//! scaled: another ≤ 2·10⁻⁷ relative. Values beyond ±bound are clamped. Measured
//! (tests/sat3d.rs) against f64 brute-force sums: 37×29×23 in [-1, 1), 2511 boxes: read-back
//! exact, shader 1.4·10⁻⁷; 160³ of 1000 + noise beside noise alone, 513 boxes: read-back
//! 1.5·10⁻¹¹, shader 1.3·10⁻⁷ — where an f32 mean-offset Kahan SAT misses 10⁻⁵ on 279.
//!
//! Memory: 8 bytes per voxel (128 MiB at 256³), twice an f32 table; the field itself is
//! the caller's. No intermediate.
//!
//! Cost, lavapipe on 2 cores (tests/sat3d.rs `build_time`; noisy: the machine was shared,
//! load 1–4.7): a first build 128³ 24–160 ms, 256³ 470–1020 ms, where the x scan, the
//! first to write the fresh table, pays its page faults (270–400 ms at 256³); a rebuild
//! into the same table ([`Sat3d::rebuild`], what a transfer-function change costs) 128³
//! 46–175 ms (typically ~50), 256³ 300–835 ms (typically ~520: x ~120, y ~120, z ~270 —
//! the z scan strides 512 KiB per step). Nested scopes [`AXIS_SCOPES`] time each scan.

use anyhow::{ensure, Result};
use bytemuck::{Pod, Zeroable};

use crate::shaders;
use crate::vk::{
    self, Binding, Buffer, ComputePipeline, Context, DescriptorSet, Filter, Image, ImageDesc,
    ImageKind, Memory, Recorder, Sampler, Timings,
};

/// The timings scope of the build.
pub const SCOPE: &str = "sat3d";

/// The nested scope of each axis's scan.
pub const AXIS_SCOPES: [&str; 3] = ["sat3d x", "sat3d y", "sat3d z"];

/// Lines per workgroup (`local_size_x` of both shaders).
const GROUP: u32 = 64;

/// `glsl/sat3d_scan.comp`'s push constants.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ScanPush {
    axis: i32,
    scale: f32,
    bound: f32,
}

/// `glsl/sat3d_probe.comp`'s push constants.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ProbePush {
    dims: [i32; 4],
    inv_scale: f32,
    count: u32,
    pad: [u32; 2],
}

/// An axis-aligned box of voxels, both corners inclusive; it may reach outside the volume.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VoxelBox {
    pub lo: [i32; 3],
    pub hi: [i32; 3],
}

impl VoxelBox {
    /// Voxels in the whole box (0 when empty), inside the volume or not.
    pub fn volume(&self) -> u64 {
        (0..3)
            .map(|a| (self.hi[a] as i64 - self.lo[a] as i64 + 1).max(0) as u64)
            .product()
    }
}

/// The exponent k of the fixed-point scale 2^k for a field of `voxels` values within
/// ±`bound`: the largest with voxels · bound · 2^k ≤ 2^61, kept where 2^±k is a normal f32.
pub fn scale_exponent(voxels: u64, bound: f32) -> i32 {
    let limit = 2f64.powi(61);
    let m = voxels.max(1) as f64 * bound as f64;
    let mut k = (limit / m).log2().floor() as i32;
    while m * 2f64.powi(k) > limit {
        k -= 1;
    }
    while m * 2f64.powi(k + 1) <= limit {
        k += 1;
    }
    k.clamp(-125, 125)
}

/// round(v · 2^k) as the scan computes it (ties to even, in f32, v clamped to ±bound).
pub fn quantise(v: f32, bound: f32, k: i32) -> i64 {
    (v.clamp(-bound, bound) * 2f32.powi(k)).round_ties_even() as i64
}

/// The 3D summed-area table of a field on the GPU.
pub struct Sat3d {
    table: Image,
    extent: [u32; 3],
    exponent: i32,
    bound: f32,
    /// The field the set reads ([`Image::id`]): rebuilds must pass that very image, which
    /// proves it alive.
    field_id: u64,
    /// Kept for the set, which refers to it.
    _sampler: Sampler,
    set: DescriptorSet,
    pipeline: ComputePipeline,
}

impl Sat3d {
    /// Bytes of the table for a field of `extent`.
    pub fn memory(extent: [u32; 3]) -> u64 {
        8 * extent.iter().map(|&e| e as u64).product::<u64>()
    }

    /// Build the table of `field` (a sampled 3D image of a float or normalised format whose
    /// first channel is the value, e.g. R32F; read with texelFetch), every |value| ≤ `bound`
    /// (larger ones are clamped; a transfer function's largest extinction, say). Returns it
    /// with the build's GPU time (scope [`SCOPE`]).
    pub fn build(ctx: &Context, field: &Image, bound: f32) -> Result<(Self, Timings)> {
        let mut sat = Self::new(ctx, field)?;
        let timings = sat.rebuild(ctx, field, bound)?;
        Ok((sat, timings))
    }

    /// The table for `field`, not built yet: [`Sat3d::record_rebuild`] fills it (with the
    /// field's producer in the same recording).
    pub fn new(ctx: &Context, field: &Image) -> Result<Self> {
        ensure!(
            field.desc().kind == ImageKind::D3,
            "the 3D SAT needs a 3D field, '{}' is {:?}",
            field.name(),
            field.desc().kind
        );
        let extent = field.extent();
        let desc = ImageDesc::computed(ImageKind::D3, vk::Format::R32G32_UINT, extent, 1);
        let table = Image::new(ctx, desc, "3D SAT")?;
        let sampler = Sampler::new(ctx, Filter::Nearest, "3D SAT field")?;
        let set = DescriptorSet::new(
            ctx,
            &[
                Binding::Texture(field, &sampler),
                Binding::StorageImage(&table),
            ],
            "3D SAT",
        )?;
        let pipeline = ComputePipeline::new(
            ctx,
            shaders::SAT3D_SCAN_COMP,
            &set,
            std::mem::size_of::<ScanPush>() as u32,
            "3D SAT",
        )?;
        Ok(Self {
            table,
            extent,
            exponent: 0,
            bound: 0.0,
            field_id: field.id(),
            _sampler: sampler,
            set,
            pipeline,
        })
    }

    /// Rebuild the table in place from `field` — the image it was built from, rewritten
    /// (a new transfer function's extinction) — with the values' new `bound`. Reuses the
    /// table, descriptor set and pipeline: what a transfer-function change costs. Returns
    /// the GPU time (scope [`SCOPE`]).
    pub fn rebuild(&mut self, ctx: &Context, field: &Image, bound: f32) -> Result<Timings> {
        ctx.execute(|rec| self.record_rebuild(rec, field, bound))
    }

    /// [`Sat3d::rebuild`] recorded into `rec` (e.g. a frame's recording, so that it is
    /// ordered after earlier frames that read the table and before the frame that reads
    /// it).
    pub fn record_rebuild(&mut self, rec: &mut Recorder, field: &Image, bound: f32) -> Result<()> {
        ensure!(
            field.id() == self.field_id,
            "the 3D SAT rebuilds from the field it was built from, not '{}'",
            field.name()
        );
        ensure!(
            bound.is_finite() && bound > 0.0,
            "the 3D SAT needs a finite positive bound of the values, got {bound}"
        );
        let voxels = self.extent.iter().map(|&e| e as u64).product::<u64>();
        let exponent = scale_exponent(voxels, bound);
        let [w, h, d] = self.extent;
        // Lanes along the first other axis: y for the x scan, x for the y and z scans.
        let groups = [
            [h.div_ceil(GROUP), d, 1],
            [w.div_ceil(GROUP), d, 1],
            [w.div_ceil(GROUP), h, 1],
        ];
        let (_table, set, pipeline) = (&self.table, &self.set, &self.pipeline);
        // The set binds `field` (sampled) and the table (storage): each scan's dispatch is
        // ordered after the previous one's writes by the barriers those bindings declare.
        rec.pass(SCOPE, &[], |rec| {
            for (axis, groups) in groups.into_iter().enumerate() {
                let push = ScanPush {
                    axis: axis as i32,
                    scale: 2f32.powi(exponent),
                    bound,
                };
                rec.begin_scope(AXIS_SCOPES[axis]);
                rec.dispatch(pipeline, set, bytemuck::bytes_of(&push), groups)?;
                rec.end_scope();
            }
            // Readers' declared uses transition the table.
            Ok(())
        })?;
        self.exponent = exponent;
        self.bound = bound;
        Ok(())
    }

    /// The table (R32G32_UINT, 3D): sample it with texelFetch through `glsl/sat3d.glsl`.
    pub fn image(&self) -> &Image {
        &self.table
    }

    pub fn extent(&self) -> [u32; 3] {
        self.extent
    }

    /// The fixed-point scale's exponent k (values are summed as round(v · 2^k)).
    pub fn exponent(&self) -> i32 {
        self.exponent
    }

    /// 2^-k, `SAT3D_INV_SCALE` of `glsl/sat3d.glsl`.
    pub fn inv_scale(&self) -> f32 {
        2f32.powi(-self.exponent)
    }

    /// The bound the values were clamped to.
    pub fn bound(&self) -> f32 {
        self.bound
    }

    /// Read the table back.
    pub fn read(&self, ctx: &Context) -> Result<Sat3dReadback> {
        let bytes = ctx.read_image(&self.table, 0)?;
        Ok(Sat3dReadback {
            table: bytemuck::pod_collect_to_vec::<u8, i64>(&bytes),
            extent: self.extent,
            exponent: self.exponent,
        })
    }

    /// Box averages evaluated on the GPU by `glsl/sat3d.glsl`'s `sat_box_average`
    /// (`glsl/sat3d_probe.comp`), one per box: the shader-side read path, for tests.
    pub fn box_averages_on_gpu(&self, ctx: &Context, boxes: &[VoxelBox]) -> Result<Vec<f32>> {
        let texels: Vec<[i32; 4]> = boxes
            .iter()
            .flat_map(|b| {
                [
                    [b.lo[0], b.lo[1], b.lo[2], 0],
                    [b.hi[0], b.hi[1], b.hi[2], 0],
                ]
            })
            .collect();
        self.probe(
            ctx,
            shaders::SAT3D_PROBE_COMP,
            bytemuck::cast_slice(&texels),
            boxes.len(),
            0,
        )
    }

    /// Run a probe shader over the table: `count` items of `input` (a storage buffer at
    /// binding 1) to one f32 each (binding 2), the table at binding 0, push constants
    /// (dims.xyz, `w`; inv_scale; count) as `glsl/sat3d_probe.comp` declares them.
    pub(crate) fn probe(
        &self,
        ctx: &Context,
        spirv: &[u8],
        input: &[u8],
        count: usize,
        w: i32,
    ) -> Result<Vec<f32>> {
        let slots = count.max(1);
        let mut input_buffer = Buffer::new(
            ctx,
            input.len().max(16) as u64,
            vk::usage::STORAGE_BUFFER,
            Memory::Upload,
            "3D SAT probe input",
        )?;
        input_buffer.write(0, input)?;
        let output = Buffer::new(
            ctx,
            (slots * 4) as u64,
            vk::usage::STORAGE_BUFFER | vk::usage::BUFFER_TRANSFER_SRC,
            Memory::Gpu,
            "3D SAT probe results",
        )?;
        let host = Buffer::readback(ctx, (slots * 4) as u64, "3D SAT probe readback")?;
        let sampler = Sampler::new(ctx, Filter::Nearest, "3D SAT probe")?;
        let set = DescriptorSet::new(
            ctx,
            &[
                Binding::Texture(&self.table, &sampler),
                Binding::Storage(&input_buffer),
                Binding::Storage(&output),
            ],
            "3D SAT probe",
        )?;
        let pipeline = ComputePipeline::new(
            ctx,
            spirv,
            &set,
            std::mem::size_of::<ProbePush>() as u32,
            "3D SAT probe",
        )?;
        let [x, y, z] = self.extent.map(|e| e as i32);
        let push = ProbePush {
            dims: [x, y, z, w],
            inv_scale: self.inv_scale(),
            count: count as u32,
            pad: [0; 2],
        };
        ctx.execute(|rec| {
            rec.pass(
                "3D SAT probe",
                &[], // the set's bindings declare the table's sampled read
                |rec| {
                    rec.dispatch(
                        &pipeline,
                        &set,
                        bytemuck::bytes_of(&push),
                        [(slots as u32).div_ceil(GROUP), 1, 1],
                    )
                },
            )?;
            rec.copy_storage_to_host(&output, &host);
            Ok(())
        })?;
        host.read_values(count)
    }
}

/// A read-back table, for box averages on the host (tests, checks).
pub struct Sat3dReadback {
    /// S(x, y, z) at x + w (y + h z), in units of 2^-k.
    pub table: Vec<i64>,
    pub extent: [u32; 3],
    pub exponent: i32,
}

impl Sat3dReadback {
    /// S at `p`, zero where a coordinate is below 0 (p ≤ extent − 1 on every axis).
    pub fn at(&self, p: [i64; 3]) -> i64 {
        if p.iter().any(|&c| c < 0) {
            return 0;
        }
        let [w, h, _] = self.extent.map(|e| e as i64);
        self.table[(p[0] + w * (p[1] + h * p[2])) as usize]
    }

    /// The exact fixed-point sum over the part of `b` inside the volume.
    pub fn box_sum(&self, b: VoxelBox) -> i64 {
        let a: [i64; 3] = std::array::from_fn(|i| b.lo[i].max(0) as i64 - 1);
        let c: [i64; 3] = std::array::from_fn(|i| (b.hi[i] as i64).min(self.extent[i] as i64 - 1));
        if (0..3).any(|i| c[i] <= a[i]) {
            return 0;
        }
        let mut s = 0i64;
        for corner in 0u32..8 {
            let p: [i64; 3] =
                std::array::from_fn(|i| if corner >> i & 1 == 1 { a[i] } else { c[i] });
            let sign = if corner.count_ones() % 2 == 0 { 1 } else { -1 };
            s = s.wrapping_add(sign * self.at(p));
        }
        s
    }

    /// The field's average over `b`, the outside counting as zero over the whole box (0 for
    /// an empty box).
    pub fn box_average(&self, b: VoxelBox) -> f64 {
        let volume = b.volume();
        if volume == 0 {
            return 0.0;
        }
        self.box_sum(b) as f64 * 2f64.powi(-self.exponent) / volume as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scan_push_matches_the_shaders_block() {
        crate::assert_host_block!(
            shaders::SAT3D_SCAN_COMP,
            "Push",
            ScanPush { axis, scale, bound },
            exact_size = false
        );
    }

    #[test]
    fn probe_push_matches_the_shaders_block() {
        crate::assert_host_block!(
            shaders::SAT3D_PROBE_COMP,
            "Push",
            ProbePush {
                dims,
                inv_scale,
                count
            },
            exact_size = false
        );
    }

    #[test]
    fn the_scale_leaves_headroom_below_2_pow_63() {
        for (voxels, bound) in [
            (1u64, 1.0f32),
            (256 * 256 * 256, 1000.0),
            (37 * 29 * 23, 0.3),
        ] {
            let k = scale_exponent(voxels, bound);
            let m = voxels as f64 * bound as f64;
            assert!(m * 2f64.powi(k) <= 2f64.powi(61), "{voxels} {bound}: k {k}");
            assert!(
                m * 2f64.powi(k + 1) > 2f64.powi(61),
                "{voxels} {bound}: k {k}"
            );
            // The largest quantised value splits into words exactly.
            let q = quantise(bound, bound, k);
            assert!(q > 0 && (q as f64 - bound as f64 * 2f64.powi(k)).abs() <= 0.5);
        }
    }
}
