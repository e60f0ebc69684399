//! Volumes in memory: a regular grid of scalar voxels with per-axis spacing.
//!
//! On upload every voxel type becomes a [0,1] value in a 3D texture with trilinear
//! filtering (thesis sect. 3.1): u8 and u16 through UNORM formats, f32 by mapping the
//! volume's value range onto [0,1] on the CPU first.

pub mod formats;
pub mod histogram;
pub mod procedural;
pub mod standins;

use anyhow::{bail, ensure, Result};

/// Voxel storage, x fastest, then y, then z.
#[derive(Clone, Debug, PartialEq)]
pub enum Voxels {
    U8(Vec<u8>),
    U16(Vec<u16>),
    F32(Vec<f32>),
}

impl Voxels {
    pub fn len(&self) -> usize {
        match self {
            Voxels::U8(v) => v.len(),
            Voxels::U16(v) => v.len(),
            Voxels::F32(v) => v.len(),
        }
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    pub fn type_name(&self) -> &'static str {
        match self {
            Voxels::U8(_) => "u8",
            Voxels::U16(_) => "u16",
            Voxels::F32(_) => "f32",
        }
    }
}

/// Largest ratio of voxel sides [`Volume::validate`] accepts (real scans: up to ~10, e.g.
/// 0.5 mm pixels with 5 mm slices).
pub const MAX_ANISOTROPY: f32 = 1e4;

#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    pub dims: [u32; 3],
    /// Voxel size along x, y, z (any unit; only ratios matter for rendering).
    pub spacing: [f32; 3],
    pub voxels: Voxels,
    /// For f32 voxels: the values mapped to 0 and 1 on upload. `None` uses the data's
    /// minimum and maximum.
    pub range: Option<(f32, f32)>,
}

impl Volume {
    pub fn new(dims: [u32; 3], spacing: [f32; 3], voxels: Voxels) -> Result<Self> {
        let v = Self {
            dims,
            spacing,
            voxels,
            range: None,
        };
        v.validate()?;
        Ok(v)
    }

    /// Fails, saying why, for dimensions below 2, a voxel count that does not match, a
    /// spacing that is not finite and positive or more anisotropic than
    /// [`MAX_ANISOTROPY`], a non-finite value, or a bad value range.
    pub fn validate(&self) -> Result<()> {
        ensure!(
            self.dims.iter().all(|&d| d >= 2),
            "volume dimensions {:?} must be at least 2 along every axis",
            self.dims
        );
        let n = self.voxel_count();
        ensure!(
            self.voxels.len() as u64 == n,
            "volume of {:?} needs {n} voxels, has {}",
            self.dims,
            self.voxels.len()
        );
        ensure!(
            self.spacing.iter().all(|s| s.is_finite() && *s > 0.0),
            "voxel spacing {:?} must be finite and positive",
            self.spacing
        );
        // The smallest side is the sample-distance unit: a volume far thinner along one
        // axis than another would need astronomically many samples (or none) per ray.
        let (lo, hi) = self
            .spacing
            .iter()
            .fold((f32::INFINITY, 0.0f32), |(lo, hi), &s| {
                (lo.min(s), hi.max(s))
            });
        ensure!(
            hi / lo <= MAX_ANISOTROPY,
            "voxel spacing {:?} has sides that differ by a factor of {:.3e}; at most \
             {MAX_ANISOTROPY} is supported (the smallest side is the unit of the sample \
             distance): check the spacing",
            self.spacing,
            hi / lo
        );
        if let Voxels::F32(v) = &self.voxels {
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                bail!("voxel {i} is not a finite number ({})", v[i]);
            }
        }
        if let Some((lo, hi)) = self.range {
            ensure!(
                lo.is_finite() && hi.is_finite() && hi > lo,
                "value range ({lo}, {hi}) must be finite with max > min"
            );
        }
        Ok(())
    }

    /// Mirrors the voxels along the given axes (0 = x, 1 = y, 2 = z). Flipping two axes is
    /// a 180° rotation and keeps the data's handedness; one axis mirrors it.
    pub fn flip(&mut self, axes: [bool; 3]) {
        fn flip_vec<T: Copy>(v: &mut [T], dims: [u32; 3], axes: [bool; 3]) {
            let [nx, ny, nz] = dims.map(|d| d as usize);
            let src = v.to_vec();
            for z in 0..nz {
                let sz = if axes[2] { nz - 1 - z } else { z };
                for y in 0..ny {
                    let sy = if axes[1] { ny - 1 - y } else { y };
                    for x in 0..nx {
                        let sx = if axes[0] { nx - 1 - x } else { x };
                        v[(z * ny + y) * nx + x] = src[(sz * ny + sy) * nx + sx];
                    }
                }
            }
        }
        if !axes.iter().any(|&a| a) {
            return;
        }
        match &mut self.voxels {
            Voxels::U8(v) => flip_vec(v, self.dims, axes),
            Voxels::U16(v) => flip_vec(v, self.dims, axes),
            Voxels::F32(v) => flip_vec(v, self.dims, axes),
        }
    }

    pub fn voxel_count(&self) -> u64 {
        self.dims.iter().map(|&d| d as u64).product()
    }

    /// Physical size along each axis.
    pub fn extent(&self) -> [f32; 3] {
        [
            self.dims[0] as f32 * self.spacing[0],
            self.dims[1] as f32 * self.spacing[1],
            self.dims[2] as f32 * self.spacing[2],
        ]
    }

    /// Extent scaled so the largest side is 1: the renderer's world box is
    /// [-e/2, e/2] with this `e`.
    pub fn normalised_extent(&self) -> [f32; 3] {
        let e = self.extent();
        let m = e[0].max(e[1]).max(e[2]);
        [e[0] / m, e[1] / m, e[2] / m]
    }

    /// The smallest voxel side in normalised (world) units: one "sample distance" unit.
    pub fn min_voxel_size(&self) -> f32 {
        let e = self.extent();
        let m = e[0].max(e[1]).max(e[2]);
        self.spacing.iter().fold(f32::INFINITY, |a, &s| a.min(s)) / m
    }

    /// Texel bytes as uploaded (f32 values mapped to [0,1] through `range`).
    /// The raw values mapped to 0 and 1 on upload: the type's range for u8 and u16, the
    /// window ([`Volume::range`]) or the data's minimum and maximum for f32.
    pub fn value_range(&self) -> (f32, f32) {
        match &self.voxels {
            Voxels::U8(_) => (0.0, 255.0),
            Voxels::U16(_) => (0.0, 65535.0),
            Voxels::F32(v) => self.range.unwrap_or_else(|| {
                let lo = v.iter().copied().fold(f32::INFINITY, f32::min);
                let hi = v.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                (lo, hi)
            }),
        }
    }

    /// The raw value a normalised (uploaded) value `s` stands for.
    pub fn raw_value(&self, s: f32) -> f32 {
        let (lo, hi) = self.value_range();
        lo + s * (hi - lo)
    }

    pub fn texel_bytes(&self) -> Vec<u8> {
        match &self.voxels {
            Voxels::U8(v) => v.clone(),
            Voxels::U16(v) => bytemuck::cast_slice(v).to_vec(),
            Voxels::F32(v) => {
                let (lo, hi) = self.value_range();
                let scale = if hi > lo { 1.0 / (hi - lo) } else { 0.0 };
                let mapped: Vec<f32> = v.iter().map(|&x| (x - lo) * scale).collect();
                bytemuck::cast_slice(&mapped).to_vec()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flip_mirrors_the_named_axes() {
        let dims = [3, 2, 2];
        let v: Vec<u8> = (0..12).collect();
        let mut vol = Volume::new(dims, [1.0; 3], Voxels::U8(v)).unwrap();
        vol.flip([true, false, false]);
        let Voxels::U8(f) = &vol.voxels else { panic!() };
        assert_eq!(&f[..3], &[2, 1, 0]);
        vol.flip([true, true, true]);
        let Voxels::U8(f) = &vol.voxels else { panic!() };
        // x flipped twice (identity), y and z once: voxel (0,0,0) comes from (0,1,1).
        assert_eq!(f[0], 9);
    }
}
