//! A viewer that answers at once (issue 36): while the view changes, frames are previews
//! at a reduced cost chosen to fit a frame-time budget; once the view has been still for
//! [`SETTLE`], one frame at full quality replaces the preview, and nothing is drawn after it
//! until the view changes again.
//!
//! The cost levers are the image's size and the sample distance: a sweep's cost is about
//! (planes) × (a fixed cost per plane + a cost per pixel), and the planes are the volume's
//! depth over the sample distance. The forward transport's light rays follow the pixels
//! (a budget per pixel), so a smaller preview also has fewer light rays. The levels form a
//! ladder; each step down it halves the preview's side (a quarter of the pixels) or
//! doubles its sample distance (half the planes), alternately.
//!
//! The ladder's rung is learned from the GPU times of the previews themselves: over the
//! budget, one rung cheaper; one rung dearer when that rung's predicted time is within
//! [`CLIMB_MARGIN`] of the budget. The prediction is the rung's own last time where it has
//! one (for this window size and model), else this rung's time times the most the step can
//! cost: the ratio of the two rungs' pixels for a size step (the sweep's fixed cost per
//! plane makes the true ratio smaller), 2 for a sample-distance step (the planes). So a
//! climb never expects to overshoot the budget. The first preview of a session is the
//! cheapest, so that the first interaction answers at once whatever the device; the rung
//! found is kept between interactions.

use std::time::Duration;

/// How long the view must stay unchanged before the full-quality frame is drawn.
pub const SETTLE: Duration = Duration::from_millis(300);
/// The preview frame-time budget unless `--preview-budget` says otherwise (GPU ms).
pub const DEFAULT_BUDGET_MS: f64 = 100.0;
/// The cheapest rung: 1/16 of the window's side and 16 × the sample distance.
pub const MAX_LEVEL: u8 = 8;
/// A preview's shorter side is never cut below this many pixels (or the window's).
pub const MIN_PREVIEW_SIDE: u32 = 16;
/// A dearer rung is taken when its predicted time is at most this share of the budget.
const CLIMB_MARGIN: f64 = 0.8;

/// The quality of one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Quality {
    /// The view as asked for: the window's size and the view's sample distance.
    Full,
    /// Rung `k` of the ladder (1 ..= [`MAX_LEVEL`]): the side divided by 2^⌈k/2⌉, the sample
    /// distance multiplied by 2^⌊k/2⌋.
    Preview(u8),
}

impl Quality {
    /// The divisor of the window's side.
    pub fn divisor(self) -> u32 {
        match self {
            Quality::Full => 1,
            Quality::Preview(k) => 1 << k.div_ceil(2),
        }
    }

    /// The factor on the view's sample distance.
    pub fn sample_factor(self) -> f32 {
        match self {
            Quality::Full => 1.0,
            Quality::Preview(k) => (1u32 << (k / 2)) as f32,
        }
    }

    /// The frame's size for a window of `window` pixels: each side divided by the
    /// divisor (rounded up), the aspect kept, the shorter side not below
    /// [`MIN_PREVIEW_SIDE`] (nor above the window's).
    pub fn size(self, window: [u32; 2]) -> [u32; 2] {
        let d = self.divisor();
        if d == 1 {
            return window;
        }
        let short = window[0].min(window[1]).max(1);
        let floor = MIN_PREVIEW_SIDE.min(short);
        // The divisor that keeps the shorter side at the floor, if `d` would cut below it.
        let d = d.min((short / floor).max(1));
        [window[0].div_ceil(d), window[1].div_ceil(d)]
    }

    /// "full" or "preview 64x48, sample distance ×4", for the title and the log.
    pub fn describe(self, window: [u32; 2]) -> String {
        match self {
            Quality::Full => "full".to_string(),
            Quality::Preview(_) => {
                let [w, h] = self.size(window);
                format!("preview {w}x{h}, sample distance x{}", self.sample_factor())
            }
        }
    }
}

/// The rung of the ladder that fits the budget, learned from the previews' GPU times.
#[derive(Clone, Debug)]
pub struct PreviewControl {
    budget_ms: f64,
    level: u8,
    /// The window size the times below are for.
    window: [u32; 2],
    /// The last GPU time of each rung (index k).
    measured: [Option<f64>; MAX_LEVEL as usize + 1],
}

impl PreviewControl {
    /// Start at the cheapest rung.
    pub fn new(budget_ms: f64) -> Self {
        Self {
            budget_ms,
            level: MAX_LEVEL,
            window: [0, 0],
            measured: [None; MAX_LEVEL as usize + 1],
        }
    }

    /// Forget the rungs' times (the model changed; a new window size does this itself).
    pub fn forget(&mut self) {
        self.measured = [None; MAX_LEVEL as usize + 1];
    }

    pub fn budget_ms(&self) -> f64 {
        self.budget_ms
    }

    /// The quality of the next preview.
    pub fn quality(&self) -> Quality {
        Quality::Preview(self.level)
    }

    /// A preview of `quality` in a window of `window` pixels took `gpu_ms`. Its time is
    /// kept for its rung; only the current rung's time moves the rung (frames recorded
    /// before the last move arrive late).
    pub fn observe(&mut self, quality: Quality, gpu_ms: f64, window: [u32; 2]) {
        let Quality::Preview(k) = quality else {
            return;
        };
        if window != self.window {
            self.window = window;
            self.forget();
        }
        self.measured[k as usize] = Some(gpu_ms);
        if k != self.level {
            return;
        }
        if gpu_ms > self.budget_ms {
            self.level = (k + 1).min(MAX_LEVEL);
        } else if k > 1 {
            let dearer = Quality::Preview(k - 1);
            let predicted = self.measured[k as usize - 1].unwrap_or_else(|| {
                if k % 2 == 1 {
                    // A size step: at most the ratio of the pixels.
                    let pixels = |q: Quality| {
                        let [w, h] = q.size(window);
                        w as f64 * h as f64
                    };
                    gpu_ms * pixels(dearer) / pixels(quality)
                } else {
                    // A sample-distance step: twice the planes.
                    gpu_ms * 2.0
                }
            });
            if predicted <= CLIMB_MARGIN * self.budget_ms {
                self.level = k - 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ladder_alternates_size_and_sample_distance() {
        let w = [512, 384];
        let steps: Vec<(u32, f32)> = (1..=MAX_LEVEL)
            .map(|k| {
                let q = Quality::Preview(k);
                (q.divisor(), q.sample_factor())
            })
            .collect();
        assert_eq!(
            steps,
            [
                (2, 1.0),
                (2, 2.0),
                (4, 2.0),
                (4, 4.0),
                (8, 4.0),
                (8, 8.0),
                (16, 8.0),
                (16, 16.0)
            ]
        );
        assert_eq!(Quality::Full.size(w), w);
        assert_eq!(Quality::Preview(3).size(w), [128, 96]);
        // 384 / 16 = 24 ≥ 16: the full divisor applies.
        assert_eq!(Quality::Preview(8).size(w), [32, 24]);
        // A small window keeps its shorter side at 16 pixels, or whole when smaller.
        assert_eq!(Quality::Preview(8).size([100, 40]), [50, 20]);
        assert_eq!(Quality::Preview(8).size([30, 10]), [30, 10]);
        assert_eq!(Quality::Preview(1).size([7, 5]), [7, 5]);
    }

    #[test]
    fn the_control_finds_the_rung_a_cost_model_fits() {
        // A device where the pixels dominate (a GPU): a frame costs planes × (0.05 ms +
        // 1.5e-5 ms per pixel), 400 planes at full quality on 512² (1.6 s). The rungs cost
        // 1.6, 3.3, 5.6, 11, 30, 59, 207, 413 ms from 8 to 1: rung 3 is the dearest within
        // 100 ms, and every climb to it is predicted within 80 ms.
        let cost = |q: Quality| {
            let [w, h] = q.size([512, 512]);
            let planes = (400.0 / q.sample_factor() as f64).ceil();
            planes * (0.05 + 1.5e-5 * (w * h) as f64)
        };
        let w = [512, 512];
        let mut c = PreviewControl::new(100.0);
        let mut seen = Vec::new();
        for _ in 0..20 {
            let q = c.quality();
            let ms = cost(q);
            seen.push(ms);
            c.observe(q, ms, w);
        }
        assert!(seen.iter().all(|&ms| ms <= 100.0), "{seen:?}");
        let q = c.quality();
        assert_eq!(q, Quality::Preview(3), "{seen:?}");
        let k = 3;
        // A slower moment (another program on the device) steps down, and the rung it
        // left, now known to overshoot, is not retried while its time says so.
        c.observe(q, 250.0, w);
        assert_eq!(c.quality(), Quality::Preview(k + 1));
        c.observe(Quality::Preview(k + 1), 1.0, w);
        assert_eq!(c.quality(), Quality::Preview(k + 1));
        // Late times of another rung do not move the rung.
        c.observe(Quality::Preview(1), 1.0, w);
        c.observe(Quality::Full, 1.0, w);
        assert_eq!(c.quality(), Quality::Preview(k + 1));
        for _ in 0..20 {
            let q = c.quality();
            c.observe(q, 1e6, w);
        }
        assert_eq!(c.quality(), Quality::Preview(MAX_LEVEL));
    }

    #[test]
    fn size_steps_are_predicted_from_the_pixels_and_times_are_per_window() {
        // At 256² rungs 7 and 8 are both 16² (the floor side). From rung 8 the step to
        // rung 7 changes only the sample distance, predicted at 2 ×; from rung 7 the size
        // step to rung 6 (32²) is predicted at 4 × rung 7's time.
        let w = [256, 256];
        assert_eq!(Quality::Preview(7).size(w), Quality::Preview(8).size(w));
        let mut c = PreviewControl::new(100.0);
        c.observe(Quality::Preview(8), 30.0, w);
        assert_eq!(c.quality(), Quality::Preview(7));
        c.observe(Quality::Preview(7), 25.0, w);
        assert_eq!(c.quality(), Quality::Preview(7), "4 × 25 ms > 80 ms");
        c.observe(Quality::Preview(7), 19.0, w);
        assert_eq!(c.quality(), Quality::Preview(6), "4 × 19 ms ≤ 80 ms");
        // Rung 6 overshoots in a larger window: one rung back. Back in the first window,
        // that time is forgotten (it was for another size) and rung 6 is tried again.
        c.observe(Quality::Preview(6), 120.0, [512, 512]);
        assert_eq!(c.quality(), Quality::Preview(7));
        c.observe(Quality::Preview(7), 19.0, w);
        assert_eq!(c.quality(), Quality::Preview(6));
    }
}
