//! Volumes in memory: a regular grid of scalar voxels with per-axis spacing.
//!
//! On upload every voxel type becomes a [0,1] value in a 3D texture with trilinear
//! filtering (thesis sect. 3.1): u8 and u16 through UNORM formats, f32 by mapping the
//! volume's value range onto [0,1] on the CPU first.

pub mod formats;
pub mod histogram;
pub mod orientation;
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
    /// The direction of each voxel axis (x, y, z) in the patient's LPS frame (DICOM's:
    /// +x left, +y posterior, +z superior), unit length, when the file states it (NIfTI
    /// sform/qform, NRRD space directions, DICOM ImageOrientationPatient).
    pub axes: Option<[[f32; 3]; 3]>,
    /// The sample type the file stores ("int16", "float32", ...), when read from a file:
    /// the voxels may hold another (signed or windowed data become f32 on loading).
    pub stored: Option<&'static str>,
    /// False when the file did not state the voxel spacing and 1 × 1 × 1 was assumed (a
    /// raw file without a sidecar, a header without spacings): the scene warns, since a
    /// CT with 5 mm slices then renders squashed.
    pub spacing_stated: bool,
    /// A label map (segmentation): its values name categories, so the renderer
    /// classifies the nearest voxel instead of interpolating (`crate::labels`).
    pub labels: bool,
}

impl Volume {
    pub fn new(dims: [u32; 3], spacing: [f32; 3], voxels: Voxels) -> Result<Self> {
        let v = Self {
            dims,
            spacing,
            voxels,
            range: None,
            axes: None,
            stored: None,
            spacing_stated: true,
            labels: false,
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
        // f32 values are mapped onto [0, 1] over their range (or the window): a span beyond
        // f32 (values near ±3e38) made every mapped value 0 and the reported range NaN.
        if let Voxels::F32(_) = &self.voxels {
            let (lo, hi) = self.value_range();
            ensure!(
                (hi - lo).is_finite(),
                "the values span {lo:e} .. {hi:e}, wider than 32-bit floats can map onto \
                 0 .. 1; give the range that matters with --window LO,HI"
            );
        }
        Ok(())
    }

    /// Mirrors the voxels along the given axes (0 = x, 1 = y, 2 = z). Flipping two axes is
    /// a 180° rotation and keeps the data's handedness; one axis mirrors it.
    pub fn flip(&mut self, axes: [bool; 3]) {
        self.reorder([0, 1, 2], axes);
    }

    /// Turns the volume about the world's axes by quarter turns
    /// ([`orientation::parse_rotation`]): new axis k is the old axis row k of `r` names,
    /// reversed where its entry is −1.
    pub fn rotate(&mut self, r: orientation::QuarterTurns) {
        let mut perm = [0usize; 3];
        let mut reverse = [false; 3];
        for k in 0..3 {
            let j = (0..3).find(|&j| r[k][j] != 0).unwrap_or(k);
            perm[k] = j;
            reverse[k] = r[k][j] < 0;
        }
        self.reorder(perm, reverse);
    }

    /// Rearranges the voxels so that new axis `k` is old axis `perm[k]`, reversed where
    /// `reverse[k]`: dims, spacing and [`Volume::axes`] follow.
    pub fn reorder(&mut self, perm: [usize; 3], reverse: [bool; 3]) {
        fn remap<T: Copy>(v: &mut Vec<T>, old: [usize; 3], perm: [usize; 3], rev: [bool; 3]) {
            let old_stride = [1, old[0], old[0] * old[1]];
            let n = perm.map(|a| old[a]);
            let stride = perm.map(|a| old_stride[a]);
            // Old index of new voxel (0,0,0) and the step per new axis, signed.
            let mut base = 0isize;
            let mut step = [0isize; 3];
            for k in 0..3 {
                if rev[k] {
                    base += ((n[k] - 1) * stride[k]) as isize;
                    step[k] = -(stride[k] as isize);
                } else {
                    step[k] = stride[k] as isize;
                }
            }
            let src = std::mem::take(v);
            let mut out = Vec::with_capacity(src.len());
            for z in 0..n[2] as isize {
                for y in 0..n[1] as isize {
                    let row = base + z * step[2] + y * step[1];
                    out.extend((0..n[0] as isize).map(|x| src[(row + x * step[0]) as usize]));
                }
            }
            *v = out;
        }
        if perm == [0, 1, 2] && !reverse.iter().any(|&r| r) {
            return;
        }
        let old = self.dims.map(|d| d as usize);
        match &mut self.voxels {
            Voxels::U8(v) => remap(v, old, perm, reverse),
            Voxels::U16(v) => remap(v, old, perm, reverse),
            Voxels::F32(v) => remap(v, old, perm, reverse),
        }
        self.dims = perm.map(|a| self.dims[a]);
        self.spacing = perm.map(|a| self.spacing[a]);
        if let Some(axes) = self.axes {
            self.axes = Some(std::array::from_fn(|k| {
                let d = axes[perm[k]];
                if reverse[k] {
                    d.map(|c| -c)
                } else {
                    d
                }
            }));
        }
    }

    /// Turns a volume whose file states its orientation ([`Volume::axes`]) so the patient
    /// stands upright facing the default camera: x towards the patient's left, y
    /// superior (up), z anterior. Each voxel axis goes to the world axis its direction is
    /// closest to (oblique scans are not resampled). Returns what was done, for the user,
    /// or `None` when the file states no orientation or the volume is upright already.
    pub fn turn_upright(&mut self) -> Option<String> {
        let axes = self.axes?;
        // LPS component (0 = L, 1 = P, 2 = S) each voxel axis is closest to, and its sign.
        let dominant = axes.map(|d| {
            let j = (0..3)
                .max_by(|&a, &b| d[a].abs().total_cmp(&d[b].abs()))
                .unwrap_or(0);
            (j, d[j] >= 0.0)
        });
        // World x = L (+LPS x), y = S (+LPS z), z = A (−LPS y).
        let want = [(0, true), (2, true), (1, false)];
        let mut perm = [usize::MAX; 3];
        let mut reverse = [false; 3];
        for (k, &(lps, positive)) in want.iter().enumerate() {
            let Some(src) = dominant.iter().position(|&(j, _)| j == lps) else {
                // Two voxel axes nearest one patient axis: parallel or oblique axes. Said,
                // not skipped quietly.
                return Some(format!(
                    "not turned upright: the file's orientation (voxel axes {axes:?} in LPS) \
                     has no voxel axis along {}, as two point the same way or the volume is \
                     oblique; turn it with --rotate, or give --orientation",
                    ["left-right", "anterior-posterior", "inferior-superior"][lps]
                ));
            };
            perm[k] = src;
            reverse[k] = dominant[src].1 != positive;
        }
        if perm == [0, 1, 2] && reverse == [false; 3] {
            return None;
        }
        let name = |(j, pos): (usize, bool)| ["RL", "AP", "IS"][j].chars().nth(pos as usize);
        let from: String = dominant.iter().filter_map(|&d| name(d)).collect();
        self.reorder(perm, reverse);
        Some(format!(
            "turned upright from the stated orientation (voxel axes x, y, z pointed {from}; \
             now L, S, A: head up, facing the camera); --flip applies after this"
        ))
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
    fn parallel_or_oblique_axes_are_said_and_leave_the_volume_as_it_is() {
        let voxels: Vec<u8> = (0..8).collect();
        for axes in [
            [[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
            [[0.6, 0.6, 0.0], [-0.6, 0.6, 0.0], [0.0, 0.0, 1.0]],
        ] {
            let mut v = Volume::new([2, 2, 2], [1.0; 3], Voxels::U8(voxels.clone())).unwrap();
            v.axes = Some(axes);
            let note = v.turn_upright().expect("a note");
            assert!(note.starts_with("not turned upright"), "{note}");
            assert_eq!(v.voxels, Voxels::U8(voxels.clone()));
        }
    }

    #[test]
    fn values_spanning_beyond_f32_are_refused_and_a_window_mends_it() {
        let mut v = Volume::new([2, 2, 2], [1.0; 3], Voxels::F32(vec![0.0; 8])).unwrap();
        if let Voxels::F32(x) = &mut v.voxels {
            x[0] = -3e38;
            x[1] = 3e38;
        }
        let e = v.validate().unwrap_err().to_string();
        assert!(e.contains("--window"), "{e}");
        v.range = Some((-1.0, 1.0));
        v.validate().unwrap();
    }

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

    /// A marker on the patient's left, superior, anterior corner ends at the world's
    /// +x, +y, +z corner, whatever the file's axes (anatomy, not arithmetic: the
    /// expected corner follows from the patient directions alone).
    #[test]
    fn turning_upright_puts_left_superior_anterior_at_plus_x_y_z() {
        let dims = [3u32, 4, 5];
        let n = 60;
        // (axes in LPS, the marker's voxel for the left-superior-anterior corner, the
        // spacing along world x, y, z after turning: that of the voxel axis moved there)
        type Case = ([[f32; 3]; 3], [usize; 3], [f32; 3]);
        let cases: [Case; 3] = [
            // NIfTI RAS+ (x right, y anterior, z superior): left = x 0.
            (
                [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]],
                [0, 3, 4],
                [1.0, 3.0, 2.0],
            ),
            // DICOM axial LPS (x left, y posterior, z superior): anterior = y 0.
            (
                [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                [2, 0, 4],
                [1.0, 3.0, 2.0],
            ),
            // Sagittal, slightly oblique: x anterior, y inferior, z left.
            (
                [[0.05, -0.99, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.05]],
                [2, 0, 4],
                [3.0, 2.0, 1.0],
            ),
        ];
        for (axes, [mx, my, mz], spacing) in cases {
            let mut v = vec![0u8; n];
            v[(mz * 4 + my) * 3 + mx] = 255;
            let mut vol = Volume::new(dims, [1.0, 2.0, 3.0], Voxels::U8(v)).unwrap();
            vol.axes = Some(axes);
            let said = vol.turn_upright().expect("turned");
            assert!(said.contains("L, S, A"), "{said}");
            let Voxels::U8(f) = &vol.voxels else { panic!() };
            let [nx, ny, nz] = vol.dims.map(|d| d as usize);
            let at = f.iter().position(|&x| x == 255).unwrap();
            assert_eq!(
                (at % nx, (at / nx) % ny, at / (nx * ny)),
                (nx - 1, ny - 1, nz - 1),
                "{axes:?}"
            );
            // Spacing moved with its axis; the new axes point L, S, A.
            assert_eq!(vol.spacing, spacing, "{axes:?}");
            let new_axes = vol.axes.unwrap();
            assert!(new_axes[0][0] > 0.9 && new_axes[1][2] > 0.9 && new_axes[2][1] < -0.9);
            assert_eq!(vol.turn_upright(), None, "upright already");
        }
    }
}
