//! Tone mapping: how linear HDR colour becomes displayable [0, 1] (the PNG writer, the
//! viewer's GPU pass and the renderer share it; pure, below all of them).

/// Linear to sRGB transfer (IEC 61966-2-1), for 8-bit output.
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Scaled colour above which every operator gives white (1 to f32 precision), the cap
/// that keeps the operators' arithmetic finite; glsl/tonemap.frag uses the same.
const WHITE_CAP: f32 = 1e9;

/// How linear HDR colour becomes displayable [0, 1] for 8-bit output (EXR is written
/// linear, before any of this).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToneMap {
    /// Exposure in stops: colours are scaled by 2^exposure first.
    pub exposure: f32,
    pub operator: ToneOperator,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ToneOperator {
    /// Clamp to [0, 1]: exact for colours already in range.
    None,
    /// x / (1 + x) per channel (Reinhard et al. 2002, simple form).
    Reinhard,
    /// Narkowicz's fit of the ACES filmic curve: (x(2.51x + 0.03)) / (x(2.43x + 0.59) + 0.14).
    Aces,
}

impl Default for ToneMap {
    fn default() -> Self {
        Self {
            exposure: 0.0,
            operator: ToneOperator::Aces,
        }
    }
}

impl ToneMap {
    /// The largest exposure, in stops either way: 2^64 keeps the scale finite in f32, and
    /// nothing a render makes needs more.
    pub const MAX_EXPOSURE: f32 = 64.0;

    /// An exposure's check: finite and within [`Self::MAX_EXPOSURE`] stops.
    pub fn check_exposure(exposure: f32) -> anyhow::Result<()> {
        anyhow::ensure!(
            exposure.is_finite() && exposure.abs() <= Self::MAX_EXPOSURE,
            "exposure {exposure} must be a number of stops from -{m} to {m}",
            m = Self::MAX_EXPOSURE
        );
        Ok(())
    }

    pub fn apply(&self, c: f32) -> f32 {
        // Capped where every operator is white (ACES' x² overflowed f32 above ~1.8e19 and
        // NaN turned the brightest pixels black; Reinhard's inf / inf likewise).
        let x = (c.max(0.0) * self.exposure.exp2()).min(WHITE_CAP);
        match self.operator {
            ToneOperator::None => x.min(1.0),
            ToneOperator::Reinhard => x / (1.0 + x),
            ToneOperator::Aces => {
                ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_brightest_colours_are_white_under_every_operator() {
        for operator in [
            ToneOperator::None,
            ToneOperator::Reinhard,
            ToneOperator::Aces,
        ] {
            for exposure in [0.0, 60.0, ToneMap::MAX_EXPOSURE] {
                let t = ToneMap { exposure, operator };
                for c in [1e20, 4e29, f32::MAX, f32::INFINITY] {
                    assert_eq!(t.apply(c), 1.0, "{operator:?}, exposure {exposure}, {c}");
                }
                assert_eq!(t.apply(0.0), 0.0);
            }
        }
    }

    #[test]
    fn exposures_beyond_the_range_are_refused() {
        assert!(ToneMap::check_exposure(64.0).is_ok());
        assert!(ToneMap::check_exposure(-64.0).is_ok());
        for e in [64.5, -100.0, f32::NAN, f32::INFINITY] {
            assert!(ToneMap::check_exposure(e).is_err(), "{e}");
        }
    }
}
