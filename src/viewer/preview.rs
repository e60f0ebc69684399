//! A viewer that answers at once (issue 36): while the view changes, frames are previews
//! at a reduced cost chosen to fit a frame-time budget; once the view has been still for
//! [`SETTLE`], one frame at full quality replaces the preview, and nothing is drawn after it
//! until the view changes again.
//!
//! The cost levers are the image's size and the sample distance: a sweep's cost is about
//! (planes) × (a fixed cost per plane + a cost per pixel), and the planes are the volume's
//! depth over the sample distance. The forward transport's light rays follow the pixels
//! (a budget per pixel), so a smaller preview also has fewer light rays, and previews
//! space them twice as far apart as the view asks (`--light-spacing`, up to its limit):
//! a quarter of the rays. The levels form a
//! ladder; each step down it halves the preview's side (a quarter of the pixels) or
//! doubles its sample distance (half the planes), alternately.
//!
//! Before the first frame the viewer renders two rungs off screen ([`CALIBRATION`]: the
//! cheapest, and the one with twice its side and half its sample distance) and fits a
//! cost model to their GPU times, t ≈ (a + b · pixels) / (sample-distance factor): a
//! fixed cost per plane and one per pixel and plane ([`PreviewControl::calibrate`]). It
//! starts at the dearest rung the model puts within [`CLIMB_MARGIN`] of the budget. A CPU
//! device has a large fixed cost per plane (lavapipe: about 1.5 ms), so its previews can be
//! larger than the pixels alone would allow; on a GPU the pixels dominate.
//!
//! From then on the rung is learned from the previews' own times: over the budget, one
//! rung cheaper; one rung dearer when that rung's predicted time is within the margin.
//! The prediction is the rung's own last time where it has one (for this window size and
//! model), else the model's, else (no model: a window too small for two sizes) this rung's
//! time times the most the step can cost: the ratio of the two rungs' pixels for a size
//! step, 2 for a sample-distance step. The rung found is kept between interactions; a new
//! model forgets the times and the fit, a new window size the times.

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
/// The rungs timed off screen before the first frame: two sizes, for the cost model.
pub const CALIBRATION: [u8; 2] = [MAX_LEVEL, MAX_LEVEL - 2];

/// What to draw next: `preview` (the controller's rung; None when previews are off) while
/// the view changed less than [`SETTLE`] ago, else a full frame, and nothing once that is
/// shown (`refined`) unless frames are drawn continuously (`--frames`). `forced`: a
/// screenshot or the last scripted frame, always full.
pub fn next_frame(
    preview: Option<Quality>,
    since_change: Duration,
    refined: bool,
    continuous: bool,
    forced: bool,
) -> Option<Quality> {
    if forced {
        return Some(Quality::Full);
    }
    match preview {
        Some(q) if since_change < SETTLE => Some(q),
        _ if refined && !continuous => None,
        _ => Some(Quality::Full),
    }
}

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
    /// The cost model (a, b): t ≈ (a + b · pixels) / sample-distance factor, in ms.
    fit: Option<(f64, f64)>,
}

fn pixels(q: Quality, window: [u32; 2]) -> f64 {
    let [w, h] = q.size(window);
    w as f64 * h as f64
}

impl PreviewControl {
    /// Start at the cheapest rung.
    pub fn new(budget_ms: f64) -> Self {
        Self {
            budget_ms,
            level: MAX_LEVEL,
            window: [0, 0],
            measured: [None; MAX_LEVEL as usize + 1],
            fit: None,
        }
    }

    /// Forget the rungs' times and the cost model (the optical model changed).
    pub fn forget(&mut self) {
        self.measured = [None; MAX_LEVEL as usize + 1];
        self.fit = None;
    }

    /// Times are per window size: a new one forgets them (the cost model stays).
    fn set_window(&mut self, window: [u32; 2]) {
        if window != self.window {
            self.window = window;
            self.measured = [None; MAX_LEVEL as usize + 1];
        }
    }

    /// Fit the cost model to GPU times of the [`CALIBRATION`] rungs in a window of
    /// `window` pixels, and move to the dearest rung it puts within the margin of the
    /// budget (returned). Without two distinct sizes among `times` nothing is fitted and
    /// the rung stays.
    pub fn calibrate(&mut self, times: &[(Quality, f64)], window: [u32; 2]) -> Quality {
        self.set_window(window);
        for &(q, ms) in times {
            if let Quality::Preview(k) = q {
                self.measured[k as usize] = Some(ms);
            }
        }
        // y = t · factor = a + b · x, x = pixels: through the first two distinct sizes.
        let points: Vec<(f64, f64)> = times
            .iter()
            .map(|&(q, ms)| (pixels(q, window), ms * q.sample_factor() as f64))
            .collect();
        let pair = points.iter().enumerate().find_map(|(i, p)| {
            points[i + 1..]
                .iter()
                .find(|q| q.0 != p.0)
                .map(|q| (*p, *q))
        });
        let Some(((x1, y1), (x2, y2))) = pair else {
            return self.quality();
        };
        let mut b = (y2 - y1) / (x2 - x1);
        let mut a = y1 - b * x1;
        // Noise can tip a line through two points below zero at one end: then the
        // steeper, pessimistic model through the origin or the flat one through the top.
        if b < 0.0 {
            (a, b) = (y1.max(y2), 0.0);
        } else if a < 0.0 {
            (a, b) = (0.0, (y1 / x1).max(y2 / x2));
        }
        self.fit = Some((a, b));
        let mut k = MAX_LEVEL;
        while k > 1
            && self
                .expected(Quality::Preview(k - 1), window)
                .is_some_and(|t| t <= CLIMB_MARGIN * self.budget_ms)
        {
            k -= 1;
        }
        self.level = k;
        self.quality()
    }

    /// A rung's expected time: its own last one, else the cost model's.
    fn expected(&self, q: Quality, window: [u32; 2]) -> Option<f64> {
        let own = match q {
            Quality::Preview(k) if window == self.window => self.measured[k as usize],
            _ => None,
        };
        own.or_else(|| {
            let (a, b) = self.fit?;
            Some((a + b * pixels(q, window)) / q.sample_factor() as f64)
        })
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
        self.set_window(window);
        self.measured[k as usize] = Some(gpu_ms);
        if k != self.level {
            return;
        }
        if gpu_ms > self.budget_ms {
            self.level = (k + 1).min(MAX_LEVEL);
        } else if k > 1 {
            let dearer = Quality::Preview(k - 1);
            let predicted = self.expected(dearer, window).unwrap_or_else(|| {
                if k % 2 == 1 {
                    // A size step: at most the ratio of the pixels.
                    gpu_ms * pixels(dearer, window) / pixels(quality, window)
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
    fn previews_while_changing_then_one_full_frame_then_nothing() {
        let p = Some(Quality::Preview(5));
        let now = Duration::ZERO;
        let still = SETTLE;
        assert_eq!(next_frame(p, now, false, false, false), p);
        // A view that changed within SETTLE stays a preview even after a full frame.
        assert_eq!(next_frame(p, now, true, false, false), p);
        assert_eq!(
            next_frame(p, still, false, false, false),
            Some(Quality::Full)
        );
        assert_eq!(next_frame(p, still, true, false, false), None);
        // --frames: full frames go on; screenshots and the last frame are full.
        assert_eq!(next_frame(p, still, true, true, false), Some(Quality::Full));
        assert_eq!(next_frame(p, now, false, false, true), Some(Quality::Full));
        // Previews off: a change draws a full frame at once, then nothing.
        assert_eq!(
            next_frame(None, now, false, false, false),
            Some(Quality::Full)
        );
        assert_eq!(next_frame(None, now, true, false, false), None);
    }

    /// planes × (fixed ms + ms per pixel), `full` planes at full quality.
    fn device(full: f64, fixed: f64, per_pixel: f64, window: [u32; 2]) -> impl Fn(Quality) -> f64 {
        move |q: Quality| {
            let planes = (full / q.sample_factor() as f64).ceil();
            planes * (fixed + per_pixel * pixels(q, window))
        }
    }

    #[test]
    fn calibration_starts_at_the_dearest_rung_that_fits_on_a_cpu_and_on_a_gpu() {
        for (what, window, full, fixed, per_pixel, want) in [
            // A CPU device, as lavapipe measured on the default scene at 256² (200
            // planes): 1.5 ms per plane, 2.5 µs per pixel and plane. From rung 8 up: 28,
            // 54, 102, 203 ms: rung 7 (16², sample distance × 8) is the dearest in 80 ms.
            ("cpu", [256, 256], 200.0, 1.5, 2.5e-3, 7),
            // A GPU, where the pixels dominate: 1.6, 3.3, 5.6, 11, 30, 59, 207 ms from
            // rung 8 to 2 at 512²: rung 3 (128², × 2).
            ("gpu", [512, 512], 400.0, 0.05, 1.5e-5, 3),
        ] {
            let cost = device(full, fixed, per_pixel, window);
            let mut c = PreviewControl::new(100.0);
            let times: Vec<(Quality, f64)> = CALIBRATION
                .iter()
                .map(|&k| (Quality::Preview(k), cost(Quality::Preview(k))))
                .collect();
            let q = c.calibrate(&times, window);
            let Quality::Preview(k) = q else { panic!() };
            assert!(cost(q) <= 80.0, "{what}: rung {k} costs {}", cost(q));
            if k > 1 {
                assert!(
                    cost(Quality::Preview(k - 1)) > 80.0,
                    "{what}: rung {} also fits ({} ms)",
                    k - 1,
                    cost(Quality::Preview(k - 1))
                );
            }
            assert_eq!(k, want, "{what}");
            // The model is exact for such a device, so every later climb is right too.
            for _ in 0..10 {
                let q = c.quality();
                c.observe(q, cost(q), window);
            }
            assert_eq!(c.quality(), q, "{what}: the rung moved");
        }
    }

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
        // that time is forgotten (it was for another size) and rung 6 is tried again
        // (no cost model here: no calibration).
        c.observe(Quality::Preview(6), 120.0, [512, 512]);
        assert_eq!(c.quality(), Quality::Preview(7));
        c.observe(Quality::Preview(7), 19.0, w);
        assert_eq!(c.quality(), Quality::Preview(6));
    }
}
