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
    pub fn apply(&self, c: f32) -> f32 {
        let x = c.max(0.0) * self.exposure.exp2();
        match self.operator {
            ToneOperator::None => x.min(1.0),
            ToneOperator::Reinhard => x / (1.0 + x),
            ToneOperator::Aces => {
                ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
            }
        }
    }
}
