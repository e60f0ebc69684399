//! The value histogram of a volume as the renderer sees it (values mapped to [0,1] as on
//! upload), its percentiles and Otsu thresholds: what a transfer function for data nobody
//! has looked at yet is derived from, and what the empty-image warning compares against.

use super::{Volume, Voxels};

/// Bins of [`Histogram`] over [0,1].
pub const BINS: usize = 256;

/// Voxels looked at, at most: every n-th voxel beyond that (enough for percentiles and
/// thresholds; a 512³ scan is counted in milliseconds).
const MAX_SAMPLES: u64 = 1 << 22;

/// Counts of the volume's normalised values in [`BINS`] equal bins over [0,1].
#[derive(Clone, Debug, PartialEq)]
pub struct Histogram {
    pub counts: Vec<u64>,
    /// Smallest and largest normalised value seen.
    pub min: f32,
    pub max: f32,
}

impl Histogram {
    pub fn of(volume: &Volume) -> Self {
        let n = volume.voxels.len() as u64;
        let stride = n.div_ceil(MAX_SAMPLES).max(1) as usize;
        let mut counts = vec![0u64; BINS];
        let (mut min, mut max) = (f32::INFINITY, f32::NEG_INFINITY);
        let mut add = |s: f32| {
            let s = s.clamp(0.0, 1.0);
            min = min.min(s);
            max = max.max(s);
            counts[((s * BINS as f32) as usize).min(BINS - 1)] += 1;
        };
        match &volume.voxels {
            Voxels::U8(v) => v
                .iter()
                .step_by(stride)
                .for_each(|&x| add(x as f32 / 255.0)),
            Voxels::U16(v) => v
                .iter()
                .step_by(stride)
                .for_each(|&x| add(x as f32 / 65535.0)),
            Voxels::F32(v) => {
                let (lo, hi) = volume.value_range();
                let scale = if hi > lo { 1.0 / (hi - lo) } else { 0.0 };
                v.iter()
                    .step_by(stride)
                    .for_each(|&x| add((x - lo) * scale));
            }
        }
        Self { counts, min, max }
    }

    fn total(&self) -> u64 {
        self.counts.iter().sum()
    }

    /// The normalised value below which a fraction `p` of the voxels lie (bin centres).
    pub fn percentile(&self, p: f64) -> f32 {
        let target = (p * self.total() as f64).ceil() as u64;
        let mut acc = 0;
        for (i, c) in self.counts.iter().enumerate() {
            acc += c;
            if acc >= target.max(1) {
                return (i as f32 + 0.5) / BINS as f32;
            }
        }
        1.0
    }

    /// Otsu's threshold over the bins `range` (between-class variance maximised): the
    /// value that best splits them into two classes, as the first bin of the upper one.
    /// Where several thresholds split equally well (an empty gap between two classes),
    /// the middle of them: the threshold then sits halfway between the classes.
    pub fn otsu(&self, range: std::ops::Range<usize>) -> usize {
        let bins = &self.counts[range.clone()];
        let total: f64 = bins.iter().map(|&c| c as f64).sum();
        let sum: f64 = bins
            .iter()
            .enumerate()
            .map(|(i, &c)| i as f64 * c as f64)
            .sum();
        let (mut w0, mut sum0) = (0.0, 0.0);
        let (mut best, mut last_best, mut best_var) = (range.start + 1, range.start + 1, -1.0);
        for (i, &c) in bins.iter().enumerate().take(bins.len().saturating_sub(1)) {
            w0 += c as f64;
            sum0 += i as f64 * c as f64;
            let w1 = total - w0;
            if w0 == 0.0 || w1 == 0.0 {
                continue;
            }
            let (m0, m1) = (sum0 / w0, (sum - sum0) / w1);
            let var = w0 * w1 * (m0 - m1) * (m0 - m1);
            if var > best_var * (1.0 + 1e-12) {
                best_var = var;
                best = range.start + i + 1;
                last_best = best;
            } else if var >= best_var * (1.0 - 1e-12) {
                last_best = range.start + i + 1;
            }
        }
        (best + last_best) / 2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn volume(voxels: Voxels) -> Volume {
        let n = voxels.len() as u32 / 4;
        Volume::new([n, 2, 2], [1.0; 3], voxels).unwrap()
    }

    #[test]
    fn otsu_splits_two_clusters_between_them() {
        // Background at 10, objects at 200: every bin in 11..=200 separates them
        // perfectly; the threshold is the middle of those.
        let mut v = vec![10u8; 700];
        v.extend(vec![200u8; 300]);
        let h = Histogram::of(&volume(Voxels::U8(v)));
        let t = h.otsu(0..BINS);
        assert!((100..=110).contains(&t), "{t}");
        assert_eq!((h.min, h.max), (10.0 / 255.0, 200.0 / 255.0));
        // 70 % of the voxels are at 10/255.
        assert!((h.percentile(0.5) - 10.5 / 256.0).abs() < 1e-6);
        assert!((h.percentile(0.9) - 200.5 / 256.0).abs() < 1e-6);
    }

    #[test]
    fn f32_values_are_binned_through_the_upload_mapping() {
        let v: Vec<f32> = (0..100).map(|i| -1000.0 + 20.0 * i as f32).collect();
        let mut vol = volume(Voxels::F32(v));
        vol.range = Some((-1000.0, 1000.0));
        let h = Histogram::of(&vol);
        assert_eq!(h.min, 0.0);
        assert!((h.max - 980.0 / 2000.0 - 0.5).abs() < 1e-6, "{}", h.max);
    }
}
